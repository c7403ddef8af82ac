"""``dustoptics fit``: files in ``DIR/NAME/``, and what would fail refused before any work."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from dustoptics.cli import main
from dustoptics.scattering import fit

COSTA = Path(__file__).resolve().parents[2] / "tables" / "costa" / "costa.nc"


def _no_fit(monkeypatch):
    def no_work(*args, **kwargs):
        raise AssertionError("fitted before the request was checked")

    monkeypatch.setattr(fit, "fit_table", no_work)


def test_fit_writes_into_dir_name_and_refuses_to_replace_before_fitting(
    tmp_path, capsys, monkeypatch
):
    argv = ["fit", str(COSTA), "--model", "hg", "--colour", "wavelengths", "--out", str(tmp_path)]
    assert main(argv) == 0
    folder = tmp_path / "costa"  # DIR/NAME/, as build and export write
    names = sorted(p.name for p in folder.iterdir())
    assert names == [f"costa_henyey-greenstein.{e}" for e in ("glsl", "hlsl", "json", "wgsl")]
    assert json.loads((folder / "costa_henyey-greenstein.json").read_text())["rows"]
    out = capsys.readouterr().out
    assert f"wrote {folder / 'costa_henyey-greenstein.json'}" in out
    _no_fit(monkeypatch)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "already exist" in err and "costa_henyey-greenstein" in err, err
    monkeypatch.undo()
    assert main([*argv, "--force"]) == 0


@pytest.mark.parametrize(
    ("options", "needle"),
    [
        (["--model", "nope"], "--model"),
        (["--prefix", "9bad"], "--prefix must start with a letter"),
        (["--prefix", "A__B"], "no '__'"),
    ],
)
def test_fit_options_that_would_fail_are_refused_before_any_work(
    tmp_path, capsys, monkeypatch, options, needle
):
    _no_fit(monkeypatch)
    assert main(["fit", "costa", *options, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / "o").exists()
