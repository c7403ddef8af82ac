"""Lorenz-Mie scattering by homogeneous spheres: the numerical kernel.

This module knows nothing of units, materials or size distributions.  Its
kernels take plain arrays (complex refractive index ``m``, size parameters
``x = 2 pi r / lambda``, quadrature weights, direction cosines ``mu``) and are
compiled with numba (``cache=True``, no ``fastmath``: fast-math reassociation
breaks identities such as Re(a_n) = |a_n|^2 for a lossless sphere).

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

from dataclasses import dataclass

import numpy as np
from numba import njit

from dustoptics._validation import as_float_array, check_positive

__all__ = [
    "wiscombe_nmax",
    "SingleSphere",
    "single_sphere",
]


@njit(cache=True, nogil=True)
def wiscombe_nmax(x: float) -> int:
    """Number of terms of the Mie series (Wiscombe 1980, Eq. 1 for 8 < x < 4200).

    n_max = x + 4.05 x^(1/3) + 2, used here for every x (it errs on the long side
    for x < 8).  The truncation error of the summed quantities is about 1e-7
    relative or below.
    """
    return int(x + 4.05 * x ** (1.0 / 3.0) + 2.0)


@njit(cache=True, nogil=True)
def _log_derivative_cf(z: complex, n: int) -> complex:
    """D_n(z) = psi_n'(z)/psi_n(z) by Lentz's continued fraction (Lentz 1976).

    D_n(z) = -n/z + J_{nu-1}(z)/J_nu(z) with nu = n + 1/2, and the Bessel
    ratio is the continued fraction 2nu/z - 1/(2(nu+1)/z - 1/(2(nu+2)/z - ...)),
    evaluated with the modified Lentz algorithm (Thompson & Barnett 1986).
    """
    tiny = 1e-300
    nu = n + 0.5
    f = 2.0 * nu / z
    c = f
    dd = 0.0 + 0.0j
    j = 1
    while True:
        bj = 2.0 * (nu + j) / z
        dd = bj - dd
        if dd == 0.0:
            dd = tiny
        c = bj - 1.0 / c
        if c == 0.0:
            c = tiny
        dd = 1.0 / dd
        delta = c * dd
        f *= delta
        j += 1
        if abs(delta - 1.0) < 1e-15 or j > 10_000_000:
            break
    return -n / z + f


@njit(cache=True, nogil=True)
def _log_derivative(z: complex, d: np.ndarray) -> None:
    """D_n(z) for n = 0..len(d)-1: the top value by continued fraction, then the
    downward recurrence D_{n-1} = n/z - 1/(D_n + n/z), stable for every complex
    z (Bohren & Huffman 1983, Eq. 4.89)."""
    n_top = d.shape[0] - 1
    dn = _log_derivative_cf(z, n_top)
    d[n_top] = dn
    inv_z = 1.0 / z  # one complex division, not two per order
    for n in range(n_top, 0, -1):
        n_z = n * inv_z
        dn = n_z - 1.0 / (dn + n_z)
        d[n - 1] = dn


@njit(cache=True, nogil=True)
def _riccati_psi(x: float, n_start: int, psi: np.ndarray) -> None:
    """psi_n(x) = x j_n(x) for n = 0..len(psi)-1 by Miller's downward recurrence.

    The upward recurrence loses all accuracy for n > x and, for x << 1, already
    at n = 1 (psi_1 = sin x / x - cos x cancels).  Downward from ``n_start``,
    psi_n is the dominant solution; the result is scaled to psi_0 = sin x or to
    psi_1, whichever is larger (they cannot both be small).
    """
    n_out = psi.shape[0]
    p_next = 0.0
    p_cur = 1e-280
    for n in range(n_start, 0, -1):
        p_prev = (2 * n + 1) / x * p_cur - p_next
        p_next = p_cur
        p_cur = p_prev
        if n - 1 < n_out:
            psi[n - 1] = p_cur
        if n < n_out:
            psi[n] = p_next
        if abs(p_cur) > 1e250:  # rescale everything stored so far
            p_cur *= 1e-250
            p_next *= 1e-250
            for k in range(n - 1, n_out):
                psi[k] *= 1e-250
    sin_x = np.sin(x)
    psi1 = sin_x / x - np.cos(x)
    if abs(sin_x) >= abs(psi1):
        scale = sin_x / psi[0]
    else:
        scale = psi1 / psi[1]
    for k in range(n_out):
        psi[k] *= scale


@njit(cache=True, nogil=True)
def _miller_start(x: float, nmax: int) -> int:
    return int(max(nmax, x) + 25 + 1.5 * np.sqrt(x))


@njit(cache=True, nogil=True)
def _mie_coefficients(
    m: complex, x: float, nmax: int, a: np.ndarray, b: np.ndarray, d: np.ndarray, psi: np.ndarray
) -> None:
    """Fill a[0:nmax], b[0:nmax] with the external coefficients a_n, b_n (n = 1..nmax).

    BH Eq. 4.88: a_n = [(D_n/m + n/x) psi_n - psi_{n-1}] / [(D_n/m + n/x) xi_n - xi_{n-1}],
    b_n the same with m D_n, xi_n = psi_n - i chi_n (chi_n = -x y_n(x)).
    ``d`` must hold nmax + 1 values, ``psi`` nmax + 1 values (workspace).
    """
    _log_derivative(m * x, d[: nmax + 1])
    _riccati_psi(x, _miller_start(x, nmax), psi[: nmax + 1])
    inv_x = 1.0 / x
    inv_m = 1.0 / m
    chi_prev = np.cos(x)  # chi_0
    chi_cur = np.cos(x) * inv_x + np.sin(x)  # chi_1
    for n in range(1, nmax + 1):
        xi_n = psi[n] - 1j * chi_cur
        xi_prev = psi[n - 1] - 1j * chi_prev
        n_x = n * inv_x
        t = d[n] * inv_m + n_x
        a[n - 1] = (t * psi[n] - psi[n - 1]) / (t * xi_n - xi_prev)
        t = m * d[n] + n_x
        b[n - 1] = (t * psi[n] - psi[n - 1]) / (t * xi_n - xi_prev)
        chi_next = (2 * n + 1) * inv_x * chi_cur - chi_prev
        chi_prev = chi_cur
        chi_cur = chi_next


@njit(cache=True, nogil=True)
def _efficiencies(x: float, nmax: int, a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """Q_ext, Q_sca and g Q_sca from the coefficients (BH Eqs. 4.61, 4.62 and p. 120)."""
    qext = 0.0
    qsca = 0.0
    gq = 0.0
    for i in range(nmax):
        n = i + 1
        c = 2.0 * n + 1.0
        ar = a[i].real
        ai = a[i].imag
        br = b[i].real
        bi = b[i].imag
        qext += c * (ar + br)
        qsca += c * (ar * ar + ai * ai + br * br + bi * bi)
        gq += c / (n * (n + 1.0)) * (ar * br + ai * bi)
        if i + 1 < nmax:
            a1 = a[i + 1]
            b1 = b[i + 1]
            gq += n * (n + 2.0) / (n + 1.0) * (
                ar * a1.real + ai * a1.imag + br * b1.real + bi * b1.imag
            )
    f = 2.0 / (x * x)
    return f * qext, f * qsca, 2.0 * f * gq


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def _amplitudes(
    nmax: int, a: np.ndarray, b: np.ndarray, pi_t: np.ndarray, tau_t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """S1, S2 at the angles of the tables (BH Eq. 4.74)."""
    n_mu = pi_t.shape[0]
    s1 = np.zeros(n_mu, dtype=np.complex128)
    s2 = np.zeros(n_mu, dtype=np.complex128)
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


@njit(cache=True, nogil=True)
def _single_sphere_kernel(m: complex, x: float, mu: np.ndarray):
    nmax = wiscombe_nmax(x)
    a = np.empty(nmax, dtype=np.complex128)
    b = np.empty(nmax, dtype=np.complex128)
    d = np.empty(nmax + 1, dtype=np.complex128)
    psi = np.empty(nmax + 1)
    _mie_coefficients(m, x, nmax, a, b, d, psi)
    qext, qsca, gq = _efficiencies(x, nmax, a, b)
    pi_t, tau_t = _pi_tau_table(mu, nmax)
    s1, s2 = _amplitudes(nmax, a, b, pi_t, tau_t)
    return qext, qsca, gq, s1, s2


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
        Phase function (|S1|^2 + |S2|^2) / (2 x^2 Q_sca pi), normalized so that
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


def single_sphere(*, m: complex, x: float, mu: np.ndarray | float = 1.0) -> SingleSphere:
    """Scatter a plane wave off one homogeneous sphere (Lorenz-Mie theory).

    Parameters
    ----------
    m : complex
        Refractive index of the sphere relative to the medium, m = n + i k with
        n > 0 and k >= 0. [-]
    x : float
        Size parameter 2 pi r / lambda (lambda in the medium), x > 0. [-]
    mu : array_like
        Cosines of the scattering angles, in [-1, 1]. [-]

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
    m = complex(m)
    if not (np.isfinite(m.real) and np.isfinite(m.imag)):
        raise ValueError(f"m must be a finite complex number; got {m!r}")
    if m.real <= 0.0 or m.imag < 0.0:
        raise ValueError(f"m must have n > 0 and k >= 0 (m = n + i k); got {m!r}")
    x = check_positive("x", x)
    mu_arr = np.atleast_1d(as_float_array("mu", mu))
    if mu_arr.ndim != 1 or np.any(np.abs(mu_arr) > 1.0):
        raise ValueError(f"mu must be a 1-D array of cosines in [-1, 1]; got {mu!r}")
    qext, qsca, gq, s1, s2 = _single_sphere_kernel(m, x, mu_arr)
    phase = (np.abs(s1) ** 2 + np.abs(s2) ** 2) / (2.0 * np.pi * x * x * qsca)
    return SingleSphere(
        qext=qext, qsca=qsca, qabs=qext - qsca, g=gq / qsca, mu=mu_arr, s1=s1, s2=s2, phase=phase
    )


# ----------------------------------------------------------------------------
# Polydisperse accumulation
# ----------------------------------------------------------------------------


#: Columns appended after the angular values in each row of :func:`_accumulate`:
#: sums of w, w x^2 Q_ext, w x^2 Q_sca, w x^2 Q_sca g, and w g.
N_SUMS = 5


@njit(cache=True, nogil=True)
def _accumulate(
    m: complex,
    x_nodes: np.ndarray,
    w_nodes: np.ndarray,
    node_panel: np.ndarray,
    n_panels: int,
    per_particle: bool,
    pi_t: np.ndarray,
    tau_t: np.ndarray,
    symmetric: bool,
) -> np.ndarray:
    """Sum the Mie quantities of many spheres with weights, per panel.

    For node j (size parameter x_j, weight w_j, panel node_panel[j]) adds to
    that panel's row the unpolarized intensity I_j(mu) = |S1_j|^2 + |S2_j|^2
    times c_j, where c_j = w_j (cross-section weighting: I_j / k^2 = 2 C_sca,j
    p_j, so the sum divided by 2 pi sum(w x^2 Q_sca) is the weighted phase
    function) or c_j = w_j / (2 pi x_j^2 Q_sca,j) when ``per_particle`` (each
    sphere's own normalized phase function, weighted by number).  Angles come
    as transposed tables pi_t[n - 1, i] = pi_n(mu_i) (tau_t likewise) at
    mu >= 0; if ``symmetric``, the next n_mu
    columns receive the values at -mu, obtained from the parity
    pi_n(-mu) = (-1)^(n-1) pi_n(mu), tau_n(-mu) = (-1)^n tau_n(mu) at no extra
    cost.  The last ``N_SUMS`` columns hold sums of w, w x^2 Q_ext,
    w x^2 Q_sca, w x^2 Q_sca g and w g (times pi (lambda / 2 pi)^2 the second
    and third are areas).  Returns an array of shape (n_panels, n_f + N_SUMS).
    """
    n_nodes = x_nodes.shape[0]
    n_mu = pi_t.shape[1]
    n_f = 2 * n_mu if symmetric else n_mu
    out = np.zeros((n_panels, n_f + N_SUMS))
    if n_nodes == 0:
        return out
    nmax_all = wiscombe_nmax(np.max(x_nodes))
    a = np.empty(nmax_all, dtype=np.complex128)
    b = np.empty(nmax_all, dtype=np.complex128)
    d = np.empty(nmax_all + 1, dtype=np.complex128)
    psi = np.empty(nmax_all + 1)
    aa = np.empty(nmax_all, dtype=np.complex128)
    bb = np.empty(nmax_all, dtype=np.complex128)
    acc = np.empty((8, n_mu))
    e1r, e1i, o1r, o1i = acc[0], acc[1], acc[2], acc[3]
    e2r, e2i, o2r, o2i = acc[4], acc[5], acc[6], acc[7]
    for j in range(n_nodes):
        x = x_nodes[j]
        w = w_nodes[j]
        row = out[node_panel[j]]
        nmax = wiscombe_nmax(x)
        _mie_coefficients(m, x, nmax, a, b, d, psi)
        qext, qsca, gq = _efficiencies(x, nmax, a, b)
        x2 = x * x
        row[n_f] += w
        row[n_f + 1] += w * x2 * qext
        row[n_f + 2] += w * x2 * qsca
        row[n_f + 3] += w * x2 * gq
        row[n_f + 4] += w * gq / qsca
        if per_particle:
            c = w / (2.0 * np.pi * x2 * qsca)
        else:
            c = w
        for k in range(nmax):
            n = k + 1
            cn = (2.0 * n + 1.0) / (n * (n + 1.0))
            aa[k] = cn * a[k]
            bb[k] = cn * b[k]
        # Parity split: e* collects terms even in mu, o* terms odd in mu, so
        # S(+mu) = e + o and S(-mu) = e - o.  Two orders (n odd, then n + 1
        # even) per pass; the inner loop runs over angles, contiguous in the
        # transposed tables, in real arithmetic, which the compiler vectorizes.
        e1r[:] = 0.0
        e1i[:] = 0.0
        o1r[:] = 0.0
        o1i[:] = 0.0
        e2r[:] = 0.0
        e2i[:] = 0.0
        o2r[:] = 0.0
        o2i[:] = 0.0
        for k in range(0, nmax, 2):
            ar0 = aa[k].real
            ai0 = aa[k].imag
            br0 = bb[k].real
            bi0 = bb[k].imag
            if k + 1 < nmax:
                ar1 = aa[k + 1].real
                ai1 = aa[k + 1].imag
                br1 = bb[k + 1].real
                bi1 = bb[k + 1].imag
                k1 = k + 1
            else:  # odd nmax: a zero even order against any valid row
                ar1 = 0.0
                ai1 = 0.0
                br1 = 0.0
                bi1 = 0.0
                k1 = k
            p0 = pi_t[k]
            t0 = tau_t[k]
            p1 = pi_t[k1]
            t1 = tau_t[k1]
            for i in range(n_mu):
                pp0 = p0[i]
                tt0 = t0[i]
                pp1 = p1[i]
                tt1 = t1[i]
                e1r[i] += ar0 * pp0 + br1 * tt1
                e1i[i] += ai0 * pp0 + bi1 * tt1
                o1r[i] += br0 * tt0 + ar1 * pp1
                o1i[i] += bi0 * tt0 + ai1 * pp1
                e2r[i] += br0 * pp0 + ar1 * tt1
                e2i[i] += bi0 * pp0 + ai1 * tt1
                o2r[i] += ar0 * tt0 + br1 * pp1
                o2i[i] += ai0 * tt0 + bi1 * pp1
        for i in range(n_mu):
            s1r = e1r[i] + o1r[i]
            s1i = e1i[i] + o1i[i]
            s2r = e2r[i] + o2r[i]
            s2i = e2i[i] + o2i[i]
            row[i] += c * (s1r * s1r + s1i * s1i + s2r * s2r + s2i * s2i)
            if symmetric:
                s1r = e1r[i] - o1r[i]
                s1i = e1i[i] - o1i[i]
                s2r = e2r[i] - o2r[i]
                s2i = e2i[i] - o2i[i]
                row[n_mu + i] += c * (s1r * s1r + s1i * s1i + s2r * s2r + s2i * s2i)
    return out


@njit(cache=True, nogil=True)
def _legendre_project(mu_half: np.ndarray, w_half: np.ndarray, f: np.ndarray, lmax: int) -> np.ndarray:
    """Legendre coefficients beta_l = (2l+1)/2 int f P_l dmu, l = 0..lmax.

    ``f`` holds values at +mu_half followed by values at -mu_half (Gauss
    nodes and weights of the positive half of a symmetric rule).
    """
    n_half = mu_half.shape[0]
    beta = np.zeros(lmax + 1)
    for i in range(n_half):
        u = mu_half[i]
        fe = w_half[i] * (f[i] + f[n_half + i])  # even part, times weight
        fo = w_half[i] * (f[i] - f[n_half + i])  # odd part, times weight
        p_prev = 0.0
        p_cur = 1.0
        for ell in range(lmax + 1):
            if ell % 2 == 0:
                beta[ell] += fe * p_cur
            else:
                beta[ell] += fo * p_cur
            p_next = ((2 * ell + 1) * u * p_cur - ell * p_prev) / (ell + 1)
            p_prev = p_cur
            p_cur = p_next
    for ell in range(lmax + 1):
        beta[ell] *= (2 * ell + 1) / 2.0
    return beta


@njit(cache=True, nogil=True)
def _legendre_regrid(
    rows: np.ndarray, mu_half: np.ndarray, w_half: np.ndarray, lmax: int, mu_half_out: np.ndarray
) -> np.ndarray:
    """Values of polynomials of degree <= lmax, given per row at a symmetric Gauss
    grid (+mu_half, then -mu_half), at the symmetric grid +mu_half_out, -mu_half_out.

    Each row is projected on P_0..P_lmax (exact when 2 len(mu_half) Gauss nodes
    integrate the row times P_lmax) and summed again by parity: the even
    orders give the part even in mu, the odd orders the odd part, so one
    Clenshaw-free pass over the output half-grid yields both signs.
    """
    n_rows = rows.shape[0]
    n_in = mu_half.shape[0]
    n_out = mu_half_out.shape[0]
    # P_l at the input and output half-grids, built once for all rows.
    p_in = np.empty((lmax + 1, n_in))
    p_out = np.empty((lmax + 1, n_out))
    for grid, table in ((mu_half, p_in), (mu_half_out, p_out)):
        for i in range(grid.shape[0]):
            u = grid[i]
            p_prev = 0.0
            p_cur = 1.0
            for ell in range(lmax + 1):
                table[ell, i] = p_cur
                p_next = ((2 * ell + 1) * u * p_cur - ell * p_prev) / (ell + 1)
                p_prev = p_cur
                p_cur = p_next
    out = np.empty((n_rows, 2 * n_out))
    beta = np.empty(lmax + 1)
    even = np.empty(n_out)
    odd = np.empty(n_out)
    for r in range(n_rows):
        row = rows[r]
        for ell in range(lmax + 1):
            acc = 0.0
            pl = p_in[ell]
            if ell % 2 == 0:
                for i in range(n_in):
                    acc += w_half[i] * (row[i] + row[n_in + i]) * pl[i]
            else:
                for i in range(n_in):
                    acc += w_half[i] * (row[i] - row[n_in + i]) * pl[i]
            beta[ell] = acc * (2 * ell + 1) / 2.0
        even[:] = 0.0
        odd[:] = 0.0
        for ell in range(lmax + 1):
            b = beta[ell]
            pl = p_out[ell]
            if ell % 2 == 0:
                for i in range(n_out):
                    even[i] += b * pl[i]
            else:
                for i in range(n_out):
                    odd[i] += b * pl[i]
        for i in range(n_out):
            out[r, i] = even[i] + odd[i]
            out[r, n_out + i] = even[i] - odd[i]
    return out


@njit(cache=True, nogil=True)
def _legendre_evaluate(beta: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Sum_l beta_l P_l(mu) by Clenshaw's recurrence."""
    lmax = beta.shape[0] - 1
    out = np.empty(mu.shape[0])
    for i in range(mu.shape[0]):
        u = mu[i]
        b1 = 0.0
        b2 = 0.0
        for ell in range(lmax, 0, -1):
            # P_{l+1} = alpha_l P_l + beta_l P_{l-1}: alpha = (2l+1)u/(l+1), beta = -l/(l+1)
            bk = beta[ell] + (2 * ell + 1) * u / (ell + 1) * b1 - (ell + 1) / (ell + 2) * b2
            b2 = b1
            b1 = bk
        out[i] = beta[0] + u * b1 - 0.5 * b2
    return out
