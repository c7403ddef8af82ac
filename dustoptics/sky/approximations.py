"""The sky an engine will draw, beside the exact one: what each approximation costs.

A renderer rarely takes the spectral optics as they are.  :class:`Approximations`
names what it does instead, each on its own or together, and
:func:`preview_sky` renders the sky with them and compares it with the exact
sky (:func:`~dustoptics.sky.scene.sky_radiance`) over the dome and near the Sun:

``phase="fit:MODEL"``
    The aerosol phase function replaced, per wavelength (per channel with
    ``channels_nm``), by an analytic model fitted to it
    (:func:`dustoptics.scattering.fit.fit_table`; MODEL one of
    :data:`~dustoptics.scattering.fit.FIT_MODELS`, an alias of
    :data:`~dustoptics.scattering.fit.FIT_MODEL_ALIASES` or ``cornette-shanks``),
    evaluated as the engine evaluates it: the analytic function itself
    (:data:`dustoptics.scattering.phase.ANALYTIC_MODELS`) at the table's angles.
    ``"fit:MODEL@NM"`` fits once, at NM nanometres, and uses that function at
    every wavelength, as Bruneton's model does with its one
    ``mie_phase_function_g`` (Cornette-Shanks, fitted at 550 nm by
    :mod:`dustoptics.io.engines.bruneton`: ``fit:cornette-shanks@550``).
    The molecules keep their phase function (engines draw Rayleigh analytically).
``channels_nm=(R, G, B)``
    Three wavelengths instead of the spectrum (:data:`ENGINE_CHANNELS_NM`:
    Bruneton's ``kLambdaR, kLambdaG, kLambdaB`` = 680, 550, 440 nm, which are
    also the three wavelengths CosmoScout VR's preprocessor accepts).  Every
    constituent's cross-sections are read linearly in wavelength at the
    channels, its phase function weighted by scattering
    (:func:`dustoptics.colour.channel_weights`, mode ``"wavelengths"``, and
    :func:`~dustoptics.colour.channel_phase`), as the exports make them.  The
    channel radiances are shown as an engine lit by a white sun shows them:
    linear sRGB ``RGB_sun * L_c``, ``RGB_sun`` the sunlight's own linear sRGB
    (ASTM G173, per unit solar luminance), back to CIE XYZ
    (:func:`dustoptics.colour.linear_srgb_to_xyz`).  A sky that is grey in
    wavelength keeps its colour exactly.
``angles="SAMPLING:N"``
    Each scattering constituent's phase function tabulated at an engine's
    ``N`` angles and read between them as the engine reads them:
    ``theta:N`` uniform in angle, 0 to 180 deg, linear in angle (dustoptics'
    textures and GLSL arrays, :mod:`dustoptics.io.textures.phase_texture`);
    ``cos:N`` uniform in cos(theta), linear in cos(theta) (the textures'
    ``"cos"`` sampling); ``cosmoscout:N`` CosmoScout VR's phase columns at the
    texel centres ``(j + 1/2) 180 / N`` deg, linear between centres and held
    within half a column of 0 and 180 deg
    (:func:`dustoptics.io.csv.cosmoscout.cosmoscout_phase_angles`).  The
    renderer reads a phase function linearly in angle between its table's
    angles, so ``cos:N`` is drawn on a table of the samples' angles and every
    0.01 deg, which follows the linear-in-cosine reading to 1e-5 for the Martian
    dust.
``float16=True``
    The phase-function samples (the engine's with ``angles``, else the
    table's own) rounded to IEEE binary16, as
    an engine's half-float texture stores them (11 significant bits: a
    relative error of at most 2^-11 for values from 2^-14 to 65504).  The
    cross-sections stay float32 uniforms in every engine and are not rounded.

The approximated sky is rendered with the same medium geometry (the slant
columns are reused), the same Sun, ground, observer, tolerance and directions
as the exact one; the moments the multiple scattering needs are projected
again from the approximated phase functions exactly as
:meth:`~dustoptics.sky.medium.Medium.from_atmosphere` projects them.  The two
renders share the work that depends only on the geometry
(:func:`dustoptics.sky._shared.shared_geometry`: the Legendre functions at the
discrete ordinates and at the Sun, the aureole's Legendre polynomials), which
the second takes from the first, bit for bit.  The cost is less than one more
sky render (a much cheaper one with three channels), plus the fit.

Differences (:class:`PreviewSummary`), over the dome (every computed direction,
means weighted by solid angle) and near the Sun (directions within
``near_sun_deg``, default 10 deg, of the Sun's centre):

- ``delta_xy``: distance between the two skies' CIE 1931 (x, y) chromaticities;
- ``luminance_ratio``: approximated over exact luminance (CIE Y under the
  sunlight), per direction (min, max) and of the solid-angle integrals (mean).

Bad input is refused before the sky is rendered, naming what would do
(:func:`check_approximations`): an unknown phase model (with the allowed
list), channels outside the set's wavelengths, float16 samples beyond 65504,
and an angle count too small for the set's phase functions at
``angle_tolerance`` (the phase function's integral over the sphere as the
engine reads it, as :func:`~dustoptics.io.csv.cosmoscout.cosmoscout_phase_error`
measures it), with the smallest count that does.
"""

from __future__ import annotations

import io as _io
import math
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any, Final

import numpy as np

from dustoptics import colour
from dustoptics._validation import check_closed_interval
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.scattering.fit import FIT_MODEL_ALIASES, FIT_MODELS, FitResult, fit_table
from dustoptics.scattering.phase import ANALYTIC_MODELS, dhg_costa2021
from dustoptics.scattering.tabulated_phase import mean_cosine, sphere_integral
from dustoptics.sky._shared import shared_geometry
from dustoptics.sky.medium import Medium, legendre_moments
from dustoptics.sky.scene import SkyRadiance, display_rgb, sky_radiance, sunlit_xyz
from dustoptics.table import CrossSections, Table

__all__ = [
    "ANGLE_SAMPLINGS",
    "ENGINE_CHANNELS_NM",
    "NEAR_SUN_DEG",
    "PHASE_CHOICES",
    "Approximations",
    "PreviewSummary",
    "SkyPreview",
    "approximate_medium",
    "check_approximations",
    "preview_sky",
    "smallest_angle_count",
]

#: Three-channel wavelengths of the engines, R, G, B: Bruneton's kLambdaR/G/B
#: (``atmosphere/model.h``) and the only three CosmoScout VR's preprocessor
#: accepts (``main.cpp``: 440, 550, 680 nm). [nm]
ENGINE_CHANNELS_NM: Final = MappingProxyType(
    {"bruneton": (680.0, 550.0, 440.0), "cosmoscout": (680.0, 550.0, 440.0)}
)

#: Extra short names of fitted phase models (beside FIT_MODEL_ALIASES).
_EXTRA_ALIASES: Final = {"cornette-shanks": "cornette-shanks1992"}

#: What ``phase`` accepts: the exact phase function or a fitted model.
PHASE_CHOICES: Final = ("exact",) + tuple(
    f"fit:{m}" for m in (*FIT_MODELS, *FIT_MODEL_ALIASES, *_EXTRA_ALIASES)
)

#: Angle samplings of ``angles="SAMPLING:N"``.
ANGLE_SAMPLINGS: Final = ("theta", "cos", "cosmoscout")

#: Radius of the region "near the Sun" unless given. [degree]
NEAR_SUN_DEG: Final = 10.0

#: Largest finite IEEE binary16 value.
_FLOAT16_MAX: Final = 65504.0
#: Angle counts searched for the smallest that does.
_MAX_ANGLES: Final = 1_000_000
#: Angles of the linear-in-angle table that stands for a ``cos:N`` reading (0.01 deg apart).
_COS_GRID_SIZE: Final = 18001
#: Angle tolerance unless given: the CosmoScout export's (0.5 %).
_ANGLE_TOLERANCE: Final = 0.005


@dataclass(frozen=True)
class Approximations:
    """What an engine does instead of the exact optics (see the module docstring).

    Parameters
    ----------
    phase : str
        ``"exact"``, ``"fit:MODEL"`` (:data:`PHASE_CHOICES`: one fit per
        wavelength, or per channel) or ``"fit:MODEL@NM"`` (one fit, at NM
        nanometres, for every wavelength: Bruneton's single
        ``mie_phase_function_g``, fitted at 550 nm by his export).  Default exact.
    channels_nm : tuple of 3 floats, optional
        R, G, B wavelengths instead of the spectrum (e.g.
        ``ENGINE_CHANNELS_NM["bruneton"]``). [nm]
    angles : str, optional
        ``"theta:N"``, ``"cos:N"`` or ``"cosmoscout:N"`` (:data:`ANGLE_SAMPLINGS`).
    float16 : bool
        Phase-function samples rounded to IEEE binary16.
    angle_tolerance : float
        Largest error of the phase function's integral over the sphere, as the
        engine reads the samples, that ``angles`` may leave (default 0.005). [-]
    near_sun_deg : float
        Radius of the region near the Sun in the comparison, 0.5 .. 90
        (default :data:`NEAR_SUN_DEG`). [degree]

    Raises
    ------
    ValueError
        An unknown phase or sampling (the message lists the allowed ones), a
        count below 2, channels that are not three positive wavelengths, or a
        tolerance or radius out of range.
    """

    phase: str = "exact"
    channels_nm: tuple[float, float, float] | None = None
    angles: str | None = None
    float16: bool = False
    angle_tolerance: float = _ANGLE_TOLERANCE
    near_sun_deg: float = NEAR_SUN_DEG

    def __post_init__(self) -> None:
        _parse_phase(self.phase)
        if self.channels_nm is not None:
            ch = tuple(float(v) for v in self.channels_nm)
            if len(ch) != 3 or not all(math.isfinite(v) and v > 0 for v in ch):
                raise ValueError(
                    f"channels_nm must be three positive wavelengths R, G, B [nm]; got "
                    f"{self.channels_nm!r}"
                )
            if len(set(ch)) != 3:
                raise ValueError(f"channels_nm must be three distinct wavelengths; got {ch!r}")
            object.__setattr__(self, "channels_nm", ch)
        if self.angles is not None:
            _parse_angles(self.angles)
        check_closed_interval("angle_tolerance", self.angle_tolerance, 1e-9, 1.0)
        check_closed_interval("near_sun_deg", self.near_sun_deg, 0.5, 90.0)

    @property
    def fit_model(self) -> str | None:
        """The fitted model's full name, or None for the exact phase function."""
        return _parse_phase(self.phase)[0]

    @property
    def fit_at_nm(self) -> float | None:
        """The one wavelength of ``"fit:MODEL@NM"``, else None. [nm]"""
        return _parse_phase(self.phase)[1]

    @property
    def any(self) -> bool:
        """True when at least one approximation is asked for."""
        return (
            self.phase != "exact"
            or self.channels_nm is not None
            or self.angles is not None
            or self.float16
        )

    def describe(self) -> str:
        """One line: the approximations, in the order they are applied."""
        parts = []
        if self.channels_nm is not None:
            parts.append("RGB " + "/".join(f"{v:g}" for v in self.channels_nm) + " nm")
        if self.phase != "exact":
            parts.append(f"phase {self.phase}")
        if self.angles is not None:
            parts.append(f"angles {self.angles}")
        if self.float16:
            parts.append("float16 phase")
        return ", ".join(parts) if parts else "none (exact)"


def _parse_phase(text: str) -> tuple[str | None, float | None]:
    """The full model name (None for exact) and the one fit's wavelength [nm] (or None)."""
    if text == "exact":
        return None, None
    choice, at, nm = str(text).partition("@")
    if choice not in PHASE_CHOICES[1:]:
        raise ValueError(
            f"phase must be one of {', '.join(PHASE_CHOICES)}, a fit optionally followed by "
            f"@NM (one fit at NM nanometres for every wavelength); got {text!r}"
        )
    name = choice.removeprefix("fit:")
    name = _EXTRA_ALIASES.get(name, name)
    name = FIT_MODEL_ALIASES.get(name, name)
    if not at:
        return name, None
    try:
        value = float(nm)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"phase: NM in fit:MODEL@NM must be a positive wavelength; got {text!r}")
    return name, value


def _parse_angles(text: str) -> tuple[str, int]:
    sampling, sep, count = str(text).partition(":")
    if sampling not in ANGLE_SAMPLINGS or not sep:
        raise ValueError(
            f"angles must be SAMPLING:N with SAMPLING one of {', '.join(ANGLE_SAMPLINGS)}; "
            f"got {text!r}"
        )
    try:
        n = int(count)
    except ValueError:
        raise ValueError(f"angles: N must be an integer; got {text!r}") from None
    if not 2 <= n <= _MAX_ANGLES:
        raise ValueError(f"angles: N must be within [2, {_MAX_ANGLES}]; got {text!r}")
    return sampling, n


# ----------------------------------------------------------------- the optics


def _scatters(table: Table) -> bool:
    return table.cross_sections is not None and bool(np.any(table.cross_sections.csca_um2 > 0))


def _engine_grid(
    table: Table, sampling: str, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """Sample angles [deg], values [sr^-1], and, for "cos", the samples' cosines."""
    if sampling == "theta":
        theta = np.linspace(0.0, 180.0, n)
        return theta, table.phase_at(theta), theta, None
    if sampling == "cosmoscout":
        centres = (np.arange(n) + 0.5) * (180.0 / n)
        return centres, table.phase_at(centres), centres, None
    mu = np.linspace(1.0, -1.0, n)
    theta = np.minimum(np.degrees(np.arccos(mu)), 180.0)
    return theta, table.phase_at(theta), theta, mu


def _read_as_engine(
    table: Table, theta: np.ndarray, values: np.ndarray, sampling: str, mu: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The samples as the engine reads them, on angles the renderer reads linearly."""
    if sampling == "theta":
        return theta, values
    if sampling == "cosmoscout":  # held within half a column of the ends
        grid = np.concatenate([[0.0], theta, [180.0]])
        return grid, np.concatenate([values[:, :1], values, values[:, -1:]], axis=1)
    assert mu is not None
    fine = np.linspace(0.0, 180.0, _COS_GRID_SIZE)
    # Sample angles within 1e-6 deg of a grid angle add nothing but round-off.
    i = np.clip(np.searchsorted(fine, theta), 1, fine.size - 1)
    near = np.minimum(np.abs(fine[i] - theta), np.abs(fine[i - 1] - theta)) < 1e-6
    grid = np.union1d(fine, theta[~near])
    x = np.cos(np.deg2rad(grid))
    read = np.array([np.interp(x, mu[::-1], row[::-1]) for row in values])
    return grid, read


def _angle_error(table: Table, sampling: str, n: int) -> float:
    """Largest |integral over the sphere as read / the table's - 1| over the wavelengths.

    Exact for the reading: linear in angle (``sphere_integral``) or, for
    ``"cos"``, the trapezoid rule in cos(theta).
    """
    theta, values, _, mu = _engine_grid(table, sampling, n)
    own = np.atleast_1d(sphere_integral(table.phase, theta_deg=table.theta_deg))
    if mu is None:
        grid, read = _read_as_engine(table, theta, values, sampling, mu)
        got = np.atleast_1d(sphere_integral(read, theta_deg=grid))
    else:
        got = 2.0 * math.pi * np.sum(0.5 * (values[:, 1:] + values[:, :-1]) * -np.diff(mu), axis=1)
    return float(np.max(np.abs(got / own - 1.0)))


def smallest_angle_count(tables: Any, sampling: str, *, tolerance: float) -> int:
    """Smallest count of ``sampling`` whose integral error is within ``tolerance`` for every table.

    Parameters
    ----------
    tables : sequence of Table
        Phase functions (the scattering constituents').
    sampling : {"theta", "cos", "cosmoscout"}
    tolerance : float
        Largest ``|integral as read / table's integral - 1|``. [-]

    Returns
    -------
    int
        Found by doubling from 2, then bisection (the error falls as the count
        grows); the count returned is checked to pass.
    """
    if sampling not in ANGLE_SAMPLINGS:
        raise ValueError(f"sampling must be one of {', '.join(ANGLE_SAMPLINGS)}; got {sampling!r}")

    def ok(n: int) -> bool:
        return all(_angle_error(t, sampling, n) <= tolerance for t in tables)

    low, high = 1, 2
    while not ok(high):
        low, high = high, 2 * high
        if high > _MAX_ANGLES:
            raise ValueError(
                f"no {sampling} sampling of up to {_MAX_ANGLES} angles reaches tolerance "
                f"{tolerance:g}"
            )
    while high - low > 1:
        mid = (low + high) // 2
        low, high = (low, mid) if ok(mid) else (mid, high)
    return high


def check_approximations(approximations: Approximations, medium: Medium | Atmosphere) -> None:
    """Refuse, before any rendering, approximations the set cannot take.

    Parameters
    ----------
    approximations : Approximations
    medium : Medium or Atmosphere
        The set (its tables are all the checks read: an atmosphere can be
        checked before its medium is built).

    Raises
    ------
    ValueError
        Channels outside the medium's wavelengths; phase samples above
        float16's 65504 (the message says float32 does); or an angle count
        whose sphere integral is off by more than ``angle_tolerance`` for a
        scattering constituent (the message names the smallest count that does).
    """
    a = approximations
    wl = np.asarray(medium.wavelength_nm, dtype=float)
    set_tables = (
        medium.tables if isinstance(medium, Medium) else tuple(c.table for c in medium.constituents)
    )
    at = a.fit_at_nm
    if at is not None:
        low, high = (min(a.channels_nm), max(a.channels_nm)) if a.channels_nm else (wl[0], wl[-1])
        if not low <= at <= high:
            raise ValueError(
                f"phase {a.phase}: {at:g} nm is outside the wavelengths the fit would read, "
                f"{low:g}-{high:g} nm (the set's, or the channels'); a wavelength within them "
                "would do"
            )
    if a.channels_nm is not None:
        for name, v in zip("RGB", a.channels_nm, strict=True):
            if not wl[0] <= v <= wl[-1]:
                raise ValueError(
                    f"channels_nm: {name} = {v:g} nm is outside the set's wavelengths "
                    f"{wl[0]:g}-{wl[-1]:g} nm; channels within them would do (nothing is "
                    "extrapolated)"
                )
    tables = [t for t in set_tables if _scatters(t)]
    if a.angles is not None:
        sampling, n = _parse_angles(a.angles)
        worst = max(_angle_error(t, sampling, n) for t in tables)
        if worst > a.angle_tolerance:
            need = smallest_angle_count(tables, sampling, tolerance=a.angle_tolerance)
            raise ValueError(
                f"angles {a.angles} is too few for set {medium.name!r}: the phase function's "
                f"integral over the sphere, as the engine reads the samples, is off by "
                f"{worst:.3g} (angle_tolerance {a.angle_tolerance:g}); the smallest that does "
                f"is {sampling}:{need}"
            )
    if a.float16:
        peak = max(float(np.max(t.phase)) for t in tables)
        if peak > _FLOAT16_MAX:
            raise ValueError(
                f"float16: the phase function of set {medium.name!r} reaches {peak:.6g} sr^-1, "
                f"beyond float16's largest value {_FLOAT16_MAX:g}; float32 textures would do"
            )


def _channel_table(
    table: Table, channels: colour.ChannelWeights, wavelength_nm: np.ndarray
) -> Table:
    """The table at three channels: cross-sections read linearly, phase weighted by scattering."""
    assert table.cross_sections is not None
    w = channels.weights
    phase = (
        colour.channel_phase(channels, table.phase, csca_um2=table.quantity("csca_um2"))
        if _scatters(table)
        else colour.channel_phase(channels, table.phase)
    )
    theta = np.asarray(table.theta_deg, dtype=float)
    return Table(
        wavelength_nm=wavelength_nm,
        theta_deg=theta,
        phase=phase,
        g=np.clip(np.atleast_1d(mean_cosine(phase, theta_deg=theta)), -1.0, 1.0),
        name=table.name,
        cross_sections=CrossSections(
            cext_um2=w @ table.cross_sections.cext_um2,
            csca_um2=w @ table.cross_sections.csca_um2,
            number_density_per_m3=table.cross_sections.number_density_per_m3,
        ),
    )


def _fitted_phase(
    table: Table, model: str, at_nm: float | None = None
) -> tuple[np.ndarray, FitResult]:
    """The fitted analytic model at the table's angles, as an engine evaluates it. [sr^-1]

    One fit per row, or with ``at_nm`` one fit of the row read there (as
    :func:`~dustoptics.scattering.fit.fit_table` reads a channel) for every row.
    """
    if at_nm is None:
        fit = fit_table(table, model=model)
        rows = fit.parameters
    else:
        fit = fit_table(table, model=model, colour="wavelengths", channels_nm=(at_nm,) * 3)
        rows = np.repeat(fit.parameters[:1], table.wavelength_nm.size, axis=0)
    mu = np.cos(np.deg2rad(np.asarray(table.theta_deg, dtype=float)))[None, :]
    p = {n: rows[:, k : k + 1] for k, n in enumerate(fit.parameter_names)}
    if fit.model == "two-term-hg-hapke2012":  # (1 - c)/2 HG(b) + (1 + c)/2 HG(-b)
        values = dhg_costa2021(mu, g1=p["b"], g2=-p["b"], alpha=0.5 * (1.0 - p["c"]))
    else:
        values = ANALYTIC_MODELS[fit.model.replace("-", "_")].phase(mu, **p)
    return np.asarray(values, dtype=float), fit


def _with_tables(medium: Medium, tables: list[Table]) -> Medium:
    """The medium with other tables: cross-sections, moments and truncation derived again.

    The moments are projected and normalized exactly as
    :meth:`Medium.from_atmosphere` does (a table left as it was keeps its
    moments); the geometry (densities, slant columns) is kept.
    """
    n_mom = medium.chi.shape[2]
    chi = np.array(
        [
            medium.chi[c]
            if t is medium.tables[c]
            else legendre_moments(t, n_mom)
            if _scatters(t)
            else np.zeros((t.wavelength_nm.size, n_mom))
            for c, t in enumerate(tables)
        ]
    )
    scatters = np.array([_scatters(t) for t in tables])
    chi[scatters] /= chi[scatters, :, :1]
    f = np.clip(chi[:, :, 2 * medium.n_streams], 0.0, 1.0 - 1e-9)
    return replace(
        medium,
        wavelength_nm=np.array(tables[0].wavelength_nm, dtype=float),
        tables=tuple(tables),
        sigma_ext_m2=np.array([t.quantity("cext_um2") for t in tables]) * 1e-12,
        sigma_sca_m2=np.array([t.quantity("csca_um2") for t in tables]) * 1e-12,
        chi=chi,
        truncation=f,
    )


def _channel_weights(
    medium: Medium, channels_nm: tuple[float, ...]
) -> tuple[colour.ChannelWeights, np.ndarray, np.ndarray]:
    """Channels over the medium's wavelengths in increasing wavelength, those and their order."""
    order = np.argsort(channels_nm)
    wl = np.asarray(channels_nm, dtype=float)[order]
    return (
        colour.channel_weights(medium.wavelength_nm, mode="wavelengths", channels_nm=wl),
        wl,
        order,
    )


def approximate_medium(
    medium: Medium, approximations: Approximations
) -> tuple[Medium, FitResult | None]:
    """The medium an engine renders: channels, fitted phase, engine angles, float16.

    Applied in that order.  Checked first (:func:`check_approximations`).

    Parameters
    ----------
    medium : Medium
        The exact medium.
    approximations : Approximations

    Returns
    -------
    Medium
        With the same geometry; at the channels' wavelengths (in increasing
        wavelength) when ``channels_nm`` is given.
    FitResult or None
        The aerosols' fit, when ``phase`` is a fit.
    """
    a = approximations
    check_approximations(a, medium)
    tables = list(medium.tables)
    if a.channels_nm is not None:
        channels, wl, _ = _channel_weights(medium, a.channels_nm)
        tables = [_channel_table(t, channels, wl) for t in tables]
    fit = None
    model = a.fit_model
    for i, role in enumerate(medium.roles):
        t = tables[i]
        fitted = model is not None and role == "aerosols"
        if not _scatters(t) or not (fitted or a.angles is not None or a.float16):
            continue  # its phase function stays as it is
        phase, theta = np.asarray(t.phase, dtype=float), np.asarray(t.theta_deg, dtype=float)
        if fitted:
            assert model is not None
            phase, fit = _fitted_phase(t, model, a.fit_at_nm)
        if a.angles is not None:
            if fitted:  # the engine's samples are the fitted function's
                t = _replace_phase(t, theta, phase)
            sampling, n = _parse_angles(a.angles)
            s_theta, values, _, mu = _engine_grid(t, sampling, n)
            if a.float16:
                values = values.astype(np.float16).astype(float)
            theta, phase = _read_as_engine(t, s_theta, values, sampling, mu)
        elif a.float16:
            phase = phase.astype(np.float16).astype(float)
        tables[i] = _replace_phase(t, theta, phase)
    if all(t is u for t, u in zip(tables, medium.tables, strict=True)):
        return medium, fit
    return _with_tables(medium, tables), fit


def _replace_phase(table: Table, theta: np.ndarray, phase: np.ndarray) -> Table:
    return Table(
        wavelength_nm=table.wavelength_nm,
        theta_deg=theta,
        phase=phase,
        g=np.clip(np.atleast_1d(mean_cosine(phase, theta_deg=theta)), -1.0, 1.0),
        name=table.name,
        cross_sections=None
        if table.cross_sections is None
        else CrossSections(
            cext_um2=table.cross_sections.cext_um2,
            csca_um2=table.cross_sections.csca_um2,
            number_density_per_m3=table.cross_sections.number_density_per_m3,
        ),
    )


# ------------------------------------------------------------- the comparison

#: The statistics of each region, in :class:`PreviewSummary` and the netCDF attributes.
_STATS: Final = (
    "delta_xy_mean",
    "delta_xy_max",
    "luminance_ratio_mean",
    "luminance_ratio_min",
    "luminance_ratio_max",
)


@dataclass(frozen=True)
class PreviewSummary:
    """The approximated sky against the exact one, in numbers.

    Attributes
    ----------
    approximations : str
        :meth:`Approximations.describe`.
    near_sun_deg : float
        Radius of the region near the Sun. [degree]
    dome_delta_xy_mean, dome_delta_xy_max : float
        Solid-angle mean and largest CIE 1931 xy distance over the dome. [-]
    dome_luminance_ratio_mean : float
        Ratio of the luminances integrated over the dome's solid angle. [-]
    dome_luminance_ratio_min, dome_luminance_ratio_max : float
        Smallest and largest ratio over the dome's directions. [-]
    sun_delta_xy_mean, sun_delta_xy_max, sun_luminance_ratio_mean, sun_luminance_ratio_min, sun_luminance_ratio_max : float
        The same within ``near_sun_deg`` of the Sun (NaN where no computed
        direction is that near, e.g. a Sun far below the horizon). [-]
    """

    approximations: str
    near_sun_deg: float
    dome_delta_xy_mean: float
    dome_delta_xy_max: float
    dome_luminance_ratio_mean: float
    dome_luminance_ratio_min: float
    dome_luminance_ratio_max: float
    sun_delta_xy_mean: float
    sun_delta_xy_max: float
    sun_luminance_ratio_mean: float
    sun_luminance_ratio_min: float
    sun_luminance_ratio_max: float

    def attributes(self) -> dict[str, Any]:
        """The netCDF attributes that carry it (``preview_*``)."""
        out: dict[str, Any] = {
            "preview_approximations": self.approximations,
            "preview_near_sun_radius_degree": self.near_sun_deg,
        }
        for region in ("dome", "sun"):
            for stat in _STATS:
                out[f"preview_{region}_{stat}"] = getattr(self, f"{region}_{stat}")
        return out

    @classmethod
    def from_attributes(cls, attrs: Any) -> PreviewSummary:
        """Read back from :meth:`attributes` (e.g. a netCDF file's ``attrs``)."""
        values = {
            f"{region}_{stat}": float(attrs[f"preview_{region}_{stat}"])
            for region in ("dome", "sun")
            for stat in _STATS
        }
        return cls(
            approximations=str(attrs["preview_approximations"]),
            near_sun_deg=float(attrs["preview_near_sun_radius_degree"]),
            **values,
        )

    def table(self) -> str:
        """A short text table for the terminal."""

        def f(v: float, fmt: str) -> str:
            return "n/a" if not math.isfinite(v) else format(v, fmt)

        head = f"{'':24s}{'dome':>22s}{f'within {self.near_sun_deg:g} deg of Sun':>26s}"
        rows = [f"approximations: {self.approximations}", head]
        for label, stat_a, stat_b, fmt in (
            ("CIE xy distance", "delta_xy_mean", "delta_xy_max", ".4f"),
            ("luminance ratio", "luminance_ratio_min", "luminance_ratio_max", ".4f"),
        ):
            cells = []
            for region in ("dome", "sun"):
                a, b = getattr(self, f"{region}_{stat_a}"), getattr(self, f"{region}_{stat_b}")
                cells.append(f"{f(a, fmt)} .. {f(b, fmt)}")
            what = "  mean .. max" if stat_a.endswith("mean") else "  min .. max"
            rows.append(f"{label + what:24s}{cells[0]:>22s}{cells[1]:>26s}")
        means = [f(getattr(self, f"{r}_luminance_ratio_mean"), ".4f") for r in ("dome", "sun")]
        rows.append(f"{'luminance ratio  mean':24s}{means[0]:>22s}{means[1]:>26s}")
        return "\n".join(rows)


@dataclass(frozen=True, eq=False)
class SkyPreview:
    """The exact sky, the approximated one, and their differences per direction.

    Attributes
    ----------
    approximations : Approximations
    exact : SkyRadiance
        The exact sky.
    approximated : SkyRadiance
        The approximated sky (at the channels' wavelengths, increasing, with
        ``channels_nm``).
    xyz_exact, xyz_approximated : numpy.ndarray, shape (n_zenith, n_azimuth, 3)
        CIE 1931 XYZ per unit solar illuminance (Y the luminance factor). [sr^-1]
    delta_xy : numpy.ndarray, shape (n_zenith, n_azimuth)
        CIE 1931 xy distance. [-]
    luminance_ratio : numpy.ndarray, shape (n_zenith, n_azimuth)
        Approximated over exact Y. [-]
    scattering_angle_deg : numpy.ndarray, shape (n_zenith, n_azimuth)
        Angle of each direction from the Sun. [degree]
    summary : PreviewSummary
    fit : FitResult or None
        The aerosols' fit, for ``phase="fit:..."``.
    """

    approximations: Approximations
    exact: SkyRadiance
    approximated: SkyRadiance
    xyz_exact: np.ndarray
    xyz_approximated: np.ndarray
    delta_xy: np.ndarray
    luminance_ratio: np.ndarray
    scattering_angle_deg: np.ndarray
    summary: PreviewSummary
    fit: FitResult | None

    def to_xarray(self) -> Any:
        """The exact sky's dataset (:meth:`SkyRadiance.to_xarray`) with the preview added.

        Variables ``approximated_radiance`` (on ``approximated_wavelength``),
        ``approximated_luminance_factor``, ``approximated_chromaticity_x``,
        ``approximated_chromaticity_y``, ``chromaticity_difference`` and
        ``luminance_ratio``; attributes ``preview_*`` (:class:`PreviewSummary`)
        and the approximations' settings.
        """
        ds = self.exact.to_xarray()
        dims = ("view_zenith_angle", "view_azimuth_angle")
        xyz = self.xyz_approximated
        total = xyz.sum(-1)
        what = self.summary.approximations
        ds = ds.assign_coords(
            approximated_wavelength=(
                "approximated_wavelength",
                self.approximated.wavelength_nm,
                {"units": "nm"},
            )
        )
        ds["approximated_radiance"] = (
            dims + ("approximated_wavelength",),
            self.approximated.radiance,
            {"units": "sr-1", "long_name": f"sky radiance with approximations: {what}"},
        )
        ds["approximated_luminance_factor"] = (
            dims,
            xyz[..., 1],
            {"units": "sr-1", "long_name": "CIE Y of the approximated sky per solar Y"},
        )
        ds["approximated_chromaticity_x"] = (dims, xyz[..., 0] / total, {"units": "1"})
        ds["approximated_chromaticity_y"] = (dims, xyz[..., 1] / total, {"units": "1"})
        ds["chromaticity_difference"] = (
            dims,
            self.delta_xy,
            {"units": "1", "long_name": "CIE 1931 xy distance, approximated to exact sky"},
        )
        ds["luminance_ratio"] = (
            dims,
            self.luminance_ratio,
            {"units": "1", "long_name": "luminance of the approximated sky over the exact"},
        )
        a = self.approximations
        ds.attrs.update(self.summary.attributes())
        ds.attrs.update(
            {
                "preview_phase": a.phase,
                "preview_channels_nm": "none"
                if a.channels_nm is None
                else ", ".join(f"{v:g}" for v in a.channels_nm),
                "preview_angles": a.angles or "none",
                "preview_float16": int(a.float16),
                "preview_angle_tolerance": a.angle_tolerance,
                "preview_colour_of_channels": "linear sRGB RGB_sun * L_c (white sun, ASTM G173), "
                "to CIE XYZ"
                if a.channels_nm is not None
                else "spectral (CIE 1931 2-degree observer, ASTM G173 sunlight)",
            }
        )
        if self.fit is not None:
            ds.attrs["preview_fit_model"] = self.fit.model
            ds.attrs["preview_fit_rms_relative_error_max"] = float(
                np.max(self.fit.rms_relative_error)
            )
        return ds

    def figure(self, *, size: int = 384, exposure: float | None = None) -> Any:
        """Side by side: exact | approximated | CIE xy distance | luminance ratio (fisheyes).

        Both skies at one exposure (default the exact sky's
        :meth:`~SkyRadiance.default_exposure`); the Sun's azimuth up.
        Needs matplotlib (the ``plot`` extra).
        """
        try:
            import matplotlib.colors
            import matplotlib.figure
        except ImportError as exc:  # pragma: no cover - depends on the extra
            raise ImportError(
                "the preview image needs matplotlib: pip install 'dustoptics[plot]'"
            ) from exc
        e = self.exact.default_exposure() if exposure is None else float(exposure)
        sky = self.exact
        xyz_e = _fisheye(sky, self.xyz_exact, size)
        xyz_a = _fisheye(sky, self.xyz_approximated, size)
        inside = np.isfinite(xyz_e[..., 0])
        rgb_e = display_rgb(np.where(inside[..., None], xyz_e, 0.0), e)
        rgb_a = display_rgb(np.where(inside[..., None], xyz_a, 0.0), e)
        rgb_e[~inside] = 0
        rgb_a[~inside] = 0
        dxy = _fisheye(sky, self.delta_xy[..., None], size)[..., 0]
        ratio = _fisheye(sky, self.luminance_ratio[..., None], size)[..., 0]
        fig = matplotlib.figure.Figure(figsize=(16, 4.6), layout="constrained")
        axes = fig.subplots(1, 4)
        s = self.summary
        axes[0].imshow(rgb_e)
        axes[0].set_title("exact (spectral)")
        axes[1].imshow(rgb_a)
        axes[1].set_title(f"approximated:\n{s.approximations}", fontsize=9)
        top = max(float(np.nanmax(dxy)), 1e-6)
        im = axes[2].imshow(dxy, cmap="magma", vmin=0.0, vmax=top)
        axes[2].set_title(f"CIE xy distance\ndome max {s.dome_delta_xy_max:.4f}")
        fig.colorbar(im, ax=axes[2], shrink=0.8)
        span = max(float(np.nanmax(np.abs(np.log2(ratio)))), 1e-4)
        im = axes[3].imshow(
            ratio, cmap="RdBu_r", norm=matplotlib.colors.LogNorm(2.0**-span, 2.0**span)
        )
        axes[3].set_title(
            f"luminance ratio approx./exact\ndome {s.dome_luminance_ratio_min:.3f} .. "
            f"{s.dome_luminance_ratio_max:.3f}"
        )
        fig.colorbar(im, ax=axes[3], shrink=0.8)
        for ax in axes:
            ax.set_xticks([])
            ax.set_yticks([])
        fig.suptitle(
            f"{sky.name}: Sun {sky.sun_elevation_deg:g} deg high (up in each fisheye); "
            f"near the Sun = within {s.near_sun_deg:g} deg"
        )
        return fig

    def png(self, *, size: int = 384, exposure: float | None = None) -> bytes:
        """:meth:`figure` as PNG file contents (no time stamp: the same bytes each time)."""
        fig = self.figure(size=size, exposure=exposure)
        buf = _io.BytesIO()
        fig.savefig(buf, format="png", dpi=80, metadata={"Software": None})
        return buf.getvalue()


def _fisheye(sky: SkyRadiance, values: np.ndarray, size: int) -> np.ndarray:
    """Values on the sky's grid as an equidistant fisheye (NaN outside the horizon)."""
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    xx, yy = np.meshgrid(c, -c)
    rad = np.hypot(xx, yy)
    inside = rad <= 1.0
    zen = np.clip(rad * 90.0, sky.view_zenith_deg[0], sky.view_zenith_deg[-1])
    azi = np.rad2deg(np.arctan2(xx, yy))
    out = sky._interpolate(values, zen, azi)
    out[~inside] = np.nan
    return out


def _channel_xyz(exact: SkyRadiance, approximated: SkyRadiance, order: np.ndarray) -> np.ndarray:
    """XYZ per unit solar illuminance of three channel radiances lit by a white sun.

    ``XYZ = M^-1 (RGB_sun * L_c)`` with ``RGB_sun`` the sunlight's linear sRGB
    per unit solar Y on the exact sky's wavelengths, so that a sky grey in
    wavelength has the exact sky's colour.
    """
    wl = exact.wavelength_nm
    sun_rgb = colour.xyz_to_linear_srgb(sunlit_xyz(wl, np.ones(wl.size)))
    rgb = np.empty_like(approximated.radiance)
    rgb[..., order] = approximated.radiance  # back to R, G, B
    return colour.linear_srgb_to_xyz(rgb * sun_rgb)


def _differences(
    sky: SkyRadiance, xyz_e: np.ndarray, xyz_a: np.ndarray, near_sun_deg: float, what: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, PreviewSummary]:
    xy_e = xyz_e[..., :2] / xyz_e.sum(-1, keepdims=True)
    xy_a = xyz_a[..., :2] / xyz_a.sum(-1, keepdims=True)
    dxy = np.hypot(*(xy_a - xy_e).transpose(2, 0, 1))
    ratio = xyz_a[..., 1] / xyz_e[..., 1]
    z = np.deg2rad(sky.view_zenith_deg)[:, None]
    a = np.deg2rad(sky.view_azimuth_deg)[None, :]
    z0 = math.radians(sky.sun_zenith_deg)
    cos_g = np.cos(z) * math.cos(z0) + np.sin(z) * math.sin(z0) * np.cos(a)
    gamma = np.degrees(np.arccos(np.clip(cos_g, -1.0, 1.0)))
    # Solid angle of each grid direction: trapezoid weights in zenith (sin z) and azimuth.
    wz = _trapezoid_weights(z[:, 0]) * np.sin(z[:, 0])
    wa = _trapezoid_weights(a[0])
    omega = wz[:, None] * wa[None, :]

    def stats(mask: np.ndarray) -> list[float]:
        if not np.any(mask) or not np.any(omega[mask] > 0):
            return [math.nan] * 5
        w = omega[mask]
        return [
            float(np.sum(w * dxy[mask]) / np.sum(w)),
            float(np.max(dxy[mask])),
            float(np.sum(w * xyz_a[..., 1][mask]) / np.sum(w * xyz_e[..., 1][mask])),
            float(np.min(ratio[mask])),
            float(np.max(ratio[mask])),
        ]

    dome = stats(np.ones_like(dxy, dtype=bool))
    sun = stats(gamma <= near_sun_deg)
    keys = _STATS
    summary = PreviewSummary(
        approximations=what,
        near_sun_deg=near_sun_deg,
        **{f"dome_{k}": v for k, v in zip(keys, dome, strict=True)},
        **{f"sun_{k}": v for k, v in zip(keys, sun, strict=True)},
    )
    return dxy, ratio, gamma, summary


def _trapezoid_weights(x: np.ndarray) -> np.ndarray:
    w = np.zeros_like(x)
    d = np.diff(x)
    w[:-1] += 0.5 * d
    w[1:] += 0.5 * d
    return w


def preview_sky(
    medium: Medium,
    approximations: Approximations,
    *,
    sun_elevation_deg: float,
    ground_albedo: float = 0.2,
    exact: SkyRadiance | None = None,
    **sky_options: Any,
) -> SkyPreview:
    """Render the sky with an engine's approximations and compare it with the exact sky.

    Parameters
    ----------
    medium : Medium
        The exact medium (:meth:`Medium.from_atmosphere`).
    approximations : Approximations
        What the engine does instead (checked before any rendering,
        :func:`check_approximations`).
    sun_elevation_deg : float
        Sun elevation of both skies. [degree]
    ground_albedo : float
        Lambertian ground albedo (read at the channels with ``channels_nm``). [-]
    exact : SkyRadiance, optional
        The exact sky of this medium, Sun and ground when already rendered
        (rendered here otherwise); the approximated sky takes its directions,
        observer altitude and tolerance.
    **sky_options
        Passed to :func:`~dustoptics.sky.scene.sky_radiance` for both skies
        (``observer_altitude_m``, ``tol``, ``view_zenith_deg``,
        ``azimuth_step_deg``, ``progress``, ``allow_large``) when ``exact`` is
        not given; with ``exact`` only ``progress`` and ``allow_large``.

    Returns
    -------
    SkyPreview

    Raises
    ------
    ValueError
        Approximations the medium cannot take (:func:`check_approximations`),
        before any rendering; sky options beside ``exact``; an ``exact`` sky
        of another Sun.
    TypeError
        ``approximations`` is not an :class:`Approximations`.
    """
    a = approximations
    if not isinstance(a, Approximations):
        raise TypeError(f"approximations must be Approximations; got {type(a).__name__}")
    approx_medium, fit = approximate_medium(medium, a)  # checked before any rendering
    with shared_geometry():  # the second render takes the first's geometry
        return _preview(
            medium, approx_medium, fit, a, sun_elevation_deg, ground_albedo, exact, sky_options
        )


def _preview(
    medium: Medium,
    approx_medium: Medium,
    fit: FitResult | None,
    a: Approximations,
    sun_elevation_deg: float,
    ground_albedo: float,
    exact: SkyRadiance | None,
    sky_options: dict[str, Any],
) -> SkyPreview:
    if exact is None:
        exact = sky_radiance(
            medium, sun_elevation_deg=sun_elevation_deg, ground_albedo=ground_albedo, **sky_options
        )
        sky_options = {k: v for k, v in sky_options.items() if k in ("progress", "allow_large")}
    else:
        extra = set(sky_options) - {"progress", "allow_large"}
        if extra:
            raise ValueError(
                f"with exact given, the directions and tolerance are the exact sky's; "
                f"{', '.join(sorted(extra))} cannot be given"
            )
        if abs(exact.sun_zenith_deg - (90.0 - sun_elevation_deg)) > 1e-9:
            raise ValueError(
                f"exact was rendered for a Sun {exact.sun_elevation_deg:g} deg high; "
                f"sun_elevation_deg is {sun_elevation_deg!r}"
            )
    albedo = np.broadcast_to(np.asarray(ground_albedo, dtype=float), medium.wavelength_nm.shape)
    order = None
    if a.channels_nm is not None:
        channels, _, order = _channel_weights(medium, a.channels_nm)
        albedo = channels.weights @ albedo
    n_az = exact.view_azimuth_deg.size
    if approx_medium is medium:  # nothing the sky reads differs: the exact sky, not rendered again
        approximated = exact
    else:
        approximated = sky_radiance(
            approx_medium,
            sun_elevation_deg=sun_elevation_deg,
            ground_albedo=albedo,
            observer_altitude_m=exact.observer_altitude_m,
            tol=exact.tol,
            view_zenith_deg=exact.view_zenith_deg,
            azimuth_step_deg=180.0 / (n_az - 1),
            **sky_options,
        )
    xyz_e = exact.xyz()
    if order is None:
        xyz_a = sunlit_xyz(approximated.wavelength_nm, approximated.radiance)
    else:
        xyz_a = _channel_xyz(exact, approximated, order)
    dxy, ratio, gamma, summary = _differences(exact, xyz_e, xyz_a, a.near_sun_deg, a.describe())
    return SkyPreview(
        approximations=a,
        exact=exact,
        approximated=approximated,
        xyz_exact=xyz_e,
        xyz_approximated=xyz_a,
        delta_xy=dxy,
        luminance_ratio=ratio,
        scattering_angle_deg=gamma,
        summary=summary,
        fit=fit,
    )
