"""Exact derivatives of single-sphere Mie results with respect to m = n + i k and x.

This module knows nothing of units, materials or size distributions.  Its
numba kernels (``cache=True``, no ``fastmath``, as :mod:`dustoptics.scattering.mie`)
take plain values and arrays (complex refractive index ``m``, size parameters
``x``, weights, direction cosines ``mu``); :func:`sphere_derivatives` is the one
public function, which validates and converts at the boundary.  The
polydisperse reference path, ``tests/reference/derivatives.py``, sums the
same kernels over a radius quadrature (:func:`_accumulate`);
:mod:`dustoptics.scattering.table_derivatives` sums the table's nodes with
``mie_derivatives_blocked._accumulate_blocked``, which takes the coefficients from the table's own
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
    _pi_tau_table,
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
    pi_t, tau_t = _pi_tau_table(mu, nmax)
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
    extra_terms: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Weighted sums over spheres of the scattering matrix and the efficiency
    sums, and their derivatives along n, k (and x).

    Each sphere's series has ``extra_terms`` more terms than Wiscombe's n_max
    (default 0, the table's): the difference of the two estimates the
    truncation error of the table's series.

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
    pi_t, tau_t = _pi_tau_table(mu, wiscombe_nmax(x_top) + extra_terms)
    for j in range(n_nodes):
        x = x_nodes[j]
        nmax = wiscombe_nmax(x) + extra_terms
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
