"""``sky compare``'s figures and progress: one line per legend entry, labelled axes (issue 28)."""

from __future__ import annotations

import io
import re
from typing import Any

import numpy as np
import pytest

from dustoptics.sky import _progress
from dustoptics.sky import compare as cmp

pytest.importorskip("xarray")
pytest.importorskip("matplotlib")

MODELS = ("collienne", "costa", "hybrid")
ELEVATIONS = (10.0, 30.0)


@pytest.fixture(scope="module")
def run() -> tuple[Any, str]:
    stream = io.StringIO()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_progress, "QUIET_SECONDS", 0.0)  # report from the start
        ds = cmp.compare_mars_models(
            models=MODELS, sun_elevations_deg=ELEVATIONS, azimuth_step_deg=45.0, progress=stream
        )
    return ds, stream.getvalue()


@pytest.fixture(scope="module")
def figures(run: tuple[Any, str]) -> Any:
    import matplotlib.pyplot as plt

    figs = cmp.plot_comparison(run[0])
    yield figs
    for fig in figs.values():
        plt.close(fig)


def test_the_transmittance_has_one_line_per_legend_entry(run: tuple[Any, str], figures) -> None:
    ds = run[0]
    (ax,) = figures["transmittance"].axes
    lines = ax.get_lines()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(lines) == len(labels) == len({line.get_label() for line in lines})
    assert [line.get_label() for line in lines] == labels
    # No two lines on top of each other: models with the same extinction share one line.
    curves = [np.asarray(line.get_ydata(), dtype=float) for line in lines]
    for i in range(len(curves)):
        for j in range(i + 1, len(curves)):
            assert not np.allclose(curves[i], curves[j], rtol=1e-12, atol=0.0)
    # Every model is on every wavelength's lines, once.
    for w in ds.wavelength.values:
        named = [lab.rsplit(", ", 1)[0] for lab in labels if lab.endswith(f", {w:g} nm")]
        assert sorted(m for lab in named for m in lab.split(" = ")) == sorted(MODELS)
        # Each line is the dataset's curve of the models it names.
        for lab, line in zip(labels, lines):
            if lab.endswith(f", {w:g} nm"):
                for m in lab.rsplit(", ", 1)[0].split(" = "):
                    np.testing.assert_allclose(
                        line.get_ydata(),
                        ds.sun_transmittance.sel(model=m, wavelength=w),
                        rtol=1e-12,
                    )


def test_the_chromaticity_points_carry_their_sun_elevations(run, figures) -> None:
    ds = run[0]
    (ax,) = figures["chromaticity"].axes
    texts = [(t.get_text(), tuple(np.round(t.xy, 12))) for t in ax.texts]
    for m in MODELS:
        for e in ELEVATIONS:
            xy = (
                float(ds.chromaticity_x.sel(model=m, sun_elevation=e)),
                float(ds.chromaticity_y.sel(model=m, sun_elevation=e)),
            )
            assert (f"{e:g}", tuple(np.round(xy, 12))) in texts


def test_every_axis_is_labelled_with_its_unit(figures) -> None:
    for name, fig in figures.items():
        for ax in fig.axes:
            labels = [lab for lab in (ax.get_xlabel(), ax.get_ylabel()) if lab]
            assert labels, f"{name}: an axes without labels"
            for lab in labels:
                assert re.search(r"\[[^]]+\]", lab), f"{name}: {lab!r} has no unit"
            if ax.name == "rectilinear" and not hasattr(ax, "_colorbar"):
                assert ax.get_xlabel() and ax.get_ylabel(), name
            assert ax.get_title() or fig.get_suptitle() or hasattr(ax, "_colorbar"), name


def test_every_sky_of_the_comparison_reports_its_progress(run: tuple[Any, str]) -> None:
    text = run[1]
    n = len(MODELS) * (1 + len(ELEVATIONS))
    for k in range(1, n + 1):
        assert re.search(rf"sky compare: sky {k} of {n}: model \d of 3 \(\w+\), ", text)
    assert re.search(r"sky compare: orders of scattering: \d+ orders .*, [\d.]+ s", text)
    assert re.search(r"sky compare: lines of sight: (\d+) of \1, [\d.]+ s", text)
    assert text.rstrip().endswith(" s")
    assert f"{n} skies of 3 models done" in text
