"""Expansion of the scattering matrix in generalized spherical functions.

The scattering matrix of a population of spheres (Bohren & Huffman 1983,
Eq. 4.77; Hovenier, van der Mee & Domke 2004) has four independent elements,
with F22 = F11 and F44 = F33::

        | a1  b1   0   0 |
    F = | b1  a2   0   0 |        a1 = a2 = 4 pi F11,  a3 = a4 = 4 pi F33,
        |  0   0  a3  b2 |        b1 = 4 pi F12,       b2 = 4 pi F34,
        |  0   0 -b2  a4 |

normalized so that (1/2) int a1 dmu = 1 (``F11`` of a table integrates to 1
over the sphere, ``a1`` to 4 pi).  Expanded in the generalized spherical
functions P^l_mn(mu) of de Rooij & van der Stap (1984) and Hovenier, van der
Mee & Domke (2004, Eqs. 2.152-2.157)::

    a1            = sum_l alpha1_l P^l_00
    a2 + a3       = sum_l (alpha2_l + alpha3_l) P^l_22
    a2 - a3       = sum_l (alpha2_l - alpha3_l) P^l_2,-2
    a4            = sum_l alpha4_l P^l_00
    b1            = sum_l beta1_l P^l_02
    b2            = sum_l beta2_l P^l_02

so alpha1_0 = 1 and alpha1_1 = 3 g.  In terms of Wigner's d-functions
(Mishchenko, Travis & Lacis 2002, Eqs. 4.75-4.80 and B.22) P^l_00 = d^l_00 =
P_l (Legendre), P^l_22 = d^l_22, P^l_2,-2 = d^l_2,-2 and P^l_02 = -d^l_02
(the factor i^(n - m) of the generalized spherical functions), so that for
Rayleigh scattering, whose F12 is negative, beta1_2 = +sqrt(6)/2 as tabulated
by de Rooij & van der Stap.  The d^l_mn follow from the three-term recurrence
of Mishchenko et al. (2002, Eq. B.22) started at l = 2 with
d^2_02 = (sqrt 6 / 4)(1 - mu^2), d^2_22 = (1 + mu)^2 / 4,
d^2_2,-2 = (1 - mu)^2 / 4.  For a finite population of spheres with at most
n_max Mie terms every element is a polynomial of degree 2 n_max in mu, and so
is every P^l_mn here (m +- n even): a Gauss rule of more than 2 n_max + 1
nodes in mu projects them exactly, and the series ends at l = 2 n_max.

Sign convention: the table's F12 and F34 are Bohren & Huffman's S12 and S34
(exp(-i w t), m = n + i k): ``F12 = (|S2|^2 - |S1|^2) / 2`` and
``F34 = Im(S2 S1*)`` up to the normalization, so F12 < 0 for Rayleigh scattering
at 90 deg.  ``beta1`` and ``beta2`` expand these same F12 and F34.  Codes that
expand in Wigner's d-functions (Mishchenko, Travis & Lacis 2002, Eqs.
4.75-4.80; scatrs) have both beta1 and beta2 of the opposite sign: their b1
and b2 are the same functions as ours, expanded in d^l_02 = -P^l_02.
Measured in ``tests/scattering/test_expansion.py::test_haze_l_against_scatrs``:
Haze L's six coefficient sets agree with scatrs' to 1e-6, the two betas with
the opposite sign.  libRadtran and the IPRT phase A files expand each
element in Legendre polynomials instead, with P34 = -4 pi F34
(:mod:`dustoptics.io.rt.libradtran_netcdf`).

DISORT's phase-function moments are ``pmom_l = alpha1_l / (2 l + 1)``, the
Legendre coefficients of P in the normalization (1/2) int P dmu = 1 with
P = sum (2 l + 1) pmom_l P_l (:func:`~dustoptics.table.pmom_from_alpha1`, defined with the table in
:mod:`dustoptics.table` and importable from here).

References
----------
.. [1] J. W. Hovenier, C. van der Mee and H. Domke, *Transfer of Polarized
   Light in Planetary Atmospheres*, Kluwer, 2004. doi:10.1007/978-1-4020-2856-4
.. [2] W. A. de Rooij and C. C. A. H. van der Stap, "Expansion of Mie
   scattering matrices in generalized spherical functions," Astron.
   Astrophys. 131, 237-248 (1984).
.. [3] M. I. Mishchenko, L. D. Travis and A. A. Lacis, *Scattering, Absorption,
   and Emission of Light by Small Particles*, Cambridge University Press,
   2002, Eqs. 4.75-4.80 and B.22.
.. [4] W. J. Wiscombe, "The delta-M method: rapid yet accurate radiative flux
   calculations for strongly asymmetric phase functions," J. Atmos. Sci. 34,
   1408-1422 (1977). doi:10.1175/1520-0469(1977)034<1408:TDMRYA>2.0.CO;2
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dustoptics._numba_cache import F8_1D, F8_2D, I8, kernel

# The moments are the table's convention (Table.pmom), defined with the data model.
# From the defining module: compile children import this one with bare package __init__s.
from dustoptics.table.components import alpha1_from_pmom, pmom_from_alpha1

__all__ = [
    "DeltaM",
    "alpha1_from_pmom",
    "delta_m",
    "evaluate_matrix",
    "pmom_from_alpha1",
]


#: (m, n) of the four d^l_mn the expansion uses.  The kernel reads them from
#: this array: passed as literals, numba would compile :func:`_wigner_d` once
#: for each pair.
_MN = np.array([[0, 0], [0, 2], [2, 2], [2, -2]], dtype=np.int64)


@kernel(F8_1D, I8, I8, I8, group="matrix")
def _wigner_d(mu: np.ndarray, lmax: int, m: int, n: int) -> np.ndarray:
    """d^l_mn(arccos mu) for l = 0..lmax, shape (lmax + 1, len(mu)), for
    (m, n) in (0, 0), (0, 2), (2, 2), (2, -2) (Mishchenko et al. 2002, Eq. B.22)."""
    n_mu = mu.shape[0]
    d = np.empty((lmax + 1, n_mu))
    d[:] = 0.0
    if m == 0 and n == 0:
        for i in range(n_mu):
            d[0, i] = 1.0
            if lmax >= 1:
                d[1, i] = mu[i]
        for ell in range(1, lmax):
            c1 = (2.0 * ell + 1.0) / (ell + 1.0)
            c2 = ell / (ell + 1.0)
            for i in range(n_mu):
                d[ell + 1, i] = c1 * mu[i] * d[ell, i] - c2 * d[ell - 1, i]
        return d
    if lmax < 2:
        return d
    for i in range(n_mu):
        u = mu[i]
        if m == 0:
            d[2, i] = 0.25 * np.sqrt(6.0) * (1.0 - u) * (1.0 + u)
        elif n == 2:
            d[2, i] = 0.25 * (1.0 + u) * (1.0 + u)
        else:
            d[2, i] = 0.25 * (1.0 - u) * (1.0 - u)
    mn = float(m * n)
    m2 = float(m * m)
    n2 = float(n * n)
    for s in range(2, lmax):
        a = 2.0 * s + 1.0
        b = (s + 1.0) * np.sqrt(s * s - m2) * np.sqrt(s * s - n2)
        c = s * np.sqrt((s + 1.0) ** 2 - m2) * np.sqrt((s + 1.0) ** 2 - n2)
        ss1 = s * (s + 1.0)
        for i in range(n_mu):
            d[s + 1, i] = (a * (ss1 * mu[i] - mn) * d[s, i] - b * d[s - 1, i]) / c
    return d


@kernel(F8_1D, F8_1D, F8_1D, F8_2D, group="matrix")
def _project(mu: np.ndarray, w: np.ndarray, f: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(2l + 1)/2 sum_i w_i f_i d[l, i] for every l."""
    lmax = d.shape[0] - 1
    out = np.empty(lmax + 1)
    for ell in range(lmax + 1):
        s = 0.0
        for i in range(mu.shape[0]):
            s += w[i] * f[i] * d[ell, i]
        out[ell] = s * (2.0 * ell + 1.0) / 2.0
    return out


@kernel(F8_1D, F8_1D, F8_1D, F8_1D, F8_1D, F8_1D, I8, group="matrix")
def _greek_coefficients(
    mu: np.ndarray,
    w: np.ndarray,
    a1: np.ndarray,
    a3: np.ndarray,
    b1: np.ndarray,
    b2: np.ndarray,
    lmax: int,
) -> np.ndarray:
    """alpha1..alpha4, beta1, beta2 (rows 0..5), l = 0..lmax, of a spheres'
    matrix (a2 = a1, a4 = a3) given at the nodes ``mu`` of a Gauss rule with
    weights ``w`` that integrates the products exactly."""
    d00 = _wigner_d(mu, lmax, _MN[0, 0], _MN[0, 1])
    d02 = _wigner_d(mu, lmax, _MN[1, 0], _MN[1, 1])
    d22 = _wigner_d(mu, lmax, _MN[2, 0], _MN[2, 1])
    d2m2 = _wigner_d(mu, lmax, _MN[3, 0], _MN[3, 1])
    n_mu = mu.shape[0]
    plus = np.empty(n_mu)
    minus = np.empty(n_mu)
    for i in range(n_mu):
        plus[i] = a1[i] + a3[i]
        minus[i] = a1[i] - a3[i]
    # Every row is written element by element: numba's array-to-row assignment
    # and unary minus of an array each compile code of their own.
    out = np.empty((6, lmax + 1))
    row0 = _project(mu, w, a1, d00)
    sum23 = _project(mu, w, plus, d22)
    dif23 = _project(mu, w, minus, d2m2)
    row3 = _project(mu, w, a3, d00)
    # P^l_02 = -d^l_02 (module docstring).
    row4 = _project(mu, w, b1, d02)
    row5 = _project(mu, w, b2, d02)
    for ell in range(lmax + 1):
        out[0, ell] = row0[ell]
        out[1, ell] = 0.5 * (sum23[ell] + dif23[ell])
        out[2, ell] = 0.5 * (sum23[ell] - dif23[ell])
        out[3, ell] = row3[ell]
        out[4, ell] = -row4[ell]
        out[5, ell] = -row5[ell]
    return out


def greek_coefficients(
    *,
    mu: np.ndarray,
    weight: np.ndarray,
    a1: np.ndarray,
    a3: np.ndarray,
    b1: np.ndarray,
    b2: np.ndarray,
    lmax: int,
) -> np.ndarray:
    """Expansion coefficients of a spheres' scattering matrix from values at quadrature nodes.

    Parameters
    ----------
    mu, weight : numpy.ndarray
        Nodes and weights of a quadrature rule on [-1, 1] that integrates the
        products of the elements with P^l_mn exactly (Gauss-Legendre with more
        than (degree + lmax) / 2 nodes). [-]
    a1, a3, b1, b2 : numpy.ndarray
        4 pi F11, 4 pi F33, 4 pi F12, 4 pi F34 at ``mu`` (module docstring). [-]
    lmax : int
        Highest order. [-]

    Returns
    -------
    numpy.ndarray, shape (6, lmax + 1)
        alpha1, alpha2, alpha3, alpha4, beta1, beta2. [-]
    """
    # C-contiguous, writable float64: the kernel's one signature.
    arrays = [
        np.require(v, dtype=np.float64, requirements=["C", "W"])
        for v in (mu, weight, a1, a3, b1, b2)
    ]
    return _greek_coefficients(*arrays, int(lmax))


def evaluate_matrix(coefficients: np.ndarray, theta_deg: np.ndarray) -> dict[str, np.ndarray]:
    """The spheres' matrix elements from their expansion coefficients.

    Parameters
    ----------
    coefficients : array_like, shape (6, n_order)
        alpha1..alpha4, beta1, beta2 (module docstring). [-]
    theta_deg : array_like
        Scattering angles. [deg]

    Returns
    -------
    dict
        ``a1, a2, a3, a4, b1, b2`` at the angles (a1 = 4 pi F11). [-]
    """
    c = np.asarray(coefficients, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] != 6:
        raise ValueError(f"coefficients must have shape (6, n_order); got {c.shape}")
    mu = np.cos(np.deg2rad(np.asarray(theta_deg, dtype=np.float64))).ravel()
    lmax = c.shape[1] - 1
    d00 = _wigner_d(mu, lmax, 0, 0)
    d02 = _wigner_d(mu, lmax, 0, 2)
    d22 = _wigner_d(mu, lmax, 2, 2)
    d2m2 = _wigner_d(mu, lmax, 2, -2)
    s23 = (c[1] + c[2]) @ d22
    d23 = (c[1] - c[2]) @ d2m2
    return {
        "a1": c[0] @ d00,
        "a2": 0.5 * (s23 + d23),
        "a3": 0.5 * (s23 - d23),
        "a4": c[3] @ d00,
        "b1": -(c[4] @ d02),
        "b2": -(c[5] @ d02),
    }


@dataclass(frozen=True)
class DeltaM:
    """Result of :func:`delta_m`.

    Attributes
    ----------
    pmom : numpy.ndarray, shape (..., n_streams)
        Truncated and renormalized moments chi'_l = (chi_l - f) / (1 - f),
        l = 0..n_streams - 1 (chi'_0 = 1). [-]
    alpha1 : numpy.ndarray
        The same as (2 l + 1) chi'_l. [-]
    fraction : numpy.ndarray, shape (...)
        Truncation fraction f = chi_{n_streams}: the share of scattering moved
        into the forward delta peak. [-]
    n_streams : int
        Number of streams the truncation is for. [-]
    """

    pmom: np.ndarray
    alpha1: np.ndarray
    fraction: np.ndarray
    n_streams: int

    def scaled_ssa(self, ssa: np.ndarray) -> np.ndarray:
        """Scaled single-scattering albedo w' = (1 - f) w / (1 - f w). [-]"""
        w = np.asarray(ssa, dtype=np.float64)
        return (1.0 - self.fraction) * w / (1.0 - self.fraction * w)

    def scaled_optical_depth(self, optical_depth: np.ndarray, ssa: np.ndarray) -> np.ndarray:
        """Scaled optical depth tau' = (1 - f w) tau. [-]"""
        return (1.0 - self.fraction * np.asarray(ssa)) * np.asarray(optical_depth, dtype=np.float64)


def delta_m(alpha1: np.ndarray, *, n_streams: int) -> DeltaM:
    """Delta-M truncation of a phase function for an n-stream solver (Wiscombe 1977).

    The phase function is replaced by f delta(1 - mu) plus (1 - f) times a
    phase function of n_streams moments, f = chi_{n_streams} (Wiscombe 1977,
    Eqs. 7-12; DISORT's choice, Stamnes et al. 1988).

    Parameters
    ----------
    alpha1 : array_like, shape (..., n_order)
        alpha1_l, l = 0..n_order - 1 (n_order > n_streams). [-]
    n_streams : int
        Number of streams (even, >= 2). [-]

    Returns
    -------
    DeltaM
    """
    if (
        isinstance(n_streams, bool)
        or not isinstance(n_streams, (int, np.integer))
        or n_streams < 2
        or n_streams % 2
    ):
        raise ValueError(f"n_streams must be an even integer >= 2; got {n_streams!r}")
    a = np.asarray(alpha1, dtype=np.float64)
    if a.ndim < 1 or a.shape[-1] <= n_streams:
        raise ValueError(
            f"alpha1 must hold orders 0..n_streams = {n_streams} (at least {n_streams + 1} values "
            f"on its last axis); got shape {a.shape}"
        )
    chi = pmom_from_alpha1(a)
    f = chi[..., n_streams]
    if np.any(f >= 1.0):
        raise ValueError(f"truncation fraction f = chi_{n_streams} must be < 1; got {np.max(f)!r}")
    trunc = (chi[..., :n_streams] - f[..., None]) / (1.0 - f[..., None])
    return DeltaM(
        pmom=trunc, alpha1=alpha1_from_pmom(trunc), fraction=np.asarray(f), n_streams=int(n_streams)
    )
