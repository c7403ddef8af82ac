"""Particles: what the dust is made of and how large it is.

- :mod:`~dustoptics.particles.materials`: refractive indices m = n + i k
  (constants, tables, dispersion formulas, orientation averages; CSV tables);
- :mod:`~dustoptics.particles.catalogue`: the materials known by name, each
  with its source;
- :mod:`~dustoptics.particles.mixing`: effective-medium mixing rules
  (Maxwell Garnett, Bruggeman) and the seed's Mars dust;
- :mod:`~dustoptics.particles.sizedist`: number size distributions n(r), the
  analytic families of the literature;
- :mod:`~dustoptics.particles.custom_sizedist`: size distributions the user puts
  together (a mixture of modes, a measured table, a density function).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.particles import catalogue, coated, custom_sizedist, materials, mixing, sizedist

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES: dict[str, tuple[str, ...]] = {}


__all__ = ["catalogue", "coated", "custom_sizedist", "materials", "mixing", "sizedist"]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
