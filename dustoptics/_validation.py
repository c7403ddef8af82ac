"""Checks at the public boundary.

Every public function validates its physical inputs with these helpers so that
bad input fails early with one message format: the parameter's name, the value
received and what is allowed.  Nothing here clamps or repairs a value.

Besides values, a request is checked for what it would cost before any work
(:func:`check_budget`): the memory a call would need is estimated from its
grids and its largest size parameter, and a call beyond
:data:`MEMORY_BUDGET_BYTES` raises a :class:`BudgetError` saying what to change,
unless the caller passes ``allow_large=True`` (``--allow-large`` on the command
line).  Output names and paths are checked by :func:`check_file_name` and
:func:`check_inside`.
"""

from __future__ import annotations

import os
import unicodedata
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "MAX_GRID_POINTS",
    "MEMORY_BUDGET_BYTES",
    "BudgetError",
    "NotANumberError",
    "as_float_array",
    "as_increasing_grid",
    "check_budget",
    "check_choice",
    "check_closed_interval",
    "check_count",
    "check_file_name",
    "check_inside",
    "check_open_interval",
    "check_positive",
    "check_real",
    "check_wavelength_unit",
]

#: Largest memory a single call may need without ``allow_large=True`` [bytes]
#: (2 GiB: well above the default Mars table's ~0.2 GB peak, below what a
#: shared workstation can give one process).
MEMORY_BUDGET_BYTES = 2 * 1024**3

#: Largest number of points of any grid given by a count or a step (angles,
#: wavelengths, texture and GLSL samples, altitudes) without ``allow_large``:
#: a million, 550 times the default 1,801 angles.
MAX_GRID_POINTS = 1_000_000


class BudgetError(ValueError):
    """A request would need more memory or work than the documented budget.

    The message says what the estimate is, the budget, which parameters to
    change, and that ``allow_large=True`` (``--allow-large``) lifts the limit.
    """


def _show(value: Any) -> str:
    """Short repr of a value for an error message."""
    arr = np.asarray(value)
    if arr.ndim == 0:
        return repr(value)
    if arr.size > 6:
        return f"array of shape {arr.shape} (first values {arr.ravel()[:3].tolist()})"
    return repr(arr.tolist())


class NotANumberError(TypeError, ValueError):
    """A string or boolean given where a number is expected.

    A TypeError (the value's type is wrong) that is also a ValueError, so that
    callers catching the package's usual ValueError for bad input see it too.
    """


def _refuse_non_number(name: str, value: Any) -> None:
    """Strings and booleans are not numbers, even where float() would take them."""
    if isinstance(value, (str, bytes, bool, np.bool_)):
        raise NotANumberError(
            f"{name} must be a real number, not {type(value).__name__}; got {value!r}"
        )


def check_real(name: str, value: Any) -> float:
    """Return ``value`` as a finite float or raise ValueError naming ``name``.

    Strings and booleans raise TypeError (``"1.5"`` and ``True`` are not numbers).
    """
    _refuse_non_number(name, value)
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
    """Return a finite float64 array (a new array, never the caller's).

    Strings and booleans raise TypeError, whether given alone or inside a
    sequence (``[True]`` is not 1 nm).
    """
    if isinstance(values, (str, bytes, bool, np.bool_)):
        raise NotANumberError(
            f"{name} must be real numbers, not {type(values).__name__}; got {values!r}"
        )
    probe = np.asarray(values) if not isinstance(values, np.ndarray) else values
    if probe.dtype.kind in "bUSV":
        raise NotANumberError(
            f"{name} must be real numbers, not {probe.dtype} values; got {_show(values)}"
        )
    if probe.dtype.kind == "O":
        for item in probe.ravel():
            _refuse_non_number(name, item)
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


def check_count(
    name: str,
    value: Any,
    *,
    minimum: int = 1,
    allow_large: bool = False,
    limit: int = MAX_GRID_POINTS,
    hint: str = "",
) -> int:
    """Return ``value`` as an int >= ``minimum`` and (unless ``allow_large``) <= ``limit``.

    Integers only: floats, strings and booleans raise TypeError.  A count beyond
    ``limit`` raises :class:`BudgetError` saying so and how to allow it.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer; got {value!r} ({type(value).__name__})")
    out = int(value)
    if out < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}; got {out!r}")
    if out > limit and not allow_large:
        raise BudgetError(
            f"{name} = {out} exceeds the budget of {limit} points{hint}; choose a smaller value, "
            "or pass allow_large=True (--allow-large) to go ahead"
        )
    return out


def check_budget(what: str, estimated_bytes: float, *, allow_large: bool, change: str) -> None:
    """Refuse a request whose estimated memory exceeds :data:`MEMORY_BUDGET_BYTES`.

    Parameters
    ----------
    what : str
        The request, for the message (e.g. ``"compute_optics"``).
    estimated_bytes : float
        Estimated peak memory of the request. [bytes]
    allow_large : bool
        Go ahead whatever the estimate.
    change : str
        Which parameters drive the estimate, for the message.

    Raises
    ------
    BudgetError
        The estimate exceeds the budget and ``allow_large`` is False.
    """
    if allow_large or estimated_bytes <= MEMORY_BUDGET_BYTES:
        return
    shown = (
        f"{estimated_bytes / 1024**3:.3g} GiB"
        if np.isfinite(estimated_bytes)
        else "unbounded memory"
    )
    raise BudgetError(
        f"{what} would need about {shown}, beyond the budget of "
        f"{MEMORY_BUDGET_BYTES / 1024**3:g} GiB; {change}, or pass allow_large=True "
        "(--allow-large on the command line) to go ahead"
    )


def check_wavelength_unit(name: str, wavelength_nm: np.ndarray) -> None:
    """Refuse wavelengths that are plainly not in nanometres.

    All below 10 nm (X-rays; 0.44 was meant as 0.44 um = 440 nm) or all above
    1e7 nm (1 cm; a value in picometres or metres misread) raise ValueError
    saying which unit was probably meant.
    """
    if wavelength_nm.size and np.all(wavelength_nm < 10.0):
        raise ValueError(
            f"{name} must be in nanometres; got {_show(wavelength_nm)}, all below 10 nm: "
            "were they micrometres? (multiply by 1000: 0.55 um = 550 nm)"
        )
    if wavelength_nm.size and np.all(wavelength_nm > 1e7):
        raise ValueError(
            f"{name} must be in nanometres; got {_show(wavelength_nm)}, all above 1e7 nm (1 cm): "
            "were they in another unit?"
        )


def check_file_name(name: str, value: Any) -> str:
    """Return ``value`` if it is a plain file name, else raise ValueError.

    A plain file name is a non-empty string that is not ``.`` or ``..``, holds
    no path separator (``/``, or ``\\`` which is one on Windows), no NUL or
    other control character, and does not start with ``-``, ``.`` or a space.
    Output directories and files are named from it, so it must not choose
    where they are written.
    """
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string; got {value!r} ({type(value).__name__})")
    bad = None
    if not value or not value.strip():
        bad = "it is empty"
    elif value in (".", "..") or value.startswith("."):
        bad = "it starts with '.'"
    elif "/" in value or "\\" in value or (os.sep in value) or (os.altsep and os.altsep in value):
        bad = "it holds a path separator"
    elif any(unicodedata.category(c).startswith("C") for c in value):
        bad = "it holds a control character"
    elif value.startswith(("-", " ")) or value.endswith(" "):
        bad = "it starts with '-' or starts or ends with a space"
    elif len(value.encode("utf-8")) > 200:
        bad = "it is longer than 200 bytes"
    if bad:
        raise ValueError(
            f"{name} must be a plain file name (letters, digits, '-', '_', no path); "
            f"got {value!r}: {bad}"
        )
    return value


def check_inside(root: Any, path: Any) -> Path:
    """Return ``path`` resolved, after checking it stays inside ``root``.

    Both are resolved (symbolic links followed, ``..`` removed); a ``path``
    that is a directory, or a link to one, is followed (files go into it);
    a file that is a symbolic link is judged by its directory (it is
    replaced, not followed, by :func:`dustoptics.io._atomic.write_files`).

    Raises
    ------
    ValueError
        ``path`` resolves outside ``root``; the message names both.
    """
    base = Path(root).resolve()
    p = Path(path)
    if p.is_dir() or p.name in ("", ".", ".."):
        where = p.resolve()  # a directory (or a link to one) is written into: follow it
    else:
        where = p.parent.resolve() / p.name
    if where != base and base not in where.parents:
        raise ValueError(
            f"output path {str(p)!r} resolves to {str(where)!r}, outside the output directory "
            f"{str(base)!r}; outputs must stay inside it (check the name and any symbolic links)"
        )
    return where
