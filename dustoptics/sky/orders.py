"""Multiple scattering by successive orders in a layered column.

The diffuse radiance of the scaled (delta-M) problem is computed in the column
above the observer by successive orders of scattering, with discrete ordinates
in ``mu`` (double Gauss, ``n_streams`` nodes per hemisphere) and a Fourier
series in the azimuth ``phi`` relative to the Sun:

    I(z, mu, phi) = sum_m I^m(z, mu) cos(m phi),   m = 0 .. 2 n_streams - 1.

The phase function enters through its Legendre moments and the addition
theorem, with the normalized associated Legendre functions
``L_l^m = sqrt((l - m)! / (l + m)!) P_l^m``: order n + 1's source is

    J^m(mu) = (omega / 2) sum_l (2 l + 1) chi_l L_l^m(mu) sum_j w_j L_l^m(mu_j) I_n^m(mu_j)

and the first order's is the Sun's beam scattered once,
``omega F0 T(z) / (4 pi) (2 - delta_m0) sum_l (2 l + 1) chi_l L_l^m(mu) L_l^m(-mu0)``.
Each order's radiance is the formal solution through the layers with a source
linear in optical depth within each layer (exact integration of the
exponentials), downward from the top (no incoming diffuse light) and upward
from a Lambertian ground that reflects the previous order's downward flux
(the direct beam for the first order).  Orders are added until the estimated
remainder of the series, ``|I_n| r / (1 - r)`` with ``r`` the ratio of
successive orders' largest radiances, is below ``tol`` times the sum: that is
the stated tolerance of the diffuse field.

The Sun's beam is attenuated along its real, spherical path to each level
(``geometry="pseudo-spherical"``, so that a Sun a little below the horizon
still lights the upper layers) or as ``exp(-tau / mu0)``
(``"plane-parallel"``, for tests against plane-parallel references).

References
----------
.. [1] J. Lenoble (ed.), *Radiative Transfer in Scattering and Absorbing
   Atmospheres: Standard Computational Procedures*, A. Deepak (1985), ch. 5,
   successive orders of scattering.
.. [2] K. Stamnes, S.-C. Tsay, W. Wiscombe and K. Jayaweera, "Numerically
   stable algorithm for discrete-ordinate-method radiative transfer in
   multiple scattering and emitting layered media," Appl. Opt. 27, 2502-2509
   (1988), doi:10.1364/AO.27.002502 (the Fourier and Legendre conventions).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.polynomial import legendre
from scipy.special import gammaln, lpmv

from dustoptics._validation import check_choice, check_closed_interval
from dustoptics.sky.medium import Medium

__all__ = ["GEOMETRIES", "DiffuseField", "normalized_legendre", "solve_orders"]

GEOMETRIES: Final = ("pseudo-spherical", "plane-parallel")
_MAX_ORDERS: Final = 400


class SkyConvergenceWarning(UserWarning):
    """The orders of scattering did not reach the tolerance."""


def normalized_legendre(n_moments: int, mu: np.ndarray) -> np.ndarray:
    """``L_l^m(mu) = sqrt((l-m)!/(l+m)!) P_l^m(mu)`` for ``m, l < n_moments``.

    Returns shape ``(n_moments [m], n_moments [l]) + mu.shape``; zero where
    ``l < m``.
    """
    mu = np.asarray(mu, dtype=float)
    out = np.zeros((n_moments, n_moments) + mu.shape)
    for m in range(n_moments):
        for ell in range(m, n_moments):
            norm = math.exp(0.5 * (gammaln(ell - m + 1) - gammaln(ell + m + 1)))
            out[m, ell] = norm * lpmv(m, ell, mu)
    return out


def _double_gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


@dataclass(frozen=True)
class DiffuseField:
    """The converged diffuse radiance of the scaled problem in the column.

    Radiances are per unit solar irradiance on a surface normal to the beam
    (``F0 = 1``) [sr^-1]; ``mu`` is the cosine of the direction of
    propagation (``> 0`` upward).

    Attributes
    ----------
    mu0 : float
        Cosine of the Sun's zenith angle at the observer. [-]
    altitude_m : numpy.ndarray, shape (n_level,)
        Level altitudes, top first. [m]
    mu, weights : numpy.ndarray, shape (2 n_streams,)
        Ordinates (upward first) and their weights over [-1, 1]. [-]
    radiance : numpy.ndarray, shape (n_modes, n_wavelength, n_level, 2 n_streams)
        Fourier components of the diffuse radiance (all orders). [sr^-1]
    moments : numpy.ndarray, shape (n_modes, n_wavelength, n_level, n_modes)
        ``M_l^m = sum_j w_j L_l^m(mu_j) I^m(mu_j)``, from which the source of
        the next order is evaluated in any direction. [sr^-1]
    sun_transmittance : numpy.ndarray, shape (n_wavelength, n_level)
        Scaled direct-beam transmittance to each level. [-]
    ground_albedo : numpy.ndarray, shape (n_wavelength,)
        Lambertian albedo of the ground. [-]
    n_orders : int
        Orders of scattering summed.
    error_estimate : numpy.ndarray, shape (n_wavelength,)
        Estimated remainder of the series relative to the largest diffuse
        radiance. [-]
    geometry : str
        How the direct beam was attenuated.
    """

    mu0: float
    altitude_m: np.ndarray
    mu: np.ndarray
    weights: np.ndarray
    radiance: np.ndarray
    moments: np.ndarray
    sun_transmittance: np.ndarray
    ground_albedo: np.ndarray
    n_orders: int
    error_estimate: np.ndarray
    geometry: str

    @property
    def flux_down_diffuse(self) -> np.ndarray:
        """Diffuse downward flux at each level, shape (n_wavelength, n_level). [-]"""
        n = self.mu.size // 2
        i0 = self.radiance[0, :, :, n:]
        return 2.0 * np.pi * np.einsum("xkj,j->xk", i0, self.weights[n:] * -self.mu[n:])

    @property
    def flux_up(self) -> np.ndarray:
        """Upward (diffuse) flux at each level, shape (n_wavelength, n_level). [-]"""
        n = self.mu.size // 2
        i0 = self.radiance[0, :, :, :n]
        return 2.0 * np.pi * np.einsum("xkj,j->xk", i0, self.weights[:n] * self.mu[:n])

    @property
    def flux_down_direct(self) -> np.ndarray:
        """Direct-beam flux on a horizontal surface at each level (scaled). [-]"""
        return max(self.mu0, 0.0) * self.sun_transmittance


def _level_altitudes(top: float, n_layers: int) -> np.ndarray:
    u = np.linspace(1.0, 0.0, n_layers + 1)
    a = 4.0
    return top * np.expm1(a * u) / np.expm1(a)


def _layer_amounts(medium: Medium, z: np.ndarray) -> np.ndarray:
    # N0 int rho dz over each layer, shape (n_constituent, n_layer) [m^-2].
    cum = np.concatenate(
        [
            np.zeros((medium.relative_density.shape[0], 1)),
            np.cumsum(
                0.5
                * (medium.relative_density[:, 1:] + medium.relative_density[:, :-1])
                * np.diff(medium.altitude_m),
                axis=1,
            ),
        ],
        axis=1,
    )
    at = np.array([np.interp(z, medium.altitude_m, c) for c in cum])
    return (at[:, :-1] - at[:, 1:]) * medium.number_density_per_m3[:, None]


def _exit_weights(dtau: np.ndarray, mu: np.ndarray) -> tuple[np.ndarray, ...]:
    # For a source linear in tau across a layer: I_exit = I_enter E + J_exit a
    # + J_enter b, with a = 1 - mu (1 - E) / dtau, b = mu (1 - E) / dtau - E.
    x = dtau[..., None] / np.abs(mu)
    e = np.exp(-x)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.where(x > 1e-6, -np.expm1(-x) / np.where(x > 0, x, 1.0), 1.0 - 0.5 * x)
    return e, 1.0 - c, c - e


def solve_orders(
    medium: Medium,
    *,
    sun_zenith_deg: float,
    ground_albedo: float | np.ndarray = 0.0,
    n_layers: int = 120,
    tol: float = 1e-4,
    geometry: str = "pseudo-spherical",
) -> DiffuseField:
    """Diffuse radiance in the column by successive orders of scattering.

    Parameters
    ----------
    medium : Medium
        The atmosphere's optics.
    sun_zenith_deg : float
        Sun's zenith angle at the observer, 0 .. 100 (beyond 90 only with the
        pseudo-spherical geometry). [deg]
    ground_albedo : float or array_like
        Lambertian albedo, one value or one per wavelength, in [0, 1]. [-]
    n_layers : int
        Layers of the column (thin near the ground).
    tol : float
        Tolerance on the remainder of the series of orders. [-]
    geometry : {"pseudo-spherical", "plane-parallel"}
        Attenuation of the Sun's beam.

    Returns
    -------
    DiffuseField
    """
    check_choice("geometry", geometry, GEOMETRIES)
    sza = check_closed_interval("sun_zenith_deg", sun_zenith_deg, 0.0, 100.0)
    if geometry == "plane-parallel" and sza >= 90.0:
        raise ValueError(
            f"sun_zenith_deg must be < 90 deg for the plane-parallel geometry; got {sza!r}"
        )
    tol = check_closed_interval("tol", tol, 1e-10, 0.1)
    nwl = medium.wavelength_nm.size
    albedo = np.broadcast_to(np.asarray(ground_albedo, dtype=float), (nwl,)).copy()
    if not np.all((albedo >= 0) & (albedo <= 1)):
        raise ValueError(f"ground_albedo must be within [0, 1]; got {ground_albedo!r}")
    if not (isinstance(n_layers, int) and 4 <= n_layers <= 1000):
        raise ValueError(f"n_layers must be an integer in [4, 1000]; got {n_layers!r}")

    n = medium.n_streams
    n_mom = 2 * n
    mu0 = math.cos(math.radians(sza))
    x, w = _double_gauss(n)
    mu = np.concatenate([x, -x])
    weights = np.concatenate([w, w])
    lam = normalized_legendre(n_mom, mu)  # (m, l, d)
    lam0 = normalized_legendre(n_mom, np.array([-mu0]))[:, :, 0]  # (m, l)

    z = _level_altitudes(medium.top_altitude_m, n_layers)
    amount = _layer_amounts(medium, z)  # (c, k)
    sig_e = medium.scaled_sigma_ext_m2  # (c, x)
    sig_s = medium.scaled_sigma_sca_m2
    dtau = np.einsum("cx,ck->xk", sig_e, amount)  # (x, k)
    sca = np.einsum("cx,ck->xk", sig_s, amount)
    with np.errstate(invalid="ignore", divide="ignore"):
        omega = np.where(dtau > 0, sca / np.where(dtau > 0, dtau, 1.0), 0.0)
        chi = np.einsum("cx,ck,cxl->xkl", sig_s, amount, medium.scaled_chi)
        chi = np.where(sca[..., None] > 0, chi / np.where(sca > 0, sca, 1.0)[..., None], 0.0)
    two_l = 2.0 * np.arange(n_mom) + 1.0
    coef = 0.5 * omega[..., None] * two_l * chi  # (x, k, l)

    radius = medium.planet_radius_m + z
    if geometry == "pseudo-spherical":
        t_sun = medium.transmittance(radius, np.full(z.shape, mu0), scaled=True)  # (x, level)
    else:
        tau_cum = np.concatenate([np.zeros((nwl, 1)), np.cumsum(dtau, axis=1)], axis=1)
        t_sun = np.exp(-tau_cum / mu0)

    e, a_exit, b_enter = _exit_weights(dtau, mu[:n])  # (x, k, n)
    n_levels = z.size
    total = np.zeros((n_mom, nwl, n_levels, 2 * n))

    # First order: the Sun's beam scattered once, at each layer's two levels.
    dm0 = np.where(np.arange(n_mom) == 0, 1.0, 2.0)
    # beam[m, x, k, d] = (2 - d_m0)/(4 pi) sum_l (2l+1) chi_l omega L(mu_d) L(-mu0)
    beam = (
        np.einsum("xkl,mld,ml->mxkd", coef, lam, lam0) * (dm0 / (2.0 * np.pi))[:, None, None, None]
    )
    j_top = beam * t_sun[None, :, :-1, None]
    j_bot = beam * t_sun[None, :, 1:, None]
    flux_prev = max(mu0, 0.0) * t_sun[:, -1]  # direct beam at the ground
    prev_norm = None
    err = np.full(nwl, np.inf)
    n_orders = 0
    for order in range(1, _MAX_ORDERS + 1):
        n_orders = order
        field = _sweep(j_top, j_bot, e, a_exit, b_enter, albedo, flux_prev, n)
        total += field
        norm = np.abs(field).max(axis=(0, 2, 3))
        ref = np.abs(total).max(axis=(0, 2, 3))
        if prev_norm is not None:
            with np.errstate(invalid="ignore", divide="ignore"):
                r = np.where(prev_norm > 0, norm / np.where(prev_norm > 0, prev_norm, 1.0), 0.0)
                err = np.where(
                    ref > 0,
                    norm
                    * np.where(r < 1, r / (1 - np.minimum(r, 1 - 1e-12)), np.inf)
                    / np.where(ref > 0, ref, 1.0),
                    0.0,
                )
            if np.all(err <= tol):
                break
        prev_norm = norm
        # Next order's source from this order's radiance.
        mom = np.einsum("mld,d,mxkd->mxkl", lam, weights, field)  # (m, x, level, l)
        j_top = np.einsum("xkl,mxkl,mld->mxkd", coef, mom[:, :, :-1], lam)
        j_bot = np.einsum("xkl,mxkl,mld->mxkd", coef, mom[:, :, 1:], lam)
        flux_prev = 2.0 * np.pi * np.einsum("xj,j->x", field[0, :, -1, n:], w * x)
    else:
        warnings.warn(
            f"orders of scattering did not reach tol={tol:g} in {_MAX_ORDERS} orders "
            f"(estimate {float(np.max(err)):.2g})",
            SkyConvergenceWarning,
            stacklevel=2,
        )
    moments = np.einsum("mld,d,mxkd->mxkl", lam, weights, total)
    return DiffuseField(
        mu0=mu0,
        altitude_m=z,
        mu=mu,
        weights=weights,
        radiance=total,
        moments=moments,
        sun_transmittance=t_sun,
        ground_albedo=albedo,
        n_orders=n_orders,
        error_estimate=np.where(np.isfinite(err), err, 0.0),
        geometry=geometry,
    )


def _sweep(
    j_top: np.ndarray,
    j_bot: np.ndarray,
    e: np.ndarray,
    a_exit: np.ndarray,
    b_enter: np.ndarray,
    albedo: np.ndarray,
    ground_flux: np.ndarray,
    n: int,
) -> np.ndarray:
    """One order's radiance at every level from its layer sources."""
    n_mom, nwl, n_layers, _ = j_top.shape
    out = np.zeros((n_mom, nwl, n_layers + 1, 2 * n))
    # Downward: enter at the layer's top, exit at its bottom.
    down = np.zeros((n_mom, nwl, 2 * n - n))
    for k in range(n_layers):
        ek, ak, bk = e[None, :, k], a_exit[None, :, k], b_enter[None, :, k]
        down = down * ek + j_bot[:, :, k, n:] * ak + j_top[:, :, k, n:] * bk
        out[:, :, k + 1, n:] = down
    # Upward from the Lambertian ground (isotropic: the m = 0 term only).
    up = np.zeros((n_mom, nwl, n))
    up[0] = (albedo * ground_flux / np.pi)[:, None]
    out[:, :, n_layers, :n] = up
    for k in range(n_layers - 1, -1, -1):
        ek, ak, bk = e[None, :, k], a_exit[None, :, k], b_enter[None, :, k]
        up = up * ek + j_top[:, :, k, :n] * ak + j_bot[:, :, k, :n] * bk
        out[:, :, k, :n] = up
    return out
