"""Checks at the public boundary.

Every public function validates its physical inputs with these helpers so that
bad input fails early with one message format: the parameter's name, the value
received and what is allowed.  Nothing here clamps or repairs a value.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "as_float_array",
    "as_increasing_grid",
    "check_choice",
    "check_closed_interval",
    "check_open_interval",
    "check_positive",
    "check_real",
]


def _show(value: Any) -> str:
    """Short repr of a value for an error message."""
    arr = np.asarray(value)
    if arr.ndim == 0:
        return repr(value)
    if arr.size > 6:
        return f"array of shape {arr.shape} (first values {arr.ravel()[:3].tolist()})"
    return repr(arr.tolist())


def check_real(name: str, value: Any) -> float:
    """Return ``value`` as a finite float or raise ValueError naming ``name``."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite real number; got {value!r}") from None
    if not np.isfinite(out):
        raise ValueError(f"{name} must be a finite real number; got {value!r}")
    return out


def check_positive(name: str, value: Any, *, unit: str = "") -> float:
    """Return ``value`` as a float > 0 or raise ValueError naming ``name``."""
    out = check_real(name, value)
    if out <= 0.0:
        suffix = f" {unit}" if unit else ""
        raise ValueError(f"{name} must be > 0{suffix}; got {value!r}")
    return out


def check_open_interval(name: str, value: Any, low: float, high: float) -> float:
    """Return ``value`` as a float in the open interval (low, high)."""
    out = check_real(name, value)
    if not (low < out < high):
        raise ValueError(f"{name} must be in the open interval ({low}, {high}); got {value!r}")
    return out


def check_closed_interval(name: str, value: Any, low: float, high: float) -> float:
    """Return ``value`` as a float in the closed interval [low, high]."""
    out = check_real(name, value)
    if not (low <= out <= high):
        raise ValueError(f"{name} must be in the closed interval [{low}, {high}]; got {value!r}")
    return out


def as_float_array(name: str, values: Any, *, ndim: int | None = None) -> np.ndarray:
    """Return a finite float64 array (a new array, never the caller's)."""
    try:
        arr = np.array(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be real numbers; got {_show(values)}") from None
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be {ndim}-dimensional; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf); got {_show(values)}")
    return arr


def as_increasing_grid(
    name: str,
    values: Any,
    *,
    low: float | None = None,
    high: float | None = None,
    unit: str = "",
) -> np.ndarray:
    """Return a non-empty, finite, strictly increasing 1-D float64 grid.

    ``low`` and ``high`` are inclusive bounds; ``low`` given as 0 with a grid of
    wavelengths is combined by the caller with a positivity check.
    """
    arr = as_float_array(name, np.atleast_1d(values) if np.ndim(values) == 0 else values, ndim=1)
    suffix = f" [{unit}]" if unit else ""
    if arr.size == 0:
        raise ValueError(f"{name} must not be empty")
    if arr.size > 1 and not np.all(np.diff(arr) > 0):
        raise ValueError(f"{name}{suffix} must be strictly increasing; got {_show(values)}")
    if low is not None and arr[0] < low:
        raise ValueError(f"{name}{suffix} must be >= {low}; got minimum {arr[0]!r}")
    if high is not None and arr[-1] > high:
        raise ValueError(f"{name}{suffix} must be <= {high}; got maximum {arr[-1]!r}")
    return arr


def check_choice(name: str, value: Any, choices: tuple[str, ...] | list[str]) -> str:
    """Return ``value`` if it is one of ``choices``, else raise listing them."""
    if value not in choices:
        valid = ", ".join(repr(c) for c in choices)
        raise ValueError(f"{name} must be one of {valid}; got {value!r}")
    return value
