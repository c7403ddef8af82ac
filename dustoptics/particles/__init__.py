"""Particles: what the dust is made of and how large it is.

- :mod:`~dustoptics.particles.materials`: refractive indices m = n + i k
  (catalogue, tables, dispersion formulas);
- :mod:`~dustoptics.particles.mixing`: effective-medium mixing rules
  (Maxwell Garnett, Bruggeman) and the seed's Mars dust;
- :mod:`~dustoptics.particles.sizedist`: number size distributions n(r).
"""

from dustoptics.particles import coated, materials, mixing, sizedist

__all__ = ["coated", "materials", "mixing", "sizedist"]
