"""``dustoptics plot`` (needs matplotlib)."""

from __future__ import annotations

import pytest
from _cli import config_fixture, run_build  # noqa: F401 (fixture config)

from dustoptics.cli import main


def test_plot_writes_a_figure(config, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    assert run_build(config, tmp_path, "--format", "hdf5") == 0
    h5 = str(tmp_path / "small-dust" / "small-dust.h5")
    for kind, suffix in (("phase", "png"), ("polar", "svg"), ("map", "png"), ("spectra", "svg")):
        out = tmp_path / f"fig-{kind}.{suffix}"
        assert main(["plot", h5, "--kind", kind, "--out", str(out)]) == 0
        assert out.stat().st_size > 0
    assert (
        main(
            [
                "plot",
                h5,
                "--kind",
                "phase",
                "--wavelengths-nm",
                "551",
                "--out",
                str(tmp_path / "f.png"),
            ]
        )
        == 1
    )
    assert "551" in capsys.readouterr().err


def test_plot_refuses_what_would_fail_at_saving_before_any_work(config, tmp_path, capsys):
    """An existing figure without --force, or a suffix no figure can have: refused before the
    table is read or anything drawn."""
    missing = str(tmp_path / "no-such-table.nc")  # reading it would fail: nothing is read
    existing = tmp_path / "fig.png"
    existing.write_bytes(b"an earlier figure")
    assert main(["plot", missing, "--out", str(existing)]) == 1
    assert "already exist" in capsys.readouterr().err
    assert main(["plot", missing, "--out", str(tmp_path / "fig.pdf")]) == 2
    assert "--out must end in .png or .svg" in capsys.readouterr().err
    assert existing.read_bytes() == b"an earlier figure"
