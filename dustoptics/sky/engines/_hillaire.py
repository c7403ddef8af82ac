"""Hillaire's (2020) sky model as numpy: the ray march and the multiple-scattering table.

S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering
Technique," Computer Graphics Forum 39(4), 13-22 (2020),
doi:10.1111/cgf.14050, and his reference implementation
(github.com/sebh/UnrealEngineSkyAtmosphere at 183ead5b, BSD-3-Clause:
``Resources/RenderSkyRayMarching.hlsl``, ``IntegrateScatteredLuminance`` and
the ``NewMultiScattCS`` kernel; ``Resources/RenderSkyCommon.hlsl``,
``sampleMediumRGB``).  Unreal Engine's SkyAtmosphere component
(:mod:`~dustoptics.sky.engines.unreal`) is his model; Unity HDRP's Physically
Based Sky in Unity 6 (:mod:`~dustoptics.sky.engines.unity`) computes the same
two passes (``SkyLUTGenerator.compute``).  What the engines differ in is an
:class:`HillaireSetup`: the medium, the aerosol phase function, the
distribution of the samples along a ray and the directions of the
multiple-scattering integral.

The sky in a direction is the integral along the view ray (to the top of the
atmosphere) of

    S = T_sun (sigma_s,R P_R(nu) + sigma_s,M P_M(nu)) + Psi_ms(h, mu_s) sigma_s,

each step integrated as a homogeneous segment, ``(S - S T_seg) / sigma_t``
times the transmittance from the observer (his Eq. 1 and slide 28 of Hillaire
2015); ``T_sun`` is the transmittance to the Sun (0 when the Sun is below the
point's horizon).  ``Psi_ms = L_2 / (1 - f_ms)`` (his Eq. 5-10) is tabulated
over the altitude and the cosine of the Sun's zenith angle: ``L_2`` is the
mean over the sphere of directions of the single scattering with an isotropic
phase function plus the lit ground (Lambertian albedo) where a ray hits it,
``f_ms`` the mean of ``int T sigma_s dt``.

Choices of this implementation (not of the engines):

- the transmittance to the Sun of the two exponential layers is the Chapman
  function's approximation that Unity HDRP uses (``ChapmanUpperApprox`` and
  ``ChapmanHorizontal`` of ``PhysicallyBasedSkyCommon.hlsl``), for both
  engines (Unreal reads a 256 x 64 transmittance texture integrated to the top
  of the atmosphere; the two differ by about 1 % of the optical depth); the
  tent layer of absorption (ozone) is integrated numerically along the Sun's
  ray (16 steps);
- the multiple-scattering table has :data:`MS_MU_SIZE` x :data:`MS_ALTITUDE_SIZE`
  nodes (the engines: 32 x 32), read bilinearly;
- the view ray has :data:`VIEW_SAMPLES` samples in the engine's distribution
  (the engines march a sky-view texture with 4 to 32 samples).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

__all__ = [
    "MS_ALTITUDE_SIZE",
    "MS_MU_SIZE",
    "VIEW_SAMPLES",
    "HillaireSetup",
    "cornette_shanks",
    "henyey_greenstein",
    "rayleigh_phase",
    "sky_radiance_rgb",
]

#: Nodes of the multiple-scattering table in the cosine of the Sun's zenith angle.
MS_MU_SIZE: Final = 12
#: Nodes of the multiple-scattering table in altitude.
MS_ALTITUDE_SIZE: Final = 8
#: Samples along a view ray.
VIEW_SAMPLES: Final = 32
#: Observer above the ground, as for the exact sky (a rover's camera). [km]
OBSERVER_ALTITUDE_KM: Final = 0.002


def rayleigh_phase(cos_theta: np.ndarray) -> np.ndarray:
    """3 / (16 pi) (1 + cos^2). [sr^-1]"""
    return 3.0 / (16.0 * math.pi) * (1.0 + cos_theta * cos_theta)


def henyey_greenstein(g: float) -> Callable[[np.ndarray], np.ndarray]:
    """Henyey-Greenstein, forward peak at cos = 1 (Hillaire's ``hgPhase(g, -cosTheta)``). [sr^-1]"""

    def phase(cos_theta: np.ndarray) -> np.ndarray:
        d = 1.0 + g * g - 2.0 * g * cos_theta
        return (1.0 - g * g) / (4.0 * math.pi * d * np.sqrt(d))

    return phase


def cornette_shanks(g: float) -> Callable[[np.ndarray], np.ndarray]:
    """Cornette-Shanks as Unity's core library writes it (``CornetteShanksPhasePartConstant``
    times ``CornetteShanksPhasePartVarying``). [sr^-1]"""
    constant = 3.0 / (8.0 * math.pi) * (1.0 - g * g) / (2.0 + g * g)

    def phase(cos_theta: np.ndarray) -> np.ndarray:
        x = np.maximum(1.0 + g * g - 2.0 * g * cos_theta, 1e-12)
        return constant * (1.0 + cos_theta * cos_theta) / (x * np.sqrt(x))

    return phase


@dataclass(frozen=True)
class HillaireSetup:
    """One engine's medium and sampling, in km and km^-1 (each vector R, G, B).

    Attributes
    ----------
    planet_radius_km, top_radius_km : float
    rayleigh_scattering_per_km, rayleigh_absorption_per_km : numpy.ndarray
        At the ground (density 1).
    rayleigh_scale_height_km : float
    mie_scattering_per_km, mie_absorption_per_km : numpy.ndarray
        At the ground.
    mie_scale_height_km : float
    mie_phase : callable
        ``phase(cos_theta) -> [sr^-1]``, cos_theta between the view and the Sun; the
        result may have a last axis of 3 (one phase function per channel).
    ozone_absorption_per_km : numpy.ndarray
        At the tent's top.
    ozone_bottom_km, ozone_peak_km, ozone_top_km : float
        The tent layer: density 0 below the bottom, 1 at the peak, 0 above the top.
    ground_albedo : numpy.ndarray
    distribution : str
        Of the samples along a view ray: ``"variable"``, Hillaire's sky-view
        march (``VariableSampleCount``: segments ``t_max (s/N)^2`` to
        ``t_max ((s+1)/N)^2``, the sample 0.3 into each); ``"quadratic"``,
        Unity's ``GetSample`` (the same segments, the sample at the middle).
    ms_distribution : str
        Of the samples along a ray of the multiple-scattering integral:
        ``"uniform"``, Hillaire's ``t = t_max (s + 0.3) / N`` (his
        ``NewMultiScattCS``, no variable count), or ``"quadratic"`` (Unity).
    directions : str
        Of the multiple-scattering integral: ``"stratified"`` (Hillaire's 8 x 8)
        or ``"hammersley"`` (Unity's 64 points).
    ms_samples : int
        Samples along each ray of the multiple-scattering integral.
    multiple_scattering_factor : float
        Scales Psi_ms (Unreal's MultiScatteringFactor).
    """

    planet_radius_km: float
    top_radius_km: float
    rayleigh_scattering_per_km: np.ndarray
    rayleigh_absorption_per_km: np.ndarray
    rayleigh_scale_height_km: float
    mie_scattering_per_km: np.ndarray
    mie_absorption_per_km: np.ndarray
    mie_scale_height_km: float
    mie_phase: Callable[[np.ndarray], np.ndarray]
    ozone_absorption_per_km: np.ndarray
    ozone_bottom_km: float
    ozone_peak_km: float
    ozone_top_km: float
    ground_albedo: np.ndarray
    distribution: str = "variable"
    ms_distribution: str = "uniform"
    directions: str = "stratified"
    ms_samples: int = 20
    multiple_scattering_factor: float = 1.0


def _densities(setup: HillaireSetup, h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    h = np.maximum(h, 0.0)
    d_r = np.exp(-h / setup.rayleigh_scale_height_km)
    d_m = np.exp(-h / setup.mie_scale_height_km)
    rise = (h - setup.ozone_bottom_km) / max(setup.ozone_peak_km - setup.ozone_bottom_km, 1e-9)
    fall = (setup.ozone_top_km - h) / max(setup.ozone_top_km - setup.ozone_peak_km, 1e-9)
    d_o = np.clip(np.minimum(rise, fall), 0.0, 1.0)
    return d_r, d_m, d_o


def _coefficients(
    setup: HillaireSetup, h: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rayleigh and Mie scattering, total scattering and extinction at altitudes ``h``, (..., 3)."""
    d_r, d_m, d_o = _densities(setup, h)
    s_r = d_r[..., None] * setup.rayleigh_scattering_per_km
    s_m = d_m[..., None] * setup.mie_scattering_per_km
    ext = (
        s_r
        + s_m
        + d_r[..., None] * setup.rayleigh_absorption_per_km
        + d_m[..., None] * setup.mie_absorption_per_km
        + d_o[..., None] * setup.ozone_absorption_per_km
    )
    return s_r, s_m, s_r + s_m, ext


def _chapman_upper(z: np.ndarray, c: np.ndarray) -> np.ndarray:
    n = 0.761643 * ((1.0 + 2.0 * z) - c * c * z)
    d = c * z + np.sqrt(z * (1.47721 + 0.273828 * (c * c * z)))
    return 0.5 * c + n / d


def _chapman_horizontal(z: np.ndarray) -> np.ndarray:
    r = 1.0 / np.sqrt(z)
    return 0.626657 * (r + 2.0 * z * r)


def _layer_column(r: np.ndarray, mu: np.ndarray, radius: float, height: float) -> np.ndarray:
    """Column of ``exp(-h / H)`` from (r, mu) to infinity (Chapman approximation). [km]"""
    z = r / height
    big_z = radius / height
    ch = _chapman_upper(z, np.abs(mu)) * np.exp(big_z - z)
    sin_t = np.sqrt(np.clip(1.0 - mu * mu, 0.0, 1.0))
    z0 = np.maximum(z * sin_t, 1e-9)
    with np.errstate(over="ignore", invalid="ignore"):  # the branch not taken overflows
        below = 2.0 * _chapman_horizontal(z0) * np.exp(np.minimum(big_z - z0, 700.0)) - ch
    return np.where(mu < 0.0, below, ch) * height


def _ozone_column(setup: HillaireSetup, r: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Column of the tent layer's density from (r, mu) to the top, 16 midpoint steps. [km]"""
    disc = r * r * (mu * mu - 1.0) + setup.top_radius_km**2
    t_top = np.maximum(-r * mu + np.sqrt(np.maximum(disc, 0.0)), 0.0)
    frac = (np.arange(16) + 0.5) / 16
    t = t_top[..., None] * frac
    rr = np.sqrt(r[..., None] ** 2 + t * t + 2.0 * r[..., None] * mu[..., None] * t)
    _, _, d_o = _densities(setup, rr - setup.planet_radius_km)
    return np.asarray(d_o.sum(axis=-1) * t_top / 16)


def sun_transmittance(
    setup: HillaireSetup, r: np.ndarray, mu: np.ndarray, *, cache: bool = False
) -> np.ndarray:
    """Transmittance to the Sun from radius ``r`` [km] at Sun zenith cosine ``mu``, (..., 3);
    0 where the planet hides the Sun.  ``cache``: keep the tent layer's column (it
    depends on the geometry and the tent only) for the next call with the same points."""
    radius = setup.planet_radius_km
    r = np.maximum(r, radius)
    col_r = _layer_column(r, mu, radius, setup.rayleigh_scale_height_km)
    col_m = _layer_column(r, mu, radius, setup.mie_scale_height_km)
    od = col_r[..., None] * (
        setup.rayleigh_scattering_per_km + setup.rayleigh_absorption_per_km
    ) + col_m[..., None] * (setup.mie_scattering_per_km + setup.mie_absorption_per_km)
    if np.any(setup.ozone_absorption_per_km > 0.0):
        key = (
            "ozone",
            setup.planet_radius_km,
            setup.top_radius_km,
            setup.ozone_bottom_km,
            setup.ozone_peak_km,
            setup.ozone_top_km,
            hash(r.tobytes()),
            hash(mu.tobytes()),
        )
        column = (
            _memo(key, lambda: _ozone_column(setup, r, mu))
            if cache
            else _ozone_column(setup, r, mu)
        )
        od = od + column[..., None] * setup.ozone_absorption_per_km
    cos_horizon = -np.sqrt(np.clip(1.0 - (radius / r) ** 2, 0.0, 1.0))
    return np.where((mu >= cos_horizon)[..., None], np.exp(-od), 0.0)


def _samples(distribution: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Fractions of the ray's length of each sample and of its segment."""
    s = np.arange(n, dtype=float)
    if distribution == "uniform":
        t = (s + 0.3) / n
        return t, np.diff(np.concatenate([[0.0], t]))
    t0, t1 = (s / n) ** 2, ((s + 1.0) / n) ** 2
    where = 0.3 if distribution == "variable" else 0.5
    return t0 + where * (t1 - t0), t1 - t0


def _sphere_exit(
    origin: np.ndarray, direction: np.ndarray, radius: float
) -> tuple[np.ndarray, np.ndarray]:
    """Far intersection with a sphere (>= 0), and the near one (NaN if none ahead)."""
    b = np.sum(origin * direction, axis=-1)
    c = np.sum(origin * origin, axis=-1) - radius * radius
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0.0))
    far = np.where(disc >= 0.0, np.maximum(-b + root, 0.0), 0.0)
    near = np.where((disc >= 0.0) & (-b - root > 0.0), -b - root, np.nan)
    return far, near


def _march(
    setup: HillaireSetup,
    origin: np.ndarray,
    direction: np.ndarray,
    sun: np.ndarray,
    t_max: np.ndarray,
    n_samples: int,
    distribution: str,
    *,
    phase: tuple[np.ndarray, np.ndarray] | None,
    psi: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Integrate along rays: (radiance, transmittance, f_ms), each (n, 3).

    ``phase`` is (Rayleigh, Mie) per ray; None: isotropic (the
    multiple-scattering pass). ``psi`` the multiple-scattering table, or None.
    """
    r, mu_s, h, dt = _ray_geometry(setup, origin, direction, sun, t_max, n_samples, distribution)
    s_r, s_m, s_all, ext = _coefficients(setup, h)
    t_sun = sun_transmittance(setup, r, mu_s, cache=True)
    if phase is None:
        scattered = s_all / (4.0 * math.pi)
    else:
        mie = phase[1]  # (n,), or (n, 3) for a chromatic phase function (Bevy's texture)
        mie = mie[:, None, :] if mie.ndim == 2 else mie[:, None, None]
        scattered = s_r * phase[0][:, None, None] + s_m * mie
    source = t_sun * scattered
    if psi is not None:
        source = source + _read_psi(setup, psi, mu_s, h) * s_all
    ext = np.maximum(ext, 1e-12)
    seg = np.exp(-ext * dt)
    before = np.exp(-(np.cumsum(ext * dt, axis=1) - ext * dt))
    radiance = np.sum(before * source * (1.0 - seg) / ext, axis=1)
    f_ms = np.sum(before * s_all * (1.0 - seg) / ext, axis=1)
    return radiance, before[:, -1] * seg[:, -1], f_ms


_GEOMETRY: dict[tuple[Any, ...], Any] = {}


def _memo(key: tuple[Any, ...], compute: Callable[[], Any]) -> Any:
    """A small cache of what depends only on the geometry (not on the fitted coefficients)."""
    if key not in _GEOMETRY:
        if len(_GEOMETRY) > 64:
            _GEOMETRY.clear()
        _GEOMETRY[key] = compute()
    return _GEOMETRY[key]


def _ray_geometry(
    setup: HillaireSetup,
    origin: np.ndarray,
    direction: np.ndarray,
    sun: np.ndarray,
    t_max: np.ndarray,
    n_samples: int,
    distribution: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Radius, Sun zenith cosine, altitude and segment length of each sample [km]."""

    def compute() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        frac, dfrac = _samples(distribution, n_samples)
        t = t_max[:, None] * frac
        dt = (t_max[:, None] * dfrac)[..., None]
        pos = origin[:, None, :] + t[..., None] * direction[:, None, :]
        r = np.linalg.norm(pos, axis=-1)
        mu_s = np.sum(pos * sun[:, None, :], axis=-1) / r
        return r, mu_s, r - setup.planet_radius_km, dt

    key = (
        "rays",
        setup.planet_radius_km,
        distribution,
        n_samples,
        hash(origin.tobytes()),
        hash(direction.tobytes()),
        hash(sun.tobytes()),
        hash(t_max.tobytes()),
    )
    return _memo(key, compute)


def _ms_directions(kind: str) -> np.ndarray:
    """The 64 directions of the multiple-scattering integral (z up)."""
    if kind == "stratified":
        i, j = np.meshgrid(np.arange(8) + 0.5, np.arange(8) + 0.5, indexing="ij")
        theta, phi = 2.0 * math.pi * i.ravel() / 8, np.arccos(1.0 - 2.0 * j.ravel() / 8)
    else:
        idx = np.arange(64)
        bits = np.array([int(f"{k:032b}"[::-1], 2) for k in idx], dtype=float) / 2.0**32
        theta, phi = 2.0 * math.pi * bits, np.arccos(1.0 - 2.0 * idx / 64)
    return np.stack(
        [np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=-1
    )


def multiple_scattering_table(setup: HillaireSetup) -> np.ndarray:
    """Psi_ms at (mu_s, altitude) nodes, shape (MS_MU_SIZE, MS_ALTITUDE_SIZE, 3). [sr^-1]"""
    mus = np.linspace(-1.0, 1.0, MS_MU_SIZE)
    heights = np.linspace(0.0, setup.top_radius_km - setup.planet_radius_km, MS_ALTITUDE_SIZE)
    heights[-1] -= 1e-3
    dirs = _ms_directions(setup.directions)
    mm, hh, dd = np.meshgrid(
        np.arange(mus.size), np.arange(heights.size), np.arange(64), indexing="ij"
    )
    mu = mus[mm.ravel()]
    origin = np.zeros((mu.size, 3))
    origin[:, 2] = setup.planet_radius_km + heights[hh.ravel()]
    sun = np.stack([np.zeros_like(mu), np.sqrt(1.0 - mu * mu), mu], axis=-1)
    direction = dirs[dd.ravel()]
    top, _ = _sphere_exit(origin, direction, setup.top_radius_km)
    _, ground = _sphere_exit(origin, direction, setup.planet_radius_km)
    hits = np.isfinite(ground)
    t_max = np.where(hits, np.nan_to_num(ground), top)
    radiance, trans, f_ms = _march(
        setup,
        origin,
        direction,
        sun,
        t_max,
        setup.ms_samples,
        setup.ms_distribution,
        phase=None,
        psi=None,
    )
    ground_pos = origin + t_max[:, None] * direction
    r_g = np.linalg.norm(ground_pos, axis=-1)
    mu_g = np.sum(ground_pos * sun, axis=-1) / r_g
    lit = sun_transmittance(setup, r_g, mu_g) * np.maximum(mu_g, 0.0)[:, None]
    radiance = radiance + np.where(hits[:, None], lit * trans * setup.ground_albedo / math.pi, 0.0)
    shape = (mus.size, heights.size, 64, 3)
    l2 = radiance.reshape(shape).mean(axis=2)
    fms = f_ms.reshape(shape).mean(axis=2)
    return np.asarray(setup.multiple_scattering_factor * l2 / (1.0 - np.minimum(fms, 0.999)))


def _read_psi(setup: HillaireSetup, psi: np.ndarray, mu: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Bilinear read of the table (clamped at its edges), (..., 3)."""
    x = np.clip((mu + 1.0) / 2.0, 0.0, 1.0) * (MS_MU_SIZE - 1)
    y = np.clip(h / (setup.top_radius_km - setup.planet_radius_km), 0.0, 1.0) * (
        MS_ALTITUDE_SIZE - 1
    )
    i = np.clip(np.floor(x).astype(int), 0, MS_MU_SIZE - 2)
    j = np.clip(np.floor(y).astype(int), 0, MS_ALTITUDE_SIZE - 2)
    fx, fy = (x - i)[..., None], (y - j)[..., None]
    return np.asarray(
        psi[i, j] * (1 - fx) * (1 - fy)
        + psi[i + 1, j] * fx * (1 - fy)
        + psi[i, j + 1] * (1 - fx) * fy
        + psi[i + 1, j + 1] * fx * fy
    )


def sky_radiance_rgb(
    setup: HillaireSetup,
    *,
    sun_elevation_deg: float,
    view_zenith_deg: np.ndarray,
    view_azimuth_deg: np.ndarray,
    psi: np.ndarray | None = None,
    view_samples: int = VIEW_SAMPLES,
) -> np.ndarray:
    """The sky per unit (white) solar illuminance, shape ``zenith.shape + (3,)``. [sr^-1]

    ``psi``: :func:`multiple_scattering_table` of ``setup`` if already made;
    ``view_samples``: samples along each view ray.
    """
    z, a = np.broadcast_arrays(
        np.radians(np.asarray(view_zenith_deg, dtype=float)),
        np.radians(np.asarray(view_azimuth_deg, dtype=float)),
    )
    shape = z.shape
    direction = np.stack(
        [np.sin(z) * np.cos(a), np.cos(z), np.sin(z) * np.sin(a)], axis=-1
    ).reshape(-1, 3)
    e = math.radians(sun_elevation_deg)
    sun = np.broadcast_to(np.array([math.cos(e), math.sin(e), 0.0]), direction.shape)
    origin = np.zeros_like(direction)
    origin[:, 1] = setup.planet_radius_km + OBSERVER_ALTITUDE_KM
    t_max, _ = _sphere_exit(origin, direction, setup.top_radius_km)
    cos_theta = direction @ np.array([math.cos(e), math.sin(e), 0.0])
    table = multiple_scattering_table(setup) if psi is None else psi
    radiance, _, _ = _march(
        setup,
        origin,
        direction,
        np.ascontiguousarray(sun),
        t_max,
        view_samples,
        setup.distribution,
        phase=(rayleigh_phase(cos_theta), setup.mie_phase(cos_theta)),
        psi=table,
    )
    return radiance.reshape(*shape, 3)
