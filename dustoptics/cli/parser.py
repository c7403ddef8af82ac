"""The argument parser of the command line, and the option types its commands share.

:func:`build_parser` makes the parser: the program's options, then one
subcommand per command module (each module's ``add_parser``, which sets the
function that runs it as the ``run`` default).  The documentation's command
reference is generated from this parser (``docs/_ext/argparse_reference.py``).
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from dustoptics import __version__
from dustoptics.cli.errors import PROG
from dustoptics.io._text import printable

__all__ = ["add_command", "build_parser"]

#: Command modules of :mod:`dustoptics.cli`, in the order of the help's command list.
_COMMAND_MODULES = (
    "build",
    "export",
    "info",
    "plot",
    "catalogue",
    "fit",
    "sweep",
    "sky",
    "retrieve",
)


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors on one line: ``dustoptics: error: <message>``."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{PROG}: error: {printable(message)} (see '{self.prog} --help')\n")


def add_command(
    sub: Any, name: str, *, help: str, examples: Sequence[str], description: str | None = None
) -> argparse.ArgumentParser:
    """A subcommand's parser, its ``--help`` ending with examples.

    Parameters
    ----------
    sub : argparse subparsers action
        Where the subcommand goes (``parser.add_subparsers()``).
    name : str
        The subcommand.
    help : str
        One line for the program's list of commands (and the description).
    examples : sequence of str
        Command lines shown at the end of the subcommand's ``--help``, each
        a complete command (``dustoptics ...``).
    description : str, optional
        Shown under the usage; default ``help``, capitalized.

    Returns
    -------
    argparse.ArgumentParser
    """
    label = "example" if len(examples) == 1 else "examples"
    parser: argparse.ArgumentParser = sub.add_parser(
        name,
        help=help,
        description=description or help[:1].upper() + help[1:] + ".",
        epilog=f"{label}:\n" + "\n".join(f"  {line}" for line in examples),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    return parser


def _float_list(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.replace(" ", ",").split(",") if v)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers; got {text!r}"
        ) from None
    if not values or not all(np.isfinite(values)):
        raise argparse.ArgumentTypeError(f"expected comma-separated finite numbers; got {text!r}")
    return values


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number; got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0; got {text!r}")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer; got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"must be an integer >= 2; got {text!r}")
    return value


def _worker_count(text: str) -> int:
    """``--workers``: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer; got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1; got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The command line's argument parser.

    Returns
    -------
    argparse.ArgumentParser
        Parsed arguments carry ``command`` (the subcommand's name) and ``run``,
        the function that runs it: ``args.run(args) -> exit status``.
    """

    parser = _Parser(
        prog=PROG,
        description="Exact, reproducible optics of atmospheric dust and lookup tables for renderers.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in _COMMAND_MODULES:
        importlib.import_module(f"dustoptics.cli.{name}").add_parser(sub)
    return parser
