"""Parameters for rendering engines' own models, beside the tables.

- :mod:`~dustoptics.io.engines.bruneton`: the parameters of Bruneton's precomputed
  atmospheric scattering (2017) for a whole atmosphere
  (:func:`~dustoptics.io.engines.bruneton.write_bruneton`) or, as the ``bruneton``
  format, one aerosol table's Mie part and phase-function snippet.
- :mod:`~dustoptics.io.engines.cosmoscout_preprocessor`: every sampling option of CosmoScout
  VR's ``bruneton-preprocessor`` chosen for a set, and its transmittance quadrature.
- :mod:`~dustoptics.io.engines.precomputation`: the orders, NU size and scattering-density
  directions a Bruneton-style precomputation needs for a set (both engines use them).
- :mod:`~dustoptics.io.engines.fit`: fitted analytic phase-function parameters
  (:mod:`dustoptics.scattering.fit`) as JSON and as GLSL, HLSL and WGSL constants
  (:func:`~dustoptics.io.engines.fit.write_fit`).
- :mod:`~dustoptics.io.engines.bevy`, :mod:`~dustoptics.io.engines.openspace`,
  :mod:`~dustoptics.io.engines.celestia`, :mod:`~dustoptics.io.engines.calcmysky`: the
  files of Bevy (ScatteringMedium terms and a phase texture in Bevy's column order),
  OpenSpace (an ``.asset`` atmosphere table), Celestia (an ``.ssc`` atmosphere block)
  and CalcMySky (an ``.atmo`` file with its GLSL phase block); their formats, fitted to
  a set's sky, are :mod:`dustoptics.sky.engines`'.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.io.engines import (
        bevy,
        bruneton,
        calcmysky,
        celestia,
        cosmoscout_preprocessor,
        fit,
        openspace,
        precomputation,
    )

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES: dict[str, tuple[str, ...]] = {}


__all__ = [
    "bevy",
    "bruneton",
    "calcmysky",
    "celestia",
    "cosmoscout_preprocessor",
    "fit",
    "openspace",
    "precomputation",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
