"""Lorenz-Mie scattering by homogeneous spheres: the numerical kernel.

This module knows nothing of units, materials or size distributions.  Its
kernels take plain arrays (complex refractive index ``m``, size parameters
``x = 2 pi r / lambda``, quadrature weights, direction cosines ``mu``) and are
compiled with numba (``cache=True``, no ``fastmath``: fast-math reassociation
breaks identities such as ``Re(a_n) = |a_n|^2`` for a lossless sphere).

One concept, the compiled Mie kernel, in one module: the coefficients of
single spheres (homogeneous or coated), the polydisperse sums that fuse them
with the angular sums in one compiled loop over radii, and the Legendre
projections between Gauss grids that those sums use; the coefficient and sum
kernels share one flat workspace layout (below).

Conventions (Bohren & Huffman 1983, chapter 4): time dependence exp(-i w t), so
an absorbing sphere has m = n + i k with k >= 0; scattering amplitudes S1, S2 in
van de Hulst's dimensionless normalization; mu = cos(theta), theta = 0 forward.
miepython uses m = n - i k; the two conventions give complex-conjugate
amplitudes and identical efficiencies, phase functions and asymmetry.

Notes
-----
The Mie coefficients are computed here rather than by calling miepython because
the polydisperse kernel must fuse them with the angular sums inside one
compiled loop over radii, and miepython exposes only per-sphere Python-level
functions (its compiled kernels are private and their signatures changed within
the 3.0 series).  The tests compare this kernel with miepython's public API and
with Wiscombe's MIEV0 reference values.

References
----------
.. [1] C. F. Bohren and D. R. Huffman, *Absorption and Scattering of Light by
   Small Particles*, Wiley, 1983. doi:10.1002/9783527618156
.. [2] W. J. Wiscombe, "Improved Mie scattering algorithms," Appl. Opt. 19,
   1505-1509 (1980). doi:10.1364/AO.19.001505
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
from numba import njit

from dustoptics._numba_cache import (
    B1,
    C16,
    F8,
    F8_1D,
    F8_1D_RO,
    F8_2D,
    I8,
    I8_1D,
    NONE,
    kernel,
    variant,
)
from dustoptics._validation import as_float_array, check_budget, check_positive

__all__ = [
    "SingleSphere",
    "single_sphere",
    "wiscombe_nmax",
]


@kernel(F8)
def wiscombe_nmax(x: float) -> int:
    """Number of terms of the Mie series (Wiscombe 1980, Eq. 1 for 8 < x < 4200).

    n_max = x + 4.05 x^(1/3) + 2, used here for every x (it errs on the long side
    for x < 8).  The truncation error of the summed quantities is about 1e-7
    relative or below.
    """
    return int(x + 4.05 * x ** (1.0 / 3.0) + 2.0)


#: Spheres whose Mie coefficients are computed together.  The recurrences for
#: one sphere are chains of dependent complex divisions (bound by latency);
#: run side by side over a batch, each step is a loop over spheres that the
#: compiler vectorizes.  LLVM's loop vectorizer skips loops of fewer than 16
#: iterations, hence 16.
LANES = 16

# The coefficient kernels work in flat float64 arrays.  Per-sphere rows of
# LANES values: the working rows in an array ``lane`` of their own (length
# _LANE), the results (x, Q_ext, Q_sca, g Q_sca) in the same rows at the start
# of the workspace (:func:`_workspace`), which continues with one block of
# _N_PLANES rows per order n = 0..n_top + 1.  The names below are offsets: row
# r starts at r * LANES, plane p of an order's block at p * LANES.  Every
# access in a loop over spheres is then a constant offset plus the sphere's
# index from the start of one view, so the compiler sees that the loop's
# stores to that view cannot overlap its loads; with a separate array per row
# it tested every pair at run time, once per loop, which cost more than the
# loop's arithmetic.  (A loop that stores to two views of one array is not
# vectorized at all: hence ``lane`` apart.)
(
    _X,
    _NMAX,
    _IZR,
    _IZI,
    _FR,
    _FI,
    _CR,
    _CI,
    _DDR,
    _DDI,
    _DONE,
    _INVX,
    _PN,
    _PC,
    _APR,
    _API,
    _BPR,
    _BPI,
    _QEXT,
    _QSCA,
    _GQ,
) = range(0, 21 * LANES, LANES)
_N_LANE_ROWS = 21
_LANE = _N_LANE_ROWS * LANES  # length of the per-sphere part
# Planes of an order's block: D_n(m x) (real, imaginary), psi_n(x), chi_n(x),
# and in the block of order n - 1, a_n and b_n (real, imaginary).
_DNR, _DNI, _PSI, _CHI, _AR, _AI, _BR, _BI = range(0, 8 * LANES, LANES)
_N_PLANES = 8
_BLK = _N_PLANES * LANES  # length of one order's block


@njit(cache=True, nogil=True, inline="always")
def _workspace(n_top: int) -> np.ndarray:
    """Workspace of the coefficient kernels for up to LANES spheres with n_max <= n_top
    (orders 0..n_top + 1: the upward sweep computes chi_{n_top + 1} too)."""
    return np.empty(_LANE + (n_top + 2) * _BLK)


@njit(cache=True, nogil=True, inline="always")
def _miller_start(x: float, nmax: int) -> int:
    return int(max(nmax, x) + 25 + 1.5 * np.sqrt(x))


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _reciprocal(re: float, im: float) -> tuple[float, float]:
    """1 / (re + i im), scaled by max(|re|, |im|) so that no square overflows;
    branch-free, so loops over spheres vectorize (error_model="numpy": no
    ZeroDivisionError branch either)."""
    s = max(abs(re), abs(im))
    inv_s = 1.0 / s
    u = re * inv_s
    v = im * inv_s
    q = inv_s / (u * u + v * v)
    return u * q, -v * q


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _reciprocal_moderate(re: float, im: float) -> tuple[float, float]:
    """1 / (re + i im) with one division, for |re + i im| within 1e-150..1e150:
    the continued fraction's and the D_n recurrence's denominators, of order
    n / |m x| (tested to x = 1e-30, where Q_sca matches Rayleigh's to 1e-15)."""
    q = 1.0 / (re * re + im * im)
    return re * q, -im * q


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _log_derivative_top(
    m: complex, n_sph: int, n_top: int, lane: np.ndarray, ws: np.ndarray
) -> None:
    """D_n(m x) = psi_n'(m x) / psi_n(m x) at n = n_top for every sphere, by
    Lentz's continued fraction (Lentz 1976, modified as by Thompson & Barnett
    1986): D_n(z) = -n/z + J_{nu-1}(z)/J_nu(z), nu = n + 1/2, with the Bessel
    ratio 2nu/z - 1/(2(nu+1)/z - 1/(2(nu+2)/z - ...)).  All spheres iterate
    together; each stops updating once its factor is within 1e-15 of 1."""
    nu = n_top + 0.5
    for s in range(n_sph):
        a, b = _reciprocal(m.real * lane[_X + s], m.imag * lane[_X + s])
        lane[_IZR + s] = a
        lane[_IZI + s] = b
        lane[_FR + s] = 2.0 * nu * a
        lane[_FI + s] = 2.0 * nu * b
        lane[_CR + s] = 2.0 * nu * a
        lane[_CI + s] = 2.0 * nu * b
        lane[_DDR + s] = 0.0
        lane[_DDI + s] = 0.0
        lane[_DONE + s] = 0.0
    tiny = 1e-30  # Lentz's guard against a zero denominator
    j = 1
    while True:
        t = 2.0 * (nu + j)
        # An integer count and no short-circuit tests: a float sum over the
        # spheres, or branches, kept the compiler from vectorizing the loop.
        n_done = 0
        for s in range(n_sph):
            bjr = t * lane[_IZR + s]
            bji = t * lane[_IZI + s]
            pr = bjr - lane[_DDR + s]
            pi = bji - lane[_DDI + s]
            pr += tiny if (pr == 0.0) & (pi == 0.0) else 0.0
            u, v = _reciprocal_moderate(pr, pi)
            lane[_DDR + s] = u
            lane[_DDI + s] = v
            rr, ri = _reciprocal_moderate(lane[_CR + s], lane[_CI + s])
            qr = bjr - rr
            qi = bji - ri
            qr += tiny if (qr == 0.0) & (qi == 0.0) else 0.0
            lane[_CR + s] = qr
            lane[_CI + s] = qi
            delr = qr * u - qi * v
            deli = qr * v + qi * u
            f_r = lane[_FR + s]
            f_i = lane[_FI + s]
            finished = lane[_DONE + s] != 0.0
            lane[_FR + s] = f_r if finished else f_r * delr - f_i * deli
            lane[_FI + s] = f_i if finished else f_r * deli + f_i * delr
            finished = finished | (abs(delr - 1.0) + abs(deli) < 1e-15)
            lane[_DONE + s] = 1.0 if finished else 0.0
            n_done += 1 if finished else 0
        j += 1
        if n_done == n_sph or j > 10_000_000:
            break
    top = ws[_LANE + n_top * _BLK : _LANE + (n_top + 1) * _BLK]  # order n_top's block
    for s in range(n_sph):
        top[_DNR + s] = lane[_FR + s] - n_top * lane[_IZR + s]
        top[_DNI + s] = lane[_FI + s] - n_top * lane[_IZI + s]


@kernel(C16, F8_1D, I8_1D, F8_1D, error_model="numpy")
def _mie_coefficients(m: complex, x: np.ndarray, nmax: np.ndarray, ws: np.ndarray) -> int:
    """External coefficients a_n, b_n (n = 1..n_top), Q_ext, Q_sca and g Q_sca
    of a batch of spheres.

    BH Eq. 4.88: a_n = [(D_n/m + n/x) psi_n - psi_{n-1}] / [(D_n/m + n/x) xi_n - xi_{n-1}],
    b_n the same with m D_n, xi_n = psi_n - i chi_n.  Sphere s (of at most
    LANES) gets its own n_max = ``nmax[s]`` terms: orders above it are set to
    zero, so sums over all n_top = max(nmax) orders equal its own truncated
    series.  Results go to workspace ``ws`` (from :func:`_workspace`, for at
    least n_top orders): a_n of sphere s at the _AR (real) and _AI planes of
    order n - 1's block, b_n at _BR and _BI; efficiencies (BH Eqs. 4.61,
    4.62 and p. 120) in the _QEXT, _QSCA and _GQ rows.  Returns n_top.

    Three sweeps over the orders, each a loop over spheres per order:

    * D_n(m x) at n_top by Lentz's continued fraction
      (:func:`_log_derivative_top`);
    * downward: psi_n(x) = x j_n(x) by Miller's recurrence
      psi_{n-1} = (2n+1)/x psi_n - psi_{n+1} from ``_miller_start`` (downward,
      psi_n is the dominant solution; the upward recurrence loses all accuracy
      for n > x, and for x << 1 already at n = 1, where
      psi_1 = sin x / x - cos x cancels), and from n_top on, together,
      D_{n-1} = n/z - 1/(D_n + n/z) (stable for every complex z, BH Eq. 4.89);
    * upward: psi_n scaled to psi_0 = sin x or to psi_1, whichever is larger
      (they cannot both be small); chi_n(x) = -x y_n(x) by the upward
      recurrence, in which it is dominant; a_n, b_n; the efficiency sums.

    Fusing the recurrences into one loop per order and sweep keeps several
    independent dependency chains in flight and the loops few.
    """
    n_sph = x.shape[0]
    # The per-sphere rows in an array of their own: loops that store to both
    # it and the orders' blocks vectorize only if the two are separate objects.
    lane = np.empty(_LANE)
    n_top = nmax[0]  # not a literal 0: callees would be compiled for that type too
    x_max = x[0]
    for s in range(n_sph):
        n_top = max(n_top, nmax[s])
        x_max = max(x_max, x[s])
        lane[_X + s] = x[s]
        lane[_NMAX + s] = nmax[s]
    _log_derivative_top(m, n_sph, n_top, lane, ws)

    # Downward sweep.
    for s in range(n_sph):
        lane[_INVX + s] = 1.0 / lane[_X + s]
        lane[_PN + s] = 0.0
        lane[_PC + s] = 1e-280
    for n in range(_miller_start(x_max, n_top), 0, -1):
        big = False
        if n > n_top:
            for s in range(n_sph):
                p = (2 * n + 1) * lane[_INVX + s] * lane[_PC + s] - lane[_PN + s]
                lane[_PN + s] = lane[_PC + s]
                lane[_PC + s] = p
                big |= abs(p) > 1e250
        else:
            o = ws[_LANE + (n - 1) * _BLK : _LANE + (n + 1) * _BLK]  # orders n - 1, n
            for s in range(n_sph):
                p = (2 * n + 1) * lane[_INVX + s] * lane[_PC + s] - lane[_PN + s]
                lane[_PN + s] = lane[_PC + s]
                lane[_PC + s] = p
                big |= abs(p) > 1e250
                o[_BLK + _PSI + s] = lane[_PN + s]
                nzr = n * lane[_IZR + s]
                nzi = n * lane[_IZI + s]
                u, v = _reciprocal_moderate(o[_BLK + _DNR + s] + nzr, o[_BLK + _DNI + s] + nzi)
                o[_DNR + s] = nzr - u
                o[_DNI + s] = nzi - v
        if big:  # rare: rescale the spheres about to overflow, and what they stored
            for s in range(n_sph):
                if abs(lane[_PC + s]) > 1e250:
                    lane[_PC + s] *= 1e-250
                    lane[_PN + s] *= 1e-250
                    for k in range(n, n_top + 1):
                        ws[_LANE + k * _BLK + _PSI + s] *= 1e-250

    # psi_0 (lane _PC, unscaled), the scale, chi_0 and chi_1.
    o = ws[_LANE : _LANE + 2 * _BLK]  # orders 0, 1
    for s in range(n_sph):
        sx = np.sin(lane[_X + s])
        cx = np.cos(lane[_X + s])
        psi1 = sx * lane[_INVX + s] - cx
        psi0 = lane[_PC + s]
        scale = sx / psi0 if abs(sx) >= abs(psi1) else psi1 / o[_BLK + _PSI + s]
        lane[_PC + s] = scale
        o[_PSI + s] = psi0 * scale
        o[_CHI + s] = cx
        o[_BLK + _CHI + s] = cx * lane[_INVX + s] + sx
        lane[_APR + s] = 0.0
        lane[_API + s] = 0.0
        lane[_BPR + s] = 0.0
        lane[_BPI + s] = 0.0
        lane[_QEXT + s] = 0.0
        lane[_QSCA + s] = 0.0
        lane[_GQ + s] = 0.0

    # Upward sweep.
    mr = m.real
    mi = m.imag
    imr, imi = _reciprocal(mr, mi)
    for n in range(1, n_top + 1):
        c = 2.0 * n + 1.0
        c_ab = c / (n * (n + 1.0))
        c_prev = (n - 1.0) * (n + 1.0) / n  # of a_{n-1} a_n* + b_{n-1} b_n* in g Q_sca
        # Orders n - 1 (receives a_n, b_n), n, n + 1.
        o = ws[_LANE + (n - 1) * _BLK : _LANE + (n + 2) * _BLK]
        for s in range(n_sph):
            p1 = o[_BLK + _PSI + s] * lane[_PC + s]
            o[_BLK + _PSI + s] = p1
            p0 = o[_PSI + s]
            c1 = o[_BLK + _CHI + s]
            c0 = o[_CHI + s]
            o[2 * _BLK + _CHI + s] = c * lane[_INVX + s] * c1 - c0
            n_x = n * lane[_INVX + s]
            d_r = o[_BLK + _DNR + s]
            d_i = o[_BLK + _DNI + s]
            keep = n <= lane[_NMAX + s]
            # a_n with t = D_n / m + n / x
            re, im = _bh_ratio(d_r * imr - d_i * imi + n_x, d_r * imi + d_i * imr, p1, p0, c1, c0)
            ar = re if keep else 0.0
            ai = im if keep else 0.0
            # b_n with t = m D_n + n / x
            re, im = _bh_ratio(mr * d_r - mi * d_i + n_x, mr * d_i + mi * d_r, p1, p0, c1, c0)
            br = re if keep else 0.0
            bi = im if keep else 0.0
            o[_AR + s] = ar
            o[_AI + s] = ai
            o[_BR + s] = br
            o[_BI + s] = bi
            lane[_QEXT + s] += c * (ar + br)
            lane[_QSCA + s] += c * (ar * ar + ai * ai + br * br + bi * bi)
            lane[_GQ + s] += c_ab * (ar * br + ai * bi) + c_prev * (
                lane[_APR + s] * ar
                + lane[_API + s] * ai
                + lane[_BPR + s] * br
                + lane[_BPI + s] * bi
            )
            lane[_APR + s] = ar
            lane[_API + s] = ai
            lane[_BPR + s] = br
            lane[_BPI + s] = bi
    for s in range(n_sph):
        f = 2.0 / (lane[_X + s] * lane[_X + s])
        ws[_X + s] = lane[_X + s]
        ws[_QEXT + s] = lane[_QEXT + s] * f
        ws[_QSCA + s] = lane[_QSCA + s] * f
        ws[_GQ + s] = lane[_GQ + s] * 2.0 * f
    return n_top


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _bh_ratio(
    tr: float, ti: float, p1: float, p0: float, c1: float, c0: float
) -> tuple[float, float]:
    """(t psi_n - psi_{n-1}) / (t xi_n - xi_{n-1}) for t = tr + i ti, psi_n = p1,
    psi_{n-1} = p0 and xi = psi - i chi with chi_n = c1, chi_{n-1} = c0: the
    common form of a_n and b_n (Bohren & Huffman 1983, Eq. 4.88)."""
    u, v = _reciprocal(tr * p1 + ti * c1 - p0, ti * p1 - tr * c1 + c0)
    nr = tr * p1 - p0
    ni = ti * p1
    return nr * u - ni * v, nr * v + ni * u


@njit(cache=True, nogil=True, inline="always")
def _log_derivatives_down(z: complex, n_top: int) -> np.ndarray:
    """D_n(z) = psi_n'(z) / psi_n(z), n = 0..n_top, by the downward recurrence
    D_{n-1} = n/z - 1/(D_n + n/z) (Bohren & Huffman 1983, Eq. 4.89, stable for
    every complex z) from D_N = 0 at N = max(n_top, |z|) + 16 + 8 |z|^(1/3).
    The start's error decays only above the turning point n ~ |z|, in a region
    whose width grows as |z|^(1/3): BHCOAT's N = max(n_top, |z|) + 15 left
    D_n wrong by 2e-5 at z = 75 and 0.2 at z = 300 (real z; against a start at
    4 |z|, which this start matches to the last bit for z = m x with x from
    0.5 to 2e4, Re m from 1.0001 to 4 and Im m up to 0.01, as
    ``mie_derivatives._log_derivative``)."""
    start = int(max(n_top, abs(z)) + 16.0 + 8.0 * abs(z) ** (1.0 / 3.0))
    d = np.empty(n_top + 1, dtype=np.complex128)
    cur = 0.0 + 0.0j
    for n in range(start, 0, -1):
        if n <= n_top:
            d[n] = cur
        cur = n / z - 1.0 / (cur + n / z)
    d[0] = cur
    return d


@kernel(C16, C16, F8, I8_1D, I8, F8_1D, group="coated", error_model="numpy")
def _coat(
    m_core: complex, m: complex, fraction: float, nmax: np.ndarray, n_sph: int, ws: np.ndarray
) -> None:
    """Turn the coefficients of homogeneous spheres of the shell's index ``m``
    (workspace ``ws`` after :func:`_mie_coefficients`) into those of coated
    spheres: a core of index ``m_core`` and radius ``fraction`` times the
    sphere's.

    Bohren & Huffman (1983, Sec. 8.1, Eqs. 8.2-8.3) divided through by the
    Riccati-Bessel functions of the complex arguments, so that only their
    logarithmic derivatives and one ratio appear (as Toon & Ackerman 1981 do
    to avoid the overflow of psi_n and chi_n of large complex argument).  The
    field in the shell is expanded in psi_n and xi_n = psi_n - i chi_n rather
    than psi_n and chi_n (any two independent solutions give the same
    coefficients): in an absorbing shell psi_n(m r) grows and xi_n(m r)
    decays with r, so the ratio R_n below is small instead of 1 - epsilon and
    1 - T does not cancel.  With x = fraction y the core's and y the sphere's
    size parameter, D_n = psi_n'/psi_n (downward recurrence),
    G_n = xi_n'/xi_n (upward recurrence G_n = 1/(n/z - G_{n-1}) - n/z from
    G_0 = i, stable: xi_n is the dominant solution in n) and
    R_n = [psi_n(m x) / xi_n(m x)] [xi_n(m y) / psi_n(m y)] (a product of
    the per-order ratios 1/(D_n + n/z) and 1/(G_n + n/z), from R_0 =
    exp(2i(m y - m x)) (1 - exp(2i m x)) / (1 - exp(2i m y))),

        T_a = R_n (m D_n(m_c x) - m_c D_n(m x)) / (m D_n(m_c x) - m_c G_n(m x)),
        T_b = R_n (m D_n(m x) - m_c D_n(m_c x)) / (m G_n(m x) - m_c D_n(m_c x)),
        D^a = (D_n(m y) - T_a G_n(m y)) / (1 - T_a), D^b likewise with T_b,

    and a_n, b_n are the homogeneous sphere's expressions (Eq. 4.88) with
    D_n(m y) replaced by D^a, D^b.  psi_n(y), chi_n(y) and D_n(m y) are read
    from the workspace.  Efficiencies are summed again.
    """
    for s in range(n_sph):
        y = ws[_X + s]
        n_s = nmax[s]
        x = fraction * y
        z_cx = m_core * x
        z_x = m * x
        z_y = m * y
        d_cx = _log_derivatives_down(z_cx, n_s)
        d_x = _log_derivatives_down(z_x, n_s)
        # xi_0 = -i exp(i z): H_0 = xi_0'/xi_0 = i, and
        # R_0 = [sin(z_x) / xi_0(z_x)] [xi_0(z_y) / sin(z_y)], written with
        # exp(2 i z), which is small where Im z is large.
        g_x = 1j
        g_y = 1j
        ratio = np.exp(2j * (z_y - z_x)) * (1.0 - np.exp(2j * z_x)) / (1.0 - np.exp(2j * z_y))
        qext = 0.0
        qsca = 0.0
        gq = 0.0
        a_prev = 0.0 + 0.0j
        b_prev = 0.0 + 0.0j
        for n in range(1, n_s + 1):
            g_x = 1.0 / (n / z_x - g_x) - n / z_x
            g_y = 1.0 / (n / z_y - g_y) - n / z_y
            o = _LANE + n * _BLK + s
            d_y = complex(ws[o + _DNR], ws[o + _DNI])
            ratio *= (g_x + n / z_x) / (d_x[n] + n / z_x) * (d_y + n / z_y) / (g_y + n / z_y)
            t_a = ratio * (m * d_cx[n] - m_core * d_x[n]) / (m * d_cx[n] - m_core * g_x)
            t_b = ratio * (m * d_x[n] - m_core * d_cx[n]) / (m * g_x - m_core * d_cx[n])
            da = (d_y - t_a * g_y) / (1.0 - t_a)
            db = (d_y - t_b * g_y) / (1.0 - t_b)
            p1 = ws[o + _PSI]
            p0 = ws[o - _BLK + _PSI]
            c1 = ws[o + _CHI]
            c0 = ws[o - _BLK + _CHI]
            ta = da / m + n / y
            tb = m * db + n / y
            ar, ai = _bh_ratio(ta.real, ta.imag, p1, p0, c1, c0)
            br, bi = _bh_ratio(tb.real, tb.imag, p1, p0, c1, c0)
            a = complex(ar, ai)
            b = complex(br, bi)
            q = o - _BLK  # a_n, b_n live in order n - 1's block
            ws[q + _AR] = ar
            ws[q + _AI] = ai
            ws[q + _BR] = br
            ws[q + _BI] = bi
            c = 2.0 * n + 1.0
            qext += c * (ar + br)
            qsca += c * (ar * ar + ai * ai + br * br + bi * bi)
            gq += c / (n * (n + 1.0)) * (a * b.conjugate()).real + (n - 1.0) * (n + 1.0) / n * (
                (a_prev * a.conjugate()).real + (b_prev * b.conjugate()).real
            )
            a_prev = a
            b_prev = b
        f = 2.0 / (y * y)
        ws[_QEXT + s] = qext * f
        ws[_QSCA + s] = qsca * f
        ws[_GQ + s] = gq * 2.0 * f


@njit(cache=True, nogil=True, inline="always")
def _pi_tau_table(mu: np.ndarray, nmax: int) -> tuple[np.ndarray, np.ndarray]:
    """Angular functions pi_n(mu), tau_n(mu) for n = 1..nmax, shape (len(mu), nmax).

    Upward recurrence (BH Eq. 4.47): pi_n = ((2n-1) mu pi_{n-1} - n pi_{n-2})/(n-1),
    tau_n = n mu pi_n - (n+1) pi_{n-1}; stable for |mu| <= 1.
    """
    n_mu = mu.shape[0]
    pi_t = np.empty((n_mu, nmax))
    tau_t = np.empty((n_mu, nmax))
    for i in range(n_mu):
        u = mu[i]
        p_prev = 0.0
        p_cur = 1.0
        for n in range(1, nmax + 1):
            pi_t[i, n - 1] = p_cur
            tau_t[i, n - 1] = n * u * p_cur - (n + 1) * p_prev
            p_next = ((2 * n + 1) * u * p_cur - (n + 1) * p_prev) / n
            p_prev = p_cur
            p_cur = p_next
    return pi_t, tau_t


@njit(cache=True, nogil=True, inline="always")
def _amplitudes(
    nmax: int, a: np.ndarray, b: np.ndarray, pi_t: np.ndarray, tau_t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """S1, S2 at the angles of the tables (BH Eq. 4.74)."""
    n_mu = pi_t.shape[0]
    s1 = np.empty(n_mu, dtype=np.complex128)
    s2 = np.empty(n_mu, dtype=np.complex128)
    for i in range(n_mu):
        acc1 = 0.0 + 0.0j
        acc2 = 0.0 + 0.0j
        for k in range(nmax):
            n = k + 1
            c = (2.0 * n + 1.0) / (n * (n + 1.0))
            p = pi_t[i, k]
            t = tau_t[i, k]
            acc1 += c * (a[k] * p + b[k] * t)
            acc2 += c * (a[k] * t + b[k] * p)
        s1[i] = acc1
        s2[i] = acc2
    return s1, s2


@kernel(C16, F8, F8_1D, C16, F8, group="sphere")
def _single_sphere_kernel(
    m: complex, x: float, mu: np.ndarray, m_core: complex, core_fraction: float
):
    nmax = wiscombe_nmax(x)
    ws = _workspace(nmax)
    # Arrays of one sphere, typed as the polydisperse kernel's batches are.
    nmax_arr = np.empty(1, dtype=np.int64)
    nmax_arr[0] = nmax
    x_arr = np.empty(1)
    x_arr[0] = x
    _mie_coefficients(m, x_arr, nmax_arr, ws)
    if core_fraction > 0.0:
        _coat(m_core, m, core_fraction, nmax_arr, nmax_arr.shape[0], ws)
    a = np.empty(nmax, dtype=np.complex128)
    b = np.empty(nmax, dtype=np.complex128)
    for k in range(nmax):
        o = ws[_LANE + k * _BLK : _LANE + (k + 1) * _BLK]
        a[k] = complex(o[_AR], o[_AI])
        b[k] = complex(o[_BR], o[_BI])
    pi_t, tau_t = _pi_tau_table(mu, nmax)
    s1, s2 = _amplitudes(nmax, a, b, pi_t, tau_t)
    return ws[_QEXT], ws[_QSCA], ws[_GQ], s1, s2


@dataclass(frozen=True)
class SingleSphere:
    """Mie solution for one homogeneous sphere.

    Attributes
    ----------
    qext, qsca, qabs : float
        Extinction, scattering and absorption efficiencies. [-]
    g : float
        Asymmetry parameter <cos theta>. [-]
    mu : numpy.ndarray
        Direction cosines at which the amplitudes were evaluated. [-]
    s1, s2 : numpy.ndarray
        Complex scattering amplitudes (van de Hulst, dimensionless; Bohren &
        Huffman's exp(-i w t) convention, m = n + i k). [-]
    phase : numpy.ndarray
        Phase function ``(|S1|^2 + |S2|^2) / (2 x^2 Q_sca pi)``, normalized so that
        2 pi int P dmu = 1. [sr^-1]
    """

    qext: float
    qsca: float
    qabs: float
    g: float
    mu: np.ndarray
    s1: np.ndarray
    s2: np.ndarray
    phase: np.ndarray


#: Smallest size parameter accepted. [-]  The kernel agrees with the Rayleigh
#: limit (Q_sca = 8/3 x^4 |K|^2, Q_abs = 4 x Im K, K = (m^2 - 1)/(m^2 + 2))
#: down to x = 1e-30 (tests/scattering/test_mie.py) and fails below about
#: 1e-60 (x^4 underflows); a sphere that small is far smaller than an atom at
#: any optical wavelength.  It bounds a single sphere and every node of the
#: radius quadrature (a distribution's lower tail).
MIN_SIZE_PARAMETER = 1e-30

#: Smallest index contrast |m - 1| accepted. [-]  The series loses about
#: eps / |m - 1| of relative precision (measured: Q_sca scales as |m - 1|^2 to
#: 1e-7 relative at |m - 1| = 1e-8); below 1e-6 a sphere scatters less than
#: 1e-12 of its area and m = 1 scatters nothing at all, so no phase
#: function is defined.
MIN_INDEX_CONTRAST = 1e-6


#: Largest |m| accepted. [-]  Beyond it m x overflows the recurrences' range
#: for the size parameters of interest; metals in the infrared reach |m| ~ 100.
MAX_INDEX = 1e4


def _kernel_mu(mu: np.ndarray) -> np.ndarray:
    """``mu`` as :func:`_single_sphere_kernel` takes it: C-contiguous, writable float64."""
    return np.require(mu, dtype=np.float64, requirements=["C", "W"])


def check_sphere_inputs(m: Any, x: Any = None) -> complex:
    """Validate a relative refractive index (and a size parameter) for the kernel.

    Returns ``m`` as a complex number.  Raises TypeError for a value that is
    not a number (strings, booleans, None) and ValueError for a non-finite m,
    n <= 0, k < 0, ``|m - 1|`` < :data:`MIN_INDEX_CONTRAST`, or ``x`` outside
    [:data:`MIN_SIZE_PARAMETER`, inf).
    """
    if isinstance(m, (str, bytes, bool, np.bool_)) or not isinstance(m, numbers.Number):
        raise TypeError(f"m must be a complex number (m = n + i k); got {m!r} ({type(m).__name__})")
    m = complex(cast(complex, m))
    if not (np.isfinite(m.real) and np.isfinite(m.imag)):
        raise ValueError(f"m must be a finite complex number; got {m!r}")
    if m.real <= 0.0 or m.imag < 0.0:
        raise ValueError(f"m must have n > 0 and k >= 0 (m = n + i k); got {m!r}")
    if abs(m) > MAX_INDEX:
        raise ValueError(f"m must have |m| <= {MAX_INDEX:g}; got {m!r}")
    if abs(m - 1.0) < MIN_INDEX_CONTRAST:
        raise ValueError(
            f"m must differ from 1 by at least {MIN_INDEX_CONTRAST:g} (|m - 1| >= {MIN_INDEX_CONTRAST:g}; "
            f"a sphere matched to its medium scatters nothing); got {m!r}"
        )
    if x is not None:
        x = check_positive("x", x)
        if x < MIN_SIZE_PARAMETER:
            raise ValueError(
                f"x must be >= {MIN_SIZE_PARAMETER:g} (smaller spheres are below the kernel's "
                f"tested domain; use the Rayleigh limit); got {x!r}"
            )
    return m


def single_sphere(
    *, m: complex, x: float, mu: np.ndarray | float = 1.0, allow_large: bool = False
) -> SingleSphere:
    """Scatter a plane wave off one homogeneous sphere (Lorenz-Mie theory).

    Parameters
    ----------
    m : complex
        Refractive index of the sphere relative to the medium, m = n + i k with
        n > 0, k >= 0 and ``|m - 1| >=`` :data:`MIN_INDEX_CONTRAST`. [-]
    x : float
        Size parameter 2 pi r / lambda (lambda in the medium),
        x >= :data:`MIN_SIZE_PARAMETER`. [-]
    mu : array_like
        Cosines of the scattering angles, in [-1, 1]. [-]
    allow_large : bool, optional
        Go ahead when the series' arrays (n_max orders at every angle) would
        exceed :data:`dustoptics._validation.MEMORY_BUDGET_BYTES`; default
        False, which raises :class:`~dustoptics._validation.BudgetError`.

    Returns
    -------
    SingleSphere
        Efficiencies, asymmetry parameter, amplitudes and phase function.

    Notes
    -----
    The series is truncated after Wiscombe's n_max (see :func:`wiscombe_nmax`);
    psi_n(x) is computed by Miller's downward recurrence, so small spheres
    (x << 1) keep full relative precision without a separate Rayleigh branch.

    References
    ----------
    Bohren & Huffman (1983), chapter 4; Wiscombe (1980), doi:10.1364/AO.19.001505.
    """
    m = check_sphere_inputs(m, x)
    x = float(x)
    mu_arr = np.atleast_1d(as_float_array("mu", mu))
    if mu_arr.ndim != 1 or np.any(np.abs(mu_arr) > 1.0):
        raise ValueError(f"mu must be a 1-D array of cosines in [-1, 1]; got {mu!r}")
    # Coefficients a_n, b_n and the recurrences (about 10 complex arrays of n_max),
    # and pi_n, tau_n at every angle.
    n_max = x + 4.05 * x ** (1.0 / 3.0) + 2.0
    check_budget(
        "single_sphere",
        16.0 * n_max * (10.0 + 2.0 * mu_arr.size),
        allow_large=allow_large,
        change=f"x = {x:g} needs n_max = {n_max:.3g} orders: use a smaller sphere or fewer angles",
    )
    qext, qsca, gq, s1, s2 = _single_sphere_kernel(m, x, _kernel_mu(mu_arr), 0j, 0.0)
    phase = (np.abs(s1) ** 2 + np.abs(s2) ** 2) / (2.0 * np.pi * x * x * qsca)
    return SingleSphere(
        qext=qext, qsca=qsca, qabs=qext - qsca, g=gq / qsca, mu=mu_arr, s1=s1, s2=s2, phase=phase
    )


def _check_index(name: str, m: complex) -> complex:
    m = complex(m)
    if not (np.isfinite(m.real) and np.isfinite(m.imag)):
        raise ValueError(f"{name} must be a finite complex number; got {m!r}")
    if m.real <= 0.0 or m.imag < 0.0:
        raise ValueError(f"{name} must have n > 0 and k >= 0 (m = n + i k); got {m!r}")
    return m


def coated_sphere(
    *, m_core: complex, m_shell: complex, x_core: float, x: float, mu: np.ndarray | float = 1.0
) -> SingleSphere:
    """Scatter a plane wave off a coated sphere: a core inside a concentric shell.

    Parameters
    ----------
    m_core, m_shell : complex
        Refractive indices of core and shell relative to the medium,
        m = n + i k, n > 0, k >= 0. [-]
    x_core : float
        Size parameter of the core, 2 pi r_core / lambda, 0 <= x_core <= x
        (0: a homogeneous sphere of the shell's index; x: of the core's). [-]
    x : float
        Size parameter of the whole sphere, 2 pi r / lambda, > 0. [-]
    mu : array_like
        Cosines of the scattering angles, in [-1, 1]. [-]

    Returns
    -------
    SingleSphere
        Efficiencies (relative to pi r^2 of the whole sphere), g, amplitudes
        and phase function.

    Notes
    -----
    Bohren & Huffman (1983, Sec. 8.1) written with logarithmic derivatives and
    one ratio of Riccati-Bessel functions (as Toon & Ackerman 1981 do), see
    :func:`_coat`; tested against scatrs' layered spheres for x <= 60 and
    k <= 1 (tests/scattering/test_coated.py).

    References
    ----------
    Bohren & Huffman (1983), chapter 8; O. B. Toon and T. P. Ackerman,
    "Algorithms for the calculation of scattering by stratified spheres,"
    Appl. Opt. 20, 3657-3660 (1981), doi:10.1364/AO.20.003657.
    """
    m_core = _check_index("m_core", m_core)
    m_shell = _check_index("m_shell", m_shell)
    x = check_positive("x", x)
    x_core = float(x_core)
    if not (np.isfinite(x_core) and 0.0 <= x_core <= x):
        raise ValueError(
            f"x_core must be in [0, x = {x!r}] (the core lies inside the sphere; a coating "
            f"cannot be thicker than the particle); got {x_core!r}"
        )
    mu_arr = np.atleast_1d(as_float_array("mu", mu))
    if mu_arr.ndim != 1 or np.any(np.abs(mu_arr) > 1.0):
        raise ValueError(f"mu must be a 1-D array of cosines in [-1, 1]; got {mu!r}")
    n_max = x + 4.05 * x ** (1.0 / 3.0) + 2.0
    check_budget(
        "coated_sphere",
        16.0 * n_max * (14.0 + 2.0 * mu_arr.size),
        allow_large=False,
        change=f"x = {x:g} needs n_max = {n_max:.3g} orders: use a smaller sphere or fewer angles",
    )
    qext, qsca, gq, s1, s2 = _single_sphere_kernel(
        m_shell, x, _kernel_mu(mu_arr), m_core, x_core / x
    )
    phase = (np.abs(s1) ** 2 + np.abs(s2) ** 2) / (2.0 * np.pi * x * x * qsca)
    return SingleSphere(
        qext=qext, qsca=qsca, qabs=qext - qsca, g=gq / qsca, mu=mu_arr, s1=s1, s2=s2, phase=phase
    )


# ----------------------------------------------------------------------------
# Polydisperse accumulation
# ----------------------------------------------------------------------------


#: Columns appended after the angular values in each row of :func:`_accumulate`:
#: sums of w, w x^2 Q_ext, w x^2 Q_sca, w x^2 Q_sca g, w g, and w x^2 Q_back.
N_SUMS = 6

#: Angular blocks of a row of :func:`_accumulate` with the scattering matrix
#: (``n_stokes`` = 4): ``I = |S1|^2 + |S2|^2``, ``Q = |S2|^2 - |S1|^2``,
#: ``U = 2 Re(S2 S1*)``, ``V = 2 Im(S2 S1*)``, each times the node's factor; in
#: Bohren & Huffman's notation (1983, Eq. 4.77) 2 S11, 2 S12, 2 S33, 2 S34.
N_STOKES = 4


#: Angles per block of :func:`angular_table`'s layout.  Each block holds the
#: eight rows of a pass (pi and tau of four orders) for BLOCK angles side by
#: side, so that every access of a pass lies at a constant offset from the
#: start of the table's row (and of the accumulators): the compiler then
#: checks at run time only that table and accumulators do not overlap, once
#: per pass, instead of 64 pairs of separate rows (which cost more than the
#: arithmetic for fewer than about 100 angles).
BLOCK = 16


@kernel(F8_1D_RO, I8)
def angular_table(mu: np.ndarray, nmax: int) -> np.ndarray:
    """pi_n(mu) and tau_n(mu), n = 1..nmax, in the blocked layout of the kernel.

    Upward recurrences (BH Eq. 4.47): pi_n = ((2n-1) mu pi_{n-1} - n pi_{n-2})/(n-1),
    tau_n = n mu pi_n - (n+1) pi_{n-1}; stable for |mu| <= 1.  Returns an
    array of shape (ceil(nmax / 4), 8 * n_pad), n_pad = len(mu) rounded up to
    a multiple of BLOCK: row q holds orders 4q+1..4q+4, for each block of BLOCK
    angles the 8 x BLOCK values pi_{4q+1}, tau_{4q+1}, pi_{4q+2}, ..., tau_{4q+4}.
    Orders above nmax and angles beyond len(mu) hold zeros.
    """
    n_mu = mu.shape[0]
    n_pad = BLOCK * ((n_mu + BLOCK - 1) // BLOCK)
    n_pass = (nmax + 3) // 4
    tab = np.empty((n_pass, 8 * n_pad))
    tab[:] = 0.0
    for i in range(n_mu):
        u = mu[i]
        base = (i // BLOCK) * 8 * BLOCK + i % BLOCK
        p_prev = 0.0
        p_cur = 1.0
        for n in range(1, nmax + 1):
            q, j = divmod(n - 1, 4)
            tab[q, base + 2 * j * BLOCK] = p_cur
            tab[q, base + (2 * j + 1) * BLOCK] = n * u * p_cur - (n + 1) * p_prev
            p_next = ((2 * n + 1) * u * p_cur - (n + 1) * p_prev) / n
            p_prev = p_cur
            p_cur = p_next
    return tab


def _accumulate(
    m: complex,
    x_nodes: np.ndarray,
    w_nodes: np.ndarray,
    node_panel: np.ndarray,
    n_panels: int,
    per_particle: bool,
    table: np.ndarray,
    n_mu: int,
    symmetric: bool,
    n_stokes: int,
    m_core: complex,
    core_fraction: float,
) -> np.ndarray:
    """Sum the Mie quantities of many spheres with weights, per panel.

    For node j (size parameter x_j, weight w_j, panel node_panel[j]) adds to
    that panel's row the unpolarized intensity I_j(mu) = |S1_j|^2 + |S2_j|^2
    times c_j, where c_j = w_j (cross-section weighting: I_j / k^2 = 2 C_sca,j
    p_j, so the sum divided by 2 pi sum(w x^2 Q_sca) is the weighted phase
    function) or c_j = w_j / (2 pi x_j^2 Q_sca,j) when ``per_particle`` (each
    sphere's own normalized phase function, weighted by number).  The angles
    are the first ``n_mu`` of ``table`` (from :func:`angular_table`, with at
    least n_max orders for every node); if ``symmetric`` (angles mu >= 0),
    the next n_mu columns receive the values at -mu, obtained from the parity
    pi_n(-mu) = (-1)^(n-1) pi_n(mu), tau_n(-mu) = (-1)^n tau_n(mu) at no extra
    cost.  With ``n_stokes`` = N_STOKES (4) the row holds four such blocks of
    n_f columns, I, Q, U, V (see :data:`N_STOKES`), for the scattering matrix;
    with 1, the intensity alone.  The last ``N_SUMS`` columns hold sums of
    w, w x^2 Q_ext, w x^2 Q_sca, w x^2 Q_sca g, w g and w x^2 Q_back (times
    pi (lambda / 2 pi)^2 the second, third and last are areas).  Returns an
    array of shape (n_panels, n_stokes n_f + N_SUMS), n_f = 2 n_mu if
    ``symmetric`` else n_mu.

    With ``core_fraction`` > 0 the spheres are coated: a core of index
    ``m_core`` and radius ``core_fraction`` times the sphere's inside a shell
    of index ``m`` (:func:`_coat`); x is then the outer size parameter.

    The Mie coefficients are computed for LANES consecutive nodes at a time,
    up to the largest n_max among them: give the nodes sorted by x.

    :func:`_accumulate_grids` on one grid (``table`` must have the layout
    :func:`angular_table` gives for n_mu angles).
    """
    width = _table_width(n_mu)
    if table.ndim != 2 or (n_mu > 0 and table.shape[1] != width):
        raise ValueError(
            f"table must be angular_table's for n_mu = {n_mu} angles (shape (n_pass, {width})); "
            f"got shape {table.shape}"
        )
    flat = np.ascontiguousarray(table, dtype=np.float64).ravel() if n_mu > 0 else np.empty(0)
    return _accumulate_grids(
        complex(m),
        np.ascontiguousarray(x_nodes, dtype=np.float64),
        np.ascontiguousarray(w_nodes, dtype=np.float64),
        np.ascontiguousarray(node_panel, dtype=np.int64),
        np.zeros(len(x_nodes), dtype=np.int64),
        int(n_panels),
        bool(per_particle),
        np.array([n_mu], dtype=np.int64),
        flat,
        np.array([0, flat.size], dtype=np.int64),
        np.empty(0),
        np.zeros(1, dtype=np.int64),
        bool(symmetric),
        int(n_stokes),
        _core_index(m_core, core_fraction),
        float(core_fraction),
    )


@njit(cache=True, nogil=True, inline="always")
def _backscatter(ws: np.ndarray, s: int, nmax: int) -> float:
    """x^2 Q_back = |sum_n (2n + 1) (-1)^n (a_n - b_n)|^2 of sphere ``s`` of
    workspace ``ws`` (Bohren & Huffman 1983, p. 122): 4 pi times the
    differential scattering cross-section at 180 deg, over (lambda / 2 pi)^2 / pi."""
    back_r = 0.0
    back_i = 0.0
    sign = -1.0
    for k in range(nmax):
        o = _LANE + k * _BLK + s
        c_n = sign * (2.0 * k + 3.0)
        back_r += c_n * (ws[o + _AR] - ws[o + _BR])
        back_i += c_n * (ws[o + _AI] - ws[o + _BI])
        sign = -sign
    return back_r * back_r + back_i * back_i


@njit(cache=True, nogil=True, inline="always")
def _add_last_pass(
    t: np.ndarray, a: np.ndarray, coef: np.ndarray, k: int, n_rest: int, n_blocks: int, nb: int
) -> None:
    """The pass of :func:`_add_sphere` over its last ``n_rest`` (1 to 3) orders,
    from order index ``k``: the full pass's sums without the missing orders' terms."""
    ar0, ai0, br0, bi0 = coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3]
    if n_rest == 1:
        for blk in range(n_blocks):
            o = blk * 8 * BLOCK
            for ii in range(nb):
                i = o + ii
                pp0 = t[i]
                tt0 = t[BLOCK + i]
                a[i] += ar0 * pp0
                a[BLOCK + i] += ai0 * pp0
                a[2 * BLOCK + i] += br0 * tt0
                a[3 * BLOCK + i] += bi0 * tt0
                a[4 * BLOCK + i] += br0 * pp0
                a[5 * BLOCK + i] += bi0 * pp0
                a[6 * BLOCK + i] += ar0 * tt0
                a[7 * BLOCK + i] += ai0 * tt0
        return
    ar1, ai1, br1, bi1 = coef[k + 1, 0], coef[k + 1, 1], coef[k + 1, 2], coef[k + 1, 3]
    if n_rest == 2:
        for blk in range(n_blocks):
            o = blk * 8 * BLOCK
            for ii in range(nb):
                i = o + ii
                pp0 = t[i]
                tt0 = t[BLOCK + i]
                pp1 = t[2 * BLOCK + i]
                tt1 = t[3 * BLOCK + i]
                a[i] += ar0 * pp0 + br1 * tt1
                a[BLOCK + i] += ai0 * pp0 + bi1 * tt1
                a[2 * BLOCK + i] += br0 * tt0 + ar1 * pp1
                a[3 * BLOCK + i] += bi0 * tt0 + ai1 * pp1
                a[4 * BLOCK + i] += br0 * pp0 + ar1 * tt1
                a[5 * BLOCK + i] += bi0 * pp0 + ai1 * tt1
                a[6 * BLOCK + i] += ar0 * tt0 + br1 * pp1
                a[7 * BLOCK + i] += ai0 * tt0 + bi1 * pp1
        return
    ar2, ai2, br2, bi2 = coef[k + 2, 0], coef[k + 2, 1], coef[k + 2, 2], coef[k + 2, 3]
    for blk in range(n_blocks):
        o = blk * 8 * BLOCK
        for ii in range(nb):
            i = o + ii
            pp0 = t[i]
            tt0 = t[BLOCK + i]
            pp1 = t[2 * BLOCK + i]
            tt1 = t[3 * BLOCK + i]
            pp2 = t[4 * BLOCK + i]
            tt2 = t[5 * BLOCK + i]
            a[i] += ar0 * pp0 + br1 * tt1 + ar2 * pp2
            a[BLOCK + i] += ai0 * pp0 + bi1 * tt1 + ai2 * pp2
            a[2 * BLOCK + i] += br0 * tt0 + ar1 * pp1 + br2 * tt2
            a[3 * BLOCK + i] += bi0 * tt0 + ai1 * pp1 + bi2 * tt2
            a[4 * BLOCK + i] += br0 * pp0 + ar1 * tt1 + br2 * pp2
            a[5 * BLOCK + i] += bi0 * pp0 + ai1 * tt1 + bi2 * pp2
            a[6 * BLOCK + i] += ar0 * tt0 + br1 * pp1 + ar2 * tt2
            a[7 * BLOCK + i] += ai0 * tt0 + bi1 * pp1 + ai2 * tt2


@kernel(F8_1D, F8, F8, I8, F8_1D, I8, B1, F8_2D, I8, B1, I8, F8_2D, F8_1D)
def _add_sphere(
    row: np.ndarray,
    w: float,
    x: float,
    nmax: int,
    ws: np.ndarray,
    s: int,
    per_particle: bool,
    table: np.ndarray,
    n_mu: int,
    symmetric: bool,
    n_stokes: int,
    coef: np.ndarray,
    acc: np.ndarray,
) -> None:
    """Add the weighted intensity and sums of sphere ``s`` of workspace ``ws``
    (after :func:`_mie_coefficients`) to its
    panel's row (see :func:`_accumulate`); ``coef`` (shape (>= n_max + 3, 4))
    and ``acc`` (length table.shape[1]) are workspace."""
    n_f = 2 * n_mu if symmetric else n_mu
    qext = ws[_QEXT + s]
    qsca = ws[_QSCA + s]
    gq = ws[_GQ + s]
    x2 = x * x
    n_a = n_stokes * n_f
    row[n_a] += w
    row[n_a + 1] += w * x2 * qext
    row[n_a + 2] += w * x2 * qsca
    row[n_a + 3] += w * x2 * gq
    row[n_a + 4] += w * gq / qsca
    row[n_a + 5] += w * _backscatter(ws, s, nmax)
    if n_mu == 0:
        return
    c = w / (2.0 * np.pi * x2 * qsca) if per_particle else w
    # (2n + 1) / (n (n + 1)) a_n and b_n as real and imaginary parts.
    n_full = nmax // 4  # passes of four orders
    n_rest = nmax - 4 * n_full  # orders of a last, short pass
    for k in range(nmax):
        n = k + 1
        cn = (2.0 * n + 1.0) / (n * (n + 1.0))
        o = _LANE + k * _BLK + s  # a_n, b_n in order n - 1's block
        coef[k, 0] = cn * ws[o + _AR]
        coef[k, 1] = cn * ws[o + _AI]
        coef[k, 2] = cn * ws[o + _BR]
        coef[k, 3] = cn * ws[o + _BI]
    # Parity split: rows 0-3 of each block of ``acc`` collect the terms of
    # S1 even in mu (real, imaginary) and odd in mu, rows 4-7 those of S2, so
    # S(+mu) = e + o and S(-mu) = e - o.  Four orders (n odd, even, odd, even)
    # per pass, in real arithmetic, which the compiler vectorizes over the
    # angles of a block; four rather than two halve the loads and stores of
    # the accumulators per order.  The last pass holds the n_max mod 4 orders
    # left, its terms added in the same order (a full pass with zero
    # coefficients for the missing orders, which added zeros, gave the same sums).
    acc[:] = 0.0
    n_blocks = table.shape[1] // (8 * BLOCK)
    # The block's trip count, BLOCK, as a value known only at run time: a loop
    # of a constant 16 would be unrolled, not vectorized.
    nb = table.shape[1] // (8 * n_blocks)
    for q in range(n_full):
        k = 4 * q
        ar0, ai0, br0, bi0 = coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3]
        ar1, ai1, br1, bi1 = coef[k + 1, 0], coef[k + 1, 1], coef[k + 1, 2], coef[k + 1, 3]
        ar2, ai2, br2, bi2 = coef[k + 2, 0], coef[k + 2, 1], coef[k + 2, 2], coef[k + 2, 3]
        ar3, ai3, br3, bi3 = coef[k + 3, 0], coef[k + 3, 1], coef[k + 3, 2], coef[k + 3, 3]
        # Offsets from one row view rather than a view per block: the
        # compiler then checks the overlap of table and accumulators once per
        # pass, not per block.
        t = table[q]
        a = acc
        for blk in range(n_blocks):
            o = blk * 8 * BLOCK
            for ii in range(nb):
                i = o + ii
                pp0 = t[i]
                tt0 = t[BLOCK + i]
                pp1 = t[2 * BLOCK + i]
                tt1 = t[3 * BLOCK + i]
                pp2 = t[4 * BLOCK + i]
                tt2 = t[5 * BLOCK + i]
                pp3 = t[6 * BLOCK + i]
                tt3 = t[7 * BLOCK + i]
                a[i] += ar0 * pp0 + br1 * tt1 + ar2 * pp2 + br3 * tt3
                a[BLOCK + i] += ai0 * pp0 + bi1 * tt1 + ai2 * pp2 + bi3 * tt3
                a[2 * BLOCK + i] += br0 * tt0 + ar1 * pp1 + br2 * tt2 + ar3 * pp3
                a[3 * BLOCK + i] += bi0 * tt0 + ai1 * pp1 + bi2 * tt2 + ai3 * pp3
                a[4 * BLOCK + i] += br0 * pp0 + ar1 * tt1 + br2 * pp2 + ar3 * tt3
                a[5 * BLOCK + i] += bi0 * pp0 + ai1 * tt1 + bi2 * pp2 + ai3 * tt3
                a[6 * BLOCK + i] += ar0 * tt0 + br1 * pp1 + ar2 * tt2 + br3 * pp3
                a[7 * BLOCK + i] += ai0 * tt0 + bi1 * pp1 + ai2 * tt2 + bi3 * pp3
    if n_rest > 0:
        _add_last_pass(table[n_full], acc, coef, 4 * n_full, n_rest, n_blocks, nb)
    if n_stokes > 1:
        _add_matrix(row, c, acc, n_mu, n_f, n_blocks, nb, symmetric)
        return
    # Intensities |S1|^2 + |S2|^2 at +mu (and -mu), block by block, so that
    # this loop too runs over the angles of a block and vectorizes.
    for blk in range(n_blocks):
        a = acc[blk * 8 * BLOCK : (blk + 1) * 8 * BLOCK]
        i0 = blk * BLOCK
        n_l = min(nb, n_mu - i0)
        plus = row[i0 : i0 + n_l]
        for i in range(n_l):
            s1r = a[i] + a[2 * BLOCK + i]
            s1i = a[BLOCK + i] + a[3 * BLOCK + i]
            s2r = a[4 * BLOCK + i] + a[6 * BLOCK + i]
            s2i = a[5 * BLOCK + i] + a[7 * BLOCK + i]
            plus[i] += c * (s1r * s1r + s1i * s1i + s2r * s2r + s2i * s2i)
        if symmetric:
            minus = row[n_mu + i0 : n_mu + i0 + n_l]
            for i in range(n_l):
                s1r = a[i] - a[2 * BLOCK + i]
                s1i = a[BLOCK + i] - a[3 * BLOCK + i]
                s2r = a[4 * BLOCK + i] - a[6 * BLOCK + i]
                s2i = a[5 * BLOCK + i] - a[7 * BLOCK + i]
                minus[i] += c * (s1r * s1r + s1i * s1i + s2r * s2r + s2i * s2i)


@njit(cache=True, nogil=True, inline="always")
def _add_matrix(
    row: np.ndarray,
    c: float,
    acc: np.ndarray,
    n_mu: int,
    n_f: int,
    n_blocks: int,
    nb: int,
    symmetric: bool,
) -> None:
    """Add c times I, Q, U, V (see :data:`N_STOKES`) at +mu (and -mu) to the
    four angular blocks of ``row`` from the parity-split amplitude sums of
    :func:`_add_sphere` in ``acc``."""
    for blk in range(n_blocks):
        a = acc[blk * 8 * BLOCK : (blk + 1) * 8 * BLOCK]
        i0 = blk * BLOCK
        n_l = min(nb, n_mu - i0)
        for half in range(2 if symmetric else 1):
            sgn = 1.0 if half == 0 else -1.0
            j0 = i0 + half * n_mu
            r_i = row[j0 : j0 + n_l]
            r_q = row[n_f + j0 : n_f + j0 + n_l]
            r_u = row[2 * n_f + j0 : 2 * n_f + j0 + n_l]
            r_v = row[3 * n_f + j0 : 3 * n_f + j0 + n_l]
            for i in range(n_l):
                s1r = a[i] + sgn * a[2 * BLOCK + i]
                s1i = a[BLOCK + i] + sgn * a[3 * BLOCK + i]
                s2r = a[4 * BLOCK + i] + sgn * a[6 * BLOCK + i]
                s2i = a[5 * BLOCK + i] + sgn * a[7 * BLOCK + i]
                p1 = s1r * s1r + s1i * s1i
                p2 = s2r * s2r + s2i * s2i
                r_i[i] += c * (p1 + p2)
                r_q[i] += c * (p2 - p1)
                # S2 S1* = (s2r s1r + s2i s1i) + i (s2i s1r - s2r s1i)
                r_u[i] += 2.0 * c * (s2r * s1r + s2i * s1i)
                r_v[i] += 2.0 * c * (s2i * s1r - s2r * s1i)


def _core_index(m_core: complex, core_fraction: float) -> complex | None:
    """``m_core`` as :func:`_accumulate_grids` takes it: None for homogeneous spheres
    (``core_fraction`` 0), for which numba compiles the kernel without :func:`_coat`."""
    return complex(m_core) if core_fraction > 0.0 else None


def _table_width(n_mu: int) -> int:
    """Columns of :func:`angular_table`'s rows for ``n_mu`` angles."""
    return 8 * BLOCK * ((n_mu + BLOCK - 1) // BLOCK)


#: :func:`_accumulate_grids`' argument types but the last two (m_core, core_fraction).
_GRIDS_ARGS = (C16, F8_1D, F8_1D, I8_1D, I8_1D, I8, B1, I8_1D, F8_1D, I8_1D, F8_1D, I8_1D, B1, I8)


@kernel(*_GRIDS_ARGS, NONE, F8)
def _accumulate_grids(
    m: complex,
    x_nodes: np.ndarray,
    w_nodes: np.ndarray,
    node_panel: np.ndarray,
    node_tier: np.ndarray,
    n_panels: int,
    per_particle: bool,
    tier_size: np.ndarray,
    tables: np.ndarray,
    table_start: np.ndarray,
    maps: np.ndarray,
    map_start: np.ndarray,
    symmetric: bool,
    n_stokes: int,
    m_core: complex | None,
    core_fraction: float,
) -> np.ndarray:
    """The sums of :func:`_accumulate` and of the tiered angular grids of
    :mod:`dustoptics.scattering.refinement`: the one compiled loop over spheres that both run.

    Node j is summed on grid ``node_tier[j]``, of tier_size[t] angles (half-grid
    angles if ``symmetric``) whose :func:`angular_table` is
    ``tables[table_start[t]:table_start[t + 1]]`` (flattened); a grid of 0
    angles sums the cross-sections alone.  The nodes come sorted by grid, then
    by x, and each panel's nodes share one grid.  Rows of grids below the last
    (symmetric Gauss grids only) are moved to the last one by the maps of
    :func:`_interpolation_maps_into` (R_even then R_odd, flattened, at
    ``maps[map_start[t]:]``).  Returns rows of shape (n_panels, n_stokes n_f
    + N_SUMS), n_f = 2 tier_size[-1] if ``symmetric`` else tier_size[-1].

    Per grid, the spheres are summed as :func:`_accumulate` describes: their
    Mie coefficients LANES at a time (:func:`_mie_coefficients`, coated by
    :func:`_coat` if ``core_fraction`` > 0; ``m_core`` is None for homogeneous
    spheres, a signature compiled without :func:`_coat`), each added to its
    panel's row by :func:`_add_sphere`.  One function, not a loop calling
    another compiled one: numba optimizes every compiled caller again with its
    callees inlined, so each level of calls above the sphere kernels cost
    seconds of compile time.
    """
    n_top = tier_size[tier_size.shape[0] - 1]
    n_f_top = 2 * n_top if symmetric else n_top
    width_top = n_stokes * n_f_top
    # np.empty and a fill rather than np.zeros and np.full: each numpy
    # constructor is compiled apart per dtype and shape, tenths of a second each.
    out = np.empty((n_panels, width_top + N_SUMS))
    out[:] = 0.0
    local = np.empty(n_panels, dtype=np.int64)
    local[:] = -1
    panel_of = np.empty(n_panels, dtype=np.int64)
    n_nodes = x_nodes.shape[0]
    j0 = 0
    while j0 < n_nodes:
        t = node_tier[j0]
        j1 = j0
        n_loc = 0
        while j1 < n_nodes and node_tier[j1] == t:
            p = node_panel[j1]
            if local[p] < 0:
                local[p] = n_loc
                panel_of[n_loc] = p
                n_loc += 1
            j1 += 1
        node_local = np.empty(j1 - j0, dtype=np.int64)
        for j in range(j0, j1):
            node_local[j - j0] = local[node_panel[j]]
        n_t = tier_size[t]
        n_f = 2 * n_t if symmetric else n_t
        width = 8 * BLOCK * ((n_t + BLOCK - 1) // BLOCK)  # angular_table's row
        flat = tables[table_start[t] : table_start[t + 1]]
        table = flat.reshape((flat.shape[0] // width if width > 0 else 0, width))
        # The grid's spheres, LANES at a time (a short last batch repeats its
        # last sphere), into rows of the grid's panels.
        rows = np.empty((n_loc, n_stokes * n_f + N_SUMS))
        rows[:] = 0.0
        x_top = x_nodes[j0]
        for j in range(j0, j1):
            x_top = max(x_top, x_nodes[j])
        nmax_all = wiscombe_nmax(x_top)
        x_b = np.empty(LANES)
        nmax_b = np.empty(LANES, dtype=np.int64)
        ws = _workspace(nmax_all)
        coef = np.empty((nmax_all + 4, 4))
        acc = np.empty(width)
        for b0 in range(j0, j1, LANES):
            n_live = min(LANES, j1 - b0)
            for s in range(LANES):
                x_b[s] = x_nodes[b0 + min(s, n_live - 1)]
                nmax_b[s] = wiscombe_nmax(x_b[s])
            _mie_coefficients(m, x_b, nmax_b, ws)
            # m_core None (homogeneous spheres) is decided when numba compiles:
            # that signature has no _coat in it.
            if m_core is not None and core_fraction > 0.0:
                _coat(m_core, m, core_fraction, nmax_b, n_live, ws)
            for s in range(n_live):
                j = b0 + s
                _add_sphere(
                    rows[node_local[j - j0]],
                    w_nodes[j],
                    x_b[s],
                    nmax_b[s],
                    ws,
                    s,
                    per_particle,
                    table,
                    n_t,
                    symmetric,
                    n_stokes,
                    coef,
                    acc,
                )
        # Rows are copied element by element: numba's array-to-slice assignment
        # compiles a shape-mismatch message (string formatting), about 2 s.
        if n_t == n_top:
            for r in range(n_loc):
                p = panel_of[r]
                for c in range(out.shape[1]):
                    out[p, c] = rows[r, c]
        else:
            size = n_t * n_top
            r_even = maps[map_start[t] : map_start[t] + size].reshape((n_t, n_top))
            r_odd = maps[map_start[t] + size : map_start[t] + 2 * size].reshape((n_t, n_top))
            # Each block of 2 n_t values moves on its own: as rows of their own.
            blocks = np.empty((n_loc * n_stokes, 2 * n_t))
            for r in range(n_loc):
                for k in range(n_stokes):
                    for c in range(2 * n_t):
                        blocks[r * n_stokes + k, c] = rows[r, k * 2 * n_t + c]
            moved = _legendre_regrid(blocks, r_even, r_odd).reshape((n_loc, width_top))
            for r in range(n_loc):
                p = panel_of[r]
                for c in range(width_top):
                    out[p, c] = moved[r, c]
                for c in range(N_SUMS):
                    out[p, width_top + c] = rows[r, 2 * n_stokes * n_t + c]
        for r in range(n_loc):
            local[panel_of[r]] = -1
        j0 = j1
    return out


# Coated spheres: a complex m_core, and _coat compiled in.
variant(_accumulate_grids, *_GRIDS_ARGS, C16, F8, group="coated")


@kernel(F8_1D_RO, F8_1D_RO, F8_1D, I8)
def _legendre_project(
    mu_half: np.ndarray, w_half: np.ndarray, f: np.ndarray, lmax: int
) -> np.ndarray:
    """Legendre coefficients beta_l = (2l+1)/2 int f P_l dmu, l = 0..lmax.

    ``f`` holds values at +mu_half followed by values at -mu_half (Gauss
    nodes and weights of the positive half of a symmetric rule); P_l of even
    l sees f's even part, of odd l its odd part.  The recurrence
    P_{l+1} = ((2l+1) mu P_l - l P_{l-1}) / (l+1) runs over l for all angles
    at once (angles innermost, which the compiler vectorizes); each l's sum
    over angles runs in four interleaved partial sums, in a fixed order.
    """
    n_half = mu_half.shape[0]
    fe = np.empty(n_half)
    fo = np.empty(n_half)
    for i in range(n_half):
        fe[i] = w_half[i] * (f[i] + f[n_half + i])  # even part, times weight
        fo[i] = w_half[i] * (f[i] - f[n_half + i])  # odd part, times weight
    p_prev = np.empty(n_half)
    p_prev[:] = 0.0
    p_cur = np.empty(n_half)
    p_cur[:] = 1.0
    beta = np.empty(lmax + 1)
    for ell in range(lmax + 1):
        g = fe if ell % 2 == 0 else fo
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        i = 0
        while i + 4 <= n_half:
            s0 += g[i] * p_cur[i]
            s1 += g[i + 1] * p_cur[i + 1]
            s2 += g[i + 2] * p_cur[i + 2]
            s3 += g[i + 3] * p_cur[i + 3]
            i += 4
        while i < n_half:
            s0 += g[i] * p_cur[i]
            i += 1
        beta[ell] = ((s0 + s1) + (s2 + s3)) * ((2 * ell + 1) / 2.0)
        c1 = (2 * ell + 1) / (ell + 1.0)
        c2 = ell / (ell + 1.0)
        for i in range(n_half):
            p_next = c1 * mu_half[i] * p_cur[i] - c2 * p_prev[i]
            p_prev[i] = p_cur[i]
            p_cur[i] = p_next
    return beta


@kernel(
    F8_1D_RO, F8_1D_RO, F8_1D_RO, F8_2D, F8_2D, error_model="numpy"
)  # y at a node: inf, then replaced
def _interpolation_maps_into(
    mu_half: np.ndarray,
    w_half: np.ndarray,
    mu_half_out: np.ndarray,
    r_even: np.ndarray,
    r_odd: np.ndarray,
) -> None:
    """Linear maps from values on a symmetric Gauss-Legendre grid to values on
    another, of the interpolating polynomial, split by parity.

    Values f at the 2 n Gauss nodes (+mu_half, then -mu_half) determine one
    polynomial of degree <= 2n - 1; every polynomial of that degree, such as
    |S|^2 of spheres with n_max <= n - 1 (degree 2 n_max), is reproduced
    exactly (the same as projecting on P_0..P_{2n-1}).  It is evaluated by the
    barycentric formula p(y) = sum_j lambda_j f_j / (y - t_j) / sum_j lambda_j
    / (y - t_j), stable for Gauss-Legendre nodes t_j (Higham 2004), whose
    weights are lambda_j = (-1)^j sqrt((1 - t_j^2) w_j) (Wang & Xiang 2012).
    With e_i = (f(mu_i) + f(-mu_i)) / 2 and o_i the odd part, the even part of
    p at mu_half_out is sum_i e_i R_even[i, :] and the odd part
    sum_i o_i R_odd[i, :]; p(+-mu_out) = even +- odd.  Writes R_even and
    R_odd, each of shape (len(mu_half), len(mu_half_out)), into the arrays
    given (views of one array, when many maps are stacked); O(n^2), not O(n^3).

    References: N. J. Higham, IMA J. Numer. Anal. 24, 547-556 (2004),
    doi:10.1093/imanum/24.4.547; H. Wang and S. Xiang, Math. Comp. 81,
    861-877 (2012), doi:10.1090/S0025-5718-2011-02549-4.
    """
    n_in = mu_half.shape[0]
    n_out = mu_half_out.shape[0]
    # Nodes in increasing order are -mu_half[n-1..0], then mu_half[0..n-1];
    # node +mu_half[i] has index n + i, node -mu_half[i] index n - 1 - i.
    lam_plus = np.empty(n_in)
    lam_minus = np.empty(n_in)
    for i in range(n_in):
        lam = np.sqrt((1.0 - mu_half[i] * mu_half[i]) * w_half[i])
        lam_plus[i] = lam if (n_in + i) % 2 == 0 else -lam
        lam_minus[i] = lam if (n_in - 1 - i) % 2 == 0 else -lam
    c_plus = np.empty(n_in)
    c_minus = np.empty(n_in)
    for k in range(n_out):
        y = mu_half_out[k]
        hit = -1
        total = 0.0
        for i in range(n_in):
            if y == mu_half[i]:
                hit = i
            c_plus[i] = lam_plus[i] / (y - mu_half[i])
            c_minus[i] = lam_minus[i] / (y + mu_half[i])
            total += c_plus[i] + c_minus[i]
        for i in range(n_in):
            if hit >= 0:  # y is a node (y > 0, so of the + half): p(y) = f there
                cp = 1.0 if i == hit else 0.0
                cm = 0.0
            else:
                cp = c_plus[i] / total
                cm = c_minus[i] / total
            r_even[i, k] = cp + cm
            r_odd[i, k] = cp - cm


#: Rows of :func:`_legendre_regrid` moved together (each map row read once for them all).
_REGRID_ROWS = 4


@kernel(F8_2D, F8_2D, F8_2D)
def _legendre_regrid(rows: np.ndarray, r_even: np.ndarray, r_odd: np.ndarray) -> np.ndarray:
    """Each row's values (+mu_half, then -mu_half) moved to the output grid
    (+mu_half_out, then -mu_half_out) by the maps of
    :func:`_interpolation_maps_into`.

    Each output value is its row's sum over i of e_i R_even[i, k] (and o_i
    R_odd[i, k]) in increasing i from 0.  Rows go _REGRID_ROWS at a time (a
    short last group repeats its last row), so that each map row is read once
    for all of them, and the output angles BLOCK at a time (the Gauss tiers'
    sizes are multiples of BLOCK; other angles beyond the last whole block
    one by one): every accumulator of a group then lies at a constant offset
    from one array's start, which the compiler vectorizes without run-time
    overlap tests (as in :func:`_add_sphere`).
    """
    n_rows = rows.shape[0]
    n_in, n_out = r_even.shape
    n_kb = n_out // BLOCK
    # BLOCK as a value known only at run time: a loop of a constant 16 would be unrolled.
    nb = n_kb * BLOCK // n_kb if n_kb > 0 else 0
    out = np.empty((n_rows, 2 * n_out))
    acc = np.empty(2 * _REGRID_ROWS * n_out)
    eo = np.empty(2 * _REGRID_ROWS)
    for r0 in range(0, n_rows, _REGRID_ROWS):
        acc[:] = 0.0
        for i in range(n_in):
            for j in range(_REGRID_ROWS):
                row = rows[min(r0 + j, n_rows - 1)]
                eo[2 * j] = 0.5 * (row[i] + row[n_in + i])
                eo[2 * j + 1] = 0.5 * (row[i] - row[n_in + i])
            e0, o0, e1, o1, e2, o2, e3, o3 = eo[0], eo[1], eo[2], eo[3], eo[4], eo[5], eo[6], eo[7]
            re = r_even[i]
            ro = r_odd[i]
            for kb in range(n_kb):
                o = kb * 2 * _REGRID_ROWS * BLOCK
                m0 = kb * BLOCK
                for kk in range(nb):
                    a = re[m0 + kk]
                    b = ro[m0 + kk]
                    acc[o + kk] += e0 * a
                    acc[o + BLOCK + kk] += o0 * b
                    acc[o + 2 * BLOCK + kk] += e1 * a
                    acc[o + 3 * BLOCK + kk] += o1 * b
                    acc[o + 4 * BLOCK + kk] += e2 * a
                    acc[o + 5 * BLOCK + kk] += o2 * b
                    acc[o + 6 * BLOCK + kk] += e3 * a
                    acc[o + 7 * BLOCK + kk] += o3 * b
        for j in range(min(_REGRID_ROWS, n_rows - r0)):
            for kb in range(n_kb):
                o = kb * 2 * _REGRID_ROWS * BLOCK + 2 * j * BLOCK
                for kk in range(BLOCK):
                    ev = acc[o + kk]
                    od = acc[o + BLOCK + kk]
                    out[r0 + j, kb * BLOCK + kk] = ev + od
                    out[r0 + j, n_out + kb * BLOCK + kk] = ev - od
    # Output angles beyond the last whole block (grids not from the Gauss tiers), one by one.
    for r in range(n_rows):
        row = rows[r]
        for k in range(n_kb * BLOCK, n_out):
            ev = 0.0
            od = 0.0
            for i in range(n_in):
                ev += 0.5 * (row[i] + row[n_in + i]) * r_even[i, k]
                od += 0.5 * (row[i] - row[n_in + i]) * r_odd[i, k]
            out[r, k] = ev + od
            out[r, n_out + k] = ev - od
    return out


@kernel(F8_1D, F8_1D)
def _legendre_evaluate(beta: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Sum_l beta_l P_l(mu) by Clenshaw's recurrence.

    P_{l+1} = alpha_l P_l + b_l P_{l-1} with alpha_l = (2l+1) mu / (l+1) and
    b_l = -l / (l+1).  The recurrence runs over l for all angles at once (the
    loop over angles innermost, which the compiler vectorizes).
    """
    lmax = beta.shape[0] - 1
    n_mu = mu.shape[0]
    b1 = np.empty(n_mu)
    b1[:] = 0.0
    b2 = np.empty(n_mu)
    b2[:] = 0.0
    for ell in range(lmax, 0, -1):
        c1 = (2 * ell + 1) / (ell + 1)
        c2 = (ell + 1) / (ell + 2)
        be = beta[ell]
        for i in range(n_mu):
            bk = be + c1 * mu[i] * b1[i] - c2 * b2[i]
            b2[i] = b1[i]
            b1[i] = bk
    out = np.empty(n_mu)
    for i in range(n_mu):
        out[i] = beta[0] + mu[i] * b1[i] - 0.5 * b2[i]
    return out
