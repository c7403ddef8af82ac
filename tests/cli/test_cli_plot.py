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
