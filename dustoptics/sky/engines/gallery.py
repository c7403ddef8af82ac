"""Side-by-side pictures of the engines' skies: exact | fitted | community.

For one engine, one planet set and one Sun elevation, :func:`engine_panels`
draws three fisheye images (equidistant, zenith at the centre, horizon at the
rim, the Sun's azimuth up, as :meth:`~dustoptics.sky.scene.SkyRadiance.fisheye`
draws them) at one exposure:

1. the exact spectral sky (:func:`~dustoptics.sky.scene.sky_radiance` with the
   tolerance and ground albedo of
   :func:`~dustoptics.sky.engines.core.reference_skies`);
2. the engine's own model (:attr:`~dustoptics.sky.engines.core.EngineModel.render`)
   with the parameters the error table fitted (a
   :class:`~dustoptics.sky.engines.report.ReportRow` of kind ``"fitted"``);
3. the same model with today's community parameters (the row of kind
   ``"community"``).

All three are computed on the same grid of zenith angles and azimuths and
interpolated bilinearly to the pixels the same way; the exposure is the exact
sky's :meth:`~dustoptics.sky.scene.SkyRadiance.default_exposure` (its
brightest sky farther than 10 deg from the Sun at display white).  No panel
draws the Sun's disc (the engines' models here leave it out).

The label of each engine panel is its CIE Delta E 2000 mean over the coarse
dome at that Sun elevation, computed again here by
:func:`~dustoptics.sky.engines.core.sky_error` on
:func:`~dustoptics.sky.engines.core.reference_skies` with the row's
parameters, and checked against the row's own value (a row made by other
code, or parameters that do not render what the table measured, are refused).
:func:`gallery_png` lays the panels of several Sun elevations out as one
labelled PNG image (the ``plot`` extra, matplotlib).
"""

from __future__ import annotations

import io as _io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from dustoptics import colour
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky.engines.core import (
    ENGINES,
    EngineModel,
    ReferenceSky,
    engine_xyz,
    sky_error,
)
from dustoptics.sky.engines.report import ReportRow
from dustoptics.sky.medium import Medium
from dustoptics.sky.scene import (
    SkyRadiance,
    check_image_size,
    check_png_support,
    display_rgb,
    sky_radiance,
)

__all__ = [
    "DELTA_E_TOLERANCE",
    "GALLERY_SUN_ELEVATIONS_DEG",
    "KINDS",
    "EnginePanels",
    "engine_panels",
    "exact_dome",
    "fisheye_directions",
    "fisheye_from_grid",
    "gallery_png",
    "row_params",
]

#: Sun elevations of the gallery: high Sun and sunset (both rows of the error table). [deg]
GALLERY_SUN_ELEVATIONS_DEG: Final = (45.0, 0.0)

#: The panels, left to right.
KINDS: Final = ("exact", "fitted", "community")

#: Largest difference allowed between the Delta E 2000 recomputed for a picture and the
#: row's own (the same code on the same directions: only the last digits of a JSON round
#: trip and of the solver's sums may differ). [-]
DELTA_E_TOLERANCE: Final = 0.05

#: Tolerance of the orders of scattering and ground albedo of the exact sky (those of
#: :func:`~dustoptics.sky.engines.core.reference_skies`).
_TOL: Final = 1e-3
_GROUND_ALBEDO: Final = 0.2


def fisheye_directions(size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each pixel's viewing zenith angle and azimuth of a fisheye ``size`` pixels wide.

    The geometry of :meth:`~dustoptics.sky.scene.SkyRadiance.fisheye`: equidistant
    (zenith angle proportional to the distance from the centre, 90 deg at the rim),
    the Sun's azimuth up; pixels outside the horizon circle get zenith angle 0.

    Returns
    -------
    zenith_deg, azimuth_deg : numpy.ndarray, shape (size, size)
        [deg]; azimuths from the Sun's, in (-180, 180].
    inside : numpy.ndarray of bool, shape (size, size)
        Within the horizon circle.
    """
    size = check_image_size("size", size, minimum=2)
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    xx, yy = np.meshgrid(c, -c)
    rad = np.hypot(xx, yy)
    inside = rad <= 1.0
    zen = np.where(inside, rad * 90.0, 0.0)
    azi = np.rad2deg(np.arctan2(xx, yy))
    return zen, azi, inside


def fisheye_from_grid(
    view_zenith_deg: np.ndarray,
    view_azimuth_deg: np.ndarray,
    xyz: np.ndarray,
    *,
    size: int,
    exposure: float,
) -> np.ndarray:
    """An 8-bit display sRGB fisheye of CIE XYZ given on a zenith-azimuth grid.

    Bilinear in zenith angle and azimuth (azimuths folded into [0, 180] by the
    sky's mirror symmetry), as :meth:`~dustoptics.sky.scene.SkyRadiance.fisheye`
    interpolates; pixels outside the horizon circle are black.

    Parameters
    ----------
    view_zenith_deg : numpy.ndarray, shape (n_zenith,)
        Increasing, from 0 to 90. [deg]
    view_azimuth_deg : numpy.ndarray, shape (n_azimuth,)
        Increasing, from 0 to 180, from the Sun's. [deg]
    xyz : numpy.ndarray, shape (n_zenith, n_azimuth, 3)
        CIE XYZ per unit solar illuminance; NaN is drawn black. [sr^-1]
    size : int
        Image side. [pixels]
    exposure : float
        Display white at ``Y * exposure = 1``. [sr]

    Returns
    -------
    numpy.ndarray, shape (size, size, 3), dtype uint8
    """
    zg = np.asarray(view_zenith_deg, dtype=float)
    ag = np.asarray(view_azimuth_deg, dtype=float)
    values = np.nan_to_num(np.asarray(xyz, dtype=float), nan=0.0)
    if values.shape != (zg.size, ag.size, 3):
        raise ValueError(
            f"xyz must have shape {(zg.size, ag.size, 3)} (zenith, azimuth, XYZ); "
            f"got {values.shape}"
        )
    if zg[0] != 0.0 or zg[-1] != 90.0 or ag[0] != 0.0 or ag[-1] != 180.0:
        raise ValueError("the grid must span zenith angles 0..90 deg and azimuths 0..180 deg")
    zen, azi, inside = fisheye_directions(size)
    a = np.abs((azi + 180.0) % 360.0 - 180.0)
    iz = np.clip(np.searchsorted(zg, zen) - 1, 0, zg.size - 2)
    fz = ((zen - zg[iz]) / (zg[iz + 1] - zg[iz]))[..., None]
    ia = np.clip(np.searchsorted(ag, a) - 1, 0, ag.size - 2)
    fa = ((a - ag[ia]) / (ag[ia + 1] - ag[ia]))[..., None]
    pixels = (
        values[iz, ia] * (1 - fz) * (1 - fa)
        + values[iz + 1, ia] * fz * (1 - fa)
        + values[iz, ia + 1] * (1 - fz) * fa
        + values[iz + 1, ia + 1] * fz * fa
    )
    rgb = display_rgb(pixels, exposure)
    rgb[~inside] = 0
    return rgb


def exact_dome(
    atmosphere: Atmosphere | Medium,
    *,
    sun_elevation_deg: float,
    view_zenith_deg: np.ndarray,
    azimuth_step_deg: float,
) -> SkyRadiance:
    """The exact spectral sky on a picture's grid, without the Sun's disc.

    :func:`~dustoptics.sky.scene.sky_radiance` with the tolerance (1e-3) and
    ground albedo (0.2) of :func:`~dustoptics.sky.engines.core.reference_skies`.
    """
    return sky_radiance(
        atmosphere,
        sun_elevation_deg=sun_elevation_deg,
        ground_albedo=_GROUND_ALBEDO,
        tol=_TOL,
        view_zenith_deg=view_zenith_deg,
        azimuth_step_deg=azimuth_step_deg,
        sun_angular_radius_deg=0.0,
    )


def row_params(engine: EngineModel, row: ReportRow, atmosphere: Atmosphere) -> dict[str, float]:
    """The values a report row's parameters give the engine's renderer in this process.

    An engine that renders a set itself (CalcMySky, Bevy's own texture) carries a
    ``set_key`` valid only in the process that made it: it is made again here
    from ``atmosphere`` (:attr:`~dustoptics.sky.engines.core.EngineModel.initial`
    for the fitted row, :attr:`~dustoptics.sky.engines.core.EngineModel.community`
    for the community row); every other value is the row's.
    """
    if row.engine != engine.name:
        raise ValueError(f"row is engine {row.engine!r}'s, not {engine.name!r}'s")
    params = dict(row.params)
    if "set_key" in params:
        make = engine.initial if row.kind == "fitted" else engine.community
        params["set_key"] = float(make(atmosphere)["set_key"])
    return params


@dataclass(frozen=True, eq=False)
class EnginePanels:
    """The three panels of one engine, planet and Sun elevation.

    Attributes
    ----------
    engine : str
        :attr:`~dustoptics.sky.engines.core.EngineModel.name`.
    planet : str
        The report's planet key (``"earth"``, ``"mars:PRESET"``).
    sun_elevation_deg : float
        [deg]
    exposure : float
        Display white at ``Y * exposure = 1``, all three panels. [sr]
    images : tuple of numpy.ndarray
        The fisheyes of :data:`KINDS`, each (size, size, 3) uint8.
    delta_e_mean : tuple of float
        CIE Delta E 2000 mean over the coarse dome of the fitted and the
        community panels (recomputed, equal to the rows' within
        :data:`DELTA_E_TOLERANCE`). [-]
    row_delta_e_mean : tuple of float
        The rows' own values. [-]
    """

    engine: str
    planet: str
    sun_elevation_deg: float
    exposure: float
    images: tuple[np.ndarray, np.ndarray, np.ndarray]
    delta_e_mean: tuple[float, float]
    row_delta_e_mean: tuple[float, float]


def _row_error(row: ReportRow, sun_elevation_deg: float) -> float:
    for e in row.errors:
        if math.isclose(e.sun_elevation_deg, sun_elevation_deg, abs_tol=1e-9):
            return float(e.delta_e_mean)
    have = [e.sun_elevation_deg for e in row.errors]
    raise ValueError(
        f"sun_elevation_deg must be one of the report's {have}; got {sun_elevation_deg!r}"
    )


def engine_panels(
    rows: Mapping[str, ReportRow],
    atmosphere: Atmosphere,
    sky: SkyRadiance,
    dome: ReferenceSky,
    *,
    size: int,
    params: Mapping[str, Mapping[str, float]] | None = None,
) -> EnginePanels:
    """Exact | fitted | community fisheyes of one engine at ``sky``'s Sun elevation.

    Parameters
    ----------
    rows : mapping
        ``{"fitted": ReportRow, "community": ReportRow}`` of one engine and planet.
    atmosphere : Atmosphere
        The rows' planet set (:func:`~dustoptics.sky.engines.report.build_planet`).
    sky : SkyRadiance
        :func:`exact_dome` of ``atmosphere`` (its grid is the engines' too; it must
        span zenith angles 0..90 deg).
    dome : ReferenceSky
        :func:`~dustoptics.sky.engines.core.reference_skies` of ``atmosphere`` at
        ``sky``'s Sun elevation: the directions of the Delta E.
    size : int
        Side of each fisheye. [pixels]
    params : mapping, optional
        ``{"fitted": ..., "community": ...}``: :func:`row_params` of the rows,
        made once for every Sun elevation (an engine that renders a set builds
        its medium once per set); default made here.

    Returns
    -------
    EnginePanels

    Raises
    ------
    ValueError
        A row is missing or of another engine, the Sun elevation is not one of the
        rows', or the recomputed Delta E differs from a row's by more than
        :data:`DELTA_E_TOLERANCE`.
    """
    missing = [k for k in KINDS[1:] if k not in rows]
    if missing:
        raise ValueError(f"rows must hold 'fitted' and 'community'; missing {missing}")
    name = rows["fitted"].engine
    if name not in ENGINES or rows["community"].engine != name:
        raise ValueError(f"rows must be of one engine of {sorted(ENGINES)}; got {name!r}")
    engine = ENGINES[name]
    elevation = sky.sun_elevation_deg
    exposure = sky.default_exposure()
    zz, aa = np.meshgrid(sky.view_zenith_deg, sky.view_azimuth_deg, indexing="ij")
    if not math.isclose(dome.sun_elevation_deg, elevation, abs_tol=1e-9):
        raise ValueError(
            f"dome is for a Sun at {dome.sun_elevation_deg:g} deg, sky at {elevation:g} deg"
        )
    grids = [sky.xyz()]
    recomputed, own = [], []
    for kind in KINDS[1:]:
        row = rows[kind]
        values = row_params(engine, row, atmosphere) if params is None else params[kind]
        rgb = engine.render(
            values, sun_elevation_deg=elevation, view_zenith_deg=zz, view_azimuth_deg=aa
        )
        grids.append(colour.linear_srgb_to_xyz(rgb))
        value = sky_error(dome, engine_xyz(engine, values, dome)).delta_e_mean
        expected = _row_error(row, elevation)
        if not abs(value - expected) <= DELTA_E_TOLERANCE:
            raise ValueError(
                f"{name} {row.planet} {kind} at {elevation:g} deg: Delta E 2000 mean "
                f"{value:.3f} from the row's parameters, but the row says {expected:.3f}"
            )
        recomputed.append(value)
        own.append(expected)
    images = tuple(
        fisheye_from_grid(
            sky.view_zenith_deg, sky.view_azimuth_deg, g, size=size, exposure=exposure
        )
        for g in grids
    )
    return EnginePanels(
        engine=name,
        planet=rows["fitted"].planet,
        sun_elevation_deg=float(elevation),
        exposure=float(exposure),
        images=(images[0], images[1], images[2]),
        delta_e_mean=(recomputed[0], recomputed[1]),
        row_delta_e_mean=(own[0], own[1]),
    )


def _planet_label(planet: str) -> str:
    if planet == "earth":
        return "Earth"
    return f"Mars, dust {planet.partition(':')[2]}"


def gallery_png(panels: Sequence[EnginePanels], *, title: str | None = None) -> bytes:
    """One labelled PNG: a row of exact | fitted | community per Sun elevation.

    Each row is labelled with its Sun elevation, each engine panel with its kind
    and Delta E 2000 mean (:attr:`EnginePanels.delta_e_mean`, one decimal); the
    title names the engine and the planet.  Pixels of the fisheyes are copied
    as they are (no resampling).  No time stamp: the same bytes each time on one
    installation (the glyphs are matplotlib's).  Needs the ``plot`` extra.

    Parameters
    ----------
    panels : sequence of EnginePanels
        Of one engine and planet, one per row, top to bottom.
    title : str, optional
        Default: the engine's title and the planet.
    """
    check_png_support()
    if not panels:
        raise ValueError("panels must hold at least one EnginePanels")
    first = panels[0]
    if any(p.engine != first.engine or p.planet != first.planet for p in panels):
        raise ValueError("panels must all be of one engine and planet")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    size = first.images[0].shape[0]
    font = max(6.0, min(11.0, size / 16.0))  # points = pixels at 72 dpi
    gap = max(2, round(font / 2))
    line = round(font * 1.5)
    width = 3 * size + 4 * gap
    height = line + len(panels) * (2 * line + size + gap) + gap
    fig = Figure(figsize=(width / 72.0, height / 72.0), dpi=72, facecolor="#1e1e1e")
    FigureCanvasAgg(fig)
    text: dict[str, Any] = {"color": "white", "fontsize": font, "ha": "center"}
    label = title or f"{ENGINES[first.engine].title}: {_planet_label(first.planet)}"
    fig.text(0.5, 1.0 - (line - 2) / height, label, **text)
    top = line
    for p in panels:
        fig.text(0.5, 1.0 - (top + line - 3) / height, f"Sun {p.sun_elevation_deg:g} deg", **text)
        captions = [
            "exact spectral sky",
            f"fitted: dE00 mean {p.delta_e_mean[0]:.1f}",
            f"community: dE00 mean {p.delta_e_mean[1]:.1f}",
        ]
        for i, (image, caption) in enumerate(zip(p.images, captions, strict=True)):
            x = gap + i * (size + gap)
            fig.text((x + size / 2) / width, 1.0 - (top + 2 * line - 3) / height, caption, **text)
            fig.figimage(image, xo=x, yo=height - (top + 2 * line + size), origin="upper")
        top += 2 * line + size + gap
    buf = _io.BytesIO()
    no_stamp: dict[str, Any] = {"Software": None}
    fig.savefig(buf, format="png", dpi=72, metadata=no_stamp, facecolor=fig.get_facecolor())
    return buf.getvalue()
