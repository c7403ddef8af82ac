"""Scattering: from one sphere to a converged population.

- :mod:`~dustoptics.scattering.mie`: the numba Mie kernel (single spheres and
  batched sums);
- :mod:`~dustoptics.scattering.quadrature`: deterministic radius nodes
  (Gauss-Legendre panels in a stretched size-parameter variable);
- :mod:`~dustoptics.scattering.optics`: :func:`compute_optics`, the adaptive
  polydisperse average that returns a :class:`~dustoptics.table.Table`, as
  request (validated once) -> solve -> assemble;
- :mod:`~dustoptics.scattering.solve`: the solve step (threads over
  wavelengths, progress) and the assemble step (checks, warnings, provenance);
- :mod:`~dustoptics.scattering.refinement`: the adaptive refinement of the
  radius quadrature at one wavelength, behind :func:`compute_optics`;
- :mod:`~dustoptics.scattering.phase`: analytic phase functions and the seed
  models' parameter sets;
- :mod:`~dustoptics.scattering.tabulated_phase`: phase functions sampled on
  angles, as renderers read them: sphere integral, renormalization, Meyran's
  hybrid blend, flattening;
- :mod:`~dustoptics.scattering.expansion`: the scattering matrix's expansion
  in generalized spherical functions, DISORT moments, delta-M truncation;
- :mod:`~dustoptics.scattering.fit`: analytic phase functions fitted to a
  table (:meth:`dustoptics.table.Table.fit`).
"""

from dustoptics.scattering import (
    expansion,
    fit,
    mie,
    optics,
    phase,
    quadrature,
    tabulated_phase,
)
from dustoptics.table import register_table_fitter

# Table.fit is served from here: the data model imports nothing above it.
register_table_fitter(fit.fit_table)

__all__ = ["expansion", "fit", "mie", "optics", "phase", "quadrature", "tabulated_phase"]
