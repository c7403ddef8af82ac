"""Exact derivatives of single-sphere Mie results with respect to m = n + i k and x.

This module knows nothing of units, materials or size distributions.  Its
numba kernels (``cache=True``, no ``fastmath``, as :mod:`dustoptics.scattering.mie`)
take plain values and arrays (complex refractive index ``m``, size parameters
``x``, weights, direction cosines ``mu``); :func:`sphere_derivatives` is the one
public function, which validates and converts at the boundary.  The
polydisperse reference path, :mod:`dustoptics.scattering.derivatives`, sums the
same kernels over a radius quadrature (:func:`_accumulate`);
:mod:`dustoptics.scattering.table_derivatives` sums the table's nodes with
:func:`_accumulate_blocked`, which takes the coefficients from the table's own
kernel (``mie._mie_coefficients``, 16 spheres at a time) and computes S1, S2
and dS1/dm, dS2/dm in one pass over the orders (and n, k from the one complex
derivative).

Conventions are those of :mod:`dustoptics.scattering.mie` (Bohren & Huffman
1983, chapter 4): time dependence exp(-i w t), m = n + i k with k >= 0, van de
Hulst's dimensionless amplitudes S1, S2, mu = cos(theta), Wiscombe's series
length n_max = x + 4.05 x^(1/3) + 2.

Derivation
----------
The coefficients are (BH Eq. 4.88, as ``mie._mie_coefficients`` writes them)

    a_n = (t_a psi_n - psi_{n-1}) / (t_a xi_n - xi_{n-1}),   t_a = D_n(m x) / m + n / x,
    b_n = (t_b psi_n - psi_{n-1}) / (t_b xi_n - xi_{n-1}),   t_b = m D_n(m x) + n / x,

with psi_n(x) = x j_n(x), chi_n(x) = -x y_n(x), xi_n = psi_n - i chi_n and
D_n(z) = psi_n'(z) / psi_n(z).  Only t depends on m, so with the denominator
d = t xi_n - xi_{n-1},

    da_n / dt = (psi_{n-1} xi_n - psi_n xi_{n-1}) / d^2 = -i / d^2,

since psi_n chi_{n-1} - psi_{n-1} chi_n = -1 (the Wronskian of psi_n and chi_n,
psi_n chi_n' - psi_n' chi_n = -1, with psi_n' = psi_{n-1} - n psi_n / x and the
same for chi_n).  With D_n' = dD_n/dz,

    dt_a/dm = x D_n' / m - D_n / m^2,      dt_b/dm = D_n + m x D_n',
    dt_a/dx = D_n' - n / x^2,              dt_b/dx = m^2 D_n' - n / x^2.

D_n(z) comes from the downward recurrence D_{n-1} = n/z - 1/(D_n + n/z)
(BH Eq. 4.89, stable for every complex z) started at D_N = 0, and its
derivative from the same recurrence differentiated,
D_{n-1}' = -n/z^2 + (D_n' - n/z^2) / (D_n + n/z)^2, started at D_N' = 0.  The
start's error decays in both by the factor 1/(D_n + n/z)^2 per step, but only
above the turning point n ~ abs(z): BHMIE's N = max(n_max, abs(z)) + 15 leaves
errors of 2e-5 at x = 50 and 0.2 at x = 200 for real m = 1.5 (measured against
a start at 4 abs(z)), so N = max(n_max, abs(z)) + 16 + 8 abs(z)^(1/3) here (the width of
the turning region grows as abs(z)^(1/3)), which agrees with a start at 4 abs(z) to
the last bit for m from 1.0001 to 4 and x from 0.5 to 2e4.  The derivative is
then that of the computed D_n.  (The Riccati equation
D_n' = n(n+1)/z^2 - 1 - D_n^2 gives it too, but cancels for n >> abs(z).)  The
x derivative adds the terms of psi_n' and xi_n':

    da_n/dx = -i (dt_a/dx) / d^2 + [(t_a psi_n' - psi_{n-1}') - a_n (t_a xi_n' - xi_{n-1}')] / d

with psi_{n-1}' = n psi_{n-1} / x - psi_n (and likewise for xi).  This is the
approach of Grainger et al. (2004), who differentiate a_n and b_n through D_n;
the expressions above, the Wronskian simplification and the differentiated
recurrence are derived here.

The coefficients a_n, b_n and the amplitudes S1(mu), S2(mu) (BH Eq. 4.74) are
holomorphic in m, so d/dn = d/dm and d/dk = i d/dm.  Real quantities follow by
the chain rule: for R(a, conj(a)), dR/dp = 2 Re(dR/da da/dp) with the
Wirtinger derivative dR/da, e.g. d abs(a)^2/dp = 2 Re(conj(a) da/dp).  So::

    Q_ext = (2/x^2) sum (2n+1) Re(a_n + b_n),
    Q_sca = (2/x^2) sum (2n+1) (abs(a_n)^2 + abs(b_n)^2),
    g Q_sca = (4/x^2) sum [n(n+2)/(n+1) Re(a_n a_{n+1}* + b_n b_{n+1}*)
                           + (2n+1)/(n(n+1)) Re(a_n b_n*)],
    Q_back = (1/x^2) abs(sum (2n+1) (-1)^n (a_n - b_n))^2

(BH Eqs. 4.61, 4.62, p. 120 and p. 122) and the scattering matrix
I = abs(S1)^2 + abs(S2)^2, Q = abs(S2)^2 - abs(S1)^2, U = 2 Re(S2 S1*), V = 2 Im(S2 S1*)
(BH Eq. 4.77: 2 S11, 2 S12, 2 S33, 2 S34) are differentiated term by term.
The phase matrix is normalized as the table's: F11 = I / (2 pi x^2 Q_sca),
2 pi int F11 dmu = 1, F12 = Q / (2 pi x^2 Q_sca), F33 and F34 likewise.

References
----------
.. [1] C. F. Bohren and D. R. Huffman, *Absorption and Scattering of Light by
   Small Particles*, Wiley, 1983. doi:10.1002/9783527618156
.. [2] R. G. Grainger, J. Lucas, G. E. Thomas and G. B. L. Ewen, "Calculation
   of Mie derivatives," Appl. Opt. 43, 5386-5393 (2004).
   doi:10.1364/AO.43.005386
.. [3] W. J. Wiscombe, "Improved Mie scattering algorithms," Appl. Opt. 19,
   1505-1509 (1980). doi:10.1364/AO.19.001505
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from dustoptics._validation import as_float_array, check_budget, check_choice
from dustoptics.scattering.mie import (
    _AI,
    _AR,
    _BI,
    _BLK,
    _BR,
    _CHI,
    _DNI,
    _DNR,
    _LANE,
    _PSI,
    BLOCK,
    LANES,
    _mie_coefficients,
    _reciprocal,
    _workspace,
    check_sphere_inputs,
    wiscombe_nmax,
)

__all__ = [
    "SphereDerivatives",
    "sphere_derivatives",
]

#: Parameters of :meth:`SphereDerivatives.derivative`: the real and imaginary
#: parts of m, the size parameter, and (for a_n, b_n, S1, S2 only) the
#: complex derivative d/dm.
PARAMETERS = ("n", "k", "x", "m")

#: Quantities of :meth:`SphereDerivatives.derivative`.
QUANTITIES = (
    "qext",
    "qsca",
    "qabs",
    "qback",
    "g",
    "a",
    "b",
    "s1",
    "s2",
    "f11",
    "f12",
    "f33",
    "f34",
)

#: Columns of the per-sphere sums of :func:`_accumulate` (as ``mie.N_SUMS``):
#: 1, x^2 Q_ext, x^2 Q_sca, x^2 g Q_sca, g, x^2 Q_back.
N_SUMS = 6


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------


@njit(cache=True, nogil=True, error_model="numpy")
def _riccati_bessel(x: float, nmax: int) -> tuple[np.ndarray, np.ndarray]:
    """psi_n(x) and chi_n(x), n = 0..nmax.

    psi_n by Miller's downward recurrence psi_{n-1} = (2n+1)/x psi_n - psi_{n+1}
    (dominant downward; rescaled on the way so nothing overflows), normalized to
    psi_0 = sin x or psi_1 = sin x / x - cos x, whichever is larger; chi_n by the
    upward recurrence from chi_0 = cos x, chi_1 = cos x / x + sin x (dominant
    upward).  The start of the downward recurrence is ``mie._miller_start``'s.
    """
    psi = np.zeros(nmax + 1)
    chi = np.empty(nmax + 1)
    start = int(max(nmax, x) + 25 + 1.5 * np.sqrt(x))
    p_next = 0.0
    p_cur = 1e-280
    inv_x = 1.0 / x
    for n in range(start, 0, -1):
        p = (2 * n + 1) * inv_x * p_cur - p_next
        p_next = p_cur
        p_cur = p
        if n - 1 <= nmax:
            psi[n - 1] = p_cur
        if abs(p_cur) > 1e250:
            p_cur *= 1e-250
            p_next *= 1e-250
            for j in range(n - 1, nmax + 1):
                psi[j] *= 1e-250
    sx = np.sin(x)
    cx = np.cos(x)
    psi1 = sx * inv_x - cx
    scale = sx / psi[0] if (abs(sx) >= abs(psi1) or nmax < 1) else psi1 / psi[1]
    for j in range(nmax + 1):
        psi[j] *= scale
    chi[0] = cx
    if nmax >= 1:
        chi[1] = cx * inv_x + sx
    for n in range(1, nmax):
        chi[n + 1] = (2 * n + 1) * inv_x * chi[n] - chi[n - 1]
    return psi, chi


@njit(cache=True, nogil=True, error_model="numpy")
def _log_derivative(z: complex, nmax: int) -> tuple[np.ndarray, np.ndarray]:
    """D_n(z) and dD_n/dz, n = 0..nmax, by the downward recurrence and its
    derivative (module docstring), from D_N = D_N' = 0 at
    N = max(nmax, abs(z)) + 16 + 8 abs(z)^(1/3)."""
    d = np.empty(nmax + 1, dtype=np.complex128)
    dd = np.empty(nmax + 1, dtype=np.complex128)
    start = int(max(nmax, abs(z)) + 16.0 + 8.0 * abs(z) ** (1.0 / 3.0))
    inv_z = 1.0 / z
    inv_z2 = inv_z * inv_z
    cur = 0.0 + 0.0j
    dcur = 0.0 + 0.0j
    for n in range(start, 0, -1):
        if n <= nmax:
            d[n] = cur
            dd[n] = dcur
        u = cur + n * inv_z
        inv_u = 1.0 / u
        dcur = -n * inv_z2 + (dcur - n * inv_z2) * inv_u * inv_u
        cur = n * inv_z - inv_u
    d[0] = cur
    dd[0] = dcur
    return d, dd


@njit(cache=True, nogil=True, error_model="numpy")
def _coefficient_derivatives(
    m: complex, x: float, nmax: int, want_x: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """a_n, b_n (n = 1..nmax, at index n - 1), da_n/dm, db_n/dm and, if
    ``want_x``, da_n/dx and db_n/dx (zeros otherwise); see the module docstring."""
    psi, chi = _riccati_bessel(x, nmax)
    d, dd = _log_derivative(m * x, nmax)
    a = np.empty(nmax, dtype=np.complex128)
    b = np.empty(nmax, dtype=np.complex128)
    da = np.empty(nmax, dtype=np.complex128)
    db = np.empty(nmax, dtype=np.complex128)
    dax = np.zeros(nmax, dtype=np.complex128)
    dbx = np.zeros(nmax, dtype=np.complex128)
    inv_m = 1.0 / m
    inv_x = 1.0 / x
    for n in range(1, nmax + 1):
        p1 = psi[n]
        p0 = psi[n - 1]
        xi1 = complex(psi[n], -chi[n])
        xi0 = complex(psi[n - 1], -chi[n - 1])
        n_x = n * inv_x
        dn = d[n]
        ddn = dd[n]
        t_a = dn * inv_m + n_x
        t_b = m * dn + n_x
        den_a = t_a * xi1 - xi0
        den_b = t_b * xi1 - xi0
        ra = 1.0 / den_a
        rb = 1.0 / den_b
        an = (t_a * p1 - p0) * ra
        bn = (t_b * p1 - p0) * rb
        # da/dt = -i / d^2 (the Wronskian; module docstring).
        ga = -1j * ra * ra
        gb = -1j * rb * rb
        a[n - 1] = an
        b[n - 1] = bn
        da[n - 1] = ga * (x * ddn * inv_m - dn * inv_m * inv_m)
        db[n - 1] = gb * (dn + m * x * ddn)
        if want_x:
            dp1 = p0 - n_x * p1  # psi_n'
            dp0 = n_x * p0 - p1  # psi_{n-1}'
            dxi1 = xi0 - n_x * xi1
            dxi0 = n_x * xi0 - xi1
            nn_x2 = n * inv_x * inv_x
            dta = ddn - nn_x2
            dtb = m * m * ddn - nn_x2
            dax[n - 1] = ga * dta + ((t_a * dp1 - dp0) - an * (t_a * dxi1 - dxi0)) * ra
            dbx[n - 1] = gb * dtb + ((t_b * dp1 - dp0) - bn * (t_b * dxi1 - dxi0)) * rb
    return a, b, da, db, dax, dbx


@njit(cache=True, nogil=True)
def _pi_tau(mu: np.ndarray, nmax: int) -> tuple[np.ndarray, np.ndarray]:
    """pi_n(mu), tau_n(mu), n = 1..nmax, shape (len(mu), nmax), by the upward
    recurrences of BH Eq. 4.47 (stable for abs(mu) <= 1)."""
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
def _amplitude_sums(
    nmax: int,
    a: np.ndarray,
    b: np.ndarray,
    da: np.ndarray,
    db: np.ndarray,
    dax: np.ndarray,
    dbx: np.ndarray,
    pi_t: np.ndarray,
    tau_t: np.ndarray,
    want_x: bool,
) -> np.ndarray:
    """S1, S2, dS1/dm, dS2/dm, dS1/dx, dS2/dx (rows 0-5) at the angles of the
    tables, shape (6, n_mu); the x rows are zero unless ``want_x``."""
    n_mu = pi_t.shape[0]
    out = np.zeros((6, n_mu), dtype=np.complex128)
    for i in range(n_mu):
        s1 = 0.0j
        s2 = 0.0j
        d1 = 0.0j
        d2 = 0.0j
        x1 = 0.0j
        x2 = 0.0j
        for k in range(nmax):
            n = k + 1.0
            c = (2.0 * n + 1.0) / (n * (n + 1.0))
            p = c * pi_t[i, k]
            t = c * tau_t[i, k]
            s1 += a[k] * p + b[k] * t
            s2 += a[k] * t + b[k] * p
            d1 += da[k] * p + db[k] * t
            d2 += da[k] * t + db[k] * p
            if want_x:
                x1 += dax[k] * p + dbx[k] * t
                x2 += dax[k] * t + dbx[k] * p
        out[0, i] = s1
        out[1, i] = s2
        out[2, i] = d1
        out[3, i] = d2
        out[4, i] = x1
        out[5, i] = x2
    return out


@njit(cache=True, nogil=True)
def _sums(
    nmax: int,
    a: np.ndarray,
    b: np.ndarray,
    da: np.ndarray,
    db: np.ndarray,
    dax: np.ndarray,
    dbx: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """x^2 Q_ext, x^2 Q_sca, x^2 g Q_sca, x^2 Q_back (values, shape (4,)) and
    their derivatives along n, k and x (shape (3, 4)); the x row is that of
    the coefficients alone (the x^2 factors absorb the explicit 1/x^2)."""
    val = np.zeros(4)
    der = np.zeros((3, 4))
    back = 0.0j
    dback = np.zeros(3, dtype=np.complex128)
    sign = -1.0
    for k in range(nmax):
        n = k + 1.0
        c = 2.0 * n + 1.0
        an = a[k]
        bn = b[k]
        val[0] += 2.0 * c * (an.real + bn.real)
        val[1] += (
            2.0
            * c
            * (an.real * an.real + an.imag * an.imag + bn.real * bn.real + bn.imag * bn.imag)
        )
        val[2] += 4.0 * c / (n * (n + 1.0)) * (an * bn.conjugate()).real
        back += sign * c * (an - bn)
        has_next = k + 1 < nmax
        cn = 4.0 * n * (n + 2.0) / (n + 1.0)
        if has_next:
            val[2] += cn * ((an * a[k + 1].conjugate()).real + (bn * b[k + 1].conjugate()).real)
        for j in range(3):
            # The direction's derivatives of a_n, b_n: d/dm, i d/dm, d/dx.
            if j == 0:
                ea = da[k]
                eb = db[k]
            elif j == 1:
                ea = 1j * da[k]
                eb = 1j * db[k]
            else:
                ea = dax[k]
                eb = dbx[k]
            der[j, 0] += 2.0 * c * (ea.real + eb.real)
            der[j, 1] += 4.0 * c * ((an.conjugate() * ea).real + (bn.conjugate() * eb).real)
            der[j, 2] += (
                4.0
                * c
                / (n * (n + 1.0))
                * ((ea * bn.conjugate()).real + (an * eb.conjugate()).real)
            )
            if has_next:
                if j == 0:
                    fa = da[k + 1]
                    fb = db[k + 1]
                elif j == 1:
                    fa = 1j * da[k + 1]
                    fb = 1j * db[k + 1]
                else:
                    fa = dax[k + 1]
                    fb = dbx[k + 1]
                der[j, 2] += cn * (
                    (ea * a[k + 1].conjugate()).real
                    + (an * fa.conjugate()).real
                    + (eb * b[k + 1].conjugate()).real
                    + (bn * fb.conjugate()).real
                )
            dback[j] += sign * c * (ea - eb)
        sign = -sign
    val[3] = back.real * back.real + back.imag * back.imag
    for j in range(3):
        der[j, 3] = 2.0 * (back.conjugate() * dback[j]).real
    return val, der


@njit(cache=True, nogil=True)
def _stokes(
    s1: complex, s2: complex, d1: complex, d2: complex
) -> tuple[float, float, float, float, float, float, float, float]:
    """I, Q, U, V of (S1, S2) and their derivatives along (dS1, dS2)."""
    p1 = s1.real * s1.real + s1.imag * s1.imag
    p2 = s2.real * s2.real + s2.imag * s2.imag
    c = s2 * s1.conjugate()
    dp1 = 2.0 * (s1.conjugate() * d1).real
    dp2 = 2.0 * (s2.conjugate() * d2).real
    dc = d2 * s1.conjugate() + s2 * d1.conjugate()
    return (
        p1 + p2,
        p2 - p1,
        2.0 * c.real,
        2.0 * c.imag,
        dp1 + dp2,
        dp2 - dp1,
        2.0 * dc.real,
        2.0 * dc.imag,
    )


@njit(cache=True, nogil=True)
def _single(
    m: complex, x: float, mu: np.ndarray
) -> tuple[
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
]:
    """One sphere: a, b, da/dm, db/dm, da/dx, db/dx, the amplitude rows of
    :func:`_amplitude_sums`, and the sums of :func:`_sums` (values, derivatives)."""
    nmax = wiscombe_nmax(x)
    a, b, da, db, dax, dbx = _coefficient_derivatives(m, x, nmax, True)
    pi_t, tau_t = _pi_tau(mu, nmax)
    amp = _amplitude_sums(nmax, a, b, da, db, dax, dbx, pi_t, tau_t, True)
    val, der = _sums(nmax, a, b, da, db, dax, dbx)
    return a, b, da, db, dax, dbx, amp, val, der


@njit(cache=True, nogil=True)
def _accumulate(
    m: complex,
    x_nodes: np.ndarray,
    weights: np.ndarray,
    mu: np.ndarray,
    per_particle: bool,
    want_x: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Weighted sums over spheres of the scattering matrix and the efficiency
    sums, and their derivatives along n, k (and x).

    Node j has size parameter ``x_nodes[j]`` and a row of weights
    ``weights[j, :]`` (column 0: the quadrature weight n(r_j) (dr/ds) w_s; the
    other columns: the same with dn/dp in place of n, one per distribution
    parameter p).  For each weight column c returns

    * ``ang[c, q, i]``: sum_j weights[j, c] X_q,j(mu_i), X = (I, Q, U, V) of
      the module docstring, each divided by 2 pi x_j^2 Q_sca,j if
      ``per_particle`` (each sphere's own normalized phase matrix);
    * ``sums[c, :]``: sum_j weights[j, c] (1, x^2 Q_ext, x^2 Q_sca,
      x^2 g Q_sca, g, x^2 Q_back)_j;

    and with column 0's weights the derivatives of the same sums with respect
    to n and k (and, if ``want_x``, to every node's x at once: direction 2):
    ``dang[d, q, i]`` and ``dsums[d, :]``.
    """
    n_nodes = x_nodes.shape[0]
    n_w = weights.shape[1]
    n_mu = mu.shape[0]
    n_dir = 3 if want_x else 2
    ang = np.zeros((n_w, 4, n_mu))
    dang = np.zeros((n_dir, 4, n_mu))
    sums = np.zeros((n_w, N_SUMS))
    dsums = np.zeros((n_dir, N_SUMS))
    if n_nodes == 0:
        return ang, dang, sums, dsums
    x_top = x_nodes[0]
    for j in range(n_nodes):
        x_top = max(x_top, x_nodes[j])
    pi_t, tau_t = _pi_tau(mu, wiscombe_nmax(x_top))
    for j in range(n_nodes):
        x = x_nodes[j]
        nmax = wiscombe_nmax(x)
        a, b, da, db, dax, dbx = _coefficient_derivatives(m, x, nmax, want_x)
        val, der = _sums(nmax, a, b, da, db, dax, dbx)
        qs = val[1]  # x^2 Q_sca
        g = val[2] / qs
        node = np.empty(N_SUMS)
        node[0] = 1.0
        node[1] = val[0]
        node[2] = val[1]
        node[3] = val[2]
        node[4] = g
        node[5] = val[3]
        w0 = weights[j, 0]
        for c in range(n_w):
            wc = weights[j, c]
            for q in range(N_SUMS):
                sums[c, q] += wc * node[q]
        for d in range(n_dir):
            dsums[d, 1] += w0 * der[d, 0]
            dsums[d, 2] += w0 * der[d, 1]
            dsums[d, 3] += w0 * der[d, 2]
            dsums[d, 4] += w0 * (der[d, 2] - g * der[d, 1]) / qs
            dsums[d, 5] += w0 * der[d, 3]
        if n_mu == 0:
            continue
        amp = _amplitude_sums(nmax, a, b, da, db, dax, dbx, pi_t, tau_t, want_x)
        scale = 1.0 / (2.0 * np.pi * qs) if per_particle else 1.0
        for i in range(n_mu):
            s1 = amp[0, i]
            s2 = amp[1, i]
            for d in range(n_dir):
                if d == 0:
                    e1 = amp[2, i]
                    e2 = amp[3, i]
                elif d == 1:
                    e1 = 1j * amp[2, i]
                    e2 = 1j * amp[3, i]
                else:
                    e1 = amp[4, i]
                    e2 = amp[5, i]
                xi, xq, xu, xv, di, dq, du, dv = _stokes(s1, s2, e1, e2)
                if d == 0:
                    for c in range(n_w):
                        wc = weights[j, c] * scale
                        ang[c, 0, i] += wc * xi
                        ang[c, 1, i] += wc * xq
                        ang[c, 2, i] += wc * xu
                        ang[c, 3, i] += wc * xv
                # d(scale X) = scale dX + X d(scale), d(scale) = -scale d(x^2 Q_sca) / (x^2 Q_sca)
                rel = -der[d, 1] / qs if per_particle else 0.0
                w = w0 * scale
                dang[d, 0, i] += w * (di + rel * xi)
                dang[d, 1, i] += w * (dq + rel * xq)
                dang[d, 2, i] += w * (du + rel * xu)
                dang[d, 3, i] += w * (dv + rel * xv)
    return ang, dang, sums, dsums


@njit(cache=True, nogil=True)
def _series_lengths(x: np.ndarray) -> np.ndarray:
    """Wiscombe's n_max of every size parameter (``mie.wiscombe_nmax``). [-]"""
    out = np.empty(x.shape[0], dtype=np.int64)
    for j in range(x.shape[0]):
        out[j] = wiscombe_nmax(x[j])
    return out


# Rows of the per-sphere working array of :func:`_batch_derivatives` (LANES
# values each, offsets as ``mie``'s): x, 1/x, 1/z^2 (re, im), n_max, the
# previous order's a, b, da/dm, db/dm (re, im), and the twelve sums.
(
    _L_X,
    _L_INVX,
    _L_IZ2R,
    _L_IZ2I,
    _L_NMAX,
    _L_APR,
    _L_API,
    _L_BPR,
    _L_BPI,
    _L_DAPR,
    _L_DAPI,
    _L_DBPR,
    _L_DBPI,
    _L_QEXT,
    _L_QSCA,
    _L_GQ,
    _L_BACKR,
    _L_BACKI,
    _L_DEXTR,
    _L_DEXTI,
    _L_DBACKR,
    _L_DBACKI,
    _L_DSCAN,
    _L_DSCAK,
    _L_DGQN,
    _L_DGQK,
) = range(0, 26 * LANES, LANES)
_L_ROWS = 26


@njit(cache=True, nogil=True, error_model="numpy")
def _batch_derivatives(
    m: complex, ws: np.ndarray, x_b: np.ndarray, nmax_b: np.ndarray, coef: np.ndarray
) -> np.ndarray:
    """m derivatives of the LANES spheres of workspace ``ws`` after
    ``mie._mie_coefficients(m, x_b, nmax_b, ws)``.

    Writes (2n+1)/(n(n+1)) times a_n, b_n, da_n/dm, db_n/dm (real and
    imaginary parts) to ``coef[n - 1, q * LANES + s]``, q = 0..7 (zero above sphere s's
    n_max, as the table's a_n, b_n), and returns the per-sphere sums, shape
    (LANES, 12): x^2 Q_ext, x^2 Q_sca, x^2 g Q_sca, x^2 Q_back, their
    derivatives along n, then along k (dm = i: Cauchy-Riemann).

    The coefficients, psi_n, chi_n and D_n(m x) are the table's own
    (``mie._mie_coefficients``, D_n from Lentz's start at n_top); dD_n/dz
    from the Riccati equation D_n' = n(n+1)/z^2 - 1 - D_n^2 (which cancels
    for n >> abs(z) to about n times the rounding error, far below the
    quadrature's), da_n/dm and db_n/dm by the formulas of the module
    docstring.  Loops over spheres innermost in real arithmetic, as the
    table's kernel, so that the compiler vectorizes them.
    """
    mr = m.real
    mi = m.imag
    imr, imi = _reciprocal(mr, mi)  # 1/m
    im2r = imr * imr - imi * imi  # 1/m^2
    im2i = 2.0 * imr * imi
    lane = np.empty(_L_ROWS * LANES)
    lane[:] = 0.0
    n_top = nmax_b[0]
    for s in range(LANES):
        n_top = max(n_top, nmax_b[s])
        x = x_b[s]
        ix2 = 1.0 / (x * x)
        lane[_L_X + s] = x
        lane[_L_INVX + s] = 1.0 / x
        lane[_L_IZ2R + s] = im2r * ix2
        lane[_L_IZ2I + s] = im2i * ix2
        lane[_L_NMAX + s] = nmax_b[s]
    sign = -1.0
    for n in range(1, n_top + 1):
        o = ws[_LANE + (n - 1) * _BLK : _LANE + (n + 1) * _BLK]  # orders n - 1, n
        ck = coef[n - 1]
        c = 2.0 * n + 1.0
        cn = c / (n * (n + 1.0))
        c2 = 2.0 * c
        c4 = 4.0 * c
        f = 4.0 * cn
        fp = 4.0 * (n - 1.0) * (n + 1.0) / n  # of the pair (n - 1, n) in g Q_sca
        sc = sign * c
        nn1 = n * (n + 1.0)
        for s in range(LANES):
            keep = n <= lane[_L_NMAX + s]
            dr = o[_BLK + _DNR + s]
            di = o[_BLK + _DNI + s]
            p1 = o[_BLK + _PSI + s]
            p0 = o[_PSI + s]
            c1 = o[_BLK + _CHI + s]
            c0 = o[_CHI + s]
            ar = o[_AR + s]
            ai = o[_AI + s]
            br = o[_BR + s]
            bi = o[_BI + s]
            x = lane[_L_X + s]
            n_x = n * lane[_L_INVX + s]
            # D' = n(n+1)/z^2 - 1 - D^2
            ddr = nn1 * lane[_L_IZ2R + s] - 1.0 - (dr * dr - di * di)
            ddi = nn1 * lane[_L_IZ2I + s] - 2.0 * dr * di
            # t_a = D/m + n/x, t_b = m D + n/x; 1/(t xi_n - xi_{n-1})
            tar = dr * imr - di * imi + n_x
            tai = dr * imi + di * imr
            tbr = mr * dr - mi * di + n_x
            tbi = mr * di + mi * dr
            ur, ui = _reciprocal(tar * p1 + tai * c1 - p0, tai * p1 - tar * c1 + c0)
            vr, vi = _reciprocal(tbr * p1 + tbi * c1 - p0, tbi * p1 - tbr * c1 + c0)
            # dt_a/dm = x D'/m - D/m^2, dt_b/dm = D + m x D'
            ear = x * (ddr * imr - ddi * imi) - (dr * im2r - di * im2i)
            eai = x * (ddr * imi + ddi * imr) - (dr * im2i + di * im2r)
            ebr = dr + x * (mr * ddr - mi * ddi)
            ebi = di + x * (mr * ddi + mi * ddr)
            # da/dt = -i / d^2: -i (u^2) = 2 ur ui - i (ur^2 - ui^2)
            gar = 2.0 * ur * ui
            gai = ui * ui - ur * ur
            gbr = 2.0 * vr * vi
            gbi = vi * vi - vr * vr
            dar = gar * ear - gai * eai
            dai = gar * eai + gai * ear
            dbr = gbr * ebr - gbi * ebi
            dbi = gbr * ebi + gbi * ebr
            dar = dar if keep else 0.0
            dai = dai if keep else 0.0
            dbr = dbr if keep else 0.0
            dbi = dbi if keep else 0.0
            ck[s] = cn * ar
            ck[LANES + s] = cn * ai
            ck[2 * LANES + s] = cn * br
            ck[3 * LANES + s] = cn * bi
            ck[4 * LANES + s] = cn * dar
            ck[5 * LANES + s] = cn * dai
            ck[6 * LANES + s] = cn * dbr
            ck[7 * LANES + s] = cn * dbi
            lane[_L_QEXT + s] += c2 * (ar + br)
            lane[_L_QSCA + s] += c2 * (ar * ar + ai * ai + br * br + bi * bi)
            lane[_L_BACKR + s] += sc * (ar - br)
            lane[_L_BACKI + s] += sc * (ai - bi)
            lane[_L_DEXTR + s] += c2 * (dar + dbr)
            lane[_L_DEXTI + s] += c2 * (dai + dbi)
            lane[_L_DBACKR + s] += sc * (dar - dbr)
            lane[_L_DBACKI + s] += sc * (dai - dbi)
            # d abs(a)^2 = 2 Re(conj(a) da); along k (da -> i da), -2 Im(conj(a) da).
            lane[_L_DSCAN + s] += c4 * (ar * dar + ai * dai + br * dbr + bi * dbi)
            lane[_L_DSCAK + s] -= c4 * (ar * dai - ai * dar + br * dbi - bi * dbr)
            # g Q_sca x^2: f Re(a_n b_n*) + fp Re(a_{n-1} a_n* + b_{n-1} b_n*); along
            # k the derivative of Re(p q*) is -Im(dp q* - p dq*).
            apr = lane[_L_APR + s]
            api = lane[_L_API + s]
            bpr = lane[_L_BPR + s]
            bpi = lane[_L_BPI + s]
            dapr = lane[_L_DAPR + s]
            dapi = lane[_L_DAPI + s]
            dbpr = lane[_L_DBPR + s]
            dbpi = lane[_L_DBPI + s]
            lane[_L_GQ + s] += f * (ar * br + ai * bi) + fp * (
                apr * ar + api * ai + bpr * br + bpi * bi
            )
            lane[_L_DGQN + s] += f * (dar * br + dai * bi + ar * dbr + ai * dbi) + fp * (
                dapr * ar
                + dapi * ai
                + apr * dar
                + api * dai
                + dbpr * br
                + dbpi * bi
                + bpr * dbr
                + bpi * dbi
            )
            lane[_L_DGQK + s] -= f * ((dai * br - dar * bi) - (ai * dbr - ar * dbi)) + fp * (
                (dapi * ar - dapr * ai)
                - (api * dar - apr * dai)
                + (dbpi * br - dbpr * bi)
                - (bpi * dbr - bpr * dbi)
            )
            lane[_L_APR + s] = ar
            lane[_L_API + s] = ai
            lane[_L_BPR + s] = br
            lane[_L_BPI + s] = bi
            lane[_L_DAPR + s] = dar
            lane[_L_DAPI + s] = dai
            lane[_L_DBPR + s] = dbr
            lane[_L_DBPI + s] = dbi
        sign = -sign
    # Orders up to the next multiple of 4 read by the angular pass: zero.
    for k in range(n_top, min(coef.shape[0], 4 * ((n_top + 3) // 4))):
        coef[k] = 0.0
    out = np.empty((LANES, 12))
    for s in range(LANES):
        br_ = lane[_L_BACKR + s]
        bi_ = lane[_L_BACKI + s]
        dbr_ = lane[_L_DBACKR + s]
        dbi_ = lane[_L_DBACKI + s]
        out[s, 0] = lane[_L_QEXT + s]
        out[s, 1] = lane[_L_QSCA + s]
        out[s, 2] = lane[_L_GQ + s]
        out[s, 3] = br_ * br_ + bi_ * bi_
        out[s, 4] = lane[_L_DEXTR + s]
        out[s, 5] = lane[_L_DSCAN + s]
        out[s, 6] = lane[_L_DGQN + s]
        # d abs(B)^2 = 2 Re(conj(B) dB); along k, -2 Im(conj(B) dB).
        out[s, 7] = 2.0 * (br_ * dbr_ + bi_ * dbi_)
        out[s, 8] = -lane[_L_DEXTI + s]
        out[s, 9] = lane[_L_DSCAK + s]
        out[s, 10] = lane[_L_DGQK + s]
        out[s, 11] = -2.0 * (br_ * dbi_ - bi_ * dbr_)
    return out


@njit(cache=True, nogil=True)
def _amplitudes_and_derivatives(
    coef: np.ndarray, s: int, nmax: int, table: np.ndarray, acc: np.ndarray
) -> None:
    """S1, S2 and dS1/dm, dS2/dm of one sphere at the angles of ``table``
    (``mie.angular_table``'s blocked layout), split by parity as the table's
    kernel splits S1, S2 (``mie._add_sphere``), into ``acc``: per block of
    BLOCK angles 16 rows, the even and odd parts (real, imaginary) of S1,
    S2 (rows 0-7, the table's layout) and of dS1, dS2 (rows 8-15).  One pass
    over the orders for the values and the derivative: the angular functions
    are read once, four orders at a time, angles innermost in real
    arithmetic (the compiler vectorizes it)."""
    acc[:] = 0.0
    n_pass = (nmax + 3) // 4
    n_blocks = acc.shape[0] // (16 * BLOCK)
    nb = acc.shape[0] // (16 * n_blocks)  # BLOCK, known at run time only
    for q in range(n_pass):
        k = 4 * q
        c0 = coef[k, s::LANES]
        c1 = coef[k + 1, s::LANES]
        c2 = coef[k + 2, s::LANES]
        c3 = coef[k + 3, s::LANES]
        ar0, ai0, br0, bi0, dar0, dai0, dbr0, dbi0 = (
            c0[0],
            c0[1],
            c0[2],
            c0[3],
            c0[4],
            c0[5],
            c0[6],
            c0[7],
        )
        ar1, ai1, br1, bi1, dar1, dai1, dbr1, dbi1 = (
            c1[0],
            c1[1],
            c1[2],
            c1[3],
            c1[4],
            c1[5],
            c1[6],
            c1[7],
        )
        ar2, ai2, br2, bi2, dar2, dai2, dbr2, dbi2 = (
            c2[0],
            c2[1],
            c2[2],
            c2[3],
            c2[4],
            c2[5],
            c2[6],
            c2[7],
        )
        ar3, ai3, br3, bi3, dar3, dai3, dbr3, dbi3 = (
            c3[0],
            c3[1],
            c3[2],
            c3[3],
            c3[4],
            c3[5],
            c3[6],
            c3[7],
        )
        t = table[q]
        a = acc
        for blk in range(n_blocks):
            o = blk * 8 * BLOCK
            d = blk * 16 * BLOCK
            for ii in range(nb):
                i = o + ii
                e = d + ii
                pp0 = t[i]
                tt0 = t[BLOCK + i]
                pp1 = t[2 * BLOCK + i]
                tt1 = t[3 * BLOCK + i]
                pp2 = t[4 * BLOCK + i]
                tt2 = t[5 * BLOCK + i]
                pp3 = t[6 * BLOCK + i]
                tt3 = t[7 * BLOCK + i]
                a[e] += ar0 * pp0 + br1 * tt1 + ar2 * pp2 + br3 * tt3
                a[BLOCK + e] += ai0 * pp0 + bi1 * tt1 + ai2 * pp2 + bi3 * tt3
                a[2 * BLOCK + e] += br0 * tt0 + ar1 * pp1 + br2 * tt2 + ar3 * pp3
                a[3 * BLOCK + e] += bi0 * tt0 + ai1 * pp1 + bi2 * tt2 + ai3 * pp3
                a[4 * BLOCK + e] += br0 * pp0 + ar1 * tt1 + br2 * pp2 + ar3 * tt3
                a[5 * BLOCK + e] += bi0 * pp0 + ai1 * tt1 + bi2 * pp2 + ai3 * tt3
                a[6 * BLOCK + e] += ar0 * tt0 + br1 * pp1 + ar2 * tt2 + br3 * pp3
                a[7 * BLOCK + e] += ai0 * tt0 + bi1 * pp1 + ai2 * tt2 + bi3 * pp3
            for ii in range(nb):
                i = o + ii
                e = d + ii
                pp0 = t[i]
                tt0 = t[BLOCK + i]
                pp1 = t[2 * BLOCK + i]
                tt1 = t[3 * BLOCK + i]
                pp2 = t[4 * BLOCK + i]
                tt2 = t[5 * BLOCK + i]
                pp3 = t[6 * BLOCK + i]
                tt3 = t[7 * BLOCK + i]
                a[8 * BLOCK + e] += dar0 * pp0 + dbr1 * tt1 + dar2 * pp2 + dbr3 * tt3
                a[9 * BLOCK + e] += dai0 * pp0 + dbi1 * tt1 + dai2 * pp2 + dbi3 * tt3
                a[10 * BLOCK + e] += dbr0 * tt0 + dar1 * pp1 + dbr2 * tt2 + dar3 * pp3
                a[11 * BLOCK + e] += dbi0 * tt0 + dai1 * pp1 + dbi2 * tt2 + dai3 * pp3
                a[12 * BLOCK + e] += dbr0 * pp0 + dar1 * tt1 + dbr2 * pp2 + dar3 * tt3
                a[13 * BLOCK + e] += dbi0 * pp0 + dai1 * tt1 + dbi2 * pp2 + dai3 * tt3
                a[14 * BLOCK + e] += dar0 * tt0 + dbr1 * pp1 + dar2 * tt2 + dbr3 * pp3
                a[15 * BLOCK + e] += dai0 * tt0 + dbi1 * pp1 + dai2 * tt2 + dbi3 * pp3


@njit(cache=True, nogil=True)
def _stokes_rows(acc: np.ndarray, sgn: float, blk: int, n_stokes: int, st: np.ndarray) -> None:
    """X = (I, Q, U, V) (the first ``n_stokes``) of one block of angles at +mu
    (``sgn`` 1) or -mu (-1) from the parity-split sums of
    :func:`_amplitudes_and_derivatives`, and their derivatives along n and
    along k (dS -> i dS, Cauchy-Riemann): ``st`` rows 0..3 X, 4..7 dX/dn,
    8..11 dX/dk (the first n_stokes of each)."""
    a = acc[blk * 16 * BLOCK : (blk + 1) * 16 * BLOCK]
    nb = st.shape[1]
    if n_stokes == 1:
        for i in range(nb):
            s1r = a[i] + sgn * a[2 * BLOCK + i]
            s1i = a[BLOCK + i] + sgn * a[3 * BLOCK + i]
            s2r = a[4 * BLOCK + i] + sgn * a[6 * BLOCK + i]
            s2i = a[5 * BLOCK + i] + sgn * a[7 * BLOCK + i]
            d1r = a[8 * BLOCK + i] + sgn * a[10 * BLOCK + i]
            d1i = a[9 * BLOCK + i] + sgn * a[11 * BLOCK + i]
            d2r = a[12 * BLOCK + i] + sgn * a[14 * BLOCK + i]
            d2i = a[13 * BLOCK + i] + sgn * a[15 * BLOCK + i]
            st[0, i] = s1r * s1r + s1i * s1i + s2r * s2r + s2i * s2i
            # dI = 2 Re(S1* dS1 + S2* dS2); along k, -2 Im(...).
            st[4, i] = 2.0 * (s1r * d1r + s1i * d1i + s2r * d2r + s2i * d2i)
            st[8, i] = -2.0 * (s1r * d1i - s1i * d1r + s2r * d2i - s2i * d2r)
        return
    for i in range(nb):
        s1r = a[i] + sgn * a[2 * BLOCK + i]
        s1i = a[BLOCK + i] + sgn * a[3 * BLOCK + i]
        s2r = a[4 * BLOCK + i] + sgn * a[6 * BLOCK + i]
        s2i = a[5 * BLOCK + i] + sgn * a[7 * BLOCK + i]
        d1r = a[8 * BLOCK + i] + sgn * a[10 * BLOCK + i]
        d1i = a[9 * BLOCK + i] + sgn * a[11 * BLOCK + i]
        d2r = a[12 * BLOCK + i] + sgn * a[14 * BLOCK + i]
        d2i = a[13 * BLOCK + i] + sgn * a[15 * BLOCK + i]
        p1 = s1r * s1r + s1i * s1i
        p2 = s2r * s2r + s2i * s2i
        st[0, i] = p1 + p2
        st[1, i] = p2 - p1
        st[2, i] = 2.0 * (s2r * s1r + s2i * s1i)
        st[3, i] = 2.0 * (s2i * s1r - s2r * s1i)
        # Re and Im of S1* dS1 and S2* dS2.
        r1 = s1r * d1r + s1i * d1i
        i1 = s1r * d1i - s1i * d1r
        r2 = s2r * d2r + s2i * d2i
        i2 = s2r * d2i - s2i * d2r
        # A = dS2 S1*, B = S2 dS1*: d(S2 S1*) = A + B along n, i (A - B) along k.
        ar_ = d2r * s1r + d2i * s1i
        ai_ = d2i * s1r - d2r * s1i
        br_ = s2r * d1r + s2i * d1i
        bi_ = s2i * d1r - s2r * d1i
        st[4, i] = 2.0 * (r1 + r2)
        st[5, i] = 2.0 * (r2 - r1)
        st[6, i] = 2.0 * (ar_ + br_)
        st[7, i] = 2.0 * (ai_ + bi_)
        st[8, i] = -2.0 * (i1 + i2)
        st[9, i] = -2.0 * (i2 - i1)
        st[10, i] = -2.0 * (ai_ - bi_)
        st[11, i] = 2.0 * (ar_ - br_)


@njit(cache=True, nogil=True, error_model="numpy")
def _accumulate_blocked(
    m: complex,
    x_nodes: np.ndarray,
    weights: np.ndarray,
    table: np.ndarray,
    n_mu: int,
    symmetric: bool,
    n_stokes: int,
    per_particle: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_accumulate` (without the x direction) on the table's own kernels.

    The Mie coefficients come LANES spheres at a time from the table's kernel
    (``mie._mie_coefficients``), their m derivatives from its D_n, psi_n and
    chi_n (:func:`_batch_derivatives`), and S1, S2, dS1/dm, dS2/dm in one pass
    over the orders at the angles of ``table`` (``mie.angular_table`` of the
    first ``n_mu`` angles, at least n_max orders of every node), and, if
    ``symmetric`` (angles mu >= 0), at -mu by parity
    (:func:`_amplitudes_and_derivatives`).  n and k are one complex
    derivative: dS/dk = i dS/dn.  Returns ``ang`` (n_w, n_stokes, n_f),
    ``dang`` (2, n_stokes, n_f), ``sums`` (n_w, N_SUMS), ``dsums``
    (2, N_SUMS), as :func:`_accumulate`, n_f = 2 n_mu if ``symmetric`` else
    n_mu; ``n_mu`` = 0 gives the sums alone.
    """
    n_nodes = x_nodes.shape[0]
    n_w = weights.shape[1]
    n_f = 2 * n_mu if symmetric else n_mu
    ang = np.zeros((n_w, n_stokes, n_f))
    dang = np.zeros((2, n_stokes, n_f))
    sums = np.zeros((n_w, N_SUMS))
    dsums = np.zeros((2, N_SUMS))
    if n_nodes == 0:
        return ang, dang, sums, dsums
    x_top = x_nodes[0]
    for j in range(n_nodes):
        x_top = max(x_top, x_nodes[j])
    n_top = wiscombe_nmax(x_top)
    ws = _workspace(n_top)
    x_b = np.empty(LANES)
    nmax_b = np.empty(LANES, dtype=np.int64)
    coef = np.zeros((4 * ((n_top + 3) // 4) + 4, 8 * LANES))
    width = table.shape[1] if n_mu > 0 else 0
    n_blocks = width // (8 * BLOCK)
    acc = np.empty(2 * width)
    st = np.empty((12, BLOCK))
    rel = np.empty(2)
    for b0 in range(0, n_nodes, LANES):
        n_live = min(LANES, n_nodes - b0)
        for s in range(LANES):
            x_b[s] = x_nodes[b0 + min(s, n_live - 1)]
            nmax_b[s] = wiscombe_nmax(x_b[s])
        _mie_coefficients(m, x_b, nmax_b, ws)
        per = _batch_derivatives(m, ws, x_b, nmax_b, coef)
        for s in range(n_live):
            j = b0 + s
            qs = per[s, 1]
            g = per[s, 2] / qs
            node = (1.0, per[s, 0], qs, per[s, 2], g, per[s, 3])
            for c in range(n_w):
                wc = weights[j, c]
                for q in range(N_SUMS):
                    sums[c, q] += wc * node[q]
            w0 = weights[j, 0]
            for d in range(2):
                o = 4 + 4 * d
                dsums[d, 1] += w0 * per[s, o]
                dsums[d, 2] += w0 * per[s, o + 1]
                dsums[d, 3] += w0 * per[s, o + 2]
                dsums[d, 4] += w0 * (per[s, o + 2] - g * per[s, o + 1]) / qs
                dsums[d, 5] += w0 * per[s, o + 3]
                rel[d] = -per[s, o + 1] / qs if per_particle else 0.0
            if n_mu == 0:
                continue
            _amplitudes_and_derivatives(coef, s, nmax_b[s], table, acc)
            scale = 1.0 / (2.0 * np.pi * qs) if per_particle else 1.0
            for blk in range(n_blocks):
                i0 = blk * BLOCK
                n_l = min(BLOCK, n_mu - i0)
                for half in range(2 if symmetric else 1):
                    _stokes_rows(acc, 1.0 - 2.0 * half, blk, n_stokes, st)
                    j0 = i0 + half * n_mu
                    for c in range(n_w):
                        wc = weights[j, c] * scale
                        for q in range(n_stokes):
                            row = ang[c, q]
                            for i in range(n_l):
                                row[j0 + i] += wc * st[q, i]
                    for d in range(2):
                        wd = w0 * scale
                        r = rel[d]
                        for q in range(n_stokes):
                            row = dang[d, q]
                            sd = st[4 + 4 * d + q]
                            sq = st[q]
                            for i in range(n_l):
                                row[j0 + i] += wd * (sd[i] + r * sq[i])
    return ang, dang, sums, dsums


@njit(cache=True, nogil=True)
def _legendre_project_rows(
    mu_half: np.ndarray, w_half: np.ndarray, rows: np.ndarray, lmax: int
) -> np.ndarray:
    """``mie._legendre_project`` of every row of ``rows`` (values at +mu_half,
    then at -mu_half) at once: beta_l = (2l+1)/2 int f P_l dmu, l = 0..lmax,
    shape (n_rows, lmax + 1).  One recurrence for P_l serves all rows."""
    n_rows = rows.shape[0]
    n_half = mu_half.shape[0]
    fe = np.empty((n_rows, n_half))
    fo = np.empty((n_rows, n_half))
    for r in range(n_rows):
        for i in range(n_half):
            fe[r, i] = w_half[i] * (rows[r, i] + rows[r, n_half + i])
            fo[r, i] = w_half[i] * (rows[r, i] - rows[r, n_half + i])
    p_prev = np.zeros(n_half)
    p_cur = np.ones(n_half)
    beta = np.empty((n_rows, lmax + 1))
    for ell in range(lmax + 1):
        g = fe if ell % 2 == 0 else fo
        c = (2 * ell + 1) / 2.0
        for r in range(n_rows):
            # Four interleaved partial sums, in a fixed order (as mie's).
            s0 = 0.0
            s1 = 0.0
            s2 = 0.0
            s3 = 0.0
            gr = g[r]
            i = 0
            while i + 4 <= n_half:
                s0 += gr[i] * p_cur[i]
                s1 += gr[i + 1] * p_cur[i + 1]
                s2 += gr[i + 2] * p_cur[i + 2]
                s3 += gr[i + 3] * p_cur[i + 3]
                i += 4
            while i < n_half:
                s0 += gr[i] * p_cur[i]
                i += 1
            beta[r, ell] = ((s0 + s1) + (s2 + s3)) * c
        c1 = (2 * ell + 1) / (ell + 1.0)
        c2 = ell / (ell + 1.0)
        for i in range(n_half):
            p_next = c1 * mu_half[i] * p_cur[i] - c2 * p_prev[i]
            p_prev[i] = p_cur[i]
            p_cur[i] = p_next
    return beta


@njit(cache=True, nogil=True)
def _legendre_evaluate_rows(beta: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """sum_l beta[r, l] P_l(mu) for every row r of ``beta``, shape (n_rows, len(mu)):
    ``mie._legendre_evaluate`` of all rows with one recurrence for P_l."""
    n_rows, n_l = beta.shape
    n_mu = mu.shape[0]
    out = np.zeros((n_rows, n_mu))
    p_prev = np.zeros(n_mu)
    p_cur = np.ones(n_mu)
    for ell in range(n_l):
        for r in range(n_rows):
            b = beta[r, ell]
            o = out[r]
            for i in range(n_mu):
                o[i] += b * p_cur[i]
        c1 = (2 * ell + 1) / (ell + 1.0)
        c2 = ell / (ell + 1.0)
        for i in range(n_mu):
            p_next = c1 * mu[i] * p_cur[i] - c2 * p_prev[i]
            p_prev[i] = p_cur[i]
            p_cur[i] = p_next
    return out


# ----------------------------------------------------------------------------
# Public boundary
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class SphereDerivatives:
    """Mie results of one homogeneous sphere and their exact derivatives.

    Values as :class:`dustoptics.scattering.mie.SingleSphere`; the derivatives
    are read with :meth:`derivative`.

    Attributes
    ----------
    m : complex
        Refractive index m = n + i k. [-]
    x : float
        Size parameter 2 pi r / lambda. [-]
    mu : numpy.ndarray
        Cosines of the scattering angles. [-]
    qext, qsca, qabs, qback : float
        Extinction, scattering, absorption and backscattering efficiencies
        (Q_back = 4 pi dC_sca/dOmega(180 deg) / (pi r^2), Bohren & Huffman p. 122). [-]
    g : float
        Asymmetry parameter. [-]
    a, b : numpy.ndarray
        Mie coefficients a_n, b_n, n = 1..n_max (complex). [-]
    s1, s2 : numpy.ndarray
        Amplitudes S1(mu), S2(mu) (complex, van de Hulst's normalization). [-]
    f11, f12, f33, f34 : numpy.ndarray
        Phase matrix normalized so that 2 pi int F11 dmu = 1, Bohren & Huffman's
        signs (F12 = (abs(S2)^2 - abs(S1)^2) / (2 pi x^2 Q_sca)). [sr^-1]
    """

    m: complex
    x: float
    mu: np.ndarray
    qext: float
    qsca: float
    qabs: float
    qback: float
    g: float
    a: np.ndarray
    b: np.ndarray
    s1: np.ndarray
    s2: np.ndarray
    f11: np.ndarray
    f12: np.ndarray
    f33: np.ndarray
    f34: np.ndarray
    _holomorphic: dict[str, tuple[np.ndarray, np.ndarray]] = field(repr=False)
    _real: dict[str, np.ndarray] = field(repr=False)

    def derivative(self, quantity: str, parameter: str) -> float | np.ndarray:
        """The derivative of ``quantity`` with respect to ``parameter``.

        Parameters
        ----------
        quantity : str
            One of ``qext``, ``qsca``, ``qabs``, ``qback``, ``g`` (floats),
            ``a``, ``b`` (complex, per order), ``s1``, ``s2`` (complex, per
            angle), ``f11``, ``f12``, ``f33``, ``f34`` (per angle).
        parameter : str
            ``"n"`` (real part of m), ``"k"`` (imaginary part), ``"x"`` (size
            parameter), or ``"m"``: the complex derivative d/dm, defined for the
            holomorphic ``a``, ``b``, ``s1``, ``s2`` only.

        Returns
        -------
        float or numpy.ndarray
            In the quantity's unit per unit of the parameter.

        Raises
        ------
        ValueError
            An unknown quantity or parameter, or ``"m"`` for a real quantity.
        """
        check_choice("quantity", quantity, QUANTITIES)
        check_choice("parameter", parameter, PARAMETERS)
        if quantity in self._holomorphic:
            d_dm, d_dx = self._holomorphic[quantity]
            if parameter == "x":
                return d_dx.copy()
            return (1j * d_dm) if parameter == "k" else d_dm.copy()
        if parameter == "m":
            raise ValueError(
                f"parameter 'm' (the complex derivative) is defined for the holomorphic a, b, "
                f"s1, s2 only; {quantity!r} is real: use 'n' or 'k'"
            )
        value = self._real[quantity][PARAMETERS.index(parameter)]
        return float(value) if np.ndim(value) == 0 else value.copy()


def sphere_derivatives(*, m: complex, x: float, mu: ArrayLike = 1.0) -> SphereDerivatives:
    """Mie results of one sphere and their exact derivatives with respect to n, k and x.

    Parameters
    ----------
    m : complex
        Refractive index relative to the medium, m = n + i k, n > 0, k >= 0,
        ``|m - 1| >=`` :data:`dustoptics.scattering.mie.MIN_INDEX_CONTRAST`. [-]
    x : float
        Size parameter 2 pi r / lambda, >=
        :data:`dustoptics.scattering.mie.MIN_SIZE_PARAMETER`. [-]
    mu : array_like
        Cosines of the scattering angles, in [-1, 1]. [-]

    Returns
    -------
    SphereDerivatives
        Values (as :func:`dustoptics.scattering.mie.single_sphere`) and, by its
        :meth:`~SphereDerivatives.derivative`, their derivatives.

    Raises
    ------
    ValueError
        Bad ``m``, ``x`` or ``mu`` (as :func:`~dustoptics.scattering.mie.single_sphere`),
        or arrays beyond the memory budget.

    Notes
    -----
    The derivatives are exact for the truncated series (Wiscombe's n_max
    orders, the same as the values'), computed from the recurrences (module
    docstring); the coefficients are computed here by the same formulas as in
    :mod:`dustoptics.scattering.mie` and agree with its to rounding (about
    1e-14 relative for x <= 200), not to the bit.

    Examples
    --------
    >>> s = sphere_derivatives(m=1.5 + 0.01j, x=3.0, mu=[1.0, 0.0, -1.0])
    >>> round(s.qext, 6), round(s.derivative("qext", "n"), 6)
    (3.363057, 6.739867)
    """
    m = check_sphere_inputs(m, x)
    x = float(x)
    mu_arr = np.atleast_1d(as_float_array("mu", mu))
    if mu_arr.ndim != 1 or np.any(np.abs(mu_arr) > 1.0):
        raise ValueError(f"mu must be a 1-D array of cosines in [-1, 1]; got {mu!r}")
    n_max = x + 4.05 * x ** (1.0 / 3.0) + 2.0
    check_budget(
        "sphere_derivatives",
        16.0 * n_max * (16.0 + 8.0 * mu_arr.size),
        allow_large=False,
        change=f"x = {x:g} needs n_max = {n_max:.3g} orders: use a smaller sphere or fewer angles",
    )
    a, b, da, db, dax, dbx, amp, val, der = _single(m, x, np.ascontiguousarray(mu_arr))
    x2 = x * x
    qext, qsca, gq, qback = val / x2
    # Derivatives along n, k, x of Q = val / x^2: the x row gains -2 Q / x.
    dq = der / x2
    dq[2] -= 2.0 * np.array([qext, qsca, gq, qback]) / x
    g = gq / qsca
    dg = (dq[:, 2] - g * dq[:, 1]) / qsca
    s1, s2 = amp[0], amp[1]
    ds1 = (amp[2], 1j * amp[2], amp[4])
    ds2 = (amp[3], 1j * amp[3], amp[5])
    norm = 2.0 * np.pi * x2 * qsca
    dnorm = 2.0 * np.pi * (der[:, 1])  # d(x^2 Q_sca) along n, k, x, times 2 pi
    p1 = np.abs(s1) ** 2
    p2 = np.abs(s2) ** 2
    c = s2 * np.conj(s1)
    stokes = (p1 + p2, p2 - p1, 2.0 * c.real, 2.0 * c.imag)
    d_stokes: list[tuple[np.ndarray, ...]] = []
    for j in range(3):
        dp1 = 2.0 * np.real(np.conj(s1) * ds1[j])
        dp2 = 2.0 * np.real(np.conj(s2) * ds2[j])
        dc = ds2[j] * np.conj(s1) + s2 * np.conj(ds1[j])
        d_stokes.append((dp1 + dp2, dp2 - dp1, 2.0 * dc.real, 2.0 * dc.imag))
    f = tuple(v / norm for v in stokes)
    df = {
        key: np.array([(d_stokes[j][q] - f[q] * dnorm[j]) / norm for j in range(3)])
        for q, key in enumerate(("f11", "f12", "f33", "f34"))
    }
    real = {
        "qext": dq[:, 0],
        "qsca": dq[:, 1],
        "qabs": dq[:, 0] - dq[:, 1],
        "qback": dq[:, 3],
        "g": dg,
        **df,
    }
    holomorphic = {"a": (da, dax), "b": (db, dbx), "s1": (amp[2], amp[4]), "s2": (amp[3], amp[5])}
    return SphereDerivatives(
        m=m,
        x=x,
        mu=mu_arr,
        qext=float(qext),
        qsca=float(qsca),
        qabs=float(qext - qsca),
        qback=float(qback),
        g=float(g),
        a=a,
        b=b,
        s1=s1,
        s2=s2,
        f11=f[0],
        f12=f[1],
        f33=f[2],
        f34=f[3],
        _holomorphic=holomorphic,
        _real=real,
    )
