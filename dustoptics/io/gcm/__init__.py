"""The dust files Mars general circulation models read.

Each format computes the build's particles again over a grid of radii (a table is one
size distribution; these files are many): :mod:`~dustoptics.io.gcm.common`.

- :mod:`~dustoptics.io.gcm.lmd`: the LMD Mars PCM's ``optprop_dustvis_TM_n50.dat`` and
  ``optprop_dustir_n50.dat`` layouts (formats ``lmd-dustvis``, ``lmd-dustir``);
- :mod:`~dustoptics.io.gcm.ames`: the NASA Ames Mars GCM's
  ``Dust_vis_wolff2010_JD_15bands.dat`` and ``Dust_ir_wolff2010_JD_15bands.dat`` layouts
  (formats ``ames-dustvis``, ``ames-dustir``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.io.gcm import ames, lmd
    from dustoptics.io.gcm.ames import read_ames
    from dustoptics.io.gcm.lmd import read_lmd

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.io.gcm.ames": ("read_ames",),
    "dustoptics.io.gcm.lmd": ("read_lmd",),
}


__all__ = ["ames", "lmd", "read_ames", "read_lmd"]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
