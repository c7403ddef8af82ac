"""The sky a table makes: spectral radiative transfer and pictures.

- :mod:`~dustoptics.sky.medium`: an atmosphere set as a scattering medium
  (per-constituent optics, Legendre moments, delta-M truncation, slant columns);
- :mod:`~dustoptics.sky.orders`: multiple scattering by successive orders
  (discrete ordinates, Fourier series in azimuth, pseudo-spherical beam);
- :mod:`~dustoptics.sky.render`: radiance along lines of sight through the
  spherical shell (exact single scattering plus the diffuse source);
- :mod:`~dustoptics.sky.scene`: the sky dome, colour and images;
- :mod:`~dustoptics.sky.space`: the limb seen from space;
- :mod:`~dustoptics.sky.approximations`: the sky an engine draws (fitted phase
  function, RGB channels, float16, its angles) beside the exact one;
- :mod:`~dustoptics.sky.compare`: the seed thesis's Mars models compared, and
  against the rovers' sky colour;
- :mod:`~dustoptics.sky.mer_search`: published Mars dusts against the rovers'
  sky colour;
- :mod:`~dustoptics.sky.job`: a sky as files (what ``dustoptics sky`` writes).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.sky import job, medium, orders, render
    from dustoptics.sky.job import SkyJob
    from dustoptics.sky.medium import Medium
    from dustoptics.sky.orders import DiffuseField, solve_orders
    from dustoptics.sky.render import line_of_sight_radiance

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.sky.job": ("SkyJob",),
    "dustoptics.sky.medium": ("Medium",),
    "dustoptics.sky.orders": ("DiffuseField", "solve_orders"),
    "dustoptics.sky.render": ("line_of_sight_radiance",),
}


__all__ = [
    "DiffuseField",
    "Medium",
    "SkyJob",
    "job",
    "line_of_sight_radiance",
    "medium",
    "orders",
    "render",
    "solve_orders",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
