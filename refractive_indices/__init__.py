"""Material catalogue of dustoptics (installed as ``dustoptics.refractive_indices``)."""
