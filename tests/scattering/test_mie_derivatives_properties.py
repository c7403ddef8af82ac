"""Property tests of the exact Mie derivatives: identities that hold for every sphere.

Kept apart from the example tests (tests/scattering/test_mie_derivatives.py).  Each
identity ties two code paths of :mod:`dustoptics.scattering.mie_derivatives` that
share nothing but the coefficients' derivatives:

- the optical theorem differentiated: Q_ext = (4 / x^2) Re S(0), so
  dQ_ext/dn = (4 / x^2) Re dS(0)/dm and dQ_ext/dk = -(4 / x^2) Im dS(0)/dm
  (the efficiency sums against the amplitude sums);
- the phase function's normalization and first moment differentiated:
  2 pi int dF11/dp dmu = 0 and 2 pi int mu dF11/dp dmu = dg/dp (exact on a
  Gauss rule of n_max + 2 nodes: F11 is a polynomial of degree 2 n_max in mu);
- a lossless sphere absorbs nothing whatever its n, so dQ_abs/dn = 0 at k = 0,
  and it starts to absorb as k grows: dQ_abs/dk > 0.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import roots_legendre

from dustoptics.scattering.mie import wiscombe_nmax
from dustoptics.scattering.mie_derivatives import sphere_derivatives

_n = st.floats(1.05, 3.0)
_k = st.one_of(st.just(0.0), st.floats(1e-4, 1.0))
_x = st.floats(-1.0, 2.0).map(lambda e: 10.0**e)  # 0.1 to 100, log-uniform


@settings(max_examples=60, deadline=None)
@given(n=_n, k=_k, x=_x)
def test_optical_theorem_differentiated(n: float, k: float, x: float) -> None:
    s = sphere_derivatives(m=complex(n, k), x=x, mu=1.0)
    ds = complex(np.asarray(s.derivative("s1", "m"))[0])
    scale = 4.0 / (x * x)
    tol = 1e-9 * (abs(ds) * scale + s.qext)
    assert abs(float(s.derivative("qext", "n")) - scale * ds.real) <= tol
    assert abs(float(s.derivative("qext", "k")) + scale * ds.imag) <= tol
    ds_dx = complex(np.asarray(s.derivative("s1", "x"))[0])
    d_dx = scale * ds_dx.real - 2.0 * s.qext / x
    assert abs(float(s.derivative("qext", "x")) - d_dx) <= 1e-9 * (abs(ds_dx) * scale + s.qext / x)


@settings(max_examples=40, deadline=None)
@given(n=_n, k=_k, x=_x)
def test_normalization_and_asymmetry_differentiated(n: float, k: float, x: float) -> None:
    mu, w = roots_legendre(int(wiscombe_nmax(x)) + 2)
    s = sphere_derivatives(m=complex(n, k), x=x, mu=mu)
    scale = 2.0 * np.pi * np.sum(w * s.f11)  # = 1
    assert abs(scale - 1.0) < 1e-11
    assert abs(2.0 * np.pi * np.sum(w * mu * s.f11) - s.g) < 1e-11
    for p in ("n", "k", "x"):
        d = np.asarray(s.derivative("f11", p))
        dg = float(s.derivative("g", p))
        size = 2.0 * np.pi * np.sum(w * np.abs(d)) + abs(dg)
        assert abs(2.0 * np.pi * np.sum(w * d)) <= 1e-10 * size, p
        assert abs(2.0 * np.pi * np.sum(w * mu * d) - dg) <= 1e-10 * size, p


@settings(max_examples=60, deadline=None)
@given(n=_n, x=_x)
def test_a_lossless_sphere_absorbs_nothing_to_first_order(n: float, x: float) -> None:
    s = sphere_derivatives(m=complex(n, 0.0), x=x)
    dn_ext = float(s.derivative("qext", "n"))
    assert abs(float(s.derivative("qabs", "n"))) <= 1e-10 * max(1.0, abs(dn_ext))
    assert float(s.derivative("qabs", "k")) > 0.0
