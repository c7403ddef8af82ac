"""Ctrl-C in the ``dustoptics`` command: one line, exit status 130, at any moment.

Python turns SIGINT into :class:`KeyboardInterrupt`, which
:func:`dustoptics.cli.errors.exit_status` turns into the line ``dustoptics:
interrupted`` and exit status 130, after the writers have rolled back what they
were writing (:mod:`dustoptics.io._atomic`).  Two moments escape it, and this
module covers them:

- the import of the package (numpy, scipy, numba, h5py: a second or more),
  before ``main`` runs.  The package imports this module first: when the
  process is the command (the ``dustoptics`` script or ``python -m
  dustoptics.cli``), an interrupt during the import prints the line and exits
  130 at once; nothing is being written yet.  A program that imports
  dustoptics as a library is left alone.
- numba compiling or loading the kernels (the first build of an install
  compiles for tens of seconds).  An exception raised there may land in one of
  llvmlite's ctypes callbacks, which prints it as "ignored" with a traceback and
  carries on.  While ``main`` runs (:func:`handling`), an interrupt that arrives
  inside numba or llvmlite exits at once as well: none of dustoptics' files is
  being written then, and numba writes its cache files whole (a temporary
  file, then a rename).
"""

from __future__ import annotations

import contextlib
import itertools
import os
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType

from dustoptics.cli.errors import EXIT_INTERRUPTED, PROG

__all__ = ["handling", "is_the_command"]

#: Packages whose frames mean "numba is compiling or loading a kernel".
_COMPILER_PACKAGES = (f"{os.sep}numba{os.sep}", f"{os.sep}llvmlite{os.sep}")


def is_the_command() -> bool:
    """Whether this process runs the ``dustoptics`` command (the script or ``-m``)."""
    script = os.path.basename(sys.argv[0]) if sys.argv else ""
    if os.path.splitext(script)[0] in ("dustoptics", "dustoptics-script"):
        return True
    argv = list(getattr(sys, "orig_argv", ()))
    return any(
        pair in (("-m", "dustoptics"), ("-m", "dustoptics.cli"))
        for pair in itertools.pairwise(argv)
    )


def _exit_now() -> None:
    os.write(2, f"{PROG}: interrupted\n".encode())
    os._exit(EXIT_INTERRUPTED)


def _while_importing(signum: int, frame: FrameType | None) -> None:
    """SIGINT before ``main`` runs: the line, and exit."""
    _exit_now()


def _in_compiler(frame: FrameType | None) -> bool:
    while frame is not None:
        if any(p in frame.f_code.co_filename for p in _COMPILER_PACKAGES):
            return True
        frame = frame.f_back
    return False


def _while_running(signum: int, frame: FrameType | None) -> None:
    """SIGINT while ``main`` runs: KeyboardInterrupt, or exit at once inside numba."""
    if _in_compiler(frame):
        _exit_now()
    raise KeyboardInterrupt


@contextlib.contextmanager
def handling() -> Iterator[None]:
    """Interrupts while the command runs, as this module describes; restored afterwards.

    Only in the main thread (where Python delivers signals), and only where
    Python's own handler, or this module's, is in place: SIGINT ignored (a
    background job, ``nohup``) stays ignored.
    """
    main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGINT) if main else None
    ours = main and previous in (signal.default_int_handler, _while_importing)
    if ours:
        signal.signal(signal.SIGINT, _while_running)
    try:
        yield
    finally:
        if ours:
            restore = signal.default_int_handler if previous is _while_importing else previous
            signal.signal(signal.SIGINT, restore)


def _install() -> None:
    if not is_the_command() or threading.current_thread() is not threading.main_thread():
        return
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _while_importing)


_install()
