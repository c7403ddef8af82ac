"""CSV sets that renderers read, each with what proves it whole.

- :mod:`~dustoptics.io.csv.seed`: the seed framework's files
  (``MiePhaseFunctionSpectrum.csv``, ``MieExtinctionSpectrum.csv``) with a JSON
  provenance sidecar (format ``csv``: :func:`write_seed_csv`, :func:`read_seed_csv`).
- :mod:`~dustoptics.io.csv.cosmoscout`: CosmoScout VR's per-constituent set
  (``<name>_phase.csv``, ``_scattering.csv``, ``_absorption.csv``, ``_density.csv``;
  format ``cosmoscout``: :func:`write_cosmoscout_constituent`,
  :func:`write_cosmoscout_set`, :func:`read_cosmoscout_constituent`,
  :func:`check_cosmoscout_set`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.io.csv import cosmoscout, seed
    from dustoptics.io.csv.cosmoscout import (
        check_cosmoscout_set,
        read_cosmoscout_constituent,
        write_cosmoscout_constituent,
        write_cosmoscout_set,
    )
    from dustoptics.io.csv.seed import read_seed_csv, write_seed_csv

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.io.csv.cosmoscout": (
        "check_cosmoscout_set",
        "read_cosmoscout_constituent",
        "write_cosmoscout_constituent",
        "write_cosmoscout_set",
    ),
    "dustoptics.io.csv.seed": ("read_seed_csv", "write_seed_csv"),
}


__all__ = [
    "check_cosmoscout_set",
    "cosmoscout",
    "read_cosmoscout_constituent",
    "read_seed_csv",
    "seed",
    "write_cosmoscout_constituent",
    "write_cosmoscout_set",
    "write_seed_csv",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
