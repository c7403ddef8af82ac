"""Atmospheres: gases, vertical columns and whole atmosphere sets.

- :mod:`~dustoptics.atmosphere.gases`: Rayleigh scattering and ozone absorption;
- :mod:`~dustoptics.atmosphere.column`: density profiles, optical depth and
  number density;
- :mod:`~dustoptics.atmosphere.parametric`: Angstrom turbidity and anomalous
  diffraction (Costa et al. 2021);
- :mod:`~dustoptics.atmosphere.aerosols`: the Earth's aerosol types of OPAC
  (Hess et al. 1998) by Mie theory, and Preetham's turbidity;
- :mod:`~dustoptics.atmosphere.sets`: an :class:`Atmosphere` of constituents
  (molecules, aerosols, ozone) and its builders for Mars and Earth;
- :mod:`~dustoptics.atmosphere.build`: the sets by name, their dust computed
  from a preset, and their provenance record (``dustoptics build mars``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.atmosphere import aerosols, build, column, gases, parametric, sets
    from dustoptics.atmosphere.build import ATMOSPHERES, build_atmosphere
    from dustoptics.atmosphere.sets import (
        Atmosphere,
        Constituent,
        earth_atmosphere,
        mars_atmosphere,
    )

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.atmosphere.build": ("ATMOSPHERES", "build_atmosphere"),
    "dustoptics.atmosphere.sets": (
        "Atmosphere",
        "Constituent",
        "earth_atmosphere",
        "mars_atmosphere",
    ),
}


__all__ = [
    "ATMOSPHERES",
    "Atmosphere",
    "Constituent",
    "aerosols",
    "build",
    "build_atmosphere",
    "column",
    "earth_atmosphere",
    "gases",
    "mars_atmosphere",
    "parametric",
    "sets",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
