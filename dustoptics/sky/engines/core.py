"""The engines' registry, the exact sky they are fitted to, the error metrics and the fit.

See the package docstring (:mod:`dustoptics.sky.engines`) for the interface.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Final

import numpy as np

from dustoptics import colour
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io.registry import Format, register
from dustoptics.sky.engines import _hillaire
from dustoptics.sky.medium import Medium
from dustoptics.sky.scene import sky_radiance, sunlit_xyz

__all__ = [
    "CHANNELS_NM",
    "DOME_AZIMUTH_DEG",
    "DOME_ZENITH_DEG",
    "ENGINES",
    "FIT_SUN_ELEVATIONS_DEG",
    "NEAR_SUN_DEG",
    "RGB",
    "SUN_EXCLUSION_DEG",
    "EngineFit",
    "EngineModel",
    "Parameter",
    "ReferenceSky",
    "SkyError",
    "channel_values",
    "dust_tint_linear_srgb",
    "engine_xyz",
    "error_header",
    "error_notes",
    "fit_engine",
    "fit_json",
    "hillaire_renderer",
    "hillaire_sky_rgb",
    "per_channel",
    "reference_skies",
    "register_engine",
    "rgb_of",
    "scale_height_m",
    "sky_error",
    "smoothstep",
    "sunlight_linear_srgb",
    "write_engine_files",
    "write_texts",
    "y_up_directions",
]

#: Sun elevations of the fit and of the error table: high Sun, afternoon, low Sun, sunset. [deg]
FIT_SUN_ELEVATIONS_DEG: Final = (45.0, 20.0, 5.0, 0.0)

#: The coarse dome's viewing zenith angles (the zenith, then every 10 deg, and 85 and 89 deg
#: near the horizon); each Sun elevation adds the zenith angle 10 deg above the Sun. [deg]
DOME_ZENITH_DEG: Final = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0, 89.0)

#: The coarse dome's azimuths from the Sun's, every 15 deg (the sky is mirror-symmetric). [deg]
DOME_AZIMUTH_DEG: Final = tuple(float(a) for a in range(0, 181, 15))

#: Angle from the Sun's centre of the "near the Sun" chromaticity. [deg]
NEAR_SUN_DEG: Final = 10.0

#: Directions closer than this to the Sun's centre are left out of every metric (the
#: engines draw a Sun disc there, the exact sky excludes the direct Sun). [deg]
SUN_EXCLUSION_DEG: Final = 2.0


@dataclass(frozen=True)
class Parameter:
    """One fitted parameter of an engine's sky model.

    Attributes
    ----------
    name : str
        The engine's name for it (a vector's components as ``NAME_r``, ``NAME_g``, ``NAME_b``).
    lower, upper : float
        Bounds the engine's editor allows (or physics does).
    log : bool
        Fitted in log space (a positive scale).
    unit : str
        Its unit, as the engine states it.
    """

    name: str
    lower: float
    upper: float
    log: bool = False
    unit: str = "-"


#: ``render(params, *, sun_elevation_deg, view_zenith_deg, view_azimuth_deg) -> rgb``:
#: linear sRGB radiance per unit solar illuminance, shape ``view_zenith_deg.shape + (3,)``.
Renderer = Callable[..., np.ndarray]


@dataclass(frozen=True)
class EngineModel:
    """An engine's own sky model and its format: one record per engine.

    Attributes
    ----------
    name : str
        The format name (``--format NAME``) and the engine's key.
    title : str
        The engine and the model, for tables.
    source : str
        The engine version and the source file (or documentation) the model was
        implemented from.
    parameters : tuple of Parameter
        What the fit adjusts.
    community_parameters : tuple of str
        What the fit adjusts in the community row (usually the exposure only:
        anyone sets it).
    render : callable
        The engine's sky (:data:`Renderer`); ``params`` holds every value
        :attr:`initial` gives.
    initial : callable
        ``initial(atmosphere) -> dict``: every value the renderer takes,
        fixed ones (planet radius) and the fit's starting point.
    community : callable
        ``community(atmosphere) -> dict``: what people use today for that planet
        (the engine's Earth defaults, with a dust tint for Mars), same keys.
    write : callable
        ``write(fit, out_dir, *, overwrite) -> list[Path]``: the engine's files
        for a fit (:class:`EngineFit`).
    """

    name: str
    title: str
    source: str
    parameters: tuple[Parameter, ...]
    community_parameters: tuple[str, ...]
    render: Renderer
    initial: Callable[[Atmosphere], dict[str, float]]
    community: Callable[[Atmosphere], dict[str, float]]
    write: Callable[..., list[Path]]

    def __post_init__(self) -> None:
        names = [p.name for p in self.parameters]
        unknown = sorted(set(self.community_parameters) - set(names))
        if unknown:
            raise ValueError(f"engine {self.name!r}: community_parameters {unknown} not fitted")


#: Engine name -> record, filled by each engine module when it is imported.
ENGINES: dict[str, EngineModel] = {}


def register_engine(engine: EngineModel, *, suffixes: tuple[str, ...] = ()) -> EngineModel:
    """Add ``engine`` to :data:`ENGINES` (names are unique) and its format to the format
    registry (:func:`dustoptics.io.registry.register`), and return it.

    The format writes a planet set (``dustoptics build mars|earth --format NAME``):
    its writer fits the engine to the set's exact sky (:func:`write_engine_files`)
    and refuses a single table, which has no atmosphere to fit to.
    """
    if engine.name in ENGINES and ENGINES[engine.name] is not engine:
        raise ValueError(f"engine {engine.name!r} is already registered")
    ENGINES[engine.name] = engine

    def write(target: Any, out_dir: Any, *, overwrite: bool = False, **_: Any) -> list[Path]:
        if not isinstance(target, Atmosphere):
            raise ValueError(
                f"format {engine.name!r} is fitted to a planet's sky: build it from a set "
                f"('dustoptics build mars|earth --format {engine.name}'), not from one table"
            )
        return write_engine_files(engine.name, target, out_dir, overwrite=overwrite)

    register(
        Format(
            name=engine.name,
            summary=f"{engine.title} parameters fitted to a set's sky (build mars|earth only)",
            write=write,
            suffixes=suffixes,
        )
    )
    return engine


def sunlight_linear_srgb() -> np.ndarray:
    """The sunlight's colour (ASTM G173 extraterrestrial spectrum) in linear sRGB, Y = 1.

    An engine lit by a Sun of this light colour and unit illuminance draws the
    sky in the units of :class:`ReferenceSky` (per unit solar illuminance).
    """
    return colour.xyz_to_linear_srgb(_white_xyz())


#: The engines' three channels, R, G, B: the wavelengths at which a set's coefficients start
#: a fit (Bruneton's kLambdaR/G/B, :data:`dustoptics.sky.approximations.ENGINE_CHANNELS_NM`). [nm]
CHANNELS_NM: Final = (680.0, 550.0, 440.0)


def channel_values(atmosphere: Atmosphere, role: str, quantity: str) -> np.ndarray:
    """A constituent's per-wavelength quantity (``"beta_sca_per_m"``, ``"beta_abs_per_m"``,
    ``"g"``) read linearly at :data:`CHANNELS_NM`; zeros if the set has no such role."""
    found = [c for c in atmosphere.constituents if c.role == role]
    if not found:
        return np.zeros(3)
    table = found[0].table
    values = np.asarray(getattr(table, quantity), dtype=float)
    return np.interp(CHANNELS_NM, np.asarray(table.wavelength_nm, dtype=float), values)


def scale_height_m(atmosphere: Atmosphere, role: str, default_m: float) -> float:
    """A constituent's scale height if its profile is exponential, else ``default_m``. [m]"""
    found = [c for c in atmosphere.constituents if c.role == role]
    height = getattr(found[0].profile, "scale_height_m", None) if found else None
    return float(height) if height is not None else default_m


def dust_tint_linear_srgb(atmosphere: Atmosphere) -> np.ndarray:
    """The colour of the light the aerosols scatter: CIE XYZ of ``beta_sca(lambda)`` under
    sunlight, in linear sRGB scaled to a largest channel of 1 and clipped to [0, 1].

    The tint of the community rows (what a user picks for "dust" when the engine
    has a colour but no spectrum).
    """
    table = atmosphere.constituent("aerosols").table
    xyz = sunlit_xyz(np.asarray(table.wavelength_nm, dtype=float), table.beta_sca_per_m)
    rgb = colour.xyz_to_linear_srgb(xyz)
    return np.asarray(np.clip(rgb / np.max(rgb), 0.0, 1.0))


def _white_xyz() -> np.ndarray:
    wl = np.arange(360.0, 831.0, 10.0)
    xyz = sunlit_xyz(wl, np.ones(wl.size))
    return np.asarray(xyz / xyz[1], dtype=float)


def _angle_from_sun(sun_elevation_deg: float, zen: np.ndarray, azi: np.ndarray) -> np.ndarray:
    s = math.radians(90.0 - sun_elevation_deg)
    z, a = np.radians(zen), np.radians(azi)
    cos_psi = np.cos(z) * math.cos(s) + np.sin(z) * math.sin(s) * np.cos(a)
    return np.degrees(np.arccos(np.clip(cos_psi, -1.0, 1.0)))


def _trapezoid(x: np.ndarray) -> np.ndarray:
    w = np.zeros(x.size)
    d = np.diff(x)
    w[:-1] += d / 2
    w[1:] += d / 2
    return w


@dataclass(frozen=True, eq=False)
class ReferenceSky:
    """The exact spectral sky on the coarse dome for one Sun elevation, as CIE XYZ.

    Attributes
    ----------
    name : str
        The atmosphere's name.
    sun_elevation_deg : float
        [deg]
    view_zenith_deg : numpy.ndarray, shape (n_zenith, n_azimuth)
        [deg]
    view_azimuth_deg : numpy.ndarray, shape (n_zenith, n_azimuth)
        From the Sun's. [deg]
    xyz : numpy.ndarray, shape (n_zenith, n_azimuth, 3)
        CIE 1931 XYZ under sunlight per unit solar illuminance
        (:func:`~dustoptics.sky.scene.sunlit_xyz`). [sr^-1]
    weight : numpy.ndarray, shape (n_zenith, n_azimuth)
        Solid-angle weights (trapezoid in cos(zenith) and azimuth), 0 within
        :data:`SUN_EXCLUSION_DEG` of the Sun; sum 1.
    white_xyz : numpy.ndarray, shape (3,)
        Reference white of L*a*b*: the sunlight's chromaticity at the
        luminance of the brightest sky farther than :data:`NEAR_SUN_DEG` from
        the Sun (as an exposure puts it at display white). [sr^-1]
    zenith_index, near_sun_index : tuple of int
        Grid indices of the zenith and of the direction :data:`NEAR_SUN_DEG`
        above the Sun.
    """

    name: str
    sun_elevation_deg: float
    view_zenith_deg: np.ndarray
    view_azimuth_deg: np.ndarray
    xyz: np.ndarray
    weight: np.ndarray
    white_xyz: np.ndarray
    zenith_index: tuple[int, int]
    near_sun_index: tuple[int, int]


def dome_zenith_deg(sun_elevation_deg: float) -> np.ndarray:
    """The coarse dome's zenith angles for a Sun elevation (:data:`DOME_ZENITH_DEG` plus the
    angle :data:`NEAR_SUN_DEG` above the Sun). [deg]"""
    near = 90.0 - sun_elevation_deg - NEAR_SUN_DEG
    return np.unique(np.array([*DOME_ZENITH_DEG, near]))


def reference_skies(
    atmosphere: Atmosphere | Medium,
    *,
    sun_elevations_deg: Sequence[float] = FIT_SUN_ELEVATIONS_DEG,
    tol: float = 1e-3,
    ground_albedo: float = 0.2,
) -> tuple[ReferenceSky, ...]:
    """The exact sky (:func:`~dustoptics.sky.scene.sky_radiance`) on the coarse dome.

    Parameters
    ----------
    atmosphere : Atmosphere or Medium
    sun_elevations_deg : sequence of float
        Sun elevations, each in [0, 80] (the direction 10 deg above the Sun
        must be on the dome). [deg]
    tol : float
        Tolerance of the series of orders of scattering. [-]
    ground_albedo : float
        Lambertian ground albedo. [-]

    Returns
    -------
    tuple of ReferenceSky
    """
    elevations = [float(e) for e in sun_elevations_deg]
    bad = [e for e in elevations if not 0.0 <= e <= 80.0]
    if not elevations or bad:
        raise ValueError(f"sun_elevations_deg must be within [0, 80] deg; got {elevations!r}")
    medium = atmosphere if isinstance(atmosphere, Medium) else Medium.from_atmosphere(atmosphere)
    azi = np.array(DOME_AZIMUTH_DEG)
    white = _white_xyz()
    out = []
    for elev in elevations:
        zen = dome_zenith_deg(elev)
        sky = sky_radiance(
            medium,
            sun_elevation_deg=elev,
            ground_albedo=ground_albedo,
            tol=tol,
            view_zenith_deg=zen,
            azimuth_step_deg=float(azi[1] - azi[0]),
        )
        zz, aa = np.meshgrid(sky.view_zenith_deg, sky.view_azimuth_deg, indexing="ij")
        xyz = sky.xyz()
        psi = _angle_from_sun(elev, zz, aa)
        w = np.outer(_trapezoid(-np.cos(np.radians(zen))), _trapezoid(np.radians(azi)))
        w = np.where(psi < SUN_EXCLUSION_DEG, 0.0, w)
        far = xyz[..., 1][psi > NEAR_SUN_DEG]
        near = (int(np.flatnonzero(zen == 90.0 - elev - NEAR_SUN_DEG)[0]), 0)
        out.append(
            ReferenceSky(
                name=medium.name,
                sun_elevation_deg=elev,
                view_zenith_deg=zz,
                view_azimuth_deg=aa,
                xyz=xyz,
                weight=w / w.sum(),
                white_xyz=white * float(np.max(far)),
                zenith_index=(0, 0),
                near_sun_index=near,
            )
        )
    return tuple(out)


def engine_xyz(engine: EngineModel, params: Mapping[str, float], sky: ReferenceSky) -> np.ndarray:
    """CIE XYZ of the engine's sky (its linear sRGB) on a reference sky's directions. [sr^-1]"""
    rgb = engine.render(
        params,
        sun_elevation_deg=sky.sun_elevation_deg,
        view_zenith_deg=sky.view_zenith_deg,
        view_azimuth_deg=sky.view_azimuth_deg,
    )
    return colour.linear_srgb_to_xyz(rgb)


@dataclass(frozen=True)
class SkyError:
    """How far an engine's sky is from the exact one at one Sun elevation.

    Attributes
    ----------
    sun_elevation_deg : float
        [deg]
    delta_e_mean, delta_e_p95 : float
        CIE Delta E 2000 over the dome (solid-angle weighted mean and 95th
        percentile), L*a*b* relative to :attr:`ReferenceSky.white_xyz`. [-]
    xy_zenith_exact, xy_zenith_engine : tuple of float
        CIE 1931 (x, y) at the zenith.
    xy_near_sun_exact, xy_near_sun_engine : tuple of float
        CIE 1931 (x, y) :data:`NEAR_SUN_DEG` above the Sun.
    luminance_ratio : float
        Engine over exact luminance integrated over the dome. [-]
    """

    sun_elevation_deg: float
    delta_e_mean: float
    delta_e_p95: float
    xy_zenith_exact: tuple[float, float]
    xy_zenith_engine: tuple[float, float]
    xy_near_sun_exact: tuple[float, float]
    xy_near_sun_engine: tuple[float, float]
    luminance_ratio: float


def _xy(xyz: np.ndarray) -> tuple[float, float]:
    s = float(np.sum(xyz))
    return (float(xyz[0] / s), float(xyz[1] / s)) if s > 0 else (math.nan, math.nan)


def _delta_e(sky: ReferenceSky, xyz: np.ndarray) -> np.ndarray:
    return colour.delta_e_ciede2000(
        colour.xyz_to_lab(np.maximum(sky.xyz, 0.0), sky.white_xyz),
        colour.xyz_to_lab(np.maximum(xyz, 0.0), sky.white_xyz),
    )


def _weighted_percentile(values: np.ndarray, weights: np.ndarray, q: float) -> float:
    order = np.argsort(values, axis=None)
    v, w = values.ravel()[order], weights.ravel()[order]
    cum = np.cumsum(w)
    return float(v[min(int(np.searchsorted(cum, q * cum[-1])), v.size - 1)])


def sky_error(sky: ReferenceSky, xyz: np.ndarray) -> SkyError:
    """The metrics of an engine's sky ``xyz`` (on ``sky``'s directions) against ``sky``."""
    de = _delta_e(sky, xyz)
    w = sky.weight
    return SkyError(
        sun_elevation_deg=sky.sun_elevation_deg,
        delta_e_mean=float(np.sum(w * de)),
        delta_e_p95=_weighted_percentile(de, w, 0.95),
        xy_zenith_exact=_xy(sky.xyz[sky.zenith_index]),
        xy_zenith_engine=_xy(xyz[sky.zenith_index]),
        xy_near_sun_exact=_xy(sky.xyz[sky.near_sun_index]),
        xy_near_sun_engine=_xy(xyz[sky.near_sun_index]),
        luminance_ratio=float(np.sum(w * xyz[..., 1]) / np.sum(w * sky.xyz[..., 1])),
    )


@dataclass(frozen=True)
class EngineFit:
    """An engine's parameters fitted to the exact sky (or a community row's, exposure fitted).

    Attributes
    ----------
    engine : str
        :attr:`EngineModel.name`.
    atmosphere : str
        The atmosphere's name.
    kind : str
        ``"fitted"`` (every parameter) or ``"community"`` (what people use, only
        :attr:`EngineModel.community_parameters` adjusted).
    params : mapping of str to float
        Every value the engine's renderer takes.
    errors : tuple of SkyError
        Per Sun elevation of the fit.
    atmosphere_info : mapping
        What the files record of the atmosphere (name, planet radius [m]).
    """

    engine: str
    atmosphere: str
    kind: str
    params: Mapping[str, float]
    errors: tuple[SkyError, ...]
    atmosphere_info: Mapping[str, Any] = field(default_factory=dict)

    @property
    def delta_e_mean(self) -> float:
        """Mean of the per-elevation Delta E 2000 means. [-]"""
        return float(np.mean([e.delta_e_mean for e in self.errors]))


def _to_vector(params: Mapping[str, float], fitted: Sequence[Parameter]) -> np.ndarray:
    return np.array([math.log(params[p.name]) if p.log else params[p.name] for p in fitted])


def _from_vector(
    x: np.ndarray, base: Mapping[str, float], fitted: Sequence[Parameter]
) -> dict[str, float]:
    out = dict(base)
    for p, v in zip(fitted, x, strict=True):
        out[p.name] = float(math.exp(v) if p.log else v)
    return out


def fit_engine(
    engine: EngineModel,
    atmosphere: Atmosphere,
    skies: Sequence[ReferenceSky],
    *,
    kind: str = "fitted",
    max_evaluations: int = 200,
    start: Mapping[str, float] | None = None,
) -> EngineFit:
    """Fit an engine's parameters to the exact skies: least squares of Delta E 2000.

    The residuals are each direction's CIE Delta E 2000 (L*a*b* relative to
    :attr:`ReferenceSky.white_xyz`, so the luminance counts as much as the
    colour) times the square root of its solid-angle weight, over every Sun
    elevation of ``skies``: the fit minimises the solid-angle mean of Delta E
    squared over the dome and the elevations.  Trust-region reflective least
    squares (:func:`scipy.optimize.least_squares`) within the parameters'
    bounds, positive scales in log space.

    Parameters
    ----------
    engine : EngineModel
    atmosphere : Atmosphere
        Gives the fixed values and the start (:attr:`EngineModel.initial`) or
        the community row (:attr:`EngineModel.community`).
    skies : sequence of ReferenceSky
        :func:`reference_skies` of ``atmosphere``.
    kind : str
        ``"fitted"``: every parameter, from the engine's start or the community
        row, whichever is closer once its exposure is fitted;
        ``"community"``: the community row, only its
        :attr:`EngineModel.community_parameters` adjusted.
    max_evaluations : int
        Most evaluations of the residuals, finite-difference Jacobians included.
    start : mapping, optional
        Every value the renderer takes, instead of the engine's start (or
        community row) for ``atmosphere``.

    Returns
    -------
    EngineFit
    """
    if kind not in ("fitted", "community"):
        raise ValueError(f"kind must be 'fitted' or 'community'; got {kind!r}")
    community = [p for p in engine.parameters if p.name in engine.community_parameters]
    if start is not None:
        starts = [dict(start)]
    elif kind == "fitted":
        starts = [dict(engine.initial(atmosphere)), dict(engine.community(atmosphere))]
    else:
        starts = [dict(engine.community(atmosphere))]
    fitted = list(engine.parameters) if kind == "fitted" else community
    roots = [np.sqrt(s.weight) for s in skies]

    def residuals_of(base: Mapping[str, float], which: Sequence[Parameter]) -> Any:
        def residuals(x: np.ndarray) -> np.ndarray:
            params = _from_vector(x, base, which)
            parts = []
            for sky, root in zip(skies, roots, strict=True):
                de = _delta_e(sky, engine_xyz(engine, params, sky))
                parts.append((root * np.nan_to_num(de, nan=100.0)).ravel())
            return np.concatenate(parts)

        return residuals

    def solve(base: Mapping[str, float], which: Sequence[Parameter], budget: int) -> Any:
        lower = np.array([math.log(p.lower) if p.log else p.lower for p in which])
        upper = np.array([math.log(p.upper) if p.log else p.upper for p in which])
        x0 = np.clip(_to_vector(base, which), lower + 1e-9, upper - 1e-9)
        if not which:
            return _from_vector(x0, base, which), float("inf")
        # Imported here: scipy.optimize costs 0.12-0.16 s CPU to import and the engines'
        # module is loaded by every `dustoptics build` (its parser lists their formats).
        from scipy.optimize import least_squares

        # max_nfev does not count the evaluations of the finite-difference Jacobian (one
        # per parameter per iteration): the budget covers both.
        result = least_squares(
            residuals_of(base, which),
            x0,
            bounds=(lower, upper),
            x_scale=1.0,
            max_nfev=max(2, budget // (len(which) + 1)),
        )
        return _from_vector(result.x, base, which), float(result.cost)

    # Each start gets its exposure (the community parameters) first; the full fit goes on
    # from the better one, so the fit starts no worse than what people use.
    candidates = [
        solve(base, community, 40) if kind == "fitted" else (base, 0.0) for base in starts
    ]
    best = min(candidates, key=lambda c: c[1])[0]
    x_params, _ = solve(best, fitted, max_evaluations) if fitted else (best, 0.0)
    params = dict(x_params)
    errors = tuple(sky_error(sky, engine_xyz(engine, params, sky)) for sky in skies)
    info = {
        "name": atmosphere.name,
        "planet_radius_m": float(atmosphere.planet_radius_m),
        "atmosphere_radius_m": float(atmosphere.atmosphere_radius_m),
    }
    return EngineFit(
        engine=engine.name,
        atmosphere=atmosphere.name,
        kind=kind,
        params=MappingProxyType(params),
        errors=errors,
        atmosphere_info=MappingProxyType(info),
    )


def write_engine_files(
    name: str,
    atmosphere: Atmosphere,
    out_dir: str | Path,
    *,
    overwrite: bool = False,
    skies: Sequence[ReferenceSky] | None = None,
) -> list[Path]:
    """Fit engine ``name`` to ``atmosphere``'s exact sky and write its files.

    Parameters
    ----------
    name : str
        A key of :data:`ENGINES`.
    atmosphere : Atmosphere
    out_dir : path
        Directory (created if missing).
    overwrite : bool
        Replace existing files.
    skies : sequence of ReferenceSky, optional
        :func:`reference_skies` of ``atmosphere`` already computed.

    Returns
    -------
    list of pathlib.Path
    """
    if name not in ENGINES:
        raise ValueError(f"engine must be one of {', '.join(map(repr, ENGINES))}; got {name!r}")
    engine = ENGINES[name]
    refs = reference_skies(atmosphere) if skies is None else skies
    return engine.write(fit_engine(engine, atmosphere, refs), out_dir, overwrite=overwrite)


# What the engines' modules share: the channels' names, the Hillaire engines' renderer and
# the fit's error in their files.

#: The suffixes of a colour's three parameters (``NAME_r``, ``NAME_g``, ``NAME_b``).
RGB: Final = ("r", "g", "b")

#: Multiple-scattering tables of the Hillaire engines by their parameters (bounded).
_PSI_CACHE: dict[tuple[tuple[str, float], ...], np.ndarray] = {}


def smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    """GLSL's ``smoothstep(e0, e1, x)``: 0 below ``e0``, 1 above ``e1``, a cubic between."""
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def y_up_directions(
    sun_elevation_deg: float, view_zenith_deg: Any, view_azimuth_deg: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Unit view directions (x, y up, z) and the Sun's, azimuth measured from the Sun's."""
    z = np.radians(np.asarray(view_zenith_deg, dtype=float))
    a = np.radians(np.asarray(view_azimuth_deg, dtype=float))
    d = np.stack([np.sin(z) * np.cos(a), np.cos(z), np.sin(z) * np.sin(a)], axis=-1)
    e = math.radians(sun_elevation_deg)
    return d, np.array([math.cos(e), math.sin(e), 0.0])


def rgb_of(params: Mapping[str, float], name: str) -> np.ndarray:
    """The three values ``NAME_r``, ``NAME_g``, ``NAME_b`` of ``params`` as an array."""
    return np.array([params[f"{name}_{c}"] for c in RGB])


def per_channel(name: str, lower: float, upper: float, unit: str) -> tuple[Parameter, ...]:
    """Three fitted scales ``NAME_r``, ``NAME_g``, ``NAME_b`` (log, within the bounds)."""
    return tuple(Parameter(f"{name}_{c}", lower, upper, log=True, unit=unit) for c in RGB)


def hillaire_sky_rgb(
    setup: _hillaire.HillaireSetup,
    params: Mapping[str, float],
    *,
    sun_elevation_deg: float,
    view_zenith_deg: Any,
    view_azimuth_deg: Any,
) -> np.ndarray:
    """Hillaire's sky of ``setup`` per unit solar illuminance times ``params["exposure"]``
    (1 if absent), linear sRGB, lit by a Sun of :func:`sunlight_linear_srgb`. [sr^-1]

    The multiple-scattering table is made once per ``params`` (the exposure aside).
    """
    key = tuple((k, float(params[k])) for k in sorted(params) if k != "exposure")
    psi = _PSI_CACHE.get(key)
    if psi is None:
        if len(_PSI_CACHE) > 16:
            _PSI_CACHE.clear()
        psi = _PSI_CACHE[key] = _hillaire.multiple_scattering_table(setup)
    rgb = _hillaire.sky_radiance_rgb(
        setup,
        sun_elevation_deg=sun_elevation_deg,
        view_zenith_deg=view_zenith_deg,
        view_azimuth_deg=view_azimuth_deg,
        psi=psi,
    )
    if "exposure" in params:
        rgb = params["exposure"] * rgb
    return np.asarray(rgb * sunlight_linear_srgb(), dtype=float)


def hillaire_renderer(
    setup: Callable[[Mapping[str, float]], _hillaire.HillaireSetup], name: str, doc: str
) -> Renderer:
    """An engine's :data:`Renderer`: :func:`hillaire_sky_rgb` of ``setup(params)``.

    Parameters
    ----------
    setup : callable
        The engine's Hillaire medium of its parameters.
    name : str
        The renderer's name (``bevy_sky_rgb``), in the module of ``setup``.
    doc : str
        Its docstring.
    """

    def render(
        params: Mapping[str, float],
        *,
        sun_elevation_deg: float,
        view_zenith_deg: Any,
        view_azimuth_deg: Any,
    ) -> np.ndarray:
        return hillaire_sky_rgb(
            setup(params),
            params,
            sun_elevation_deg=sun_elevation_deg,
            view_zenith_deg=view_zenith_deg,
            view_azimuth_deg=view_azimuth_deg,
        )

    render.__name__ = render.__qualname__ = name
    render.__module__ = setup.__module__
    render.__doc__ = doc
    return render


def error_header(fit: EngineFit) -> list[str]:
    """The comment lines of the fit's sky error, one per Sun elevation."""
    return [
        "Sky error against the exact spectral sky (CIE Delta E 2000, dome mean / 95th pct):",
        *(
            f"  Sun {e.sun_elevation_deg:g} deg: {e.delta_e_mean:.2f} / {e.delta_e_p95:.2f}"
            for e in fit.errors
        ),
    ]


def error_notes(fit: EngineFit) -> tuple[str, ...]:
    """The fit's sky error as notes, one per Sun elevation, with the luminance ratio."""
    return tuple(
        f"Sun {e.sun_elevation_deg:g} deg: Delta E 2000 {e.delta_e_mean:.2f} mean, "
        f"{e.delta_e_p95:.2f} 95th pct, luminance ratio {e.luminance_ratio:.3f}"
        for e in fit.errors
    )


def fit_json(fit: EngineFit, header: list[str], engine: str, source: str, **fields: Any) -> str:
    """The JSON file of a fit: ``header`` as its comment, the engine, the source read, the
    atmosphere and kind, ``fields`` in order, and the sky error per Sun elevation."""
    errors = [
        {
            "sun_elevation_deg": e.sun_elevation_deg,
            "delta_e2000_mean": e.delta_e_mean,
            "delta_e2000_p95": e.delta_e_p95,
            "luminance_ratio": e.luminance_ratio,
        }
        for e in fit.errors
    ]
    document = {
        "comment": header,
        "engine": engine,
        "source": source,
        "atmosphere": fit.atmosphere,
        "kind": fit.kind,
        **fields,
        "errors": errors,
    }
    return json.dumps(document, indent=2, allow_nan=False) + "\n"


def write_texts(
    fit: EngineFit, out_dir: Any, name: str, texts: Mapping[str, str], *, overwrite: bool
) -> list[Path]:
    """Write ``texts`` (suffix -> text) as ``STEM_NAME.SUFFIX`` atomically, UTF-8 (the stem
    is the atmosphere's name, :func:`dustoptics.io._atomic.safe_stem`)."""
    base = Path(out_dir) / f"{safe_stem(fit.atmosphere)}_{name}"
    return write_files(
        {Path(f"{base}.{k}"): v.encode("utf-8") for k, v in texts.items()}, overwrite=overwrite
    )
