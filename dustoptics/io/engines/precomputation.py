"""The sampling a Bruneton-style precomputation needs for an atmosphere set.

E. Bruneton's precomputed atmospheric scattering (2017) [1]_ and CosmoScout VR's
``bruneton-preprocessor`` [2]_, which is built on it, discretize the same
integrals: orders of scattering summed one by one, the angle between the view
and the Sun (``nu``) on ``SCATTERING_TEXTURE_NU_SIZE`` slices, and the
scattering density integrated over ``S x 2S`` incident directions.  Their
defaults (4 orders, NU 8, S 16) were chosen for the Earth; a Martian dust
layer needs more of each.  This module is one concept: the rules that choose
those three numbers from a set's optics, each with the error it leaves.
:mod:`~dustoptics.io.engines.bruneton` and :mod:`~dustoptics.io.csv.cosmoscout`
write them into their exports and refuse a value the set cannot live with.

Scattering orders (:func:`scattering_orders`)
    A path model: the number of scatterings a photon undergoes on its way to an
    observer on the ground, looking along the horizon, is Poisson-distributed
    with mean ``m = sum_c f_c beta_sca,c L_c / 2``, where ``L_c`` is the
    constituent's horizontal column from the ground to the top (``sqrt(pi R H /
    2)`` for an exponential of scale height ``H``).  ``K`` orders leave out the
    fraction ``P(Poisson(m) > K) / (1 - exp(-m))`` of the diffuse radiance; ``K``
    is the smallest that leaves out at most the tolerance.  ``f_c = 1`` for a
    forward-scattering constituent (asymmetry ``g >= 0.1``) and 0.4 for a
    Rayleigh-like one: with these factors the rule reproduces backward Monte
    Carlo transport in the spherical shell with the full tabulated phase
    functions (black ground) for the Mars set at 550 and 680 nm (``K`` 10-12)
    and the Earth set at 440 nm (``K`` 5-6); only ``g = 0`` and ``g = 0.78`` are
    validated, and a bright ground needs more orders than this rule says.
NU size (:func:`nu_interpolation_error`)
    Bruneton stores the orders >= 2 on slices ``nu_j = -1 + 2 j / (N - 1)`` and
    interpolates linearly in ``nu`` between two slices; the slice next to the Sun
    is ``arccos(1 - 2 / (N - 1))`` away (44 deg at N = 8, 21 deg at 32, 14.5 deg at
    64).  The stored field near the Sun has the angular shape of the phase
    function convolved with itself (the second order, ``p * p``).  The estimate
    is that kernel's interpolation error, weighted by the second order's share
    of the diffuse sky (``w = m / 2`` of the first order in the path model, at
    most 1), relative to the sky ``p + w (p * p)`` between 5 and 90 deg from the
    Sun (single scattering, applied exactly at render time, is not
    interpolated), times 0.08.  That factor is measured: his precomputation run
    headless (``scripts/bruneton_headless.py``: the Mars set at 680, 550,
    440 nm, Sun 30 deg high, 3 orders, S = 48, textures R/MU/MU_S 8/32/16)
    differs from the same at NU 128 by 89, 40 and 17 % at NU 16, 32 and 64
    (10-20 deg from the Sun), 0.078-0.087 of the ideal kernel's error; with
    S = 16 the coarser scattering density blurs the field and the errors are
    smaller (24, 6.5, under 4 %), so the estimate is on the safe side for
    S < 48.  ``N x MU_S <= 2048`` (``GL_MAX_3D_TEXTURE_SIZE`` of llvmpipe and
    of many GPUs) caps N at 64 for ``MU_S = 32``: for the Martian dust that
    leaves about 16 % near the Sun, within 5 % beyond 14 deg from it (the
    notes say so), and NU 32 would leave 40 % up to 20 deg.
Scattering-density directions (:func:`scattering_density_error`)
    ``ComputeScatteringDensity`` integrates over ``S`` zenith by ``2 S``
    azimuth midpoints (``dtheta = dphi = pi / S``); the error measure is how far
    that rule's integral of each constituent's phase function is from 1, over
    64 quasi-random output directions.  The Martian dust's forward peak
    (half width at half maximum 3.7 deg) needs ``S = 64`` for 0.5 %; at S = 16 the
    integral spans 0.82-1.37.

References
----------
.. [1] E. Bruneton, "Precomputed atmospheric scattering: a new implementation"
   (2017), https://github.com/ebruneton/precomputed_atmospheric_scattering, read at
   commit d9954923ccd810be2d4443268a182bcb96544c1e (``atmosphere/constants.h``,
   ``atmosphere/functions.glsl``, ``atmosphere/model.cc``).
.. [2] German Aerospace Center (DLR), CosmoScout VR, ``plugins/csp-atmospheres/
   bruneton-preprocessor``, https://github.com/cosmoscout/cosmoscout-vr, read at
   commit e59005a3bbea2426c841f30da6cb35a4d313455e (identical to v1.10.0 there).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Final

import numpy as np
from scipy.special import roots_legendre

from dustoptics._validation import check_open_interval

if TYPE_CHECKING:
    from dustoptics.atmosphere.sets import Atmosphere

__all__ = [
    "BRUNETON_DEFAULTS",
    "MAX_3D_TEXTURE_SIZE",
    "NU_SIZES",
    "SCATTERING_DENSITY_SAMPLE_COUNTS",
    "PrecomputationSampling",
    "effective_scale_height_m",
    "horizontal_column_m",
    "nu_clear_angle_deg",
    "nu_interpolation_error",
    "precomputation_sampling",
    "scattering_density_error",
    "scattering_orders",
]

#: Bruneton's own choices (``atmosphere/constants.h``, ``functions.glsl``, ``model.h``).
BRUNETON_DEFAULTS: Final = {
    "transmittance_texture_width": 256,
    "transmittance_texture_height": 64,
    "scattering_texture_r_size": 32,
    "scattering_texture_mu_size": 128,
    "scattering_texture_mu_s_size": 32,
    "scattering_texture_nu_size": 8,
    "irradiance_texture_width": 64,
    "irradiance_texture_height": 16,
    "scattering_density_sample_count": 16,
    "indirect_irradiance_sample_count": 32,
    "num_scattering_orders": 4,
}

#: Largest 3-D texture width assumed (``GL_MAX_3D_TEXTURE_SIZE`` of Mesa's llvmpipe, measured,
#: and of many GPUs): ``NU x MU_S`` must not exceed it.
MAX_3D_TEXTURE_SIZE: Final = 2048

#: NU sizes tried, smallest first.
NU_SIZES: Final = (8, 12, 16, 24, 32, 48, 64, 96, 128)

#: Scattering-density sample counts S tried, smallest first (S x 2S directions).
SCATTERING_DENSITY_SAMPLE_COUNTS: Final = (16, 24, 32, 48, 64, 96, 128)

#: Path factor f of a constituent by its asymmetry parameter (see the module docstring).
_F_FORWARD: Final = 1.0
_F_RAYLEIGH: Final = 0.4
_G_FORWARD: Final = 0.1

#: Angles from the Sun over which the NU error is measured. [deg]
_NU_ANGLES_DEG: Final = (5.0, 90.0)
#: The NU estimate's factor: his precomputation run headless (scripts/bruneton_headless.py;
#: the Mars set at 440, 550, 680 nm, Sun 30 deg high, K = 3, S = 48, R/MU/MU_S 8/32/16) differs
#: from the same with NU 128 by 89, 40 and 17 % at NU 16, 32, 64, where the ideal kernel's
#: interpolation error is 10.9, 5.1 and 1.96: 0.082, 0.078, 0.087 of it.
_NU_CALIBRATION: Final = 0.08

_LEGENDRE_ORDER: Final = 600
_GAUSS_NODES: Final = 2000
_N_PROFILE: Final = 20001


# ------------------------------------------------------------------ the set's optics


@dataclass(frozen=True)
class _Scatterer:
    """One scattering constituent at the engine's wavelengths."""

    role: str
    beta_sca_per_m: np.ndarray  # (n_wl,) where the profile is 1
    g: np.ndarray  # (n_wl,)
    theta_deg: np.ndarray  # (n_theta,)
    phase: np.ndarray  # (n_wl, n_theta) [sr^-1]
    column_m: float  # horizontal column from the ground [m]


def _rows(values: np.ndarray, grid_nm: np.ndarray, wavelength_nm: np.ndarray) -> np.ndarray:
    """Rows linear in wavelength (as Bruneton's Interpolate and our GLSL snippet do)."""
    values = np.asarray(values, dtype=np.float64)
    if grid_nm.size == 1:
        return np.repeat(values[:1], wavelength_nm.size, axis=0)
    i = np.clip(np.searchsorted(grid_nm, wavelength_nm) - 1, 0, grid_nm.size - 2)
    t = np.clip((wavelength_nm - grid_nm[i]) / (grid_nm[i + 1] - grid_nm[i]), 0.0, 1.0)
    if values.ndim == 1:
        return values[i] * (1 - t) + values[i + 1] * t
    return values[i] * (1 - t)[:, None] + values[i + 1] * t[:, None]


def _scatterers(atmosphere: Atmosphere, wavelength_nm: np.ndarray | None) -> list[_Scatterer]:
    grid = np.asarray(atmosphere.wavelength_nm, dtype=np.float64)
    wl = grid if wavelength_nm is None else np.asarray(wavelength_nm, dtype=np.float64)
    out = []
    for c in atmosphere.constituents:
        t = c.table
        assert t.cross_sections is not None  # a constituent has cross-sections
        if not np.any(t.cross_sections.csca_um2 > 0):
            continue
        out.append(
            _Scatterer(
                role=c.role,
                beta_sca_per_m=_rows(t.beta_sca_per_m, grid, wl),
                g=_rows(t.g, grid, wl),
                theta_deg=np.asarray(t.theta_deg, dtype=np.float64),
                phase=_rows(t.phase, grid, wl),
                column_m=horizontal_column_m(
                    c.profile,
                    planet_radius_m=atmosphere.planet_radius_m,
                    top_altitude_m=atmosphere.thickness_m,
                ),
            )
        )
    return out


def effective_scale_height_m(profile: Any, *, top_altitude_m: float) -> float:
    """``sqrt(int rho dz / int |rho''| dz)`` over [0, top]: the scale height of an exponential.

    The trapezoid rule's error on a profile is ``dz^2 / 12`` times ``int rho''``;
    this length makes the step rules of the engines hold for any profile (for
    a piecewise-linear one the curvature sits in its kinks). [m]
    """
    z = np.linspace(0.0, float(top_altitude_m), _N_PROFILE)
    rho = np.asarray(profile.relative_density(z), dtype=np.float64)
    column = float(np.sum(0.5 * (rho[1:] + rho[:-1]) * np.diff(z)))
    curvature = float(np.sum(np.abs(np.diff(np.diff(rho) / np.diff(z)))))
    if curvature <= 0.0:
        return math.inf
    return math.sqrt(column / curvature)


def horizontal_column_m(profile: Any, *, planet_radius_m: float, top_altitude_m: float) -> float:
    """Column of a relative density along the horizontal from the ground to the top. [m]"""
    r = float(planet_radius_m)
    length = math.sqrt((r + top_altitude_m) ** 2 - r * r)
    s = np.linspace(0.0, length, _N_PROFILE)
    z = np.clip(np.sqrt(r * r + s * s) - r, 0.0, top_altitude_m)
    rho = np.asarray(profile.relative_density(z), dtype=np.float64)
    return float(np.sum(0.5 * (rho[1:] + rho[:-1]) * np.diff(s)))


def _path_scatterings(scatterers: list[_Scatterer]) -> np.ndarray:
    """Mean number of scatterings m of the path model, per wavelength."""
    m = np.zeros_like(scatterers[0].beta_sca_per_m)
    for s in scatterers:
        f = np.where(np.abs(s.g) >= _G_FORWARD, _F_FORWARD, _F_RAYLEIGH)
        m = m + f * s.beta_sca_per_m * s.column_m / 2.0
    return m


def _orders_for(m: float, tolerance: float) -> int:
    if m <= 0.0:
        return 1
    from scipy.stats import poisson  # here: scipy.stats costs ~0.4 s of `import dustoptics`

    norm = -math.expm1(-m)
    k = 1
    while poisson.sf(k, m) / norm > tolerance:
        k += 1
    return k


def scattering_orders(
    atmosphere: Atmosphere, *, tolerance: float, wavelength_nm: Any = None
) -> tuple[int, float]:
    """Orders of scattering (single included) the set needs, and the path model's m.

    Parameters
    ----------
    atmosphere : Atmosphere
    tolerance : float
        Largest fraction of the diffuse radiance the orders beyond may carry. [-]
    wavelength_nm : array_like, optional
        The engine's wavelengths (default the set's; coefficients linear in
        wavelength between the set's). [nm]

    Returns
    -------
    (int, float)
        ``K`` (Bruneton's ``Init(K)``; CosmoScout's ``multiScatteringOrder`` is
        ``K - 1``) and the largest mean number of scatterings ``m`` over the
        wavelengths.
    """
    tol = check_open_interval("tolerance", tolerance, 0.0, 1.0)
    scatterers = _scatterers(atmosphere, _wavelengths(wavelength_nm))
    if not scatterers:
        return 1, 0.0
    m = _path_scatterings(scatterers)
    return max(_orders_for(float(v), tol) for v in m), float(m.max())


# ------------------------------------------------------------------ NU


@functools.lru_cache(maxsize=1)
def _gauss_legendre() -> tuple[np.ndarray, np.ndarray]:
    x, w = roots_legendre(_GAUSS_NODES)
    return x, w


def _legendre_moments(theta_deg: np.ndarray, phase: np.ndarray, lmax: int) -> np.ndarray:
    """chi_l (chi_0 = 1) of phase rows (n, n_theta) by Gauss-Legendre in mu."""
    x, w = _gauss_legendre()
    ang = np.degrees(np.arccos(x))
    p = np.array([np.interp(ang, theta_deg, row) for row in np.atleast_2d(phase)])
    pw = p * w  # (n, nodes)
    chi = np.empty((pw.shape[0], lmax + 1))
    p0, p1 = np.ones_like(x), x
    chi[:, 0] = pw @ p0
    chi[:, 1] = pw @ p1
    for ell in range(1, lmax):
        p0, p1 = p1, ((2 * ell + 1) * x * p1 - ell * p0) / (ell + 1)
        chi[:, ell + 1] = pw @ p1
    return chi / chi[:, :1]


def _legendre_table(mu: np.ndarray, lmax: int) -> np.ndarray:
    """P_l(mu) for l = 0..lmax, shape (lmax + 1, n)."""
    table = np.empty((lmax + 1, mu.size))
    table[0] = 1.0
    table[1] = mu
    for ell in range(1, lmax):
        table[ell + 1] = ((2 * ell + 1) * mu * table[ell] - ell * table[ell - 1]) / (ell + 1)
    return table


def _series(chi: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """sum_l (2 l + 1) / (4 pi) chi_l P_l(mu), one row per row of chi. [sr^-1]"""
    ell = np.arange(chi.shape[-1])
    coef = (2 * ell + 1) / (4 * np.pi) * np.atleast_2d(chi)
    return coef @ _legendre_table(np.asarray(mu, dtype=np.float64), chi.shape[-1] - 1)


def _nu_errors(
    scatterers: list[_Scatterer], sizes: tuple[int, ...], tolerance: float = 0.05
) -> dict[int, tuple[float, float]]:
    """NU size -> (estimated sky error 5-90 deg from the Sun, angle beyond which it is <= tol)."""
    beta = np.array([s.beta_sca_per_m for s in scatterers])  # (n_c, n_wl)
    theta = np.linspace(0.0, 180.0, 3601)
    mix = (
        sum(
            s.beta_sca_per_m[:, None]
            * np.array([np.interp(theta, s.theta_deg, r) for r in s.phase])
            for s in scatterers
        )
        / beta.sum(axis=0)[:, None]
    )
    chi = _legendre_moments(theta, mix, _LEGENDRE_ORDER)
    weight = np.minimum(_path_scatterings(scatterers) / 2.0, 1.0)  # order 2 / order 1
    ang = np.linspace(_NU_ANGLES_DEG[0], _NU_ANGLES_DEG[1], 512)
    mu = np.cos(np.radians(ang))
    single = _series(chi, mu)
    kernel = _series(chi**2, mu)
    out = {}
    for n in sizes:
        nodes = -1.0 + 2.0 * np.arange(n) / (n - 1)
        at_nodes = _series(chi**2, nodes)
        lerp = np.array([np.interp(mu, nodes, row) for row in at_nodes])
        err = weight[:, None] * np.abs(lerp - kernel) / (single + weight[:, None] * kernel)
        est = _NU_CALIBRATION * err.max(axis=0)  # per angle, worst wavelength
        beyond = np.maximum.accumulate(est[::-1])[::-1]  # worst at this angle or farther
        clear = ang[np.argmax(beyond <= tolerance)] if np.any(beyond <= tolerance) else 90.0
        out[n] = (float(est.max()), float(clear))
    return out


def nu_interpolation_error(
    atmosphere: Atmosphere, *, nu_size: int, wavelength_nm: Any = None
) -> float:
    """Estimated sky error of NU slices, 5 to 90 deg from the Sun (module docstring). [-]

    The largest over the angles and wavelengths of the calibrated estimate
    ``0.08 w |lerp(p * p) - p * p| / (p + w p * p)``.
    """
    if isinstance(nu_size, bool) or not isinstance(nu_size, (int, np.integer)) or nu_size < 2:
        raise ValueError(f"nu_size must be an integer >= 2; got {nu_size!r}")
    scatterers = _scatterers(atmosphere, _wavelengths(wavelength_nm))
    if not scatterers:
        return 0.0
    return _nu_errors(scatterers, (int(nu_size),))[int(nu_size)][0]


def nu_clear_angle_deg(
    atmosphere: Atmosphere, *, nu_size: int, nu_tolerance: float = 0.05, wavelength_nm: Any = None
) -> float:
    """Angle from the Sun beyond which NU slices keep the estimated sky error within a tolerance.

    The estimate of :func:`nu_interpolation_error`, per angle from the Sun;
    90 if it exceeds ``nu_tolerance`` up to 90 deg, 5 if it never does. [deg]
    """
    if isinstance(nu_size, bool) or not isinstance(nu_size, (int, np.integer)) or nu_size < 2:
        raise ValueError(f"nu_size must be an integer >= 2; got {nu_size!r}")
    tol = check_open_interval("nu_tolerance", nu_tolerance, 0.0, 1.0)
    scatterers = _scatterers(atmosphere, _wavelengths(wavelength_nm))
    if not scatterers:
        return _NU_ANGLES_DEG[0]
    return _nu_errors(scatterers, (int(nu_size),), tol)[int(nu_size)][1]


# ------------------------------------------------------------------ scattering density


def _fibonacci_directions(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def _density_errors(scatterers: list[_Scatterer], counts: tuple[int, ...]) -> dict[int, float]:
    out_dirs = _fibonacci_directions(64)
    result = {}
    for s_count in counts:
        d = math.pi / s_count
        t = (np.arange(s_count) + 0.5) * d
        f = (np.arange(2 * s_count) + 0.5) * d
        tt, ff = np.meshgrid(t, f, indexing="ij")
        incident = np.stack(
            [np.sin(tt) * np.cos(ff), np.sin(tt) * np.sin(ff), np.cos(tt)], axis=-1
        ).reshape(-1, 3)
        d_omega = (np.sin(tt) * d * d).ravel()
        ang = np.degrees(np.arccos(np.clip(out_dirs @ incident.T, -1.0, 1.0)))
        worst = 0.0
        for s in scatterers:
            # Linear interpolation in angle as weights on the table's nodes, per output
            # direction: the rule's integral of every row at once.
            theta = s.theta_deg
            i0 = np.clip(np.searchsorted(theta, ang, side="right") - 1, 0, theta.size - 2)
            t = np.clip((ang - theta[i0]) / (theta[i0 + 1] - theta[i0]), 0.0, 1.0)
            rows = np.arange(out_dirs.shape[0])[:, None] * theta.size
            size = out_dirs.shape[0] * theta.size
            weights = np.bincount(
                (rows + i0).ravel(), weights=((1.0 - t) * d_omega).ravel(), minlength=size
            ) + np.bincount((rows + i0 + 1).ravel(), weights=(t * d_omega).ravel(), minlength=size)
            norm = weights.reshape(out_dirs.shape[0], theta.size) @ s.phase.T
            worst = max(worst, float(np.max(np.abs(norm - 1.0))))
        result[s_count] = worst
    return result


def scattering_density_error(
    atmosphere: Atmosphere, *, sample_count: int, wavelength_nm: Any = None
) -> float:
    """Largest error of the S x 2S direction rule's integral of a phase function (module docstring). [-]"""
    if (
        isinstance(sample_count, bool)
        or not isinstance(sample_count, (int, np.integer))
        or sample_count < 1
    ):
        raise ValueError(f"sample_count must be an integer >= 1; got {sample_count!r}")
    scatterers = _scatterers(atmosphere, _wavelengths(wavelength_nm))
    if not scatterers:
        return 0.0
    return _density_errors(scatterers, (int(sample_count),))[int(sample_count)]


# ------------------------------------------------------------------ all three


@dataclass(frozen=True)
class PrecomputationSampling:
    """Orders, NU size and scattering-density directions chosen for a set.

    Attributes
    ----------
    tolerance : float
        The error each choice keeps within. [-]
    num_scattering_orders : int
        ``K``, orders of scattering including the single one (Bruneton's
        ``Init(K)``; CosmoScout's ``multiScatteringOrder`` is ``K - 1``).
    scattering_texture_nu_size : int
        ``SCATTERING_TEXTURE_NU_SIZE``.
    scattering_density_sample_count : int
        ``S`` of ``ComputeScatteringDensity`` (``S x 2S`` directions).
    indirect_irradiance_sample_count : int
        ``S`` of ``ComputeIndirectIrradiance`` (``S/2 x 2S``), the same angular
        step, at least Bruneton's 32.
    scattering_texture_mu_s_size : int
        ``SCATTERING_TEXTURE_MU_S_SIZE`` (Bruneton's 32), which with NU makes
        the 3-D texture's width.
    mean_scatterings : float
        Largest ``m`` of the path model over the wavelengths. [-]
    orders_error : float
        Share of the diffuse radiance in orders beyond ``K``, by the path
        model. [-]
    nu_error : float
        :func:`nu_interpolation_error` at the chosen NU. [-]
    nu_clear_angle_deg : float
        Angle from the Sun beyond which that estimate is within the NU
        tolerance. [deg]
    scattering_density_error : float
        :func:`scattering_density_error` at the chosen S. [-]
    wavelength_nm : tuple of float
        The wavelengths the rules were evaluated at. [nm]
    notes : tuple of str
        Where a choice could not meet the tolerance, why.
    """

    tolerance: float
    num_scattering_orders: int
    scattering_texture_nu_size: int
    scattering_density_sample_count: int
    indirect_irradiance_sample_count: int
    scattering_texture_mu_s_size: int
    mean_scatterings: float
    orders_error: float
    nu_error: float
    nu_clear_angle_deg: float
    scattering_density_error: float
    wavelength_nm: tuple[float, ...]
    notes: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the choices, their errors and the rules' sources."""
        return {
            "tolerance": self.tolerance,
            "num_scattering_orders": self.num_scattering_orders,
            "scattering_texture_nu_size": self.scattering_texture_nu_size,
            "scattering_density_sample_count": self.scattering_density_sample_count,
            "indirect_irradiance_sample_count": self.indirect_irradiance_sample_count,
            "scattering_texture_mu_s_size": self.scattering_texture_mu_s_size,
            "errors": {
                "orders (path model: diffuse radiance beyond K)": self.orders_error,
                "nu (estimated sky error of the NU slices, 5-90 deg from the Sun)": self.nu_error,
                "nu: within the NU tolerance beyond, from the Sun [deg]": self.nu_clear_angle_deg,
                "scattering density (S x 2S rule's phase-function integral)": (
                    self.scattering_density_error
                ),
            },
            "mean_scatterings_along_the_horizon": self.mean_scatterings,
            "wavelengths_nm": list(self.wavelength_nm),
            "rules": "dustoptics.io.engines.precomputation (module docstring)",
            "notes": list(self.notes),
        }


def _wavelengths(wavelength_nm: Any) -> np.ndarray | None:
    if wavelength_nm is None:
        return None
    wl = np.atleast_1d(np.asarray(wavelength_nm, dtype=np.float64))
    if wl.ndim != 1 or wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise ValueError(f"wavelength_nm must be positive wavelengths [nm]; got {wavelength_nm!r}")
    return wl


def _check_given(
    name: str, value: Any, needed: int, why: str, smallest: str = "the smallest that does"
) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer; got {value!r} ({type(value).__name__})")
    if value < needed:
        raise ValueError(
            f"{name} {int(value)} is too small for this set: {why}; {smallest} is {needed}"
        )
    return int(value)


def precomputation_sampling(
    atmosphere: Atmosphere,
    *,
    tolerance: float = 0.005,
    nu_tolerance: float = 0.05,
    wavelength_nm: Any = None,
    num_scattering_orders: int | None = None,
    nu_size: int | None = None,
    scattering_density_sample_count: int | None = None,
    mu_s_size: int = 32,
) -> PrecomputationSampling:
    """Choose K, NU and S for a set, or check the values given against it.

    Parameters
    ----------
    atmosphere : Atmosphere
    tolerance : float, default 0.005
        Error allowed to the orders (path model) and to the scattering-density
        rule. [-]
    nu_tolerance : float, default 0.05
        Error allowed to the NU interpolation (:func:`nu_interpolation_error`). [-]
    wavelength_nm : array_like, optional
        The engine's wavelengths: Bruneton's three 680, 550, 440 nm, or every
        wavelength of the set (CosmoScout's passes; the default). [nm]
    num_scattering_orders, nu_size, scattering_density_sample_count : int, optional
        Values to use instead of the chosen ones; refused (``ValueError``
        naming the smallest value that does) if below what the set needs.
    mu_s_size : int, default 32
        ``SCATTERING_TEXTURE_MU_S_SIZE``: NU is at most ``2048 / mu_s_size``.

    Returns
    -------
    PrecomputationSampling

    Raises
    ------
    ValueError
        A given value below what the set needs at the tolerance (the message
        names the smallest that does), or a NU above ``2048 / mu_s_size``.
    """
    tol = check_open_interval("tolerance", tolerance, 0.0, 1.0)
    nu_tol = check_open_interval("nu_tolerance", nu_tolerance, 0.0, 1.0)
    wl = _wavelengths(wavelength_nm)
    scatterers = _scatterers(atmosphere, wl)
    used_wl = tuple(float(v) for v in (atmosphere.wavelength_nm if wl is None else wl))
    nu_cap = MAX_3D_TEXTURE_SIZE // int(mu_s_size)
    notes: list[str] = []
    if not scatterers:
        k, m, nu, s = 1, 0.0, BRUNETON_DEFAULTS["scattering_texture_nu_size"], 16
        nu_err = dens_err = nu_clear = 0.0
    else:
        m_all = _path_scatterings(scatterers)
        m = float(m_all.max())
        k = max(_orders_for(float(v), tol) for v in m_all)
        sizes = tuple(n for n in NU_SIZES if n <= nu_cap)
        nu_errs = _nu_errors(scatterers, sizes, nu_tol)
        nu = next((n for n in sizes if nu_errs[n][0] <= nu_tol), sizes[-1])
        capped = nu_errs[nu][0] > nu_tol
        if capped:
            notes.append(
                f"NU {nu}, the largest with NU x MU_S <= {MAX_3D_TEXTURE_SIZE} at MU_S {mu_s_size}, "
                f"leaves an estimated {nu_errs[nu][0]:.2g} of the sky radiance near the Sun; "
                f"within {nu_tol:g} beyond {nu_errs[nu][1]:.3g} deg from it"
            )
        dens = {}
        s = SCATTERING_DENSITY_SAMPLE_COUNTS[-1]
        for count in SCATTERING_DENSITY_SAMPLE_COUNTS:
            dens.update(_density_errors(scatterers, (count,)))
            if dens[count] <= tol:
                s = count
                break
        (nu_err, nu_clear), dens_err = nu_errs[nu], dens[s]
        if num_scattering_orders is not None:
            k = _check_given(
                "num_scattering_orders", num_scattering_orders, k,
                f"{tol:g} of the diffuse radiance would lie beyond it (m = {m:.3g})",
            )  # fmt: skip
        if nu_size is not None:
            if nu_size > nu_cap:
                raise ValueError(
                    f"nu_size {nu_size!r} makes the scattering texture {nu_size} x {mu_s_size} "
                    f"texels wide, more than GL_MAX_3D_TEXTURE_SIZE {MAX_3D_TEXTURE_SIZE}; at most "
                    f"{nu_cap}"
                )
            given = _nu_errors(scatterers, (int(nu_size),), nu_tol).get(int(nu_size), (0.0, 0.0))
            why = (
                f"its slices leave an estimated {given[0]:.2g} of the sky radiance near the Sun, "
                f"more than {nu_tol:g} up to {given[1]:.3g} deg from it"
            )
            smallest = "the smallest that does"
            if capped:
                why += (
                    f"; the largest NU a {MAX_3D_TEXTURE_SIZE}-texel-wide texture allows leaves "
                    f"{nu_err:.2g} (within {nu_tol:g} beyond {nu_clear:.3g} deg)"
                )
                smallest = "the least the set needs"
            nu = _check_given("nu_size", nu_size, nu, why, smallest)
            nu_err, nu_clear = _nu_errors(scatterers, (nu,), nu_tol)[nu]
        if scattering_density_sample_count is not None:
            s = _check_given(
                "scattering_density_sample_count", scattering_density_sample_count, s,
                f"its S x 2S directions would integrate the phase function to worse than {tol:g}",
            )  # fmt: skip
            dens_err = _density_errors(scatterers, (s,))[s]
    from scipy.stats import poisson  # here: see _orders_for above: ~0.4 s at import

    orders_err = 0.0 if m <= 0.0 else float(poisson.sf(k, m) / -math.expm1(-m))
    return PrecomputationSampling(
        tolerance=tol,
        num_scattering_orders=int(k),
        scattering_texture_nu_size=int(nu),
        scattering_density_sample_count=int(s),
        indirect_irradiance_sample_count=max(
            int(s), BRUNETON_DEFAULTS["indirect_irradiance_sample_count"]
        ),
        scattering_texture_mu_s_size=int(mu_s_size),
        mean_scatterings=m,
        orders_error=orders_err,
        nu_error=float(nu_err),
        nu_clear_angle_deg=float(nu_clear),
        scattering_density_error=float(dens_err),
        wavelength_nm=used_wl,
        notes=tuple(notes),
    )
