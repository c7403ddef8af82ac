"""The tables kept in ``tables/`` are those the current code builds.

``scripts/build_tables.py --check`` logic, per preset: same input hash, same
grids, numbers equal to 1e-9 relative.  When this fails, run
``python scripts/build_tables.py`` and commit the result.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from dustoptics.models import presets

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "build_tables.py"


def _script():
    spec = importlib.util.spec_from_file_location("build_tables", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("name", presets.list_presets())
def test_stored_table_is_current(name):
    assert _script().differences(name) == []


def test_check_detects_a_stale_table(tmp_path):
    script = _script()
    script.build(["costa"], root=tmp_path)
    assert script.differences("costa", root=tmp_path) == []
    stored = script.open_table(script.table_path("costa", tmp_path))
    stale = stored.replace(phase=stored.phase * (1 + 1e-6))
    stale.save(script.table_path("costa", tmp_path), overwrite=True)
    assert script.differences("costa", root=tmp_path) == [
        "costa: phase differs by up to 1.00e-06 relative"
    ]
