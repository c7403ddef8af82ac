"""Models: named dust models as data.

- :mod:`~dustoptics.models.config`: the TOML configuration schema, parsed and
  validated (:func:`~dustoptics.models.config.parse_config`);
- :mod:`~dustoptics.models.compute`: :func:`~dustoptics.models.compute.build_table`,
  which turns a configuration into a table;
- :mod:`~dustoptics.models.presets`: the seeds' named models, shipped as
  TOML files in ``dustoptics/models/data/presets/``;
- :mod:`~dustoptics.models.files`: configuration files users write
  (:func:`~dustoptics.models.files.load_config`), checked against the presets.
"""

from dustoptics.models import compute, config, files, presets

__all__ = ["compute", "config", "files", "presets"]
