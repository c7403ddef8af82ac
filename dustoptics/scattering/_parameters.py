"""Parameters of the phase functions: a scalar or an array, checked alike.

The analytic phase functions (:mod:`dustoptics.scattering.phase`) and the
operations on phase tables (:mod:`dustoptics.scattering.tabulated_phase`)
broadcast over their parameters, so a parameter is a number or an array of
numbers; both are checked here with one message format.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from dustoptics._validation import (
    _show,
    as_float_array,
    check_closed_interval,
    check_open_interval,
)

__all__ = ["FloatArray", "FloatOrArray", "float_or_array", "in_interval", "mixing_weight"]

FloatArray = NDArray[np.float64]
FloatOrArray = float | FloatArray


def float_or_array(values: FloatArray) -> FloatOrArray:
    """A Python float for 0-d results, the array otherwise."""
    return float(values) if values.ndim == 0 else values


def _interval_text(low: float, high: float, closed: bool) -> str:
    return f"closed interval [{low}, {high}]" if closed else f"open interval ({low}, {high})"


def in_interval(
    name: str, value: Any, low: float, high: float, *, closed: bool
) -> float | FloatArray:
    """A finite parameter (scalar or array) inside an interval, else ValueError.

    Scalars go through the shared helpers so that the message is the project's
    one format; arrays get the same message plus the offending values.
    """
    if np.ndim(value) == 0:
        check = check_closed_interval if closed else check_open_interval
        return check(name, value, low, high)
    arr = as_float_array(name, value)
    inside = (low <= arr) & (arr <= high) if closed else (low < arr) & (arr < high)
    if not np.all(inside):
        raise ValueError(
            f"{name} must be in the {_interval_text(low, high, closed)}; got "
            f"{_show(value)} (out of range: {_show(arr[~inside])})"
        )
    return arr


def mixing_weight(name: str, value: Any) -> float | FloatArray:
    """A mixing weight in [0, 1]."""
    return in_interval(name, value, 0.0, 1.0, closed=True)
