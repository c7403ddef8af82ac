"""Exit status and error messages of the command line.

Exit status: 0 on success, 1 on failure (an output exists without
``--force``, a damaged input file, an input the physics rejects), 2 on a
usage error (unknown preset, format or option value: :class:`UsageError`, a
configuration file that does not follow the schema, argparse's own).  Errors
are printed as ``dustoptics: error: <message>`` on stderr, on one line and
without a traceback.  A closed output pipe (``dustoptics info f.h5 | head``)
is not an error.  An interrupt (Ctrl-C, SIGINT) anywhere in a command, the
first compilation of the kernels included, prints one line,
``dustoptics: interrupted``, and exits 130 (128 + SIGINT, as shells do); the
files being written are left as they were (:mod:`dustoptics.io._atomic`
writes them whole or not at all).
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable

__all__ = [
    "EXIT_FAILURE",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_USAGE",
    "PROG",
    "UsageError",
    "exit_status",
]

#: The program's name, the first word of every message.
PROG = "dustoptics"

#: Exit status of a command that did what it was asked.
EXIT_OK = 0
#: Exit status of a command that failed (its input, the physics, the file system).
EXIT_FAILURE = 1
#: Exit status of a command given wrongly (argparse's own status for usage errors).
EXIT_USAGE = 2
#: Exit status of a command interrupted by Ctrl-C (128 + SIGINT, as a shell reports it).
EXIT_INTERRUPTED = 130


class UsageError(ValueError):
    """A command-line usage error (exit status 2)."""


def _silence_stdout() -> None:
    """After a broken pipe, send further output to devnull so exit is quiet."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def _one_line(exc: BaseException) -> str:
    """An error message on one line (h5py's span several), control characters escaped."""
    # Here, not at the top: this module is imported before numba's cache is set up (cli).
    from dustoptics.io._text import printable

    return printable(" ".join(str(exc).split()))


def exit_status(command: Callable[[], int]) -> int:
    """Run ``command`` and return its exit status, an error's printed on stderr.

    Parameters
    ----------
    command : callable
        ``command() -> int``: parses the arguments and runs the command.

    Returns
    -------
    int
        ``command``'s status; 0 on a broken pipe; 2 on a :class:`UsageError`
        or a configuration error; 1 on any other error a user can cause
        (:class:`OSError`, :class:`ValueError`, :class:`TypeError`,
        :class:`ImportError` of an optional dependency); 130 on an interrupt
        (:class:`KeyboardInterrupt`).
    """
    try:
        return command()
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_OK
    except ValueError as exc:
        # FormatError is a ValueError too (1); a configuration's error is a usage error.
        usage = isinstance(exc, UsageError) or _is_config_error(exc)
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE if usage else EXIT_FAILURE
    except (OSError, TypeError, ImportError) as exc:
        # FileExistsError/PermissionError are OSErrors.
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        _interrupted()
        return EXIT_INTERRUPTED


def _is_config_error(exc: BaseException) -> bool:
    """Whether ``exc`` is a :class:`dustoptics.models.config.ConfigError`.

    Raised only by that module, so imported by then: looked up, not imported (it imports
    scipy and numba: ``dustoptics --help`` took 1.2-1.4 s of CPU time with the import,
    0.20-0.24 s without it, /usr/bin/time).
    """
    config = sys.modules.get("dustoptics.models.config")
    return config is not None and isinstance(exc, config.ConfigError)


def _interrupted() -> None:
    """The one line an interrupt prints (after a progress line left open on a terminal)."""
    try:
        tty = sys.stderr.isatty()
    except (AttributeError, ValueError):
        tty = False
    newline = "\n" if tty else ""
    with contextlib.suppress(OSError, ValueError):  # stderr closed: the status says it
        print(f"{newline}{PROG}: interrupted", file=sys.stderr, flush=True)
