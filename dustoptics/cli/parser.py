"""The argument parser of the command line, and the option types its commands share.

:func:`build_parser` makes the parser: the program's options, then one
subcommand per command module (each module's ``add_parser``, which sets the
function that runs it as the ``run`` default).  The documentation's command
reference is generated from this parser (``docs/_ext/argparse_reference.py``).
"""

from __future__ import annotations

import argparse
import importlib
import re
import textwrap
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from dustoptics import __version__
from dustoptics.cli.errors import PROG
from dustoptics.io._text import printable

__all__ = ["HELP_COLUMNS", "HelpFormatter", "add_command", "build_parser"]

#: Width of ``--help``, whatever the terminal's: an 80-column terminal shows it unwrapped.
HELP_COLUMNS = 80

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
    "engines",
)


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors on one line: ``dustoptics: error: <message>``."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{PROG}: error: {printable(message)} (see '{self.prog} --help')\n")


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Help at most :data:`HELP_COLUMNS` wide, never breaking a word at its hyphens.

    argparse's own formatter follows the terminal's width and breaks
    ``--allow-large`` into ``--allow-`` and ``large``; this one wraps the
    options' help at spaces only.  Descriptions and epilogs keep their line
    breaks; a line too long is wrapped: an example (an indented command line)
    with a shell continuation (`` \\``), an entry of a list (``name  text``)
    under its text.
    """

    def __init__(self, prog: str, **kwargs: Any) -> None:
        kwargs.setdefault("width", HELP_COLUMNS)
        super().__init__(prog, **kwargs)

    def start_section(self, heading: str | None) -> None:
        if heading:  # a group's title, wrapped too (its colon included)
            room = self._width - self._current_indent - 1
            heading = "\n".join(
                textwrap.wrap(heading, room, break_on_hyphens=False, break_long_words=False)
            )
        super().start_section(heading)

    def _split_lines(self, text: str, width: int) -> list[str]:
        text = " ".join(text.split())
        return textwrap.wrap(text, width, break_on_hyphens=False, break_long_words=False)

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        lines = []
        for line in text.splitlines():
            own = indent + line[: len(line) - len(line.lstrip())]
            # A list's entry (``name  text``) wraps under its text; an example (an indented
            # command) with a shell continuation, so that it can still be pasted.
            column = re.match(r"\s*\S+\s{2,}", line)
            example = own != indent and column is None
            wrapped = textwrap.wrap(
                line.strip(),
                width - 2 if example else width,
                initial_indent=own,
                subsequent_indent=indent + " " * column.end() if column else own + "    " * example,
                break_on_hyphens=False,
                break_long_words=False,
            ) or [""]
            lines += [w + " \\" for w in wrapped[:-1]] + wrapped[-1:] if example else wrapped
        return "\n".join(lines) + "\n"


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
        formatter_class=HelpFormatter,
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
        formatter_class=HelpFormatter,
        description="Exact, reproducible optics of atmospheric dust and lookup tables for renderers.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in _COMMAND_MODULES:
        importlib.import_module(f"dustoptics.cli.{name}").add_parser(sub)
    return parser
