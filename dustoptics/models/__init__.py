"""Models: named dust models as data.

- :mod:`~dustoptics.models.config`: the TOML configuration schema and
  :func:`build_table`, which turns a configuration into a table;
- :mod:`~dustoptics.models.presets`: the seeds' named models, shipped as
  TOML files in ``dustoptics/models/data/presets/``.
"""

from dustoptics.models import config, presets

__all__ = ["config", "presets"]
