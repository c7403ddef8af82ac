"""``dustoptics sweep``: an existing ``FILE.nc`` is replaced only with ``--force``, checked first.

The sweep itself is :func:`dustoptics.sweep.sweep`'s (``tests/sweep``); here it is replaced by
a stand-in that records its call.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

import dustoptics.sweep
from dustoptics.cli import main


@pytest.fixture(name="calls")
def calls_fixture(monkeypatch):
    calls: list = []

    def recorded(config, **kwargs):
        calls.append(kwargs)
        return SimpleNamespace(sizes={"point": 2})

    monkeypatch.setattr(dustoptics.sweep, "sweep", recorded)
    return calls


def test_an_existing_netcdf_file_needs_force(tmp_path, capsys, calls):
    out = tmp_path / "sweep.nc"
    out.write_bytes(b"an earlier sweep")
    assert main(["sweep", "my.toml", "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "already exists; use --force" in err and len(err.splitlines()) == 1
    assert calls == [] and out.read_bytes() == b"an earlier sweep"  # before any work
    assert main(["sweep", "my.toml", "--out", str(out), "--quiet", "--force"]) == 0
    assert len(calls) == 1


def test_an_existing_store_is_resumed_without_force(tmp_path, calls):
    store = tmp_path / "sweep.zarr"
    store.mkdir()
    assert main(["sweep", "my.toml", "--out", str(store), "--quiet"]) == 0
    assert calls[0]["out"] == store
