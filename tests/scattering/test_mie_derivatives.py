"""Exact Mie derivatives (dustoptics.scattering.mie_derivatives) against finite
differences of dustoptics' own Mie kernel and against scatrs' closed forms.

Finite differences: the central difference of :func:`dustoptics.scattering.mie.single_sphere`
with step h (one-sided, second order, where k = 0 leaves no room below) has a
truncation error c h^2 + O(h^4) and a round-off error below 2 eps_f |f| / (2 h),
eps_f the relative rounding of the kernel's values (1e-13 for x <= 200: the
kernel agrees with scatrs and miepython to a few 1e-14).  The difference of the
steps h and 2h is 3 c h^2, three times the truncation error of step h, so the
tolerance is

    |D(h) - D(2h)| + 4 eps_f |f| / h  (+ 1e-12 |f'| for the exact side's rounding),

elementwise (every angle on its own).  Steps: h = 1e-4 / max(1, x) in n and k
(the functions vary on a scale of 1 / x in m), 1e-4 in x.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from dustoptics.scattering import mie
from dustoptics.scattering.mie_derivatives import sphere_derivatives

MU = np.cos(np.deg2rad([0.0, 5.0, 30.0, 60.0, 90.0, 120.0, 150.0, 175.0, 180.0]))
INDICES = (1.5 + 0.01j, 1.33 + 0.0j, 2.0 + 1.0j, 1.55 + 0.003j)
SIZES = (0.1, 1.0, 10.0, 60.0, 200.0)
EPS_F = 1e-13
REAL_QUANTITIES = ("qext", "qsca", "qabs", "g")


def _values(m: complex, x: float) -> dict[str, np.ndarray]:
    r = mie.single_sphere(m=m, x=x, mu=MU)
    return {
        "qext": np.array(r.qext),
        "qsca": np.array(r.qsca),
        "qabs": np.array(r.qext - r.qsca),
        "g": np.array(r.g),
        "f11": r.phase,
        "s1r": r.s1.real,
        "s1i": r.s1.imag,
        "s2r": r.s2.real,
        "s2i": r.s2.imag,
    }


def _difference(
    f: Callable[[float], dict[str, np.ndarray]], h: float, one_sided: bool
) -> dict[str, np.ndarray]:
    if one_sided:  # second order: (-3 f(0) + 4 f(h) - f(2h)) / (2h)
        f0, f1, f2 = f(0.0), f(h), f(2.0 * h)
        return {q: (-3.0 * f0[q] + 4.0 * f1[q] - f2[q]) / (2.0 * h) for q in f0}
    fp, fm = f(h), f(-h)
    return {q: (fp[q] - fm[q]) / (2.0 * h) for q in fp}


@pytest.mark.parametrize("m", INDICES)
@pytest.mark.parametrize("x", SIZES)
def test_values_agree_with_the_mie_kernel(m: complex, x: float) -> None:
    s = sphere_derivatives(m=m, x=x, mu=MU)
    r = mie.single_sphere(m=m, x=x, mu=MU)
    for name in ("qext", "qsca", "g"):
        assert getattr(s, name) == pytest.approx(getattr(r, name), rel=1e-12, abs=1e-14)
    np.testing.assert_allclose(s.f11, r.phase, rtol=1e-11)
    scale = np.max(np.abs(r.s1))
    np.testing.assert_allclose(s.s1, r.s1, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(s.s2, r.s2, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("m", INDICES)
@pytest.mark.parametrize("x", SIZES)
@pytest.mark.parametrize("parameter", ["n", "k", "x"])
def test_derivatives_against_finite_differences(m: complex, x: float, parameter: str) -> None:
    s = sphere_derivatives(m=m, x=x, mu=MU)
    h = 1e-4 if parameter == "x" else 1e-4 / max(1.0, x)
    one_sided = parameter == "k" and m.imag == 0.0

    def f(d: float) -> dict[str, np.ndarray]:
        if parameter == "x":
            return _values(m, x + d)
        return _values(m + (d if parameter == "n" else 1j * d), x)

    f0 = f(0.0)
    d_h = _difference(f, h, one_sided)
    d_2h = _difference(f, 2.0 * h, one_sided)
    exact = {q: np.asarray(s.derivative(q, parameter)) for q in (*REAL_QUANTITIES, "f11")}
    for amp in ("s1", "s2"):
        d = np.asarray(s.derivative(amp, parameter))
        exact[amp + "r"], exact[amp + "i"] = d.real, d.imag
    for q, value in exact.items():
        scale = np.abs(f0[q])
        if q.startswith("s"):  # a complex amplitude: round-off relative to its modulus
            scale = np.hypot(f0[q[:2] + "r"], f0[q[:2] + "i"])
        tol = np.abs(d_h[q] - d_2h[q]) + 4.0 * EPS_F * scale / h + 1e-12 * np.abs(value)
        # g and Q_abs are differences of the kernel's sums: their round-off is that of Q_ext.
        if q in ("g", "qabs"):
            tol += 4.0 * EPS_F * float(f0["qext"]) / h
        err = np.abs(value - d_h[q])
        assert np.all(err <= tol), (q, parameter, float(np.max(err - tol)), err, tol)


@pytest.mark.parametrize("m", INDICES)
@pytest.mark.parametrize("x", (0.3, 5.0, 40.0))
def test_coefficients_are_holomorphic(m: complex, x: float) -> None:
    """d/dk = i d/dn for a_n and b_n, checked on the kernel's own coefficients by
    differences along both axes (Cauchy-Riemann)."""
    s = sphere_derivatives(m=m, x=x)
    h = 1e-5 / max(1.0, x)
    k_step = 1j * h
    plus_n = sphere_derivatives(m=m + h, x=x)
    minus_n = sphere_derivatives(m=m - h, x=x)
    plus_k = sphere_derivatives(m=m + k_step, x=x)
    base = sphere_derivatives(m=m, x=x)
    along_n = (plus_n.a - minus_n.a) / (2 * h)
    along_k = (plus_k.a - base.a) / h  # first order: k may be 0
    np.testing.assert_allclose(along_n, s.derivative("a", "m"), rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(along_k, s.derivative("a", "k"), rtol=1e-3, atol=1e-7)


def test_against_scatrs_single_spheres() -> None:
    """scatrs 0.3's closed-form derivatives (scatrs.mie, with dustoptics' n_max),
    rtol 1e-9 of each quantity's scale."""
    scatrs = pytest.importorskip("scatrs")
    for m in INDICES:
        for x in SIZES:
            s = sphere_derivatives(m=m, x=x, mu=MU)
            n_max = int(mie.wiscombe_nmax(x))
            e = scatrs.mie.efficiencies(x, m, n_max=n_max, derivatives=True, allow_unvalidated=True)
            pm = scatrs.mie.phase_matrix(
                x, m, MU, n_max=n_max, derivatives=True, allow_unvalidated=True
            )
            amp = scatrs.mie.amplitudes(
                x, m, MU, n_max=n_max, derivatives=True, allow_unvalidated=True
            )
            for ours, theirs in (("n", "m_real"), ("k", "m_imag"), ("x", "x")):
                de = e.d(theirs)
                for q in ("qext", "qsca", "qabs", "qback", "g"):
                    a = s.derivative(q, ours)
                    b = float(getattr(de, q[0] + "_" + q[1:]) if q != "g" else de.g)
                    assert a == pytest.approx(b, rel=1e-9, abs=1e-9 * max(1.0, s.qext)), (m, x, q)
                dp = pm.d(theirs)
                for q in ("f11", "f12", "f33", "f34"):
                    # scatrs normalizes F11 to a mean of 1 over the sphere: 4 pi ours.
                    a = 4.0 * np.pi * np.asarray(s.derivative(q, ours))
                    b = getattr(dp, q)
                    scale = np.max(np.abs(dp.f11))
                    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * scale, err_msg=q)
                da = amp.d(theirs)
                for q in ("s1", "s2"):
                    b = getattr(da, q)
                    np.testing.assert_allclose(
                        s.derivative(q, ours), b, rtol=0, atol=1e-9 * np.max(np.abs(b))
                    )


def test_derivative_names_are_checked() -> None:
    s = sphere_derivatives(m=1.5 + 0.01j, x=2.0)
    with pytest.raises(ValueError, match="quantity"):
        s.derivative("qfoo", "n")
    with pytest.raises(ValueError, match="parameter"):
        s.derivative("qext", "r")
    with pytest.raises(ValueError, match="'m'.*holomorphic"):
        s.derivative("qext", "m")
    assert s.derivative("a", "k") == pytest.approx(1j * s.derivative("a", "m"))


def test_inputs_are_checked_as_the_kernel_checks_them() -> None:
    with pytest.raises(ValueError, match="k >= 0"):
        sphere_derivatives(m=1.5 - 0.1j, x=1.0)
    with pytest.raises(ValueError, match="x must be"):
        sphere_derivatives(m=1.5, x=0.0)
    with pytest.raises(ValueError, match="mu must be"):
        sphere_derivatives(m=1.5, x=1.0, mu=[2.0])
