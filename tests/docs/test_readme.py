"""The README's Python examples run as written, in order, in one namespace (a reader pastes
them one after the other)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def _python_blocks() -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", README.read_text(encoding="utf-8"), re.M | re.S)


def test_the_readme_has_its_python_examples():
    assert len(_python_blocks()) >= 5


@pytest.mark.slow  # the last block runs a 12-point sweep on a local Dask cluster
def test_every_python_example_of_the_readme_runs(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")  # block 2 plots
    pytest.importorskip("dask")  # the sweep's block
    monkeypatch.chdir(tmp_path)
    import matplotlib

    matplotlib.use("Agg")
    namespace: dict[str, object] = {}
    for i, block in enumerate(_python_blocks(), start=1):
        try:
            exec(compile(block, f"README.md python block {i}", "exec"), namespace)
        except Exception as exc:  # the block's number in the failure
            raise AssertionError(f"README python block {i} fails: {exc!r}") from exc
    assert (tmp_path / "mars-dust.nc").is_file() and (tmp_path / "storm.zarr").is_dir()
    assert namespace["p_rgb"].shape == (3, 1801)  # type: ignore[attr-defined]
