"""Sky radiance seen by an observer: integration along lines of sight.

For each viewing direction the radiance reaching the observer is integrated
along the straight line of sight through the spherical shell, to the top of
the atmosphere or to the ground:

    L = int sum_c beta_sca,c(s) P_c(Theta) F0 T'_sun(s) T'(0, s) ds           (single scattering)
      + int sum_c N_c(s) sigma'_sca,c J'_c(s, mu_s, phi_s) T'(0, s) ds       (orders >= 2)
      + T'(0, s_g) (A / pi) E_ground                                         (the ground)
      + Delta L_aureole(Theta)                                               (secondary scattering)

Single scattering takes every constituent's tabulated phase function at the
scattering angle ``Theta`` (the angle between the view and the Sun) and the
Sun's path to each point in the spherical shell.  The orders >= 2 use the
converged diffuse field of :mod:`dustoptics.sky.orders` (delta-M scaled
problem, pseudo-spherical beam): its source function ``J'`` at each point's
altitude, evaluated exactly in the local direction of propagation from the
field's Legendre moments (a sum over ``l`` of ``L_l^m(mu)``, the levels'
moments interpolated linearly in altitude) and summed over the Fourier modes
at the local azimuth from the Sun.

Every beam, the Sun's and the line of sight, is attenuated with the delta-M
scaled extinction ``T'``, while the single scattering takes the true phase
function: this is Nakajima & Tanaka's TMS method (DISORT's intensity
correction does the same: the exact phase function over ``1 - f omega``,
with the scaled optical depths).  Light scattered into the truncated forward
peak (a few degrees wide for micron-sized dust) stays in the beam, as the
delta-M approximation assumes.

The truncation leaves one error that no affordable number of streams
removes: light scattered twice within the forward peak spreads over a few
to about twenty degrees around the Sun, where the delta-M problem keeps it
in the beam.  ``Delta L_aureole`` is Nakajima & Tanaka's IMS correction for
it, the second order of scattering in the column above the observer taken as
homogeneous: ``F0 / (4 pi) sum_l (2 l + 1) a_l P_l(cos Theta) xi(A, B)`` with
``a_l = (omega chi_l - omega f)^2 - (omega f)^2`` for ``l >= 2 n_streams`` and
``-(omega f)^2`` below (the column's scattering-weighted moments of the true
phase functions to :data:`~dustoptics.sky.medium.AUREOLE_MOMENTS`), and
``xi(A, B) = A B ((A - B - 1) e^-B + e^-A) / (A - B)^2`` the double-scattering
path integral with ``A`` the line of sight's optical depth to the top and
``B`` the Sun's scaled one.  It is applied in every direction (it vanishes
away from the Sun); with it the radiance is within 0.3 % of converged CDISORT
in every direction a plane-parallel model can judge (``scripts/sky_vs_disort.py``).

The line of sight is sampled at ``s_end expm1(a i / n) / expm1(a)`` (dense
near the observer) and integrated with a source function (emission over
scaled extinction) linear in optical depth between samples and each
segment's optical depth exact for densities exponential between samples.
Rays that share a view cosine (a row of the sky dome) share their samples,
view transmittances and diffuse source modes, computed once per row.  Only
the multiple-scattering source takes the column above the observer as
laterally uniform; single scattering and every transmittance are spherical.

Radiances are per unit solar irradiance normal to the beam (``F0 = 1``):
[sr^-1].  The direct Sun is not included.

References
----------
.. [1] T. Nakajima and M. Tanaka, "Algorithms for radiative intensity
   calculations in moderately thick atmospheres using a truncation
   approximation," J. Quant. Spectrosc. Radiat. Transfer 40, 51-69 (1988),
   doi:10.1016/0022-4073(88)90031-3.
.. [2] K. Stamnes, S.-C. Tsay, W. Wiscombe and I. Laszlo, "DISORT, a
   general-purpose Fortran program for discrete-ordinate-method radiative
   transfer in scattering and emitting layered media: documentation of
   methodology," report (2000), sec. 3.6 (TMS and IMS as DISORT applies them).
"""

from __future__ import annotations

import contextvars
import math
from concurrent.futures import ThreadPoolExecutor
from typing import Final, NamedTuple, TextIO

import numba
import numpy as np

from dustoptics._numba_cache import F8, F8_1D, F8_2D, I8, I8_1D, kernel
from dustoptics._validation import MEMORY_BUDGET_BYTES, BudgetError, check_budget
from dustoptics.sky._progress import Reporter, reporter
from dustoptics.sky._shared import geometry_memo, in_threads
from dustoptics.sky.medium import (
    _B1_1D,
    _F8_3D,
    _F8_4D,
    _I8_2D,
    Medium,
    MediumOptics,
    _interp_columns,
    _path_breaks,
    _scatters,
    _search_left,
    _sort_small,
)
from dustoptics.sky.orders import DiffuseField, normalized_legendre

__all__ = [
    "MODE_CUTOFF",
    "N_PATH",
    "WORK_BUDGET",
    "RenderCost",
    "aureole_correction",
    "check_render_cost",
    "estimate_render_cost",
    "line_of_sight_radiance",
    "source_modes",
    "source_table",
]

#: Samples of the direction-cosine grid of :func:`source_table`.
N_SOURCE_MU: Final = 181
#: Samples along each line of sight.
N_PATH: Final = 64
#: Stretch of the samples along a line of sight from the ground: dense near
#: the observer, where the densities are largest.
PATH_STRETCH: Final = 6.0
#: Largest work (multiply-adds) of one call without ``allow_large``: some
#: five minutes on two cores.
WORK_BUDGET: Final = 1e12
#: Bytes of the diffuse source's modes at the samples of the rows computed per call of the
#: kernels (between progress reports): 32 rows of the default dome.
_CHUNK_BYTES: Final = 32 * 2**20


def source_table(medium: Medium, field: DiffuseField) -> np.ndarray:
    """The multiple-scattering source per constituent on a grid of cosines.

    ``J_c^m(level, mu) = (1/2) sum_l (2 l + 1) chi'_{c,l} L_l^m(mu) M_l^m(level)``,
    on ``mu = linspace(-1, 1, N_SOURCE_MU)`` (direction of propagation).
    The renderer evaluates the same sum at each point's own direction.

    Returns
    -------
    numpy.ndarray, shape (n_constituent, n_modes, n_wavelength, n_level, N_SOURCE_MU)
        Per unit scaled scattering cross-section and number density. [sr^-1]
    """
    n_mom = 2 * medium.n_streams
    grid = np.linspace(-1.0, 1.0, N_SOURCE_MU)
    lam = normalized_legendre(n_mom, grid)  # (m, l, u)
    two_l = 2.0 * np.arange(n_mom) + 1.0
    chi = 0.5 * two_l * medium.scaled_chi  # (c, x, l)
    weighted = chi[:, None, :, None, :] * field.moments[None]  # (c, m, x, k, l)
    return np.einsum("cmxkl,mlu->cmxku", weighted, lam, optimize=True)


#: Fourier modes of the multiple-scattering source whose largest contribution
#: to the emission (over levels, directions and wavelengths) is below this
#: fraction of the largest mode-0 contribution are dropped: 100 times below
#: the default tolerance of the orders, so dropping them changes no radiance
#: by more than 1e-6 of the brightest diffuse source.
MODE_CUTOFF: Final = 1e-6


def source_modes(medium: Medium, field: DiffuseField) -> np.ndarray:
    """Fourier modes kept per constituent: 1 + the last mode above :data:`MODE_CUTOFF`.

    The size of constituent c's source in mode m, weighted by its scaled
    scattering coefficient ``N0 sigma'_sca``, is bounded (``|L_l^m| <= 1``)
    by ``N0 sigma'_sca (1/2) sum_l (2 l + 1) |chi'_l M_l^m|``, the largest over
    levels and wavelengths; modes beyond the last one whose bound is above
    the cutoff times the largest mode-0 bound are left out of the
    line-of-sight sums (exactly zero for Rayleigh scattering beyond m = 2 and
    for a pure absorber).

    Parameters
    ----------
    medium : Medium
        The atmosphere's optics.
    field : DiffuseField
        The converged diffuse field.

    Returns
    -------
    numpy.ndarray of int64, shape (n_constituent,)
    """
    n_mom = 2 * medium.n_streams
    two_l = 2.0 * np.arange(n_mom) + 1.0
    chi = np.abs(0.5 * two_l * medium.scaled_chi)  # (c, x, l)
    weight = medium.scaled_sigma_sca_m2 * medium.number_density_per_m3[:, None]  # (c, x)
    bound = np.einsum("cxl,mxkl->cmxk", chi, np.abs(field.moments)) * weight[:, None, :, None]
    size = bound.max(axis=(2, 3))  # (c, m)
    ref = size[:, 0].max()
    out = np.zeros(size.shape[0], dtype=np.int64)
    if ref <= 0.0:
        return out
    for c, row in enumerate(size):
        above = np.nonzero(row > MODE_CUTOFF * ref)[0]
        out[c] = above[-1] + 1 if above.size else 0
    return out


def _packed_index(n_mom: int, n_modes: int) -> np.ndarray:
    # Offset of (m, l = m) in the packed (m, l >= m) layout, m < n_modes (+ the end).
    sizes = n_mom - np.arange(n_modes)
    return np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)


def _source_coefficients(
    medium: Medium, field: DiffuseField, scatterers: np.ndarray, n_modes: int
) -> np.ndarray:
    """``(1/2) (2 l + 1) chi'_{c,l} M_l^m(level)``, packed as :func:`_source_kernel` reads it.

    Shape (n_level, n_scatterer, packed (m, l >= m), n_wavelength).
    """
    n_mom = 2 * medium.n_streams
    two_l = 2.0 * np.arange(n_mom) + 1.0
    chi = np.ascontiguousarray(0.5 * two_l * medium.scaled_chi[scatterers])  # (c, x, l)
    offsets = _packed_index(n_mom, n_modes)
    n_level = field.altitude_m.size
    out = np.empty((n_level, scatterers.size, int(offsets[-1]), medium.wavelength_nm.size))
    _pack_coefficients(chi, field.moments, offsets, out)
    return out


@kernel(_F8_3D, _F8_4D, I8_1D, _F8_4D, group="sky")
def _pack_coefficients(
    chi: np.ndarray, moments: np.ndarray, offsets: np.ndarray, out: np.ndarray
) -> None:
    # out[k, q, offsets[m] + l - m, x] = chi[q, x, l] M[m, x, k, l], l >= m.
    n_level, n_s, _, nwl = out.shape
    n_mom = chi.shape[2]
    for k in range(n_level):
        for q in range(n_s):
            for m in range(offsets.shape[0] - 1):
                for ell in range(m, n_mom):
                    p = offsets[m] + ell - m
                    for x in range(nwl):
                        out[k, q, p, x] = chi[q, x, ell] * moments[m, x, k, ell]


@numba.njit(cache=True, nogil=True)
def _normalized_legendre_packed(mu: float, n_mom: int, n_modes: int, out: np.ndarray) -> None:
    """``L_l^m(mu)`` (the normalization of :func:`normalized_legendre`) packed by (m, l >= m)."""
    s = math.sqrt(max(0.0, 1.0 - mu * mu))
    mm = 1.0  # L_m^m
    p = 0
    for m in range(n_modes):
        if m > 0:
            mm = -mm * s * math.sqrt((2.0 * m - 1.0) / (2.0 * m))
        out[p] = mm
        if m + 1 < n_mom:
            prev, cur = mm, math.sqrt(2.0 * m + 1.0) * mu * mm
            out[p + 1] = cur
            for ell in range(m + 1, n_mom - 1):
                nxt = ((2.0 * ell + 1.0) * mu * cur - math.sqrt((ell - m) * (ell + m)) * prev) / (
                    math.sqrt((ell + 1.0 - m) * (ell + 1.0 + m))
                )
                prev, cur = cur, nxt
                out[p + ell + 1 - m] = cur
        p += n_mom - m


@numba.njit(cache=True, nogil=True)
def _phi_b(t: float) -> float:
    # (1 - e^-t (1 + t)) / t, the weight of the far end of a linear source.
    if t < 1e-4:
        return t * (0.5 - t * (1.0 / 3.0 - t * 0.125))
    return -(math.expm1(-t) + t * math.exp(-t)) / t


@numba.njit(cache=True, nogil=True)
def _log_mean(a: float, b: float) -> float:
    # Mean of a quantity exponential between two samples (arithmetic if one is 0).
    if a <= 0.0 or b <= 0.0:
        return 0.5 * (a + b)
    r = a / b
    if abs(r - 1.0) < 1e-6:
        return 0.5 * (a + b)
    return (a - b) / math.log(r)


@kernel(
    I8,
    I8,
    F8_1D,
    F8,
    F8,
    F8,
    I8,
    F8,
    F8_1D,
    F8_2D,
    F8_2D,
    F8_1D,
    F8_1D,
    _F8_3D,
    _F8_3D,
    _F8_3D,
    _I8_2D,
    F8_2D,
    _B1_1D,
    group="sky",
)
def _row_kernel(
    lo: int,
    hi: int,
    mu_rows: np.ndarray,
    r0: float,
    r_top: float,
    r_ground: float,
    n_path: int,
    stretch: float,
    altitude: np.ndarray,
    density: np.ndarray,
    sig_ext_scaled: np.ndarray,
    level_altitude: np.ndarray,
    edges: np.ndarray,
    geo: np.ndarray,
    dens_out: np.ndarray,
    wb: np.ndarray,
    level: np.ndarray,
    t_end: np.ndarray,
    hits: np.ndarray,
) -> None:
    """Rows ``lo .. hi - 1`` (one view cosine each): samples, densities, path weights, the levels around each sample.

    ``wb[row, i, x]`` is sample i's weight in the path integral over its
    scaled extinction (multiplies the emission); ``level[row, i]`` is the
    upper of the two levels of the diffuse field that bracket sample i and
    ``geo[row, i, 3]`` the sample's fraction of the way to the lower one.
    The samples are the ``n_path + 1`` stretched ones and the row's crossings
    of the ``edges`` (altitudes [m]), sorted; the unused places at the end
    repeat the last sample (segments of length 0, weight 0).
    """
    n_c, nwl = sig_ext_scaled.shape
    n_lev = level_altitude.shape[0]
    nz = altitude.shape[0]
    a = stretch
    norm = math.expm1(a)
    for row in range(lo, hi):
        mv = mu_rows[row]
        b = r0 * mv
        disc_g = b * b - (r0 * r0 - r_ground * r_ground)
        ground = mv < 0.0 and disc_g >= 0.0
        if ground:
            s_end = -b - math.sqrt(disc_g)
        else:
            s_end = -b + math.sqrt(max(0.0, b * b + r_top * r_top - r0 * r0))
        hits[row] = ground
        beta = np.empty(nwl)
        beta_prev = np.empty(nwl)
        tau = np.zeros(nwl)
        n_samples = geo.shape[1]
        s_all = np.empty(n_samples)
        for i in range(n_samples):
            s_all[i] = s_end * math.expm1(a * i / n_path) / norm if i <= n_path else s_end
        crossings = _path_breaks(r0, mv, s_end, r_ground, edges)
        if crossings.size:
            for i in range(crossings.size):
                s_all[n_path + 1 + i] = crossings[i]
            _sort_small(s_all)
        for i in range(n_samples):
            s = s_all[i]
            x_r = math.sqrt(max(r0 * r0 + s * s + 2.0 * r0 * s * mv, 0.0))
            z = x_r - r_ground
            mu_loc = min(max((r0 * mv + s) / x_r, -1.0), 1.0)
            geo[row, i, 0] = s
            geo[row, i, 1] = x_r
            geo[row, i, 2] = mu_loc
            iz = _search_left(altitude, z) - 1
            iz = min(max(iz, 0), nz - 2)
            fz = (z - altitude[iz]) / (altitude[iz + 1] - altitude[iz])
            fz = min(max(fz, 0.0), 1.0)
            for c in range(n_c):
                dens_out[row, i, c] = density[c, iz] * (1.0 - fz) + density[c, iz + 1] * fz
            for x in range(nwl):
                acc = 0.0
                for c in range(n_c):
                    acc += sig_ext_scaled[c, x] * dens_out[row, i, c]
                beta[x] = acc
            if i > 0:
                ds = s - geo[row, i - 1, 0]
                for x in range(nwl):
                    dt = 0.0
                    for c in range(n_c):
                        dt += sig_ext_scaled[c, x] * _log_mean(
                            dens_out[row, i - 1, c], dens_out[row, i, c]
                        )
                    dt *= ds
                    # The previous sample's weight gains its share of this segment.
                    e0 = math.exp(-tau[x])
                    pb = _phi_b(dt)
                    pa = -math.expm1(-dt) - pb
                    w_prev = wb[row, i - 1, x] + e0 * pa
                    wb[row, i - 1, x] = w_prev / beta_prev[x] if beta_prev[x] > 0.0 else 0.0
                    wb[row, i, x] = e0 * pb
                    tau[x] += dt
            else:
                for x in range(nwl):
                    wb[row, i, x] = 0.0
            for x in range(nwl):
                beta_prev[x] = beta[x]
            # The diffuse field's levels (descending altitudes) around the sample.
            k = 0
            while k < n_lev - 2 and level_altitude[k + 1] > z:
                k += 1
            fk = (level_altitude[k] - z) / (level_altitude[k] - level_altitude[k + 1])
            level[row, i] = k
            geo[row, i, 3] = min(max(fk, 0.0), 1.0)
        # The last sample's weight over its extinction.
        for x in range(nwl):
            wb[row, n_samples - 1, x] = (
                wb[row, n_samples - 1, x] / beta[x] if beta[x] > 0.0 else 0.0
            )
            t_end[row, x] = math.exp(-tau[x])


@kernel(
    I8,
    I8,
    I8_1D,
    _F8_3D,
    _F8_3D,
    _F8_3D,
    _I8_2D,
    F8_2D,
    _F8_4D,
    I8_1D,
    I8_1D,
    I8,
    _F8_4D,
    group="sky",
)
def _source_kernel(
    lo: int,
    hi: int,
    samples: np.ndarray,
    geo: np.ndarray,
    dens: np.ndarray,
    wb: np.ndarray,
    level: np.ndarray,
    sig_sca_scaled: np.ndarray,
    coeffs: np.ndarray,
    scatterers: np.ndarray,
    modes_used: np.ndarray,
    n_mom: int,
    g: np.ndarray,
) -> None:
    """The diffuse source's Fourier modes at samples ``samples[lo:hi]``, times their path weights.

    ``g[row, i, m, x] = wb[row, i, x] sum_c N_c sigma'_sca,c J_c^m(z_i, mu_i)``,
    ``J^m`` summed over ``l`` in the sample's own direction of propagation
    (``L_l^m(-mu_loc)``) from the moments of the two levels around it (linear
    in altitude).  ``samples`` lists the flat indices ``row * n_samples + i``
    sorted by level, so that each thread reads one level's coefficients for
    many samples in a row (they are tens of megabytes: read once per sample
    they made this step memory-bound).  The threads take contiguous parts of
    ``samples``.
    """
    n_samples = geo.shape[1]
    n_s = scatterers.shape[0]
    nwl = sig_sca_scaled.shape[1]
    n_modes = g.shape[2]
    n_packed = coeffs.shape[2]
    for j in range(lo, hi):
        flat = samples[j]
        row = flat // n_samples
        i = flat - row * n_samples
        lv = np.empty(n_packed)
        tsum = np.empty(nwl)
        _normalized_legendre_packed(-geo[row, i, 2], n_mom, n_modes, lv)
        k = level[row, i]
        fk = geo[row, i, 3]
        for m in range(n_modes):
            for x in range(nwl):
                g[row, i, m, x] = 0.0
        for q in range(n_s):
            c = scatterers[q]
            d = dens[row, i, c]
            if d == 0.0:
                continue
            p = 0
            for m in range(n_modes):
                if m >= modes_used[q]:
                    break
                for x in range(nwl):
                    tsum[x] = 0.0
                for _ell in range(m, n_mom):
                    w0 = lv[p] * (1.0 - fk)
                    w1 = lv[p] * fk
                    for x in range(nwl):
                        tsum[x] += w0 * coeffs[k, q, p, x] + w1 * coeffs[k + 1, q, p, x]
                    p += 1
                for x in range(nwl):
                    g[row, i, m, x] += d * sig_sca_scaled[c, x] * tsum[x]
        for m in range(n_modes):
            for x in range(nwl):
                g[row, i, m, x] *= wb[row, i, x]


@kernel(
    I8,
    I8,
    I8_1D,
    F8_1D,
    F8_1D,
    F8_1D,
    F8,
    F8_1D,
    F8_2D,
    F8_2D,
    _F8_3D,
    F8_1D,
    F8_1D,
    _F8_3D,
    _F8_3D,
    _F8_3D,
    _F8_3D,
    _F8_4D,
    F8_2D,
    _B1_1D,
    F8_1D,
    F8_1D,
    F8_2D,
    group="sky",
)
def _ray_kernel(
    lo: int,
    hi: int,
    row_start: np.ndarray,
    mu_view: np.ndarray,
    phi_view: np.ndarray,
    mu_sun_ray: np.ndarray,
    r0: float,
    n0: np.ndarray,
    sig_sca: np.ndarray,
    sig_ext_scaled: np.ndarray,
    phase_ss: np.ndarray,
    radius_grid: np.ndarray,
    mu_grid: np.ndarray,
    columns: np.ndarray,
    geo: np.ndarray,
    dens: np.ndarray,
    wb: np.ndarray,
    g: np.ndarray,
    t_end: np.ndarray,
    hits: np.ndarray,
    ground_albedo: np.ndarray,
    ground_diffuse: np.ndarray,
    out: np.ndarray,
) -> None:
    """Radiance ``out`` of the rays of rows ``lo .. hi - 1``: single scattering, the ground,
    the diffuse source.

    Rays ``row_start[row] .. row_start[row + 1]`` belong to ``row``; the diffuse
    source at a sample is the row's modes ``g[row, i, m]`` times ``cos(m phi)``
    at the sample's own azimuth from the Sun.  A thread takes a row and walks
    its samples, each sample's modes used by every ray of the row while they
    are in the cache.
    """
    n_modes = g.shape[2]
    n_c, nwl = sig_ext_scaled.shape
    n_samples = geo.shape[1]
    r_ground = radius_grid[0]
    for row in range(lo, hi):
        first = row_start[row]
        n_ray = row_start[row + 1] - first
        if n_ray == 0:
            continue
        acc = np.zeros((n_ray, nwl))
        diffuse = np.zeros((n_ray, nwl))
        cos_theta = np.empty(n_ray)
        col = np.zeros(n_c)
        cm = np.empty(max(n_modes, 2))
        for r in range(n_ray):
            ray = first + r
            mu_sun = mu_sun_ray[ray]
            sin_sun = math.sqrt(max(0.0, 1.0 - mu_sun * mu_sun))
            mv = mu_view[ray]
            sv = math.sqrt(max(0.0, 1.0 - mv * mv))
            cos_theta[r] = mv * mu_sun + sv * sin_sun * math.cos(phi_view[ray])
        for i in range(n_samples):
            s = geo[row, i, 0]
            x_r = geo[row, i, 1]
            mu_loc = geo[row, i, 2]
            sl = math.sqrt(max(0.0, 1.0 - mu_loc * mu_loc))
            for r in range(n_ray):
                ray = first + r
                mus_loc = (r0 * mu_sun_ray[ray] + s * cos_theta[r]) / x_r
                # Single scattering, the Sun's beam through the shell.
                if _interp_columns(x_r, mus_loc, radius_grid, mu_grid, columns, col):
                    for x in range(nwl):
                        tau_sun = 0.0
                        ss = 0.0
                        for c in range(n_c):
                            tau_sun += sig_ext_scaled[c, x] * col[c] * n0[c]
                            ss += sig_sca[c, x] * dens[row, i, c] * phase_ss[ray, c, x]
                        acc[r, x] += wb[row, i, x] * ss * math.exp(-tau_sun)
                if n_modes == 0:
                    continue
                # Diffuse source: its modes at the local azimuth from the Sun.
                ssl = math.sqrt(max(0.0, 1.0 - mus_loc * mus_loc))
                if sl * ssl > 1e-12:
                    cphi = (cos_theta[r] - mu_loc * mus_loc) / (sl * ssl)
                    cphi = min(max(cphi, -1.0), 1.0)
                else:
                    cphi = 1.0
                cm[0] = 1.0
                cm[1] = cphi
                for m in range(2, n_modes):
                    cm[m] = 2.0 * cphi * cm[m - 1] - cm[m - 2]
                for m in range(n_modes):
                    w = cm[m]
                    for x in range(nwl):
                        diffuse[r, x] += w * g[row, i, m, x]
        for r in range(n_ray):
            ray = first + r
            if hits[row]:
                s_end = geo[row, n_samples - 1, 0]
                mus_g = (r0 * mu_sun_ray[ray] + s_end * cos_theta[r]) / r_ground
                lit = mus_g > 0.0 and _interp_columns(
                    r_ground, mus_g, radius_grid, mu_grid, columns, col
                )
                for x in range(nwl):
                    direct = 0.0
                    if lit:
                        tau_sun = 0.0
                        for c in range(n_c):
                            tau_sun += sig_ext_scaled[c, x] * col[c] * n0[c]
                        direct = mus_g * math.exp(-tau_sun)
                    e_g = ground_albedo[x] / math.pi * (direct + ground_diffuse[x])
                    acc[r, x] += e_g * t_end[row, x]
            for x in range(nwl):
                out[ray, x] = acc[r, x] + diffuse[r, x]


class RenderCost(NamedTuple):
    """What :func:`estimate_render_cost` expects a line-of-sight call to need."""

    memory_bytes: float
    work: float


def estimate_render_cost(
    medium: Medium | MediumOptics, *, n_rays: int, n_rows: int, n_path: int
) -> RenderCost:
    """Estimate the memory and work of the line-of-sight integration.

    Memory: the radiances and single-scattering phases of every ray, the
    diffuse source's coefficients at every level, and one chunk of rows'
    samples and source modes.  Work: per row and sample, the diffuse source
    (every scattering constituent's packed moments at two levels); per ray and
    sample, the source modes and the single scattering at every wavelength.

    Parameters
    ----------
    medium : Medium or MediumOptics
        The atmosphere's optics.
    n_rays, n_rows : int
        Lines of sight, and distinct view cosines among them.
    n_path : int
        Samples along each line of sight.

    Returns
    -------
    RenderCost
    """
    n_mom = 2 * medium.n_streams
    nwl = medium.wavelength_nm.size
    n_c = len(medium.tables)
    n_s = sum(1 for t in medium.tables if _scatters(t))
    packed = n_mom * (n_mom + 1) / 2.0
    levels = 121.0
    chunk = _rows_per_chunk(n_rows, n_path, n_mom, nwl)
    memory = 8.0 * (
        n_rays * nwl * (3 + n_c)
        + levels * n_s * packed * nwl
        + chunk * (n_path + 1) * (n_mom + 2 + n_c) * nwl
    )
    work = (
        n_rows * (n_path + 1) * 2.0 * n_s * packed * nwl
        + n_rays * (n_path + 1) * (n_mom + 2 * n_c + 8) * nwl
    )
    return RenderCost(memory, work)


def check_render_cost(
    medium: Medium | MediumOptics,
    *,
    n_rays: int,
    n_rows: int,
    n_path: int,
    allow_large: bool,
    what: str,
) -> RenderCost:
    """:func:`estimate_render_cost`, then refuse a request beyond the budget.

    Raises
    ------
    dustoptics._validation.BudgetError
        Estimated memory above :data:`dustoptics._validation.MEMORY_BUDGET_BYTES`
        or work above :data:`WORK_BUDGET`, and ``allow_large`` is False; the
        message names the number of lines of sight and the largest allowed.
    """
    cost = estimate_render_cost(medium, n_rays=n_rays, n_rows=n_rows, n_path=n_path)
    if allow_large:
        return cost
    per_ray_mem = cost.memory_bytes / max(n_rays, 1)
    per_ray_work = cost.work / max(n_rays, 1)
    largest = int(min(MEMORY_BUDGET_BYTES / per_ray_mem, WORK_BUDGET / per_ray_work))
    change = (
        f"{what} must be at most about {largest} lines of sight with "
        f"{medium.wavelength_nm.size} wavelengths, n_streams={medium.n_streams} and "
        f"n_path={n_path}; ask for fewer directions"
    )
    label = f"the line-of-sight integration ({n_rays} lines of sight)"
    check_budget(label, cost.memory_bytes, allow_large=False, change=change)
    if cost.work > WORK_BUDGET:
        raise BudgetError(
            f"{label} would need about {cost.work:.3g} multiply-adds, beyond the budget of "
            f"{WORK_BUDGET:g} (about five minutes); {change}, or pass allow_large=True "
            "(--allow-large on the command line) to go ahead"
        )
    return cost


def _xi(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # A B ((A - B - 1) e^-B + e^-A) / (A - B)^2, and A^2 e^-A / 2 where A = B.
    d = a - b
    near = np.abs(d) < 1e-4 * np.maximum(1.0, np.abs(a))
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        far = a * b * ((d - 1.0) * np.exp(-b) + np.exp(-a)) / np.where(near, 1.0, d * d)
        # Series about A = B: A^2 e^-A (1/2 + d/6 + ...) with b = a - d.
        close = a * b * np.exp(-b) * (0.5 - d / 6.0)
    return np.where(near, close, far)


#: Scattering angles of the tabulated aureole correction. [deg]
_AUREOLE_THETA_DEG: Final = np.linspace(0.0, 180.0, 3601)


def _aureole_basis(n_moments: int) -> np.ndarray:
    # (2 l + 1) / (4 pi) P_l(cos theta) on _AUREOLE_THETA_DEG, shape (theta, l).
    ell = np.arange(n_moments)
    grid = np.cos(np.deg2rad(_AUREOLE_THETA_DEG))
    p_l = np.polynomial.legendre.legvander(grid, ell[-1])
    out = p_l * ((2 * ell + 1) / (4.0 * np.pi))
    out.setflags(write=False)
    return out


def aureole_correction(
    medium: Medium,
    *,
    theta_deg: np.ndarray,
    view_optical_depth: np.ndarray,
    sun_optical_depth: np.ndarray,
    column_optical_depth: np.ndarray | None = None,
) -> np.ndarray:
    """Nakajima & Tanaka's IMS correction of the secondary scattering (per unit F0).

    ``Delta L = (1 / 4 pi) sum_l (2 l + 1) a_l P_l(cos Theta) xi(A, B)``, the
    column above the observer taken as homogeneous (its scattering-weighted
    moments; see the module's docstring).

    Parameters
    ----------
    medium : Medium
        The atmosphere's optics (``chi`` to :data:`~dustoptics.sky.medium.AUREOLE_MOMENTS`).
    theta_deg : array_like, shape (n,)
        Scattering angles. [deg]
    view_optical_depth : array_like, shape (n, n_wavelength)
        ``A``: true optical depth of each line of sight to the top. [-]
    sun_optical_depth : array_like, shape (n, n_wavelength)
        ``B``: scaled optical depth of the Sun's path to the observer. [-]
    column_optical_depth : array_like, shape (n_constituent, n_wavelength), optional
        Vertical optical depth of each constituent above the observer
        (default the whole column). [-]

    Returns
    -------
    numpy.ndarray, shape (n, n_wavelength)
        The correction to add to the radiance. [sr^-1]
    """
    n_mom = 2 * medium.n_streams
    tau_c = (
        medium.vertical_optical_depth() if column_optical_depth is None else column_optical_depth
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        ssa = np.where(
            medium.sigma_ext_m2 > 0,
            medium.sigma_sca_m2 / np.where(medium.sigma_ext_m2 > 0, medium.sigma_ext_m2, 1.0),
            0.0,
        )
    tau_sca = tau_c * ssa  # (c, x)
    tau = tau_c.sum(axis=0)
    safe = np.where(tau > 0, tau, 1.0)
    w_chi = np.einsum("cx,cxl->xl", tau_sca, medium.chi) / safe[:, None]  # omega chi_l
    w_f = (tau_sca * medium.truncation).sum(axis=0) / safe  # omega f
    a = (w_chi - w_f[:, None]) ** 2 - w_f[:, None] ** 2
    a[:, :n_mom] = -(w_f[:, None] ** 2)
    a[tau <= 0] = 0.0
    table = (
        geometry_memo(("aureole-legendre", a.shape[1]), lambda: _aureole_basis(a.shape[1])) @ a.T
    )
    th = np.asarray(theta_deg, dtype=float)
    idx = np.clip(th / 0.05, 0.0, _AUREOLE_THETA_DEG.size - 1.0)
    i0 = np.minimum(idx.astype(np.int64), _AUREOLE_THETA_DEG.size - 2)
    f = (idx - i0)[:, None]
    c = table[i0] * (1.0 - f) + table[i0 + 1] * f  # (n, x)
    return c * _xi(np.asarray(view_optical_depth, float), np.asarray(sun_optical_depth, float))


def line_of_sight_radiance(
    medium: Medium,
    field: DiffuseField,
    *,
    view_zenith_deg: np.ndarray,
    view_azimuth_deg: np.ndarray,
    observer_altitude_m: float = 2.0,
    n_path: int = N_PATH,
    aureole: bool = True,
    progress: TextIO | Reporter | None = None,
    allow_large: bool = False,
) -> np.ndarray:
    """Sky radiance in viewing directions from an observer in the atmosphere.

    Parameters
    ----------
    medium : Medium
        The atmosphere's optics.
    field : DiffuseField
        The converged diffuse field for the Sun's zenith angle at the observer.
    view_zenith_deg : array_like
        Zenith angles of the viewing directions, 0 .. 180. [deg]
    view_azimuth_deg : array_like
        Azimuths of the viewing directions from the Sun's azimuth (same
        shape). [deg]
    observer_altitude_m : float
        Observer above the ground, below the top. [m]
    n_path : int
        Samples along each line of sight.
    aureole : bool
        Add the secondary-scattering correction (:func:`aureole_correction`).
    progress : text stream, optional
        Where to report the lines of sight done after the first two seconds
        (e.g. ``sys.stderr``); None is silent.
    allow_large : bool
        Go ahead beyond the memory and work budget (:func:`check_render_cost`).

    Returns
    -------
    numpy.ndarray, shape view_zenith_deg.shape + (n_wavelength,)
        Radiance per unit solar irradiance. [sr^-1]
    """
    vz = np.asarray(view_zenith_deg, dtype=float)
    va = np.asarray(view_azimuth_deg, dtype=float)
    if vz.shape != va.shape:
        raise ValueError(
            f"view_zenith_deg and view_azimuth_deg must have the same shape; got {vz.shape} "
            f"and {va.shape}"
        )
    if not (np.all(np.isfinite(vz)) and np.all((vz >= 0) & (vz <= 180))):
        raise ValueError("view_zenith_deg must be finite and within [0, 180] deg")
    if not np.all(np.isfinite(va)):
        raise ValueError("view_azimuth_deg must be finite")
    h = float(observer_altitude_m)
    if not (0.0 <= h < medium.top_altitude_m):
        raise ValueError(
            f"observer_altitude_m must be within [0, {medium.top_altitude_m:g}) m (inside the "
            f"atmosphere); got {observer_altitude_m!r}"
        )
    if not (isinstance(n_path, int) and 4 <= n_path <= 100_000):
        raise ValueError(f"n_path must be an integer in [4, 100000]; got {n_path!r}")
    mu_view = np.cos(np.deg2rad(vz)).ravel()
    phi_view = np.deg2rad(va).ravel()
    radius = medium.planet_radius_m + h
    # The aureole correction (vectorized numpy, 0.2-0.3 s) in a thread of its own beside the
    # lines of sight, whose serial parts leave a core free; added as before.
    with ThreadPoolExecutor(max_workers=1) as pool:
        correction = None
        if aureole and field.mu0 > 0.0:
            context = contextvars.copy_context()  # the caller's shared geometry

            def aureole_part() -> np.ndarray:
                return _aureole_for_observer(medium, field, mu_view, phi_view, radius)

            correction = pool.submit(context.run, aureole_part)
        out = _radiance(
            medium,
            field,
            mu_view=mu_view,
            phi_view=phi_view,
            mu_sun=np.full(mu_view.shape, field.mu0),
            radius_m=radius,
            n_path=n_path,
            report=reporter(progress),
            allow_large=allow_large,
        )
        if correction is not None:
            out += correction.result()
    return out.reshape(vz.shape + (medium.wavelength_nm.size,))


def _aureole_for_observer(
    medium: Medium, field: DiffuseField, mu_view: np.ndarray, phi_view: np.ndarray, radius: float
) -> np.ndarray:
    """:func:`aureole_correction` for lines of sight upward from radius ``radius``."""
    mu0 = field.mu0
    cos_t = np.clip(
        mu_view * mu0
        + np.sqrt(np.maximum(0.0, 1 - mu_view**2)) * math.sqrt(1 - mu0**2) * np.cos(phi_view),
        -1.0,
        1.0,
    )
    up = mu_view > 0.0
    out = np.zeros((mu_view.size, medium.wavelength_nm.size))
    if not np.any(up):
        return out
    r = np.full(int(up.sum()), radius)
    view = -np.log(np.maximum(medium.transmittance(r, mu_view[up]), 1e-300)).T  # (n, x)
    sun = -np.log(
        np.maximum(medium.transmittance(np.array([radius]), np.array([mu0]), scaled=True), 1e-300)
    ).T  # (1, x)
    vertical = medium.slant.columns(np.array([radius]), np.array([1.0]))[:, 0]  # (c,)
    column = medium.sigma_ext_m2 * (medium.number_density_per_m3 * vertical)[:, None]
    out[up] = aureole_correction(
        medium,
        theta_deg=np.rad2deg(np.arccos(cos_t[up])),
        view_optical_depth=view,
        sun_optical_depth=np.broadcast_to(sun, view.shape),
        column_optical_depth=column,
    )
    return out


def _rows_per_chunk(n_rows: int, n_path: int, n_modes: int, nwl: int) -> int:
    # Rows whose samples' source modes (the largest buffer) fit in _CHUNK_BYTES.
    per_row = 8.0 * (n_path + 1) * (max(n_modes, 1) + 2) * nwl
    return int(max(1, min(n_rows, _CHUNK_BYTES // per_row)))


def _radiance(
    medium: Medium,
    field: DiffuseField,
    *,
    mu_view: np.ndarray,
    phi_view: np.ndarray,
    mu_sun: np.ndarray,
    radius_m: float,
    n_path: int,
    stretch: float = PATH_STRETCH,
    report: Reporter | None = None,
    allow_large: bool = False,
) -> np.ndarray:
    """Radiance along rays from radius ``radius_m`` (checked by the callers).

    Each ray has its own view cosine, azimuth from the Sun [rad] and Sun
    cosine at its start; the multiple-scattering source is ``field``'s.
    Samples along each ray are at ``s_end expm1(stretch i / n) / expm1(stretch)``
    (dense near the start; nearly uniform for a small ``stretch``).  Rays with
    the same view cosine share their samples (a row).
    Returns shape (n_rays, n_wavelength). [sr^-1]
    """
    report = report if report is not None else reporter(None)
    mu_rows, ray_row = np.unique(np.asarray(mu_view, dtype=float), return_inverse=True)
    ray_row = ray_row.ravel()
    n_rays = mu_view.size
    check_render_cost(
        medium,
        n_rays=n_rays,
        n_rows=mu_rows.size,
        n_path=n_path,
        allow_large=allow_large,
        what="the request",
    )
    cos_theta = np.clip(
        mu_view * mu_sun
        + np.sqrt(np.maximum(0.0, 1 - mu_view**2))
        * np.sqrt(np.maximum(0.0, 1 - mu_sun**2))
        * np.cos(phi_view),
        -1.0,
        1.0,
    )
    theta = np.rad2deg(np.arccos(cos_theta))
    # Rays sorted by row: a row's rays are contiguous.
    order = np.argsort(ray_row, kind="stable")
    bounds = np.searchsorted(ray_row[order], np.arange(mu_rows.size + 1))
    phase = np.ascontiguousarray(
        np.stack(
            [
                t.phase_at(theta[order]).T
                if _scatters(t)
                else np.zeros((theta.size, t.wavelength_nm.size))
                for t in medium.tables
            ],
            axis=1,
        )
    )  # (sorted ray, c, x)
    mu_sorted = np.ascontiguousarray(mu_view[order], dtype=float)
    phi_sorted = np.ascontiguousarray(phi_view[order], dtype=float)
    sun_sorted = np.ascontiguousarray(mu_sun[order], dtype=float)
    density = np.ascontiguousarray(medium.density(medium.altitude_m))
    modes_used = source_modes(medium, field)
    scatterers = np.flatnonzero([_scatters(t) for t in medium.tables]).astype(np.int64)
    n_modes = int(modes_used.max()) if modes_used.size else 0
    coeffs = _source_coefficients(medium, field, scatterers, max(n_modes, 1))
    modes_kept = modes_used[scatterers].astype(np.int64)
    ground_diffuse = np.ascontiguousarray(field.flux_down_diffuse[:, -1])
    nwl = medium.wavelength_nm.size
    n_c = len(medium.tables)
    n_mom = 2 * medium.n_streams
    r_ground = medium.planet_radius_m
    r_top = medium.planet_radius_m + medium.top_altitude_m
    sig_ext_scaled = medium.scaled_sigma_ext_m2
    sig_sca_scaled = medium.scaled_sigma_sca_m2
    out = np.empty((n_rays, nwl))
    edges = np.ascontiguousarray(medium.edges_m, dtype=float)
    # Samples per row: the stretched ones and up to two crossings of each edge.
    n_samples = n_path + 1 + 2 * edges.size
    chunk = _rows_per_chunk(mu_rows.size, n_samples - 1, n_modes, nwl)
    done = 0
    for start in range(0, mu_rows.size, chunk):
        stop = min(start + chunk, mu_rows.size)
        rows = mu_rows[start:stop]
        nr = rows.size
        geo = np.empty((nr, n_samples, 4))
        dens = np.empty((nr, n_samples, n_c))
        wb = np.zeros((nr, n_samples, nwl))
        level = np.empty((nr, n_samples), dtype=np.int64)
        g = np.empty((nr, n_samples, n_modes, nwl))
        t_end = np.empty((nr, nwl))
        hits = np.zeros(nr, dtype=np.bool_)
        row_args = (
            rows,
            float(radius_m),
            r_top,
            r_ground,
            int(n_path),
            float(stretch),
            medium.altitude_m,
            density,
            sig_ext_scaled,
            field.altitude_m,
            edges,
            geo,
            dens,
            wb,
            level,
            t_end,
            hits,
        )
        in_threads(_row_kernel, nr, *row_args)
        if n_modes:
            samples = np.argsort(level.ravel(), kind="stable")
            source_args = (
                samples,
                geo,
                dens,
                wb,
                level,
                sig_sca_scaled,
                coeffs,
                scatterers,
                modes_kept,
                n_mom,
                g,
            )
            in_threads(_source_kernel, samples.size, *source_args)
        a, b = bounds[start], bounds[stop]
        rays = np.zeros((b - a, nwl))
        ray_args = (
            bounds[start : stop + 1] - a,
            mu_sorted[a:b],
            phi_sorted[a:b],
            sun_sorted[a:b],
            float(radius_m),
            medium.number_density_per_m3,
            medium.sigma_sca_m2,
            sig_ext_scaled,
            phase[a:b],
            medium.slant.radius_m,
            medium.slant.mu,
            medium.slant.column_m,
            geo,
            dens,
            wb,
            g,
            t_end,
            hits,
            field.ground_albedo,
            ground_diffuse,
            rays,
        )
        in_threads(_ray_kernel, nr, *ray_args)
        out[order[a:b]] = rays
        done += b - a
        report(f"lines of sight: {done} of {n_rays}", last=done == n_rays)
    return out
