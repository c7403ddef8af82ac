"""The seed thesis's sky comparisons of the Mars dust models, as data and figures.

Meyran (2022, ch. 5) chose the hybrid model by rendering skies with each
dust phase function and comparing radiance against scattering angle, the
luminance relative to the zenith, the chromaticity looking away from the Sun
against the Mars Exploration Rovers, and the transmittance of the Sun.
:func:`compare_mars_models` computes the same quantities for the seed's four
models and :func:`plot_comparison` draws them, one figure per quantity with
every model in it.

The four models differ in their phase function only: ``collienne``
(Cornette-Shanks, g = 0.8), ``costa`` (Costa et al.'s double
Henyey-Greenstein), ``blue-moons`` (physical Mie) and ``hybrid`` (Mie blended
with Costa's DHG).  The analytic models carry no cross-sections, so every
model takes the extinction and scattering cross-sections of the Blue Moon's
Mie dust, scaled to the same vertical optical depth; molecules are CO2
(``costa2021-mars``).  This is a choice of this comparison, recorded in the
dataset's attributes.

The rover chromaticity range is Bell et al. (2006): MER Pancam sky
chromaticity means x = 0.396-0.408, y = 0.377-0.383 (Spirit and Opportunity),
as quoted by Meyran (2022).

References
----------
.. [1] J. F. Bell III et al., "In-flight calibration and performance of the
   Mars Exploration Rover Panoramic Camera (Pancam) instruments,"
   J. Geophys. Res. 111, E12S05 (2006) (sky chromaticity means).
.. [2] T. Meyran, "Physically based real-time rendering of the Martian
   atmosphere," M.Sc. thesis, Hochschule Hannover (2022), ch. 5.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Final, TextIO

import numpy as np

from dustoptics._validation import check_positive
from dustoptics.atmosphere.sets import Atmosphere, mars_atmosphere
from dustoptics.sky._progress import reporter
from dustoptics.sky.medium import Medium
from dustoptics.sky.scene import SkyRadiance, sky_radiance
from dustoptics.table import Table

__all__ = [
    "COMPARISON_WAVELENGTHS_NM",
    "MARS_MODELS",
    "MER_SKY_CHROMATICITY",
    "compare_mars_models",
    "mars_sky_atmosphere",
    "plot_comparison",
]

#: The seed's four Mars dust models (preset names).
MARS_MODELS: Final = ("collienne", "costa", "blue-moons", "hybrid")
#: Wavelengths of the radiance comparisons (Meyran 2022). [nm]
COMPARISON_WAVELENGTHS_NM: Final = (444.0, 670.0)
#: MER Pancam sky chromaticity means (Bell et al. 2006, as quoted by Meyran 2022).
MER_SKY_CHROMATICITY: Final = {"x": (0.396, 0.408), "y": (0.377, 0.383)}
#: Looking away from the Sun: view elevation 30 deg, azimuth 180 deg from the Sun.
AWAY_FROM_SUN: Final = {"view_zenith_deg": 60.0, "view_azimuth_deg": 180.0}
_MIE_CROSS_SECTIONS: Final = "blue-moons"


def _grid(extra_nm: tuple[float, ...]) -> tuple[float, ...]:
    base = np.arange(360.0, 831.0, 10.0)
    return tuple(float(w) for w in np.unique(np.concatenate([base, np.asarray(extra_nm)])))


def _preset_table(name: str, wavelength_nm: tuple[float, ...]) -> Table:
    from dustoptics.models import compute, presets

    cfg = presets.load_preset(name)
    cfg = replace(cfg, optics=replace(cfg.optics, wavelengths_nm=wavelength_nm))
    return compute.build_table(cfg)


def mars_sky_atmosphere(
    model: str = "hybrid",
    *,
    optical_depth: float = 0.5,
    reference_wavelength_nm: float = 550.0,
    wavelength_nm: tuple[float, ...] | None = None,
    cross_sections: Table | None = None,
) -> Atmosphere:
    """Mars with one of the seed's dust models, for the sky.

    Parameters
    ----------
    model : {"collienne", "costa", "blue-moons", "hybrid"} or str
        A preset name; its phase function is the dust's.
    optical_depth : float
        Vertical dust optical depth at ``reference_wavelength_nm``. [-]
    reference_wavelength_nm : float
        Wavelength of the optical depth, on the grid. [nm]
    wavelength_nm : tuple of float, optional
        Wavelengths; default 360..830 step 10 plus 444 and 670. [nm]
    cross_sections : Table, optional
        Where the dust's cross-sections come from when the model has none;
        default the ``blue-moons`` Mie table on the same grid.

    Returns
    -------
    Atmosphere
    """
    if not isinstance(model, str) or not model:
        raise ValueError(f"model must be a preset name; got {model!r}")
    check_positive("optical_depth", optical_depth)
    grid = _grid(COMPARISON_WAVELENGTHS_NM) if wavelength_nm is None else tuple(wavelength_nm)
    dust = _preset_table(model, grid)
    if not dust.has_cross_sections:
        mie = (
            cross_sections
            if cross_sections is not None
            else _preset_table(_MIE_CROSS_SECTIONS, grid)
        )
        if not np.array_equal(mie.wavelength_nm, dust.wavelength_nm):
            raise ValueError("cross_sections must be on the model's wavelengths")
        dust = dust.replace(
            cext_um2=mie.cext_um2,
            csca_um2=mie.csca_um2,
            mean_geometric_cross_section_um2=mie.mean_geometric_cross_section_um2,
        )
    return mars_atmosphere(
        dust_table=dust,
        optical_depth=optical_depth,
        reference_wavelength_nm=reference_wavelength_nm,
        name=f"mars-{model}",
    )


def _scattering_angle(
    view_zenith: np.ndarray, view_azimuth: np.ndarray, sun_zenith: float
) -> np.ndarray:
    mv = np.cos(np.deg2rad(view_zenith))
    ms = math.cos(math.radians(sun_zenith))
    c = mv * ms + np.sqrt(1 - mv**2) * math.sqrt(1 - ms**2) * np.cos(np.deg2rad(view_azimuth))
    return np.rad2deg(np.arccos(np.clip(c, -1.0, 1.0)))


def compare_mars_models(
    *,
    models: tuple[str, ...] = MARS_MODELS,
    optical_depth: float = 0.5,
    sun_elevation_deg: float = 10.0,
    sun_elevations_deg: tuple[float, ...] = (2.0, 5.0, 10.0, 20.0, 30.0, 45.0, 60.0),
    ground_albedo: float = 0.2,
    tol: float = 1e-4,
    azimuth_step_deg: float = 2.0,
    progress: TextIO | None = None,
    allow_large: bool = False,
) -> Any:
    """The thesis's sky comparisons for several Mars dust models.

    Parameters
    ----------
    models : tuple of str
        Preset names (default the seed's four).
    optical_depth : float
        Vertical dust optical depth at 550 nm. [-]
    sun_elevation_deg : float
        Sun elevation of the radiance and luminance comparisons. [deg]
    sun_elevations_deg : tuple of float
        Sun elevations of the chromaticity and transmittance curves. [deg]
    ground_albedo : float
        Lambertian ground albedo. [-]
    tol : float
        Tolerance of the orders of scattering. [-]
    azimuth_step_deg : float
        Azimuth step of the sky grid. [deg]
    progress : text stream, optional
        Where to report the models, orders of scattering and lines of sight
        done after the first two seconds; None is silent.
    allow_large : bool
        Go ahead beyond the memory and work budget of each sky.

    Returns
    -------
    xarray.Dataset
        ``radiance_almucantar`` and ``radiance_principal_plane`` [sr^-1] at
        444 and 670 nm with their scattering angles; ``relative_luminance``
        over the sky (Y / Y_zenith); ``chromaticity_x``/``_y`` looking away
        from the Sun and ``sun_transmittance`` against Sun elevation.
    """
    import xarray as xr

    for m in models:
        if not isinstance(m, str):
            raise ValueError(f"models must be preset names; got {m!r}")
    report = reporter(progress, label="sky compare")
    grid = _grid(COMPARISON_WAVELENGTHS_NM)
    mie = _preset_table(_MIE_CROSS_SECTIONS, grid)
    sel = [grid.index(w) for w in COMPARISON_WAVELENGTHS_NM]
    sun_zen = 90.0 - sun_elevation_deg
    almu_az = np.arange(0.0, 180.01, 1.0)
    pp_zen = np.arange(0.0, 90.01, 1.0)
    per_model: dict[str, dict[str, np.ndarray]] = {}
    sky: SkyRadiance | None = None
    for k, model in enumerate(models):
        report(f"model {k + 1} of {len(models)} ({model})")
        atm = mars_sky_atmosphere(
            model, optical_depth=optical_depth, wavelength_nm=grid, cross_sections=mie
        )
        medium = Medium.from_atmosphere(atm)
        sky = sky_radiance(
            medium,
            sun_elevation_deg=sun_elevation_deg,
            ground_albedo=ground_albedo,
            tol=tol,
            azimuth_step_deg=azimuth_step_deg,
            progress=report,
            allow_large=allow_large,
        )
        almu = sky.at(np.full(almu_az.shape, sun_zen), almu_az)[:, sel]
        pp = np.concatenate(
            [sky.at(pp_zen[::-1], np.zeros(pp_zen.size)), sky.at(pp_zen[1:], np.full(90, 180.0))]
        )[:, sel]
        y = sky.xyz()[..., 1]
        chrom = []
        trans = []
        for elev in sun_elevations_deg:
            s = sky_radiance(
                medium,
                sun_elevation_deg=elev,
                ground_albedo=ground_albedo,
                tol=tol,
                view_zenith_deg=np.array([59.0, 60.0, 61.0]),
                azimuth_step_deg=45.0,
                progress=report,
                allow_large=allow_large,
            )
            chrom.append(s.chromaticity(s.at(**AWAY_FROM_SUN)))
            trans.append(s.sun_transmittance[sel])
        per_model[model] = {
            "almucantar": almu,
            "principal": pp,
            "relative_luminance": y / y[0, 0],
            "chromaticity": np.array(chrom),
            "transmittance": np.array(trans),
        }
    assert sky is not None
    pp_signed = np.concatenate([-pp_zen[::-1], pp_zen[1:]])  # negative: toward the Sun
    pp_az = np.where(pp_signed <= 0, 0.0, 180.0)
    stack = lambda key: np.stack([per_model[m][key] for m in models])  # noqa: E731
    ds = xr.Dataset(
        {
            "radiance_almucantar": (
                ("model", "almucantar_azimuth", "wavelength"),
                stack("almucantar"),
                {
                    "units": "sr-1",
                    "long_name": "sky radiance per unit solar irradiance, almucantar",
                },
            ),
            "radiance_principal_plane": (
                ("model", "principal_plane_angle", "wavelength"),
                stack("principal"),
                {
                    "units": "sr-1",
                    "long_name": "sky radiance per unit solar irradiance, principal plane",
                },
            ),
            "relative_luminance": (
                ("model", "view_zenith_angle", "view_azimuth_angle"),
                stack("relative_luminance"),
                {"units": "1", "long_name": "luminance relative to the zenith"},
            ),
            "chromaticity_x": (
                ("model", "sun_elevation"),
                stack("chromaticity")[..., 0],
                {"units": "1", "long_name": "CIE 1931 x looking away from the Sun"},
            ),
            "chromaticity_y": (
                ("model", "sun_elevation"),
                stack("chromaticity")[..., 1],
                {"units": "1", "long_name": "CIE 1931 y looking away from the Sun"},
            ),
            "sun_transmittance": (
                ("model", "sun_elevation", "wavelength"),
                stack("transmittance"),
                {"units": "1", "long_name": "transmittance of the direct Sun to the ground"},
            ),
        },
        coords={
            "model": ("model", list(models)),
            "wavelength": ("wavelength", list(COMPARISON_WAVELENGTHS_NM), {"units": "nm"}),
            "almucantar_azimuth": ("almucantar_azimuth", almu_az, {"units": "degree"}),
            "almucantar_scattering_angle": (
                "almucantar_azimuth",
                _scattering_angle(np.full(almu_az.shape, sun_zen), almu_az, sun_zen),
                {"units": "degree"},
            ),
            "principal_plane_angle": (
                "principal_plane_angle",
                pp_signed,
                {"units": "degree", "long_name": "view zenith angle, negative toward the Sun"},
            ),
            "principal_plane_scattering_angle": (
                "principal_plane_angle",
                _scattering_angle(np.abs(pp_signed), pp_az, sun_zen),
                {"units": "degree"},
            ),
            "view_zenith_angle": ("view_zenith_angle", sky.view_zenith_deg, {"units": "degree"}),
            "view_azimuth_angle": ("view_azimuth_angle", sky.view_azimuth_deg, {"units": "degree"}),
            "sun_elevation": ("sun_elevation", list(sun_elevations_deg), {"units": "degree"}),
        },
        attrs={
            "title": "Mars sky comparisons of dust models (after Meyran 2022, ch. 5)",
            "sun_elevation_deg": float(sun_elevation_deg),
            "optical_depth_550nm": float(optical_depth),
            "ground_albedo": float(ground_albedo),
            "orders_tolerance": float(tol),
            "away_from_sun": "view elevation 30 degree, azimuth 180 degree from the Sun",
            "cross_sections": (
                "every model uses the Blue Moon's Mie dust cross-sections scaled to the optical "
                "depth; the models differ in their phase function only"
            ),
            "mer_chromaticity_x": list(MER_SKY_CHROMATICITY["x"]),
            "mer_chromaticity_y": list(MER_SKY_CHROMATICITY["y"]),
            "mer_chromaticity_source": "Bell et al. 2006, JGR 111, E12S05 (as quoted by Meyran 2022)",
        },
    )
    return ds


def plot_comparison(ds: Any) -> dict[str, Any]:
    """Figures of :func:`compare_mars_models`: one per quantity, every model in it.

    Returns a mapping of figure names to matplotlib figures (needs the
    ``plot`` extra).
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the extra
        raise ImportError(
            "plotting the sky comparison needs matplotlib: pip install 'dustoptics[plot]'"
        ) from exc
    figs: dict[str, Any] = {}
    models = [str(m) for m in ds.model.values]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharey="row", constrained_layout=True)
    for j, w in enumerate(ds.wavelength.values):
        for m in models:
            axes[0, j].semilogy(
                ds.almucantar_scattering_angle,
                ds.radiance_almucantar.sel(model=m, wavelength=w),
                label=m,
            )
            axes[1, j].semilogy(
                ds.principal_plane_scattering_angle,
                ds.radiance_principal_plane.sel(model=m, wavelength=w),
                ".",
                markersize=2,
                label=m,
            )
        axes[0, j].set_title(f"almucantar, {w:g} nm")
        axes[1, j].set_title(f"principal plane, {w:g} nm")
        for i in range(2):
            axes[i, j].set_xlabel("scattering angle [degree]")
    axes[0, 0].set_ylabel("radiance / solar irradiance [sr$^{-1}$]")
    axes[1, 0].set_ylabel("radiance / solar irradiance [sr$^{-1}$]")
    axes[0, 0].legend()
    fig.suptitle(f"Mars sky radiance, Sun at {ds.attrs['sun_elevation_deg']:g} degree")
    figs["radiance"] = fig

    fig, axes = plt.subplots(
        1,
        len(models),
        figsize=(3.2 * len(models), 3.4),
        subplot_kw={"projection": "polar"},
        constrained_layout=True,
    )
    axes = np.atleast_1d(axes)
    zen = ds.view_zenith_angle.values
    az = np.deg2rad(ds.view_azimuth_angle.values)
    for ax, m in zip(axes, models):
        lum = ds.relative_luminance.sel(model=m).values
        full_az = np.concatenate([az, 2 * np.pi - az[::-1]])
        full = np.concatenate([lum, lum[:, ::-1]], axis=1)
        pc = ax.pcolormesh(full_az, zen, full, shading="auto", norm=matplotlib.colors.LogNorm())
        ax.set_theta_zero_location("N")
        ax.set_yticks([30, 60, 90])
        ax.set_yticklabels([])
        ax.set_title(m)
    fig.colorbar(pc, ax=list(axes), label="luminance / zenith luminance")
    figs["luminance"] = fig

    fig, ax = plt.subplots(figsize=(5, 4.5), constrained_layout=True)
    x0, x1 = MER_SKY_CHROMATICITY["x"]
    y0, y1 = MER_SKY_CHROMATICITY["y"]
    ax.add_patch(
        matplotlib.patches.Rectangle(
            (x0, y0), x1 - x0, y1 - y0, color="0.8", label="MER (Bell et al. 2006)"
        )
    )
    for m in models:
        ax.plot(ds.chromaticity_x.sel(model=m), ds.chromaticity_y.sel(model=m), "o-", label=m)
    ax.set_xlabel("CIE x")
    ax.set_ylabel("CIE y")
    ax.set_title("sky chromaticity away from the Sun\nagainst Sun elevation")
    ax.legend(fontsize="small")
    figs["chromaticity"] = fig

    fig, ax = plt.subplots(figsize=(5, 4), constrained_layout=True)
    for m in models:
        for w, style in zip(ds.wavelength.values, ("-", "--")):
            ax.plot(
                ds.sun_elevation,
                ds.sun_transmittance.sel(model=m, wavelength=w),
                style,
                label=f"{m}, {w:g} nm",
            )
    ax.set_xlabel("Sun elevation [degree]")
    ax.set_ylabel("direct transmittance [1]")
    ax.legend(fontsize="x-small")
    figs["transmittance"] = fig
    return figs
