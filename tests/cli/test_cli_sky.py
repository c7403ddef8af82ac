"""``dustoptics sky``: files in ``DIR/NAME/``; sizes, presets and existing files checked first.

The sky itself is computed by :mod:`dustoptics.sky` (``tests/sky``); here the job's files are
replaced by stand-ins, so that only what the command line does is tested.
"""

from __future__ import annotations

import pytest

from dustoptics.cli import main
from dustoptics.sky.job import SkyJob


@pytest.fixture(name="stand_in")
def stand_in_fixture(monkeypatch):
    """SkyJob.files gives each announced file a few bytes (no sky is computed)."""
    monkeypatch.setattr(SkyJob, "files", lambda self: dict.fromkeys(self.targets(), b"sky"))


def _no_sky(monkeypatch):
    def no_work(self):
        raise AssertionError("computed before the request was checked")

    monkeypatch.setattr(SkyJob, "files", no_work)


@pytest.mark.parametrize(
    ("argv", "folder"),
    [
        (["sky", "mars", "--dust", "costa"], "mars-costa"),
        (["sky", "earth", "--sunset"], "earth"),
        (["sky", "compare", "--models", "costa,hybrid"], "mars-comparison"),
    ],
)
def test_sky_writes_into_dir_name(tmp_path, capsys, stand_in, argv, folder):
    assert main([*argv, "--out", str(tmp_path), "--quiet"]) == 0
    assert [p.name for p in tmp_path.iterdir()] == [folder]
    names = [p.name for p in (tmp_path / folder).iterdir()]
    assert names and all(n.startswith(folder) for n in names)


def test_sky_refuses_to_replace_before_any_work(tmp_path, capsys, stand_in, monkeypatch):
    argv = ["sky", "earth", "--out", str(tmp_path), "--quiet"]
    assert main(argv) == 0
    _no_sky(monkeypatch)
    assert main(argv) == 1
    assert "already exist" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("options", "needle"),
    [
        (["earth", "--size", "8"], "--size: must be an integer in [16, 8192]"),
        (["mars", "--dust", "nope"], "--dust: unknown preset 'nope'"),
        (["mars", "--dust", "../x"], "--dust: unknown preset '../x'"),
        (["compare", "--models", "costa,my dust"], "--models: unknown preset 'my dust'"),
    ],
)
def test_sky_options_that_would_fail_are_refused_before_any_work(
    tmp_path, capsys, monkeypatch, options, needle
):
    _no_sky(monkeypatch)
    assert main(["sky", *options, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / "o").exists()
