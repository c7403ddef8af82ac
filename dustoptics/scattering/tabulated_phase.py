"""Tabulated phase functions: the table a renderer reads, and what is done to it.

A renderer reads a phase function sampled at scattering angles ``theta_deg``
and interpolated linearly in ``theta`` between the samples.  The functions
here work on such tables (the last axis runs over the angles, any leading axes
over wavelengths or channels), exactly for that piecewise-linear function:

- :func:`sphere_integral` integrates it over the sphere, :func:`mean_cosine`
  gives its asymmetry parameter, :func:`renormalize` makes it integrate to one;
- :func:`hybrid` is Meyran 2022's blend of a Mie table with an analytic one,
  :func:`flatten` CosmoScout VR's isotropic "phase flattening", both
  renormalized;
- :func:`tabulate` samples an analytic phase function
  (:mod:`dustoptics.scattering.phase`) on a grid of angles.

Conventions are those of :mod:`dustoptics.scattering.phase`: a phase function
is a density per steradian with ``2 pi int_{-1}^{1} P dmu = 1``, and
``theta = 0`` is the forward direction.  A table that spans the sphere runs
from exactly 0 to exactly 180 degree.

References
----------
.. [1] T. Meyran, "Physically based real-time rendering of the Martian
   atmosphere," M.Sc. thesis, Hochschule Hannover, 2022.
.. [2] German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres,
   https://github.com/cosmoscout/cosmoscout-vr.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Final

import numpy as np
from numpy.typing import ArrayLike

from dustoptics._validation import as_float_array, as_increasing_grid
from dustoptics.scattering._parameters import (
    FloatArray,
    FloatOrArray,
    float_or_array,
    mixing_weight,
)

__all__ = [
    "flatten",
    "hybrid",
    "mean_cosine",
    "renormalize",
    "sphere_integral",
    "tabulate",
]

_FOUR_PI: Final = 4.0 * math.pi


def _table_grid(theta_deg: ArrayLike) -> FloatArray:
    """A table angle grid: strictly increasing, from exactly 0 to exactly 180 deg."""
    theta = as_increasing_grid("theta_deg", theta_deg, low=0.0, high=180.0, unit="deg")
    if theta.size < 2 or theta[0] != 0.0 or theta[-1] != 180.0:
        raise ValueError(
            f"theta_deg [deg] must start at exactly 0 and end at exactly 180 (the table "
            f"must cover the sphere); got {theta.size} values from {theta[0]!r} to {theta[-1]!r}"
        )
    return theta


def _table(name: str, phase: ArrayLike, theta: FloatArray) -> FloatArray:
    """A phase table: finite, nonnegative, last axis on the angle grid."""
    p = as_float_array(name, phase)
    if p.ndim == 0 or p.shape[-1] != theta.size:
        raise ValueError(
            f"{name} has shape {p.shape} but theta_deg has shape {theta.shape}: the last "
            f"axis of {name} must run over theta_deg"
        )
    if np.any(p < 0.0):
        raise ValueError(f"{name} must be >= 0 [sr^-1]; got minimum {float(p.min())!r}")
    return p


def _h_minus_sin(h: FloatArray) -> FloatArray:
    """``h - sin(h)`` without cancellation for small ``h``.

    Below 0.5 rad the Taylor series ``h^3/3! - h^5/5! + ... + h^19/19!`` (nested),
    whose truncation is below ``h^21/21! < 1e-26``; above it, the direct
    difference loses at most ``6 eps / h^2 < 6e-15`` relative.
    """
    h2 = h * h
    series = np.ones_like(h)
    for n in range(9, 1, -1):  # factors (2n)(2n+1): 342, 272, ..., 20
        series = 1.0 - h2 / ((2 * n) * (2 * n + 1)) * series
    series = h * h2 / 6.0 * series
    return np.where(h < 0.5, series, h - np.sin(h))


def _linear_theta_weights(theta_deg: FloatArray) -> FloatArray:
    """Weights ``w`` with ``sum_i w_i P_i = int_0^pi P(theta) sin(theta) dtheta``.

    Exact for ``P`` linear in ``theta`` on each interval (see :func:`sphere_integral`).
    """
    t = np.deg2rad(theta_deg)
    t0, t1 = t[:-1], t[1:]
    h = t1 - t0
    one_minus_cos = 2.0 * np.sin(0.5 * h) ** 2
    h_minus_sin = _h_minus_sin(h)
    left = (np.sin(t0) * one_minus_cos + np.cos(t0) * h_minus_sin) / h
    right = (np.sin(t1) * one_minus_cos - np.cos(t1) * h_minus_sin) / h
    w = np.zeros_like(t)
    w[:-1] += left
    w[1:] += right
    return w


def sphere_integral(phase: ArrayLike, *, theta_deg: ArrayLike) -> FloatOrArray:
    """Sphere integral of a phase table read by linear interpolation in angle.

    Computes ``2 pi int_0^pi P(theta) sin(theta) dtheta = 2 pi int_{-1}^{1} P dmu``
    exactly for the function a renderer reads from the table: linear in
    ``theta`` between samples.  On ``[t0, t1]`` with ``h = t1 - t0`` and
    ``P = P0 + (P1 - P0)(t - t0)/h``,

    .. math::

        \\int_{t_0}^{t_1} P \\sin t\\, dt = P_0 w_0 + P_1 w_1, \\quad
        w_0 = \\frac{\\sin t_0 (1 - \\cos h) + \\cos t_0 (h - \\sin h)}{h}, \\quad
        w_1 = \\frac{\\sin t_1 (1 - \\cos h) - \\cos t_1 (h - \\sin h)}{h}

    (from ``int (t - t0) sin t dt = sin t - (t - t0) cos t``; ``w0 + w1 =
    cos t0 - cos t1``).  ``1 - cos h`` is evaluated as ``2 sin^2(h/2)`` and
    ``h - sin h`` by its series for small ``h``, so the weights keep full
    relative precision on fine grids.

    Parameters
    ----------
    phase : array_like
        Phase table, shape ``(..., n_theta)``, nonnegative. [sr^-1]
    theta_deg : array_like
        Scattering angles, shape ``(n_theta,)``, strictly increasing from
        exactly 0 to exactly 180. [deg]

    Returns
    -------
    float or numpy.ndarray
        ``2 pi int P dmu`` per row, shape ``phase.shape[:-1]``. [-]
    """
    theta = _table_grid(theta_deg)
    p = _table("phase", phase, theta)
    return float_or_array(2.0 * math.pi * (p @ _linear_theta_weights(theta)))


def mean_cosine(phase: ArrayLike, *, theta_deg: ArrayLike) -> FloatOrArray:
    """Mean cosine (asymmetry parameter) of a phase table read linearly in angle.

    Computes ``g = 2 pi int_{-1}^{1} P mu dmu`` exactly for ``P`` linear in
    ``theta`` between samples:
    ``int P sin(t) cos(t) dt = (1/4) int_0^{2 pi} P(u/2) sin(u) du`` with
    ``u = 2 t``, and ``P`` is linear in ``u`` on each interval, so the weights
    of :func:`sphere_integral` on the doubled grid integrate it exactly (their
    derivation holds on any interval, not only within [0, pi]).

    Parameters
    ----------
    phase : array_like
        Phase table, shape ``(..., n_theta)``, normalized to 1. [sr^-1]
    theta_deg : array_like
        Scattering angles, strictly increasing from exactly 0 to exactly 180. [deg]

    Returns
    -------
    float or numpy.ndarray
        g per row, shape ``phase.shape[:-1]``. [-]

    Examples
    --------
    >>> theta = np.linspace(0.0, 180.0, 1801)
    >>> from dustoptics.scattering.phase import henyey_greenstein
    >>> p = henyey_greenstein(np.cos(np.deg2rad(theta)), g=0.5)
    >>> abs(mean_cosine(p, theta_deg=theta) - 0.5) < 1e-5
    True
    """
    theta = _table_grid(theta_deg)
    p = _table("phase", phase, theta)
    return float_or_array(0.5 * math.pi * (p @ _linear_theta_weights(2.0 * theta)))


def renormalize(phase: ArrayLike, *, theta_deg: ArrayLike) -> FloatArray:
    """Scale each row of a phase table so that :func:`sphere_integral` gives 1.

    Parameters
    ----------
    phase : array_like
        Phase table, shape ``(..., n_theta)``, nonnegative with a positive
        integral in every row. [sr^-1]
    theta_deg : array_like
        Scattering angles, strictly increasing from exactly 0 to exactly 180. [deg]

    Returns
    -------
    numpy.ndarray
        A new table (the input is not modified), normalized to 1 to rounding
        (< 1e-12) under linear interpolation in ``theta``. [sr^-1]
    """
    theta = _table_grid(theta_deg)
    p = _table("phase", phase, theta)
    total = 2.0 * math.pi * (p @ _linear_theta_weights(theta))
    if np.any(total <= 0.0):
        raise ValueError(
            "phase must have a positive sphere integral in every row; some rows are all zero"
        )
    return p / total[..., None]


def hybrid(
    p_mie: ArrayLike,
    p_analytic: ArrayLike,
    *,
    theta_deg: ArrayLike,
    weight: ArrayLike = 0.5,
) -> FloatArray:
    """Meyran's hybrid phase function: a blend of two tables, renormalized.

    .. math:: P_h = \\mathrm{renormalize}\\left[(1 - w) P_{mie} + w P_{analytic}\\right]

    with the renormalization of :func:`renormalize` applied to each
    wavelength row.

    Parameters
    ----------
    p_mie : array_like
        Mie phase table, shape ``(..., n_theta)``, nonnegative. [sr^-1]
    p_analytic : array_like
        Analytic phase table (e.g. Costa et al.'s DHG tabulated with
        :func:`tabulate`), the same shape. [sr^-1]
    theta_deg : array_like
        Scattering angles, strictly increasing from exactly 0 to exactly 180. [deg]
    weight : array_like, optional
        Weight ``w`` of the analytic table, in [0, 1]: a scalar, or an array over
        angle of shape ``(n_theta,)``, or anything else that broadcasts to the
        tables' shape.  Meyran 2022 calls the blend a simple linear
        interpolation without stating ``w``; 0.5 is the default. [-]

    Returns
    -------
    numpy.ndarray
        The hybrid table, normalized per row. [sr^-1]

    Notes
    -----
    The inputs are blended as given; each should already be normalized, or the
    effective weight differs from ``w``.

    References
    ----------
    .. [1] T. Meyran, "Physically based real-time rendering of the Martian
       atmosphere," M.Sc. thesis, Hochschule Hannover, 2022, section 4.
    """
    theta = _table_grid(theta_deg)
    pm = _table("p_mie", p_mie, theta)
    pa = _table("p_analytic", p_analytic, theta)
    if pm.shape != pa.shape:
        raise ValueError(
            f"p_mie has shape {pm.shape} but p_analytic has shape {pa.shape}; they must match"
        )
    w = _broadcast_weight("weight", weight, pm.shape)
    return renormalize((1.0 - w) * pm + w * pa, theta_deg=theta)


def _broadcast_weight(name: str, value: Any, shape: tuple[int, ...]) -> FloatArray:
    w = np.asarray(mixing_weight(name, value), dtype=np.float64)
    try:
        if np.broadcast_shapes(w.shape, shape) != shape:
            raise ValueError
    except ValueError:
        raise ValueError(
            f"{name} has shape {w.shape}, which does not broadcast to the table's shape {shape} "
            f"(use a scalar or an array over theta_deg of shape ({shape[-1]},))"
        ) from None
    return w


def flatten(phase: ArrayLike, *, theta_deg: ArrayLike, amount: ArrayLike) -> FloatArray:
    """CosmoScout VR's isotropic "phase flattening", renormalized.

    .. math:: P' = \\mathrm{renormalize}\\left[(1 - a) P + \\frac{a}{4 \\pi}\\right]

    Parameters
    ----------
    phase : array_like
        Phase table, shape ``(..., n_theta)``, nonnegative. [sr^-1]
    theta_deg : array_like
        Scattering angles, strictly increasing from exactly 0 to exactly 180. [deg]
    amount : array_like
        Flattening ``a`` in [0, 1]: 0 leaves the table (renormalized), 1 makes it
        isotropic.  A scalar or anything that broadcasts to the table's shape. [-]

    Returns
    -------
    numpy.ndarray
        The flattened table, normalized per row. [sr^-1]

    Notes
    -----
    The constant ``1/(4 pi)`` integrates to exactly 1 under the same
    quadrature, so for an already normalized table the renormalization only
    removes rounding.

    References
    ----------
    .. [1] German Aerospace Center (DLR), CosmoScout VR, plugin
       csp-atmospheres, https://github.com/cosmoscout/cosmoscout-vr.
    """
    theta = _table_grid(theta_deg)
    p = _table("phase", phase, theta)
    a = _broadcast_weight("amount", amount, p.shape)
    return renormalize((1.0 - a) * p + a / _FOUR_PI, theta_deg=theta)


def tabulate(
    function: Callable[..., FloatOrArray], *, theta_deg: ArrayLike, **params: Any
) -> FloatArray:
    """Sample an analytic phase function on a grid of scattering angles.

    Parameters
    ----------
    function : callable
        A phase function of :mod:`dustoptics.scattering.phase` (or any
        ``f(mu, **params)``).
    theta_deg : array_like
        Scattering angles, strictly increasing in [0, 180]. [deg]
    **params
        The function's parameters; give per-wavelength values a trailing axis
        (shape ``(n_wl, 1)``) to get a ``(n_wl, n_theta)`` table.

    Returns
    -------
    numpy.ndarray
        ``function(cos(theta), **params)``. [sr^-1]

    Notes
    -----
    Sampled values are not renormalized: under linear interpolation in angle a
    sampled analytic function integrates to 1 only up to the interpolation
    error.  Pass the result through :func:`renormalize` to export it.
    """
    theta = as_increasing_grid("theta_deg", theta_deg, low=0.0, high=180.0, unit="deg")
    mu = np.clip(np.cos(np.deg2rad(theta)), -1.0, 1.0)
    return np.asarray(function(mu, **params), dtype=np.float64)
