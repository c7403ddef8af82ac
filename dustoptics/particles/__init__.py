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

from dustoptics.particles import catalogue, coated, custom_sizedist, materials, mixing, sizedist

__all__ = ["catalogue", "coated", "custom_sizedist", "materials", "mixing", "sizedist"]
