"""What a table does through modules above it: writing files, fitting models.

The table package is the bottom of the package: of the package it imports only the
validation and file helpers.  Writing a file and fitting a model need modules that
import it, so they register themselves here when imported (``import
dustoptics`` imports them all), the way xarray's backends register their
engines.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the fitter imports this package, not the other way round
    from dustoptics.scattering.fit import FitResult

__all__ = ["TableWriter", "register_table_fitter", "register_table_writer"]


#: A table file writer: ``writer(table, path, *, overwrite=False) -> pathlib.Path``.
TableWriter = Callable[..., Path]

#: Lower-case file suffix -> the writer :meth:`Table.save` uses for it; the
#: first suffix registered is the default (a path without a suffix gets it).
_WRITERS: dict[str, TableWriter] = {}

#: The function behind :meth:`Table.fit` (one at most).
_FITTERS: list[Callable[..., FitResult]] = []


def register_table_writer(suffixes: Sequence[str], writer: TableWriter) -> None:
    """Let :meth:`Table.save` write files with these suffixes through ``writer``.

    :mod:`dustoptics.io.tables.netcdf` registers its writer for ``.nc``,
    ``.h5``, ``.hdf5`` and ``.nc4`` when it is imported, which ``import
    dustoptics`` does.  Registering the same writer again changes nothing.

    Parameters
    ----------
    suffixes : sequence of str
        File suffixes with their dot, e.g. ``(".nc", ".h5")``, matched
        without regard to case.  The first suffix ever registered is the
        default of a path without one.
    writer : callable
        ``writer(table, path, *, overwrite=False) -> pathlib.Path``: writes
        one file at ``path`` (whose suffix is one of ``suffixes``).

    Raises
    ------
    ValueError
        A suffix that is not a dot followed by letters and digits, or one
        already registered to another writer (nothing is registered).
    """
    if isinstance(suffixes, str):
        raise TypeError(
            f"suffixes must be a sequence of suffixes, not one string; got {suffixes!r}"
        )
    if not callable(writer):
        raise TypeError(f"writer must be callable; got {writer!r}")
    keys = []
    for suffix in suffixes:
        if not (isinstance(suffix, str) and suffix[:1] == "." and suffix[1:].isalnum()):
            raise ValueError(
                f"suffixes must be file suffixes like '.nc' (a dot, then letters and digits); "
                f"got {suffix!r}"
            )
        key = suffix.lower()
        if _WRITERS.get(key, writer) is not writer:
            raise ValueError(
                f"table file suffix {suffix!r} is already registered to "
                f"{getattr(_WRITERS[key], '__qualname__', _WRITERS[key])!r}"
            )
        keys.append(key)
    for key in keys:
        _WRITERS[key] = writer


def register_table_fitter(fitter: Callable[..., FitResult]) -> None:
    """Make ``fitter`` the function behind :meth:`Table.fit`.

    :mod:`dustoptics.scattering` registers
    :func:`~dustoptics.scattering.fit.fit_table` when it is imported, which
    ``import dustoptics`` does.  Registering the same function again changes
    nothing.

    Parameters
    ----------
    fitter : callable
        ``fitter(table, *, model, colour, channels_nm, forward_cutoff_deg) -> FitResult``.

    Raises
    ------
    ValueError
        Another function is already registered.
    """
    if not callable(fitter):
        raise TypeError(f"fitter must be callable; got {fitter!r}")
    if _FITTERS and _FITTERS[0] is not fitter:
        raise ValueError(
            f"Table.fit is already served by {getattr(_FITTERS[0], '__qualname__', _FITTERS[0])!r}"
        )
    _FITTERS[:] = [fitter]
