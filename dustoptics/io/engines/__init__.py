"""Parameters for rendering engines' own models, beside the tables.

- :mod:`~dustoptics.io.engines.bruneton`: the parameters of Bruneton's precomputed
  atmospheric scattering (2017) for a whole atmosphere
  (:func:`~dustoptics.io.engines.bruneton.write_bruneton`) or, as the ``bruneton``
  format, one aerosol table's Mie part and phase-function snippet.
- :mod:`~dustoptics.io.engines.fit`: fitted analytic phase-function parameters
  (:mod:`dustoptics.scattering.fit`) as JSON and as GLSL, HLSL and WGSL constants
  (:func:`~dustoptics.io.engines.fit.write_fit`).
"""

from __future__ import annotations

from dustoptics.io.engines import bruneton, fit

__all__ = ["bruneton", "fit"]
