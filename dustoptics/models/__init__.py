"""Models: named dust models as data.

- :mod:`~dustoptics.models.config`: the TOML configuration schema, parsed and
  validated (:func:`~dustoptics.models.config.parse_config`);
- :mod:`~dustoptics.models.compute`: :func:`~dustoptics.models.compute.build_table`,
  which turns a configuration into a table;
- :mod:`~dustoptics.models.presets`: the seeds' named models, shipped as
  TOML files in ``dustoptics/models/data/presets/``;
- :mod:`~dustoptics.models.files`: configuration files users write
  (:func:`~dustoptics.models.files.load_config`), checked against the presets;
- :mod:`~dustoptics.models.build`: a configuration's table computed with
  progress (:class:`TableBuilder`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.models import build, compute, config, files, presets
    from dustoptics.models.build import TableBuilder

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.models.build": ("TableBuilder",),
}


__all__ = [
    "TableBuilder",
    "build",
    "compute",
    "config",
    "files",
    "presets",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
