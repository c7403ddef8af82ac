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

from dustoptics.models import build, compute, config, files, presets
from dustoptics.models.build import TableBuilder

__all__ = [
    "TableBuilder",
    "build",
    "compute",
    "config",
    "files",
    "presets",
]
