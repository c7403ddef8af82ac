"""The table's path of the Mie derivatives: dS/dm summed on the table's own blocked kernels.

:mod:`dustoptics.scattering.mie_derivatives` derives and checks the exact
derivatives of one sphere's results with respect to m (its single-sphere
kernels and the reference sums of ``tests/reference/derivatives.py``).
This module is the same mathematics laid out for speed, as
:mod:`dustoptics.scattering.table_derivatives` uses it: the coefficients come
from the table's own kernel (``mie._mie_coefficients``, ``LANES`` spheres at a
time), dD_n/dz from the Riccati equation dD_n/dz = -1 + (n (n + 1) / z^2) - D_n^2,
da_n/dm and db_n/dm and the sums' n and k derivatives in one loop over spheres
in real arithmetic (:func:`_batch_derivatives`), and S1, S2 with dS1/dm,
dS2/dm in one pass over ``mie.angular_table``'s blocked layout
(:func:`_accumulate_blocked`), the k derivative from the n derivative by
Cauchy-Riemann (dS/dk = i dS/dn for S analytic in m).  The Legendre
projections of the derivative rows (:func:`_legendre_project_rows`,
:func:`_legendre_evaluate_rows`) carry them to the output angles.

Its numba kernels are ``cache=True`` and use no ``fastmath``, as
:mod:`dustoptics.scattering.mie`'s.  Conventions are those of
:mod:`dustoptics.scattering.mie` (Bohren & Huffman 1983, chapter 4).
"""

from __future__ import annotations

import numpy as np
from numba import njit

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
    wiscombe_nmax,
)
from dustoptics.scattering.mie_derivatives import N_SUMS

__all__: list[str] = []


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


@njit(cache=True, nogil=True, inline="always")
def _add_four_orders(a: np.ndarray, e0: int, t: np.ndarray, i0: int, nb: int, c: tuple) -> None:
    """Add four orders n (odd, even, odd, even) of parity-split amplitude sums
    of one block of ``nb`` angles: to the eight rows ``a[e0 + r BLOCK:]``,
    r = 0..7 (S1's part even in mu, real and imaginary, its odd part, then
    S2's), the coefficients ``c`` = (ar_0, ai_0, br_0, bi_0, ..., bi_3) times
    pi_n, tau_n from ``t[i0:]`` (one pass's row of ``mie.angular_table``, the
    block's 8 x BLOCK values), ar_k + i ai_k standing for (2n+1)/(n(n+1)) a_n
    and br_k + i bi_k for the same of b_n, n = 4q + k + 1 (or their m
    derivatives, for dS1/dm and dS2/dm).  One loop over the block's angles in
    real arithmetic, which the compiler vectorizes.

    The same loop as ``mie._add_sphere``'s, which keeps its own copy: this
    helper inlined there cost the first build's compile 0.3-0.5 s of CPU
    (``mie._accumulate_grids`` 2.7-2.9 s against 2.3-2.5 s, three interleaved
    runs each, load 3-4), and that kernel's compile time is a target of its own.
    """
    ar0, ai0, br0, bi0, ar1, ai1, br1, bi1, ar2, ai2, br2, bi2, ar3, ai3, br3, bi3 = c
    for ii in range(nb):
        i = i0 + ii
        e = e0 + ii
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


@njit(cache=True, nogil=True)
def _amplitudes_and_derivatives(
    coef: np.ndarray, s: int, nmax: int, table: np.ndarray, acc: np.ndarray, with_m: bool
) -> None:
    """S1, S2 and dS1/dm, dS2/dm of one sphere at the angles of ``table``
    (``mie.angular_table``'s blocked layout), split by parity as the table's
    kernel splits S1, S2 (``mie._add_sphere``), into ``acc``: per block of
    BLOCK angles 16 rows, the even and odd parts (real, imaginary) of S1,
    S2 (rows 0-7, the table's layout) and of dS1, dS2 (rows 8-15).  One pass
    over the orders for the values and the derivative: the angular functions
    are read once, four orders at a time, angles innermost in real
    arithmetic (the compiler vectorizes it).  Without ``with_m`` (no
    parameter of the refractive index asked for) rows 8-15 stay zero: the
    amplitudes alone cost half."""
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
        # (2n+1)/(n(n+1)) times a_n, b_n (real, imaginary) and da_n/dm, db_n/dm.
        val = (
            c0[0], c0[1], c0[2], c0[3], c1[0], c1[1], c1[2], c1[3],
            c2[0], c2[1], c2[2], c2[3], c3[0], c3[1], c3[2], c3[3],
        )  # fmt: skip
        der = (
            c0[4], c0[5], c0[6], c0[7], c1[4], c1[5], c1[6], c1[7],
            c2[4], c2[5], c2[6], c2[7], c3[4], c3[5], c3[6], c3[7],
        )  # fmt: skip
        t = table[q]
        a = acc
        for blk in range(n_blocks):
            o = blk * 8 * BLOCK
            d = blk * 16 * BLOCK
            # S1, S2 (rows 0-7), then dS1/dm, dS2/dm (rows 8-15): one loop each.
            _add_four_orders(a, d, t, o, nb, val)
            if with_m:
                _add_four_orders(a, d + 8 * BLOCK, t, o, nb, der)


@njit(cache=True, nogil=True, inline="always")
def _at_mu(a: np.ndarray, i: int, sgn: float) -> tuple[float, ...]:
    """S1, S2, dS1/dm, dS2/dm (real, imaginary) at angle ``i`` of one block of
    :func:`_amplitudes_and_derivatives`' parity-split sums ``a``: the even part
    plus ``sgn`` times the odd (``sgn`` 1 at +mu, -1 at -mu)."""
    return (
        a[i] + sgn * a[2 * BLOCK + i],
        a[BLOCK + i] + sgn * a[3 * BLOCK + i],
        a[4 * BLOCK + i] + sgn * a[6 * BLOCK + i],
        a[5 * BLOCK + i] + sgn * a[7 * BLOCK + i],
        a[8 * BLOCK + i] + sgn * a[10 * BLOCK + i],
        a[9 * BLOCK + i] + sgn * a[11 * BLOCK + i],
        a[12 * BLOCK + i] + sgn * a[14 * BLOCK + i],
        a[13 * BLOCK + i] + sgn * a[15 * BLOCK + i],
    )


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
            s1r, s1i, s2r, s2i, d1r, d1i, d2r, d2i = _at_mu(a, i, sgn)
            st[0, i] = s1r * s1r + s1i * s1i + s2r * s2r + s2i * s2i
            # dI = 2 Re(S1* dS1 + S2* dS2); along k, -2 Im(...).
            st[4, i] = 2.0 * (s1r * d1r + s1i * d1i + s2r * d2r + s2i * d2i)
            st[8, i] = -2.0 * (s1r * d1i - s1i * d1r + s2r * d2i - s2i * d2r)
        return
    for i in range(nb):
        s1r, s1i, s2r, s2i, d1r, d1i, d2r, d2i = _at_mu(a, i, sgn)
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


@njit(cache=True, nogil=True)
def _work_arrays(x_top: float, table: np.ndarray, n_mu: int) -> tuple[np.ndarray, ...]:
    """Work arrays of :func:`_accumulate_into` for nodes up to size parameter
    ``x_top`` at the angles of ``table``."""
    n_top = wiscombe_nmax(x_top)
    width = table.shape[1] if n_mu > 0 else 0
    return (
        _workspace(n_top),
        np.empty(LANES),
        np.empty(LANES, dtype=np.int64),
        np.zeros((4 * ((n_top + 3) // 4) + 4, 8 * LANES)),
        np.empty(2 * width),
        np.empty((12, BLOCK)),
        np.empty(2),
    )


@njit(cache=True, nogil=True, error_model="numpy")
def _accumulate_into(
    m: complex,
    x_nodes: np.ndarray,
    weights: np.ndarray,
    table: np.ndarray,
    n_mu: int,
    symmetric: bool,
    n_stokes: int,
    per_particle: bool,
    with_m: bool,
    work: tuple[np.ndarray, ...],
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """The body of :func:`_accumulate_blocked`: adds the nodes' sums to ``out``
    = (ang, dang, sums, dsums), with the work arrays ``work`` of
    :func:`_work_arrays` (made for at least the nodes' largest n_max), which
    calls on several node sets share."""
    ws, x_b, nmax_b, coef, acc, st, rel = work
    ang, dang, sums, dsums = out
    n_nodes = x_nodes.shape[0]
    n_w = weights.shape[1]
    width = table.shape[1] if n_mu > 0 else 0
    n_blocks = width // (8 * BLOCK)
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
            _amplitudes_and_derivatives(coef, s, nmax_b[s], table, acc, with_m)
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
                    for d in range(2 if with_m else 0):
                        wd = w0 * scale
                        r = rel[d]
                        for q in range(n_stokes):
                            row = dang[d, q]
                            sd = st[4 + 4 * d + q]
                            sq = st[q]
                            for i in range(n_l):
                                row[j0 + i] += wd * (sd[i] + r * sq[i])


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
    with_m: bool,
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
    n_mu; ``n_mu`` = 0 gives the sums alone.  Without ``with_m`` the
    angular m derivatives are not summed (``dang`` stays zero): the
    distribution's parameters alone need the amplitudes only.
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
    work = _work_arrays(x_top, table, n_mu)
    _accumulate_into(
        m,
        x_nodes,
        weights,
        table,
        n_mu,
        symmetric,
        n_stokes,
        per_particle,
        with_m,
        work,
        (ang, dang, sums, dsums),
    )
    return ang, dang, sums, dsums


@njit(cache=True, nogil=True, error_model="numpy")
def _accumulate_groups(
    m: complex,
    x_nodes: np.ndarray,
    weights: np.ndarray,
    starts: np.ndarray,
    table: np.ndarray,
    n_mu: int,
    n_stokes: int,
    per_particle: bool,
    with_m: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_accumulate_blocked` (at the angles ``mu`` of ``table``, not
    symmetric) of each group of nodes ``starts[g]:starts[g + 1]`` on its own,
    in one call: one set of work arrays, no call per group.  Returns ``ang``
    (n_group, n_w, n_stokes, n_mu), ``dang`` (n_group, 2, n_stokes, n_mu),
    ``sums`` (n_group, n_w, N_SUMS), ``dsums`` (n_group, 2, N_SUMS), each
    group's rows equal to its own :func:`_accumulate_blocked` call's."""
    n_group = starts.shape[0] - 1
    n_w = weights.shape[1]
    ang = np.zeros((n_group, n_w, n_stokes, n_mu))
    dang = np.zeros((n_group, 2, n_stokes, n_mu))
    sums = np.zeros((n_group, n_w, N_SUMS))
    dsums = np.zeros((n_group, 2, N_SUMS))
    if x_nodes.shape[0] == 0:
        return ang, dang, sums, dsums
    x_top = x_nodes[0]
    for j in range(x_nodes.shape[0]):
        x_top = max(x_top, x_nodes[j])
    work = _work_arrays(x_top, table, n_mu)
    for g in range(n_group):
        a, b = starts[g], starts[g + 1]
        if b > a:
            _accumulate_into(
                m,
                x_nodes[a:b],
                weights[a:b],
                table,
                n_mu,
                False,
                n_stokes,
                per_particle,
                with_m,
                work,
                (ang[g], dang[g], sums[g], dsums[g]),
            )
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
