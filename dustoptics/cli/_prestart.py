"""The first ``dustoptics build``: compiling starts before the package is imported.

The first build of an install compiles the numba kernels of a Mie table (seconds
of CPU time, on every core: :func:`dustoptics._numba_cache.compile_kernels`).  The
command itself first imports numpy, scipy, numba, h5py and the package, most of a
second on one core.  The package imports this module first (after
:mod:`~dustoptics.cli._interrupt`), and when the process is the command
``dustoptics build`` (the script or ``python -m dustoptics.cli``; not ``--help``)
and numba's cache holds none of the kernels, :func:`start` starts the compiling
children at once (:func:`dustoptics._numba_cache.prestart`): they import the
kernels' modules on the other cores while this process imports, and the build
hands them kernels.  Anywhere else (a program importing dustoptics, a later
build) it does nothing.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from dustoptics import _numba_cache
from dustoptics.cli._interrupt import is_the_command

__all__ = ["start"]

#: Commands that compute Mie tables (and so compile their kernels on a first run).
COMMANDS = ("build",)


def _command(argv: Sequence[str]) -> str | None:
    """The subcommand of ``argv`` (its first argument), None with a help or version
    option anywhere."""
    if any(a in ("-h", "--help", "--version") for a in argv):
        return None
    return argv[0] if argv else None


def start(argv: Sequence[str] | None = None) -> int:
    """Start compiling if this process is ``dustoptics build`` on an empty cache;
    returns the children started (0: nothing done).

    Call after :func:`dustoptics._numba_cache.configure` (the children compile into
    the cache it chose).
    """
    if not is_the_command():
        return 0
    if _command(sys.argv[1:] if argv is None else argv) not in COMMANDS:
        return 0

    return _numba_cache.prestart()
