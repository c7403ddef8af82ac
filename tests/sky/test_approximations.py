"""The preview of an engine's approximations: identity, an independent fit, float16, refusals, files."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from dustoptics.cli import main
from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.scattering.tabulated_phase import mean_cosine, sphere_integral
from dustoptics.sky import Medium
from dustoptics.sky.approximations import (
    PHASE_CHOICES,
    Approximations,
    PreviewSummary,
    approximate_medium,
    check_approximations,
    preview_sky,
)
from dustoptics.sky.compare import mars_sky_atmosphere
from dustoptics.sky.scene import sky_radiance

xr = pytest.importorskip("xarray")
mpl_image = pytest.importorskip("matplotlib.image")

#: A coarse dome and few streams: the tests compare skies with each other, not with nature.
SKY = {"view_zenith_deg": np.arange(0.0, 90.1, 10.0), "azimuth_step_deg": 20.0}
SUN_DEG = 10.0
ALBEDO = 0.2
#: Unit roundoff of IEEE binary16 (11 significant bits, round to nearest).
U16 = 2.0**-11


@pytest.fixture(scope="module")
def atmosphere():  # type: ignore[no-untyped-def]
    return mars_sky_atmosphere("hybrid", optical_depth=0.5)


@pytest.fixture(scope="module")
def medium(atmosphere):  # type: ignore[no-untyped-def]
    return Medium.from_atmosphere(atmosphere, n_streams=8)


@pytest.fixture(scope="module")
def exact(medium):  # type: ignore[no-untyped-def]
    return sky_radiance(medium, sun_elevation_deg=SUN_DEG, ground_albedo=ALBEDO, **SKY)


def _preview(medium, exact, **kw):  # type: ignore[no-untyped-def]
    return preview_sky(
        medium, Approximations(**kw), sun_elevation_deg=SUN_DEG, ground_albedo=ALBEDO, exact=exact
    )


def test_exact_against_exact_differs_by_nothing(medium, exact) -> None:  # type: ignore[no-untyped-def]
    pv = _preview(medium, exact)
    assert pv.approximated is exact  # nothing differs: not rendered again
    assert np.array_equal(pv.approximated.radiance, exact.radiance)
    assert np.all(pv.delta_xy == 0.0)
    assert np.all(pv.luminance_ratio == 1.0)
    s = pv.summary
    assert (s.dome_delta_xy_max, s.sun_delta_xy_max) == (0.0, 0.0)
    assert s.dome_luminance_ratio_mean == 1.0 and s.sun_luminance_ratio_mean == 1.0


def test_rebuilt_moments_are_the_medium_s_own(medium) -> None:  # type: ignore[no-untyped-def]
    # The table's own angles (1801, 0.1 deg) as the engine's: the same phase
    # function, so the moments projected again are those of Medium.from_atmosphere.
    n = medium.tables[1].theta_deg.size
    assert np.array_equal(medium.tables[1].theta_deg, np.linspace(0.0, 180.0, n))
    approx, fit = approximate_medium(medium, Approximations(angles=f"theta:{n}"))
    assert fit is None and approx is not medium
    assert np.array_equal(approx.chi, medium.chi)
    assert np.array_equal(approx.truncation, medium.truncation)
    assert approx.slant is medium.slant  # the geometry is reused


def _hg(mu: np.ndarray, g: np.ndarray) -> np.ndarray:
    # Written out here, independently of dustoptics.scattering.phase.
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * mu) ** 1.5)


def test_dhg_preview_against_an_independent_recomputation(atmosphere, medium, exact) -> None:  # type: ignore[no-untyped-def]
    pv = _preview(medium, exact, phase="fit:dhg")
    fit = pv.fit
    assert fit is not None and fit.model == "dhg-costa2021"
    # The fitted DHG evaluated by hand at the table's angles, put into the
    # atmosphere, and the medium and sky made from it the ordinary way.
    dust = atmosphere.constituent("aerosols")
    theta = np.asarray(dust.table.theta_deg)
    mu = np.cos(np.deg2rad(theta))[None, :]
    g1, g2, alpha = (fit.parameter(n)[:, None] for n in ("g1", "g2", "alpha"))
    phase = alpha * _hg(mu, g1) + (1.0 - alpha) * _hg(mu, g2)
    table = dust.table.replace(phase=phase, g=mean_cosine(phase, theta_deg=theta))
    constituents = tuple(
        replace(c, table=table) if c.role == "aerosols" else c for c in atmosphere.constituents
    )
    other = Medium.from_atmosphere(replace(atmosphere, constituents=constituents), n_streams=8)
    sky = sky_radiance(other, sun_elevation_deg=SUN_DEG, ground_albedo=ALBEDO, **SKY)
    np.testing.assert_allclose(pv.approximated.radiance, sky.radiance, rtol=1e-9, atol=0)
    # And the fit changes the sky (else the comparison above proves nothing).
    assert pv.summary.dome_delta_xy_max > 1e-3


def test_float16_error_within_the_half_float_epsilon(medium, exact) -> None:  # type: ignore[no-untyped-def]
    approx, _ = approximate_medium(medium, Approximations(float16=True))
    for t16, t in zip(approx.tables, medium.tables, strict=True):
        if not np.any(t.cross_sections.csca_um2 > 0):
            continue
        assert np.all(t.phase >= 2.0**-14)  # binary16's normal range: relative rounding holds
        rel = np.abs(t16.phase / t.phase - 1.0)
        assert rel.max() <= U16  # each sample: round to nearest, 11 significant bits
        assert rel.max() > U16 / 4  # and it was rounded
    pv = _preview(medium, exact, float16=True)
    # Every order n of scattering is a positive-weighted integral of n phase
    # factors, each renormalized to 1 over the sphere: within (1 + u)/(1 - u)
    # of its own, so the order is within (1 + 2u)^n and the sky within
    # (1 + 2u)^N - 1 with N the orders summed.
    n_orders = max(pv.approximated.n_orders, exact.n_orders)
    bound = (1.0 + 2.0 * U16 / (1.0 - U16)) ** n_orders - 1.0
    rel = np.abs(pv.approximated.radiance / exact.radiance - 1.0)
    assert 0.0 < rel.max() <= bound
    assert np.abs(pv.luminance_ratio - 1.0).max() <= bound


def test_rgb_channels_are_read_at_the_engine_s_wavelengths(medium, exact) -> None:  # type: ignore[no-untyped-def]
    pv = _preview(medium, exact, channels_nm=(680.0, 550.0, 440.0))
    assert pv.approximated.wavelength_nm.tolist() == [440.0, 550.0, 680.0]
    # The three rows of the 10 nm grid: the channels' radiances are the spectral
    # sky's at those wavelengths up to the multiple scattering's own coupling
    # (none: each wavelength is solved on its own).
    rows = [int(np.flatnonzero(exact.wavelength_nm == w)[0]) for w in (440.0, 550.0, 680.0)]
    np.testing.assert_allclose(pv.approximated.radiance, exact.radiance[..., rows], rtol=1e-9)
    # Only the colour of three channels differs from the spectrum's.
    assert 1e-4 < pv.summary.dome_delta_xy_max < 0.05


def test_unknown_phase_is_refused_with_the_allowed_list(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(ValueError, match="phase must be one of exact, fit:henyey-greenstein"):
        Approximations(phase="fit:gaussian")
    out = tmp_path / "x"
    assert main(["sky", "mars", "--phase", "fit:gaussian", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--phase" in err and "fit:dhg" in err and "fit:cornette-shanks" in err
    assert not out.exists()
    assert "fit:cornette-shanks" in PHASE_CHOICES
    # Options that tune a preview, without one, would change nothing: refused too.
    for extra in (["--near-sun", "5"], ["--rgb", "--angle-tolerance", "0.01"]):
        assert main(["sky", "mars", *extra, "--out", str(out)]) == 2
        assert "applies to" in capsys.readouterr().err
        assert not out.exists()


def _angle_error(table, n: int) -> float:  # type: ignore[no-untyped-def]
    # theta:N read linearly in angle, integrated exactly (independent of the module).
    grid = np.linspace(0.0, 180.0, n)
    own = sphere_integral(table.phase, theta_deg=table.theta_deg)
    got = sphere_integral(table.phase_at(grid), theta_deg=grid)
    return float(np.max(np.abs(np.asarray(got) / np.asarray(own) - 1.0)))


def test_too_few_angles_refused_with_the_smallest_that_does(atmosphere, medium) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=r"the smallest that does is theta:(\d+)") as info:
        check_approximations(Approximations(angles="theta:19"), medium)
    need = int(info.value.args[0].rsplit("theta:", 1)[1])
    with pytest.raises(ValueError, match=f"the smallest that does is theta:{need}$"):
        check_approximations(Approximations(angles="theta:19"), atmosphere)  # before the medium
    scattering = [t for t in medium.tables if np.any(t.cross_sections.csca_um2 > 0)]
    assert max(_angle_error(t, need) for t in scattering) <= 0.005
    assert max(_angle_error(t, need - 1) for t in scattering) > 0.005
    check_approximations(Approximations(angles=f"theta:{need}"), medium)  # accepted


def test_set_cannot_take_refused_before_any_rendering(
    medium, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=r"R = 900 nm is outside the set's wavelengths"):
        check_approximations(Approximations(channels_nm=(900.0, 550.0, 440.0)), medium)
    # A phase function beyond float16's 65504 (a narrow HG lobe).
    dust = medium.tables[1]
    mu = np.cos(np.deg2rad(dust.theta_deg))
    peaked = np.tile(henyey_greenstein(mu, g=0.9999), (dust.wavelength_nm.size, 1))
    assert peaked.max() > 65504.0
    narrow = replace(medium, tables=(medium.tables[0], dust.replace(phase=peaked)))
    with pytest.raises(ValueError, match="float32 textures would do"):
        check_approximations(Approximations(float16=True), narrow)

    def no_render(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise AssertionError("the sky was rendered")

    monkeypatch.setattr("dustoptics.sky.scene.sky_radiance", no_render)
    out = tmp_path / "x"
    assert main(["sky", "mars", "--angles", "cosmoscout:19", "--out", str(out)]) == 1
    assert "the smallest that does is cosmoscout:" in capsys.readouterr().err
    assert not any(out.rglob("*.*"))


def test_netcdf_round_trip_and_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "sky"
    argv = ["sky", "mars", "--rgb", "--phase", "fit:cs", "--size", "32", "--out", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "CIE xy distance" in printed and "within 10 deg of Sun" in printed
    folder = out / "mars-hybrid"
    img = mpl_image.imread(folder / "mars-hybrid_preview.png")
    assert img.shape[0] > 100 and img.shape[1] > 3 * img.shape[0]  # four panels side by side
    with xr.open_dataset(folder / "mars-hybrid_sky.nc", engine="scipy") as ds:
        s = PreviewSummary.from_attributes(ds.attrs)
        assert s.table() in printed
        assert ds.attrs["preview_phase"] == "fit:cs"
        assert ds.attrs["preview_channels_nm"] == "680, 550, 440"
        # The summary agrees with the variables it was made from.
        dxy = np.hypot(
            ds.approximated_chromaticity_x - ds.chromaticity_x,
            ds.approximated_chromaticity_y - ds.chromaticity_y,
        )
        np.testing.assert_allclose(dxy, ds.chromaticity_difference, rtol=1e-12, atol=1e-15)
        assert s.dome_delta_xy_max == float(ds.chromaticity_difference.max())
        ratio = ds.approximated_luminance_factor / ds.luminance_factor
        np.testing.assert_allclose(ratio, ds.luminance_ratio, rtol=1e-12)
        assert s.dome_luminance_ratio_min == float(ds.luminance_ratio.min())
        assert ds.approximated_radiance.shape[-1] == 3


def test_engine_angles_are_read_as_the_engines_read_them(medium) -> None:  # type: ignore[no-untyped-def]
    dust = medium.tables[1]
    probe = np.array([0.0, 0.37, 1.3, 7.9, 45.2, 90.0, 179.6, 180.0])
    # cos:N, linear in cos(theta) between samples uniform in cos(theta).
    n = 4096
    approx, _ = approximate_medium(medium, Approximations(angles=f"cos:{n}"))
    mu = np.linspace(1.0, -1.0, n)
    samples = dust.phase_at(np.degrees(np.arccos(mu)))
    want = np.array([np.interp(np.cos(np.deg2rad(probe)), mu[::-1], r[::-1]) for r in samples])
    np.testing.assert_allclose(approx.tables[1].phase_at(probe), want, rtol=1e-5)
    # cosmoscout:N, texel centres (j + 1/2) 180 / N, held within half a column of the ends.
    n = 360
    approx, _ = approximate_medium(medium, Approximations(angles=f"cosmoscout:{n}"))
    centres = (np.arange(n) + 0.5) * 180.0 / n
    samples = dust.phase_at(centres)
    want = np.array([np.interp(probe, centres, r) for r in samples])
    np.testing.assert_allclose(approx.tables[1].phase_at(probe), want, rtol=1e-12)
    assert np.array_equal(approx.tables[1].phase_at(0.0), samples[:, 0])


def test_one_fit_for_all_wavelengths_is_bruneton_s_g(atmosphere, medium) -> None:  # type: ignore[no-untyped-def]
    from dustoptics.io.engines.bruneton import bruneton_parameters

    g = bruneton_parameters(atmosphere).mie_phase_function_g  # his export's one g, at 550 nm
    for channels in (None, (680.0, 550.0, 440.0)):
        a = Approximations(phase="fit:cornette-shanks@550", channels_nm=channels)
        approx, fit = approximate_medium(medium, a)
        assert fit is not None and fit.model == "cornette-shanks1992"
        assert fit.parameters[0, 0] == pytest.approx(g, rel=1e-12)
        dust = approx.tables[1]
        mu = np.cos(np.deg2rad(dust.theta_deg))
        cs = 3.0 * (1.0 - g * g) * (1.0 + mu * mu) / (2.0 * (2.0 + g * g))
        cs = cs / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * mu) ** 1.5)
        np.testing.assert_allclose(dust.phase, np.tile(cs, (dust.wavelength_nm.size, 1)), rtol=1e-9)
    with pytest.raises(ValueError, match="700 nm is outside the wavelengths the fit would read"):
        check_approximations(
            Approximations(phase="fit:cs@700", channels_nm=(680.0, 550.0, 440.0)), medium
        )


def test_a_sky_grey_in_wavelength_keeps_its_colour_in_three_channels(exact) -> None:  # type: ignore[no-untyped-def]
    # An identity of the white-sun reading: RGB_sun * L for every channel is the
    # sunlight's own colour scaled by L, which is what the spectrum gives.
    from dustoptics.sky.approximations import _channel_xyz

    level = np.linspace(0.01, 0.2, exact.view_zenith_deg.size)[:, None, None]
    grey = replace(exact, radiance=np.broadcast_to(level, exact.radiance.shape).copy())
    channels = replace(
        exact,
        wavelength_nm=np.array([440.0, 550.0, 680.0]),
        radiance=np.broadcast_to(level, exact.radiance.shape[:2] + (3,)).copy(),
    )
    got = _channel_xyz(grey, channels, np.array([2, 1, 0]))  # R, G, B = 680, 550, 440 nm
    np.testing.assert_allclose(got, grey.xyz(), rtol=1e-12)


def test_renders_sharing_their_geometry_are_bit_for_bit_those_alone(medium, exact) -> None:  # type: ignore[no-untyped-def]
    # The preview's second render takes the first's angular bases (the Legendre
    # functions at the ordinates and the Sun, the aureole's): the same bits as alone.
    from dustoptics.sky import _shared

    approx, _ = approximate_medium(medium, Approximations(phase="fit:dhg"))
    alone = sky_radiance(approx, sun_elevation_deg=SUN_DEG, ground_albedo=ALBEDO, **SKY)
    with _shared.shared_geometry():
        first = sky_radiance(medium, sun_elevation_deg=SUN_DEG, ground_albedo=ALBEDO, **SKY)
        memo = _shared._MEMO.get()
        assert memo is not None
        kept = dict(memo)
        assert {k[0] for k in kept} == {"double-gauss", "sun-legendre", "aureole-legendre"}
        second = sky_radiance(approx, sun_elevation_deg=SUN_DEG, ground_albedo=ALBEDO, **SKY)
        assert memo.keys() == kept.keys()  # nothing computed again
        assert all(memo[k] is v for k, v in kept.items())
    assert _shared._MEMO.get() is None  # nothing is kept outside the scope
    assert np.array_equal(first.radiance, exact.radiance)
    assert np.array_equal(second.radiance, alone.radiance)
    assert not np.array_equal(second.radiance, first.radiance)
