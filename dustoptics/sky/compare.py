"""The seed thesis's sky comparisons of the Mars dust models, as data and figures.

Meyran (2022, ch. 5) chose the hybrid model by rendering skies with each
model and comparing radiance against scattering angle, the luminance
relative to the zenith, the chromaticity looking away from the Sun against
the Mars Exploration Rovers, and the transmittance of the Sun.
:func:`compare_mars_models` computes the same quantities for the thesis's four
models, :func:`plot_comparison` draws them, one figure per quantity with every
model in it, and :func:`rover_comparison` (or :func:`mer_chromaticity`, which
computes only that) sets the chromaticity against the rovers' range in a
table.

The four models as the thesis defines them (Meyran 2022, sections 3.4, 4.1
and appendix A.1.2):

- ``collienne``: Collienne et al.'s (2013) molecular-scattering
  coefficients, "inverted" to grow with wavelength (5.75e-6, 13.57e-6 and
  19.918e-6 m^-1 at 440, 510 and 680 nm, Meyran's eq. (3.1)), with a scale
  height of 8 km, and the thin grey aerosol of Bruneton's model that Meyran
  assumed for it (Angstrom alpha 0 and beta 5.328e-3, i.e. a vertical
  optical depth of 5.328e-3 at every wavelength; single-scattering albedo
  0.9, Meyran's Table 4.1) with a Cornette-Shanks phase function (g = 0.8).
  Between 440 and 680 nm the coefficient is interpolated linearly in
  wavelength, outside it is held at the end values (the thesis does not say
  how its 48-wavelength framework spread the three values).  The dust
  optical depth of the comparison does not apply to it.
- ``costa``: Costa et al.'s double Henyey-Greenstein phase function with the
  Blue Moon's Mie cross-sections (Meyran's configuration reads the Blue
  Moon's extinction file for Costa's model too);
- ``blue-moons``: the Blue Moon's Mie dust (phase function and
  cross-sections);
- ``hybrid``: the Blue Moon's Mie phase function blended with Costa's DHG,
  the Mie cross-sections.

The three dust models are scaled to the comparison's optical depth; their
molecules are CO2 (``costa2021-mars``).  The thesis's own dust amount, its
``N0 = 4.64e8`` with no stated unit, does not give an optical depth.

The rover chromaticity range is Bell, Savransky & Wolff (2006), the source
Meyran cites for it: the means of the Spirit and Opportunity sky and horizon
surveys span x = 0.396-0.408, y = 0.377-0.383.

References
----------
.. [1] J. F. Bell III, D. Savransky and M. J. Wolff, "Chromaticity of the
   Martian sky as observed by the Mars Exploration Rover Pancam
   instruments," J. Geophys. Res. 111, E12 (2006), doi:10.1029/2006JE002687.
.. [2] T. Meyran, "Physically based real-time rendering of the Martian
   atmosphere," M.Sc. thesis, Hochschule Hannover (2022), ch. 3-5, app. A.
.. [3] P. Collienne, R. Wolff, A. Gerndt and T. Kuhlen, "Physically based
   rendering of the Martian atmosphere," 2013 (as cited by Meyran 2022).
.. [4] E. Bruneton, "Precomputed atmospheric scattering: a new
   implementation," 2017 (its Mie Angstrom parameters).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Final, TextIO

import numpy as np

from dustoptics._validation import check_closed_interval, check_positive
from dustoptics.atmosphere.sets import Atmosphere, Constituent, mars_atmosphere
from dustoptics.models import compute, presets
from dustoptics.scattering import phase as _phase
from dustoptics.sky._progress import Reporter, reporter
from dustoptics.sky.medium import Medium
from dustoptics.sky.orders import N_LAYERS, check_orders_cost
from dustoptics.sky.render import N_PATH, check_render_cost
from dustoptics.sky.scene import SkyRadiance, default_view_zenith_deg, sky_radiance
from dustoptics.table import CrossSections, Provenance, Source, Table

__all__ = [
    "BELL_2006",
    "COLLIENNE_AEROSOL_OPTICAL_DEPTH",
    "COLLIENNE_AEROSOL_SINGLE_SCATTERING_ALBEDO",
    "COMPARISON_WAVELENGTHS_NM",
    "MARS_MODELS",
    "MER_SKY_CHROMATICITY",
    "RoverComparison",
    "RoverRow",
    "collienne_molecules",
    "compare_mars_models",
    "mars_sky_atmosphere",
    "mer_chromaticity",
    "mer_distance",
    "plot_comparison",
    "read_rover_comparison",
    "rover_comparison",
]

#: The seed's four Mars models (preset names).
MARS_MODELS: Final = ("collienne", "costa", "blue-moons", "hybrid")
#: Wavelengths of the radiance comparisons (Meyran 2022). [nm]
COMPARISON_WAVELENGTHS_NM: Final = (444.0, 670.0)
#: The source of :data:`MER_SKY_CHROMATICITY` (Meyran 2022's reference [57]).
BELL_2006: Final = (
    'J. F. Bell III, D. Savransky and M. J. Wolff, "Chromaticity of the Martian sky as '
    'observed by the Mars Exploration Rover Pancam instruments," J. Geophys. Res. 111(E12) '
    "(2006), doi:10.1029/2006JE002687"
)
#: The rovers' range of sky chromaticity means: Spirit and Opportunity, sky and horizon
#: surveys, x = 0.408, 0.396, 0.405, 0.400 and y = 0.382, 0.383, 0.377, 0.381
#: (Bell, Savransky & Wolff 2006, as Meyran 2022 quotes them).
MER_SKY_CHROMATICITY: Final = {"x": (0.396, 0.408), "y": (0.377, 0.383)}
#: Looking away from the Sun: view elevation 30 deg, azimuth 180 deg from the Sun.
AWAY_FROM_SUN: Final = {"view_zenith_deg": 60.0, "view_azimuth_deg": 180.0}
#: Vertical optical depth of the aerosol of Collienne's model: Bruneton's Mie
#: Angstrom beta 5.328e-3 with alpha 0 (Meyran 2022, appendix A.1.2). [-]
COLLIENNE_AEROSOL_OPTICAL_DEPTH: Final = 5.328e-3
#: Its single-scattering albedo: Meyran's Table 4.1, 0.432e-3 / 0.48e-3. [-]
COLLIENNE_AEROSOL_SINGLE_SCATTERING_ALBEDO: Final = 0.9
#: Scale height of Collienne's molecules (Meyran 2022, appendix A.1.2). [m]
COLLIENNE_MOLECULES_SCALE_HEIGHT_M: Final = 8000.0
_MIE_CROSS_SECTIONS: Final = "blue-moons"


def _grid(extra_nm: tuple[float, ...]) -> tuple[float, ...]:
    base = np.arange(360.0, 831.0, 10.0)
    return tuple(float(w) for w in np.unique(np.concatenate([base, np.asarray(extra_nm)])))


def _preset_table(name: str, wavelength_nm: tuple[float, ...]) -> Table:
    cfg = presets.load_preset(name)
    cfg = replace(cfg, optics=replace(cfg.optics, wavelengths_nm=wavelength_nm))
    return compute.build_table(cfg)


def collienne_molecules(wavelength_nm: tuple[float, ...], *, like: Table) -> Table:
    """Collienne et al.'s molecular-scattering coefficients over a wavelength grid.

    The three published coefficients (:data:`dustoptics.scattering.phase.COLLIENNE2013_MARS`,
    5.75e-6, 13.57e-6 and 19.918e-6 m^-1 at 440, 510 and 680 nm, growing with
    wavelength) interpolated linearly in wavelength and held at the end
    values outside 440-680 nm, carried per unit number density.

    Parameters
    ----------
    wavelength_nm : tuple of float
        The grid. [nm]
    like : Table
        A molecule table on the same grid whose (Rayleigh) phase function is kept.

    Returns
    -------
    Table
        ``csca_um2 = cext_um2 = beta * 1e12``, ``number_density_per_m3 = 1``.
    """
    c = _phase.COLLIENNE2013_MARS
    wl = np.asarray(wavelength_nm, dtype=float)
    if not np.array_equal(like.wavelength_nm, wl):
        raise ValueError("like must be on wavelength_nm")
    beta = np.interp(wl, c.wavelength_nm, c.rayleigh_scattering_per_m)
    return Table(
        name="collienne2013-molecules",
        wavelength_nm=wl,
        theta_deg=like.theta_deg,
        phase=like.phase,
        g=like.g,
        cross_sections=CrossSections(
            cext_um2=beta * 1e12, csca_um2=beta * 1e12, number_density_per_m3=1.0
        ),
        provenance=Provenance(
            inputs={"kind": "collienne2013-molecules", "wavelength_nm": wl},
            sources=(
                Source(name="collienne2013", role="scattering coefficients", citation=c.citation),
            ),
            notes=(
                "Three published coefficients (440, 510, 680 nm) interpolated linearly in "
                "wavelength, held at the end values outside; carried per unit density.",
            ),
        ),
    )


def _collienne(grid: tuple[float, ...]) -> Atmosphere:
    dust = _preset_table("collienne", grid)
    grey = np.ones(len(grid))
    dust = dust.replace(
        cross_sections={
            "cext_um2": grey,
            "csca_um2": COLLIENNE_AEROSOL_SINGLE_SCATTERING_ALBEDO * grey,
            "mean_geometric_cross_section_um2": 1.0,
        },
    )
    atm = mars_atmosphere(
        dust_table=dust,
        optical_depth=COLLIENNE_AEROSOL_OPTICAL_DEPTH,
        molecules_scale_height_m=COLLIENNE_MOLECULES_SCALE_HEIGHT_M,
        name="mars-collienne",
    )
    mol, aerosols = atm.constituents
    mol = Constituent(
        role="molecules", table=collienne_molecules(grid, like=mol.table), profile=mol.profile
    )
    return replace(atm, constituents=(mol, aerosols))


def mars_sky_atmosphere(
    model: str = "hybrid",
    *,
    optical_depth: float = 0.5,
    reference_wavelength_nm: float = 550.0,
    wavelength_nm: tuple[float, ...] | None = None,
    cross_sections: Table | None = None,
) -> Atmosphere:
    """Mars with one of the seed's models, for the sky.

    Parameters
    ----------
    model : {"collienne", "costa", "blue-moons", "hybrid"} or str
        A preset name.  ``"collienne"`` is Collienne's model as the thesis
        defines it (its molecules and its thin grey aerosol, see the module
        docstring: ``optical_depth``, ``reference_wavelength_nm`` and
        ``cross_sections`` do not apply); any other preset is the dust, its
        phase function the preset's.
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
    if model == "collienne":
        return _collienne(grid)
    dust = _preset_table(model, grid)
    if dust.cross_sections is None:
        mie = (
            cross_sections
            if cross_sections is not None
            else _preset_table(_MIE_CROSS_SECTIONS, grid)
        )
        if not np.array_equal(mie.wavelength_nm, dust.wavelength_nm):
            raise ValueError("cross_sections must be on the model's wavelengths")
        assert mie.cross_sections is not None  # a Mie table
        dust = dust.replace(
            cross_sections={
                "cext_um2": mie.cross_sections.cext_um2,
                "csca_um2": mie.cross_sections.csca_um2,
                "mean_geometric_cross_section_um2": mie.cross_sections.mean_geometric_cross_section_um2,
            },
        )
    return mars_atmosphere(
        dust_table=dust,
        optical_depth=optical_depth,
        reference_wavelength_nm=reference_wavelength_nm,
        name=f"mars-{model}",
    )


# ------------------------------------------------------------ the rovers' range


def mer_distance(x: float, y: float) -> tuple[float, float]:
    """How far a chromaticity lies outside the rovers' range, per coordinate.

    Returns
    -------
    (dx, dy) : tuple of float
        0 inside :data:`MER_SKY_CHROMATICITY`, otherwise the signed distance
        to the nearest edge (positive: above the range). [-]

    Examples
    --------
    >>> mer_distance(0.400, 0.380)
    (0.0, 0.0)
    >>> [round(d, 4) for d in mer_distance(0.4205, 0.3750)]
    [0.0125, -0.002]
    """
    out = []
    for value, (low, high) in ((x, MER_SKY_CHROMATICITY["x"]), (y, MER_SKY_CHROMATICITY["y"])):
        out.append(float(value - high if value > high else value - low if value < low else 0.0))
    return out[0], out[1]


def _signed(d: float) -> str:
    """A distance outside the range: 4 decimals, or 2 digits when below 5e-5."""
    return f"{d:+.4f}" if abs(d) >= 5e-5 else f"{d:+.1e}"


def _verdict(dx: float, dy: float) -> str:
    """``"inside"``, or the coordinates outside the range and by how much."""
    parts = [f"{k} {_signed(d)}" for k, d in (("x", dx), ("y", dy)) if d != 0.0]
    return ", ".join(parts) if parts else "inside"


@dataclass(frozen=True)
class RoverRow:
    """One model at one Sun elevation against the rovers' range.

    Attributes
    ----------
    model : str
        The model (preset name).
    sun_elevation_deg : float
        Sun elevation. [deg]
    x, y : float
        CIE 1931 chromaticity looking away from the Sun (:data:`AWAY_FROM_SUN`). [-]
    dx, dy : float
        :func:`mer_distance` of ``(x, y)``: 0 inside the range. [-]
    """

    model: str
    sun_elevation_deg: float
    x: float
    y: float
    dx: float
    dy: float

    @property
    def inside(self) -> bool:
        """Inside the rovers' range in both coordinates."""
        return self.dx == 0.0 and self.dy == 0.0

    @property
    def verdict(self) -> str:
        """``"inside"`` or how far outside, e.g. ``"x +0.0125"``."""
        return _verdict(self.dx, self.dy)


@dataclass(frozen=True)
class RoverComparison:
    """Sky chromaticity of Mars models against the rovers' range (a table).

    Attributes
    ----------
    rows : tuple of RoverRow
        One per model and Sun elevation.
    optical_depth : float
        Vertical dust optical depth at 550 nm (not Collienne's aerosol's). [-]
    ground_albedo : float
        Lambertian ground albedo. [-]
    """

    rows: tuple[RoverRow, ...]
    optical_depth: float
    ground_albedo: float

    def to_text(self) -> str:
        """The table as plain text, with the range and its source."""
        x0, x1 = MER_SKY_CHROMATICITY["x"]
        y0, y1 = MER_SKY_CHROMATICITY["y"]
        width = max([len("model")] + [len(r.model) for r in self.rows])
        lines = [
            f"sky chromaticity looking away from the Sun (view elevation 30 degree) against "
            f"the MER range x {x0:.3f}-{x1:.3f}, y {y0:.3f}-{y1:.3f} (Bell, Savransky & Wolff "
            f"2006); dust optical depth {self.optical_depth:g} at 550 nm, ground albedo "
            f"{self.ground_albedo:g}",
            f"{'model':<{width}}  Sun [deg]       x       y  MER range",
        ]
        for r in self.rows:
            lines.append(
                f"{r.model:<{width}}  {r.sun_elevation_deg:9.1f}  {r.x:.4f}  {r.y:.4f}  {r.verdict}"
            )
        return "\n".join(lines)


def _rows(model: str, elevations: Any, xy: np.ndarray) -> list[RoverRow]:
    return [
        RoverRow(model, float(e), float(x), float(y), *mer_distance(float(x), float(y)))
        for e, (x, y) in zip(elevations, np.asarray(xy).reshape(-1, 2))
    ]


def rover_comparison(ds: Any) -> RoverComparison:
    """The rover table of :func:`compare_mars_models`' dataset (or its file read back)."""
    rows: list[RoverRow] = []
    for m in ds.model.values:
        xy = np.stack(
            [ds.chromaticity_x.sel(model=m).values, ds.chromaticity_y.sel(model=m).values], axis=-1
        )
        rows += _rows(str(m), ds.sun_elevation.values, xy)
    return RoverComparison(
        rows=tuple(rows),
        optical_depth=float(ds.attrs["optical_depth_550nm"]),
        ground_albedo=float(ds.attrs["ground_albedo"]),
    )


def read_rover_comparison(path: str | Path) -> RoverComparison:
    """:func:`rover_comparison` of a ``mars-comparison.nc`` written by ``sky compare``."""
    import xarray as xr  # lazy: xarray adds 0.7-1 s to start-up (-X importtime)

    with xr.open_dataset(Path(path)) as ds:
        return rover_comparison(ds.load())


def _away_chromaticity(
    medium: Medium,
    elevation_deg: float,
    *,
    ground_albedo: float,
    tol: float,
    report: Reporter,
    allow_large: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) away from the Sun and the Sun's transmittance, one solve."""
    s = sky_radiance(
        medium,
        sun_elevation_deg=elevation_deg,
        ground_albedo=ground_albedo,
        tol=tol,
        view_zenith_deg=np.array([59.0, 60.0, 61.0]),
        azimuth_step_deg=45.0,
        progress=report,
        allow_large=allow_large,
    )
    return s.chromaticity(s.at(**AWAY_FROM_SUN)), s.sun_transmittance


def mer_chromaticity(
    *,
    models: tuple[str, ...] = MARS_MODELS,
    sun_elevations_deg: tuple[float, ...] = (5.0, 30.0, 60.0),
    optical_depth: float = 0.5,
    ground_albedo: float = 0.2,
    tol: float = 1e-4,
    progress: TextIO | Reporter | None = None,
    allow_large: bool = False,
) -> RoverComparison:
    """Only the chromaticity of :func:`compare_mars_models`, against the rovers.

    One medium per model and one solve of the orders of scattering per Sun
    elevation, with the sky at three view zenith angles: a few seconds per row.

    Parameters
    ----------
    models : tuple of str
        Presets (default the thesis's four).
    sun_elevations_deg : tuple of float
        Sun elevations, -10 .. 90. [deg]
    optical_depth : float
        Vertical dust optical depth at 550 nm. [-]
    ground_albedo : float
        Lambertian ground albedo, 0 .. 1. [-]
    tol : float
        Tolerance of the orders of scattering. [-]
    progress : text stream, optional
        Where to report after the first two seconds; None is silent.
    allow_large : bool
        Go ahead beyond the budget of each sky.

    Returns
    -------
    RoverComparison
    """
    models = _check_models(models)
    check_positive("optical_depth", optical_depth)
    check_closed_interval("ground_albedo", ground_albedo, 0.0, 1.0)
    for e in sun_elevations_deg:
        check_closed_interval("sun_elevations_deg", e, -10.0, 90.0)
    report = reporter(progress, label="sky compare")
    grid = _grid(COMPARISON_WAVELENGTHS_NM)
    mie = _preset_table(_MIE_CROSS_SECTIONS, grid)
    rows: list[RoverRow] = []
    for k, model in enumerate(models):
        report(f"model {k + 1} of {len(models)} ({model})")
        atm = mars_sky_atmosphere(
            model, optical_depth=optical_depth, wavelength_nm=grid, cross_sections=mie
        )
        medium = Medium.from_atmosphere(atm)
        xy = [
            _away_chromaticity(
                medium,
                float(e),
                ground_albedo=ground_albedo,
                tol=tol,
                report=report,
                allow_large=allow_large,
            )[0]
            for e in sun_elevations_deg
        ]
        rows += _rows(model, sun_elevations_deg, np.array(xy))
    report(f"{len(models)} models done", last=True)
    return RoverComparison(
        rows=tuple(rows), optical_depth=float(optical_depth), ground_albedo=float(ground_albedo)
    )


def _check_models(models: tuple[str, ...]) -> tuple[str, ...]:
    if isinstance(models, str) or not models:
        raise ValueError(f"models must be a non-empty tuple of preset names; got {models!r}")
    for m in models:
        if not isinstance(m, str) or not m:
            raise ValueError(f"models must be preset names; got {m!r}")
    return tuple(models)


def _scattering_angle(
    view_zenith: np.ndarray, view_azimuth: np.ndarray, sun_zenith: float
) -> np.ndarray:
    mv = np.cos(np.deg2rad(view_zenith))
    ms = math.cos(math.radians(sun_zenith))
    c = mv * ms + np.sqrt(1 - mv**2) * math.sqrt(1 - ms**2) * np.cos(np.deg2rad(view_azimuth))
    return np.rad2deg(np.arccos(np.clip(c, -1.0, 1.0)))


def _check_comparison_cost(
    medium: Medium, *, azimuth_step_deg: float, tol: float, allow_large: bool
) -> None:
    """The budget of each sky of :func:`compare_mars_models` (the dome, away from the Sun)."""
    check_orders_cost(medium, n_layers=N_LAYERS, tol=tol, allow_large=allow_large)
    n_zenith = default_view_zenith_deg().size
    n_az = round(180.0 / azimuth_step_deg) + 1
    check_render_cost(
        medium,
        n_rays=n_zenith * n_az,
        n_rows=n_zenith,
        n_path=N_PATH,
        allow_large=allow_large,
        what="the comparison's sky (view zenith angles x azimuth_step_deg)",
    )


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

    Raises
    ------
    ValueError
        A parameter out of range, before any work.
    dustoptics._validation.BudgetError
        A sky beyond the memory and work budget without ``allow_large``,
        refused before the first sky (the models share the grids).
    """
    import xarray as xr  # lazy: xarray adds 0.7-1 s to start-up (-X importtime)

    models = _check_models(models)
    check_positive("optical_depth", optical_depth)
    check_closed_interval("sun_elevation_deg", sun_elevation_deg, -10.0, 90.0)
    for e in sun_elevations_deg:
        check_closed_interval("sun_elevations_deg", e, -10.0, 90.0)
    check_closed_interval("ground_albedo", ground_albedo, 0.0, 1.0)
    check_closed_interval("azimuth_step_deg", azimuth_step_deg, 0.05, 45.0)
    report = reporter(progress, label="sky compare")
    grid = _grid(COMPARISON_WAVELENGTHS_NM)
    mie = _preset_table(_MIE_CROSS_SECTIONS, grid)
    sel = [grid.index(w) for w in COMPARISON_WAVELENGTHS_NM]
    n_steps = len(models) * (1 + len(sun_elevations_deg))
    sun_zen = 90.0 - sun_elevation_deg
    almu_az = np.arange(0.0, 180.01, 1.0)
    pp_zen = np.arange(0.0, 90.01, 1.0)
    per_model: dict[str, dict[str, np.ndarray]] = {}
    sky: SkyRadiance | None = None
    step = 0
    for k, model in enumerate(models):
        report(f"model {k + 1} of {len(models)} ({model}): its optics", last=True)
        atm = mars_sky_atmosphere(
            model, optical_depth=optical_depth, wavelength_nm=grid, cross_sections=mie
        )
        medium = Medium.from_atmosphere(atm)
        if k == 0:  # every sky's budget before the first (the models share the grids)
            _check_comparison_cost(
                medium, azimuth_step_deg=azimuth_step_deg, tol=tol, allow_large=allow_large
            )
        step += 1
        report(
            f"sky {step} of {n_steps}: model {k + 1} of {len(models)} ({model}), the dome at "
            f"Sun {sun_elevation_deg:g} deg",
            last=True,
        )
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
            step += 1
            report(
                f"sky {step} of {n_steps}: model {k + 1} of {len(models)} ({model}), away from "
                f"the Sun at {float(elev):g} deg",
                last=True,
            )
            xy, t = _away_chromaticity(
                medium,
                float(elev),
                ground_albedo=ground_albedo,
                tol=tol,
                report=report,
                allow_large=allow_large,
            )
            chrom.append(xy)
            trans.append(t[sel])
        per_model[model] = {
            "almucantar": almu,
            "principal": pp,
            "relative_luminance": y / y[0, 0],
            "chromaticity": np.array(chrom),
            "transmittance": np.array(trans),
        }
    assert sky is not None
    report(f"{n_steps} skies of {len(models)} models done", last=True)
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
            "models": (
                "collienne: Collienne et al.'s molecular coefficients and Bruneton's grey "
                "aerosol (optical depth 5.328e-3, albedo 0.9, Cornette-Shanks g 0.8); costa, "
                "hybrid: their phase functions with the Blue Moon's Mie cross-sections scaled to "
                "the optical depth; blue-moons: Mie (Meyran 2022, sections 3.4, 4.1, app. A)"
            ),
            "mer_chromaticity_x": list(MER_SKY_CHROMATICITY["x"]),
            "mer_chromaticity_y": list(MER_SKY_CHROMATICITY["y"]),
            "mer_chromaticity_source": BELL_2006,
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
            axes[i, j].set_ylabel("radiance / solar irradiance [sr$^{-1}$]")
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
        ax.set_yticklabels(["30", "60", "90"], fontsize="x-small")
        ax.tick_params(axis="x", labelsize="x-small")
        ax.set_xlabel(
            "azimuth from the Sun [degree] (Sun up);\nradius: view zenith angle [degree]",
            fontsize="x-small",
        )
        ax.set_title(m)
    fig.colorbar(pc, ax=list(axes), label="luminance / zenith luminance [1]")
    fig.suptitle(
        f"Mars sky luminance relative to the zenith, Sun at {ds.attrs['sun_elevation_deg']:g} "
        "degree"
    )
    figs["luminance"] = fig

    fig, ax = plt.subplots(figsize=(5, 4.5), constrained_layout=True)
    x0, x1 = MER_SKY_CHROMATICITY["x"]
    y0, y1 = MER_SKY_CHROMATICITY["y"]
    ax.add_patch(
        matplotlib.patches.Rectangle(
            (x0, y0), x1 - x0, y1 - y0, color="0.8", label="MER (Bell, Savransky & Wolff 2006)"
        )
    )
    for m in models:
        xs, ys = ds.chromaticity_x.sel(model=m).values, ds.chromaticity_y.sel(model=m).values
        ax.plot(xs, ys, "o-", label=m)
        for e, x, y in zip(ds.sun_elevation.values, xs, ys):
            ax.annotate(
                f"{e:g}", (x, y), fontsize="x-small", xytext=(3, 3), textcoords="offset points"
            )
    ax.set_xlabel("CIE 1931 x [1]")
    ax.set_ylabel("CIE 1931 y [1]")
    ax.set_title("sky chromaticity away from the Sun\n(labels: Sun elevation [degree])")
    ax.legend(fontsize="small")
    figs["chromaticity"] = fig

    fig, ax = plt.subplots(figsize=(5, 4), constrained_layout=True)
    styles = ("-", "--", ":", "-.")
    for j, w in enumerate(ds.wavelength.values):
        for k, group in enumerate(_same_curves(ds.sun_transmittance.sel(wavelength=w), models)):
            ax.plot(
                ds.sun_elevation,
                ds.sun_transmittance.sel(model=group[0], wavelength=w),
                styles[j % len(styles)],
                color=f"C{k}",
                marker="o",
                markersize=3,
                label=f"{' = '.join(group)}, {w:g} nm",
            )
    ax.set_xlabel("Sun elevation [degree]")
    ax.set_ylabel("direct transmittance of the Sun [1]")
    ax.set_title(
        "the Sun's transmittance to the ground\n(models with the same extinction share a line)"
    )
    ax.legend(fontsize="x-small")
    figs["transmittance"] = fig
    return figs


def _same_curves(values: Any, models: list[str]) -> list[list[str]]:
    """The models grouped by equal curves (to 1e-12): one line, one legend entry per group.

    The dust models that share the Blue Moon's cross-sections (costa, hybrid,
    blue-moons) have the same extinction, hence the same transmittance.
    """
    groups: list[list[str]] = []
    curves: list[np.ndarray] = []
    for m in models:
        curve = np.asarray(values.sel(model=m), dtype=float)
        for g, c in zip(groups, curves):
            if np.allclose(curve, c, rtol=1e-12, atol=0.0):
                g.append(m)
                break
        else:
            groups.append([m])
            curves.append(curve)
    return groups
