"""Tests for dustoptics.particles.custom_sizedist: mixtures, tables, density functions,
and rebuilding any distribution from its provenance record.

Moments and tail fractions are checked against ``scipy.integrate.quad`` of the density
(``_sizedist_reference``), which shares no code with the closed forms.
"""

from __future__ import annotations

import importlib
import math
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from _sizedist_reference import (
    FAST,
    MARS_COARSE,
    MARS_FINE,
    MOMENT_ORDERS,
    check_against_density,
    check_bounds,
    continuous,
    quad_moment,
)
from hypothesis import given

import dustoptics as do
from dustoptics.particles import custom_sizedist
from dustoptics.particles.custom_sizedist import (
    DensityDistribution,
    MultiModal,
    TabulatedDistribution,
    from_dict,
)
from dustoptics.particles.sizedist import (
    DeirmendjianGamma,
    Gamma,
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    Monodisperse,
    PowerLaw,
    SizeDistribution,
)


def cosmoscout_mars() -> MultiModal:
    return MultiModal(modes=(MARS_FINE, MARS_COARSE), relative_number_densities=(1000.0, 1.0))


# ------------------------------------------------------------------- mixtures


@pytest.mark.parametrize("eps", [1e-2, 1e-6])
def test_radius_bounds_of_the_cosmoscout_mixture(eps: float) -> None:
    mars = cosmoscout_mars()
    check_bounds(mars, eps, 0.0, 6.0)
    r_lo, r_hi = mars.radius_bounds_um(tail_fraction=eps)
    assert r_lo == MARS_FINE.radius_bounds_um(tail_fraction=eps)[0]
    assert r_hi == MARS_COARSE.radius_bounds_um(tail_fraction=eps)[1]


@FAST
@given(dist=continuous)
def test_single_mode_mixture_equals_the_mode(dist: SizeDistribution) -> None:
    mix = MultiModal(modes=(dist,), relative_number_densities=(3.7,))
    assert mix.number_fractions == (1.0,)
    r = np.geomspace(0.01, 50.0, 25) * dist.r_eff_um
    np.testing.assert_allclose(mix.pdf(r), dist.pdf(r), rtol=1e-15)
    for k in (0, *MOMENT_ORDERS):
        assert mix.moment(k) == pytest.approx(dist.moment(k), rel=1e-15)
        np.testing.assert_allclose(
            mix.moment_tail_fraction(k, r, upper=True),
            dist.moment_tail_fraction(k, r, upper=True),
            rtol=1e-14,
        )
    assert mix.r_eff_um == pytest.approx(dist.r_eff_um, rel=1e-13)
    assert mix.v_eff == pytest.approx(dist.v_eff, rel=1e-10)
    assert mix.radius_bounds_um(tail_fraction=1e-5) == dist.radius_bounds_um(tail_fraction=1e-5)


def test_mixture_is_the_weighted_sum_of_its_modes() -> None:
    modes = (
        ModifiedGamma(r_eff_um=0.3, v_eff=0.1),
        LogNormal(median_radius_um=2.0, sigma=0.3),
        Gamma(shape=5.0, scale_um=0.1),
    )
    mix = MultiModal(modes=modes, relative_number_densities=[2.0, 1.0, 1.0])
    w = (0.5, 0.25, 0.25)
    assert mix.number_fractions == pytest.approx(w, rel=1e-15)
    r = np.geomspace(0.01, 20.0, 30)
    np.testing.assert_allclose(
        mix.pdf(r), sum(wi * m.pdf(r) for wi, m in zip(w, modes, strict=True)), rtol=1e-14
    )
    for k in (0.5, *MOMENT_ORDERS):
        expected = sum(wi * m.moment(k) for wi, m in zip(w, modes, strict=True))
        assert mix.moment(k) == pytest.approx(expected, rel=1e-14)
        assert mix.moment(k) == pytest.approx(quad_moment(mix, k), rel=1e-8)
        # The tail fraction is the moment-weighted mean of the modes' fractions.
        c = np.array([wi * m.moment(k) for wi, m in zip(w, modes, strict=True)])
        tails = np.array([m.moment_tail_fraction(k, r, upper=False) for m in modes])
        np.testing.assert_allclose(
            mix.moment_tail_fraction(k, r, upper=False),
            c @ tails / c.sum(),
            rtol=1e-13,
            atol=1e-300,
        )


def test_cosmoscout_mars_mixture() -> None:
    mars = cosmoscout_mars()
    assert mars.number_fractions == pytest.approx((1000 / 1001, 1 / 1001), rel=1e-15)
    assert quad_moment(mars, 0.0) == pytest.approx(1.0, rel=1e-9)
    for k in MOMENT_ORDERS:
        assert mars.moment(k) == pytest.approx(quad_moment(mars, k), rel=1e-8)
    # In number the fine mode dominates; in cross-section the coarse one does.
    assert mars.mean_radius_um < 0.05
    assert 0.5 < mars.r_eff_um < 1.4
    d = mars.to_dict()
    assert d["model"] == "multimodal" and "CosmoScout" in d["citation"]
    assert [m["parameters"] for m in d["modes"]] == [
        {"r_eff_um": 0.04, "v_eff": 0.1},
        {"r_eff_um": 1.4, "v_eff": 0.35},
    ]
    assert d["parameters"]["relative_number_densities"] == [1000.0, 1.0]


def test_mixture_with_a_monodisperse_mode() -> None:
    dist = Monodisperse(radius_um=0.8)
    mix = MultiModal(modes=(dist, Gamma(shape=2.0, scale_um=1.0)), relative_number_densities=(1, 3))
    assert not mix.has_density and not mix.is_monodisperse
    assert mix.moment(2) == pytest.approx(0.25 * 0.64 + 0.75 * 6.0, rel=1e-14)
    with pytest.raises(TypeError, match="no probability density"):
        mix.pdf(1.0)
    two = MultiModal(modes=(dist, dist), relative_number_densities=(1, 2))
    assert two.is_monodisperse


def test_mixtures_are_immutable_and_hashable() -> None:
    assert cosmoscout_mars() == cosmoscout_mars()
    assert len({cosmoscout_mars(), cosmoscout_mars(), MARS_FINE}) == 2


# ------------------------------------------------- tables and density functions


def test_tabulated_dn_dr_and_dn_dlnr_and_csv(tmp_path) -> None:
    r = np.array([0.1, 0.3, 0.7, 1.5, 3.0])
    dndr = np.array([0.0, 2.0, 1.5, 0.4, 0.0])
    a = TabulatedDistribution(radius_um=r, dn_dr=dndr)
    check_against_density(a, 0.1, 3.0, points=r)
    # The same table as dN/dln r = r n(r) at the points.
    b = TabulatedDistribution(radius_um=r, dn_dlnr=r * dndr)
    np.testing.assert_allclose(b.pdf(r), a.pdf(r), rtol=1e-14)
    assert b.moment(3.0) == pytest.approx(a.moment(3.0), rel=1e-14)
    path = tmp_path / "sizes.csv"
    path.write_text(
        "# measured\nradius_um,dn_dlnr\n" + "".join(f"{x},{y}\n" for x, y in zip(r, r * dndr))
    )
    c = TabulatedDistribution.from_csv(path)
    assert c.moment(2.0) == pytest.approx(a.moment(2.0), rel=1e-14)


def test_density_distribution_is_the_public_way_to_define_one() -> None:
    """Any density function and bounds, no subclassing; it equals the built-in
    model with the same density (here a modified gamma on a wide range)."""
    ref = ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
    d = DensityDistribution(
        density=lambda r: r**2 * np.exp(-r / 0.32), r_min_um=1e-4, r_max_um=40.0, name="gamma 3"
    )
    for k in (0.0, 2.0, 3.0, 6.0):
        assert d.moment(k) == pytest.approx(ref.moment(k), rel=1e-9)
    assert d.radius_bounds_um(tail_fraction=1e-7)[1] == pytest.approx(
        ref.radius_bounds_um(tail_fraction=1e-7)[1], rel=1e-6
    )
    assert d.to_dict()["parameters"]["name"] == "gamma 3"


def test_user_distributions_through_compute_optics() -> None:
    """The radius quadrature needs only pdf and the tail bounds: a tabulated
    table that is the modified gamma's density on 400 points gives its
    optics (to the table's interpolation error, 1e-4)."""
    ref = ModifiedGamma(r_eff_um=0.5, v_eff=0.1)
    r = np.linspace(0.02, 3.0, 4000)
    tab = TabulatedDistribution(radius_um=r, dn_dr=ref.pdf(r))
    a = do.compute_optics(1.5 + 0.01j, ref, [550.0], [0.0, 90.0, 180.0])
    b = do.compute_optics(1.5 + 0.01j, tab, [550.0], [0.0, 90.0, 180.0])
    np.testing.assert_allclose(b.cross_sections.cext_um2, a.cross_sections.cext_um2, rtol=1e-4)
    np.testing.assert_allclose(b.phase, a.phase, rtol=1e-3)


def test_a_density_distribution_truncated() -> None:
    d = DensityDistribution(density=lambda r: np.exp(-r), r_min_um=0.01, r_max_um=10.0)
    check_against_density(d.truncated(r_min_um=0.1, r_max_um=2.0), 0.1, 2.0)


# -------------------------------------------------------------------- records

RECORDED: list[SizeDistribution] = [
    ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
    Gamma(shape=3.0, scale_um=0.32),
    LogNormal(median_radius_um=0.5, sigma=0.4),
    ModifiedLogNormal(r_eff_um=1.4, v_eff=0.35),
    Monodisperse(radius_um=0.8),
    DeirmendjianGamma(alpha=6.0, b=1.5, gamma=1.0),
    PowerLaw(exponent=4.0, r_min_um=0.05, r_max_um=10.0),
    ModifiedGamma(r_eff_um=1.6, v_eff=0.2).truncated(r_min_um=0.1, r_max_um=3.0),
    LogNormal(median_radius_um=0.2, sigma=0.6).truncated(r_min_um=0.05),
    MultiModal(
        modes=(MARS_FINE, MultiModal(modes=(MARS_COARSE,), relative_number_densities=(1.0,))),
        relative_number_densities=(1000.0, 1.0),
    ),
]


@pytest.mark.parametrize("dist", RECORDED, ids=lambda d: d.model)
def test_from_dict_rebuilds_every_model(dist: SizeDistribution) -> None:
    again = from_dict(dist.to_dict())
    assert again == dist
    assert again.to_dict() == dist.to_dict()


def test_from_dict_rebuilds_a_table() -> None:
    # Tables are compared by identity: the record of the rebuilt one is the same.
    tab = TabulatedDistribution(radius_um=[0.1, 0.3, 1.0], dn_dlnr=[0.0, 2.0, 0.5])
    again = from_dict(tab.to_dict())
    assert isinstance(again, TabulatedDistribution)
    assert again.to_dict() == tab.to_dict()


@pytest.mark.parametrize(
    ("record", "match"),
    [
        (
            {"model": "weibull", "parameters": {}},
            r"model must be one of 'modified_gamma', .*'weibull'",
        ),
        ({"model": "gamma"}, "needs a 'parameters' mapping"),
        ({"model": "gamma", "parameters": {"shape": 3.0}}, "'gamma' has wrong parameters"),
        ({"model": "multimodal", "parameters": {}}, "needs a list of 'modes'"),
        (
            DensityDistribution(
                density=lambda r: np.exp(-r), r_min_um=0.01, r_max_um=10.0
            ).to_dict(),
            "cannot be rebuilt from its record",
        ),
    ],
)
def test_from_dict_rejects_bad_records(record: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        from_dict(record)


# ------------------------------------------------------------ old import paths

MOVED = ("DensityDistribution", "MultiModal", "TabulatedDistribution", "from_dict")


@pytest.mark.parametrize("name", MOVED)
def test_the_old_sizedist_path_is_gone(name: str) -> None:
    """The user's distributions live in custom_sizedist only (the old path was never released)."""
    sizedist = importlib.import_module("dustoptics.particles.sizedist")
    assert not hasattr(sizedist, name)
    assert hasattr(custom_sizedist, name)


def test_the_public_names_do_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert (do.MultiModal, do.TabulatedDistribution, do.DensityDistribution) == (
            MultiModal,
            TabulatedDistribution,
            DensityDistribution,
        )
    sizedist = importlib.import_module("dustoptics.particles.sizedist")
    with pytest.raises(AttributeError, match="has no attribute 'Nothing'"):
        sizedist.Nothing  # noqa: B018


# ------------------------------------------------------------------ bad input

BAD_CONSTRUCTIONS: list[tuple[Callable[[], object], str]] = [
    (
        lambda: MultiModal(modes=(), relative_number_densities=()),
        r"modes must contain at least one",
    ),
    (
        lambda: MultiModal(modes=(MARS_FINE, MARS_COARSE), relative_number_densities=(1.0, -1.0)),
        r"relative_number_densities must all be > 0; got \[1\.0, -1\.0\]",
    ),
    (
        lambda: MultiModal(modes=(MARS_FINE, MARS_COARSE), relative_number_densities=(1.0, 0.0)),
        r"relative_number_densities must all be > 0",
    ),
    (
        lambda: MultiModal(modes=(MARS_FINE,), relative_number_densities=(math.nan,)),
        r"relative_number_densities must be finite",
    ),
    (
        lambda: MultiModal(modes=(MARS_FINE,), relative_number_densities=(math.inf,)),
        r"relative_number_densities must be finite",
    ),
    (
        lambda: MultiModal(modes=(MARS_FINE, MARS_COARSE), relative_number_densities=(1.0,)),
        r"relative_number_densities must have one entry per mode \(2 modes\); got 1",
    ),
    (
        lambda: TabulatedDistribution(radius_um=[0.1, 0.3, 0.2], dn_dr=[1, 1, 1]),
        "strictly increasing",
    ),
    (
        lambda: TabulatedDistribution(radius_um=[0.1, 0.2, 0.2], dn_dr=[1, 1, 1]),
        "strictly increasing",
    ),
    (
        lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dr=[1, -1]),
        r"dn_dr must be finite and >= 0; got -1.0",
    ),
    (
        lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dlnr=[1, np.nan]),
        "dn_dlnr must be finite",
    ),
    (lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dr=[0, 0]), "holds no particles"),
    (
        lambda: TabulatedDistribution(radius_um=[0.1, 0.2], dn_dr=[1, 1], dn_dlnr=[1, 1]),
        "exactly one",
    ),
    (
        lambda: DensityDistribution(density=lambda r: -r, r_min_um=0.1, r_max_um=1.0),
        "finite and >= 0",
    ),
]


@pytest.mark.parametrize(("build", "message"), BAD_CONSTRUCTIONS)
def test_bad_parameters_raise(build: Callable[[], object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build()


def test_bad_modes_raise_type_error() -> None:
    with pytest.raises(TypeError, match=r"modes\[1\] must be a SizeDistribution"):
        MultiModal(modes=(MARS_FINE, 1.0), relative_number_densities=(1.0, 1.0))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="modes must be a sequence"):
        MultiModal(modes=MARS_FINE, relative_number_densities=(1.0,))  # type: ignore[arg-type]


# ----------------------------------------------------------- refused inputs (issue 29)


@pytest.mark.parametrize("special", ["fifo", "/dev/zero", "directory"])
def test_from_csv_refuses_what_is_not_a_regular_file_before_reading(tmp_path, special) -> None:
    import os

    from dustoptics.io import FormatError

    path = tmp_path / "sizes.csv"
    if special == "fifo":
        os.mkfifo(path)  # a reader that opened it would block forever
    elif special == "directory":
        path.mkdir()
    else:
        path = Path(special)
    with pytest.raises(FormatError, match="not a regular file|is a directory"):
        TabulatedDistribution.from_csv(path)


def test_from_csv_refuses_a_cell_beyond_the_csv_limit_and_a_huge_file(tmp_path, monkeypatch):
    from dustoptics import _files
    from dustoptics.io import FormatError

    path = tmp_path / "sizes.csv"
    path.write_text("radius_um,dn_dr\n1," + "9" * (200 * 1024) + "\n")
    with pytest.raises(FormatError, match="not a valid CSV file.*field larger than field limit"):
        TabulatedDistribution.from_csv(path)
    path.write_text("radius_um,dn_dr\n1,1\n2,1\n")
    monkeypatch.setattr(_files, "MAX_TEXT_BYTES", 10)
    monkeypatch.setattr(_files.read_checked, "__kwdefaults__", {"limit": 10})
    with pytest.raises(FormatError, match="larger than the 10-byte limit"):
        TabulatedDistribution.from_csv(path)


@pytest.mark.parametrize("modes", [None, 3, "mode", {"a": 1}])
def test_multimodal_names_modes_that_are_not_a_sequence(modes) -> None:
    with pytest.raises(TypeError, match="modes must be a sequence of SizeDistribution"):
        MultiModal(modes=modes, relative_number_densities=(1.0,))
