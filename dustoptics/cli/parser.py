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
import sys
import textwrap
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from dustoptics import __version__
from dustoptics.cli.errors import PROG
from dustoptics.io._text import printable

__all__ = ["HELP_COLUMNS", "HelpFormatter", "add_command", "build_parser", "detail_group"]

#: Width of ``--help``, whatever the terminal's: an 80-column terminal shows it unwrapped.
HELP_COLUMNS = 80

#: The commands, in the order of the help's command list: name -> (the module of
#: :mod:`dustoptics.cli` that adds it, its line in the list).  A command line imports the
#: module of its command only (:func:`build_parser`): the others' imports are not its.
COMMANDS: dict[str, tuple[str, str]] = {
    "build": ("build", "compute a preset or configuration file and write its tables"),
    "export": ("export", "convert a table file into other formats"),
    "info": ("info", "what any file or folder dustoptics writes holds and how it was made"),
    "plot": ("plot", "plot a table (needs the 'plot' extra: matplotlib)"),
    "presets": ("catalogue", "list the presets, or print one's configuration file"),
    "materials": ("catalogue", "list the refractive-index catalogue"),
    "fit": ("fit", "fit an analytic phase function (HG, double HG, ...) to a table"),
    "sweep": (
        "sweep",
        "compute a configuration over its [sweep] axes on Dask (needs the 'sweep' extra)",
    ),
    "sky": (
        "sky",
        "render the sky an atmosphere makes: images, data and the thesis's comparisons",
    ),
    "retrieve": (
        "retrieve",
        "fit dust parameters (size, index, hematite fraction) to observations",
    ),
    "engines": (
        "engines",
        "rendering engines' sky models fitted to the exact sky, and the error they cost",
    ),
}


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors on one line (``dustoptics: error: <message>``) and a short
    ``--help``.

    Argument groups marked with :func:`detail_group` (each format's options) are left out of
    ``--help`` and shown by ``--help-all``, which a parser gets with its first such group.
    """

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{PROG}: error: {printable(message)} (see '{self.prog} --help')\n")

    def format_help(self, *, full: bool = False) -> str:
        groups = self._action_groups
        hidden = [] if full else [g for g in groups if getattr(g, "detail", False)]
        helps = [(a, a.help) for g in hidden for a in g._group_actions]
        # Out of the usage line too: argparse leaves out the actions whose help is SUPPRESS.
        for action, _ in helps:
            action.help = argparse.SUPPRESS
        self._action_groups = [g for g in groups if g not in hidden]
        try:
            return super().format_help()
        finally:
            self._action_groups = groups
            for action, text in helps:
                action.help = text


class _HelpAll(argparse.Action):
    """``--help-all``: the whole help, the detail groups included."""

    def __init__(self, option_strings: Sequence[str], dest: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest=argparse.SUPPRESS, nargs=0, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, *args: Any, **kwargs: Any) -> None:
        text = (
            parser.format_help(full=True) if isinstance(parser, _Parser) else parser.format_help()
        )
        parser._print_message(text, sys.stdout)
        parser.exit(0)


def detail_group(
    parser: argparse.ArgumentParser, title: str, description: str | None = None
) -> argparse._ArgumentGroup:
    """An argument group shown by ``--help-all`` only (``--help`` says it is there).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser; it gets ``--help-all`` with its first detail group.
    title, description : str
        The group's heading and text.

    Returns
    -------
    argparse._ArgumentGroup
    """
    if not any(isinstance(a, _HelpAll) for a in parser._actions):
        parser.add_argument(
            "--help-all",
            action=_HelpAll,
            help="show this help with every format's options (left out of --help), and exit",
        )
    group = parser.add_argument_group(title, description)
    group.detail = True  # type: ignore[attr-defined]
    return group


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
    sub: Any,
    name: str,
    *,
    examples: Sequence[str],
    help: str | None = None,
    description: str | None = None,
) -> argparse.ArgumentParser:
    """A subcommand's parser, its ``--help`` ending with examples.

    Parameters
    ----------
    sub : argparse subparsers action
        Where the subcommand goes (``parser.add_subparsers()``).
    name : str
        The subcommand.
    help : str, optional
        One line for the program's list of commands (and the description); default the
        command's line in :data:`COMMANDS`.
    examples : sequence of str
        Command lines shown at the end of the subcommand's ``--help``, each
        a complete command (``dustoptics ...``).
    description : str, optional
        Shown under the usage; default ``help``, capitalized.

    Returns
    -------
    argparse.ArgumentParser
    """
    help = help if help is not None else COMMANDS[name][1]
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


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The command line's argument parser.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments it will parse: the module of the command they name (their first)
        is imported and adds the command; the other commands are there by name and help
        line only (their modules, and what those import, are not the command's: a warm
        ``build`` imported every command's, the sky's and the retrieval's included).  None:
        every command complete (the documentation's command reference).

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
    wanted = None if argv is None else COMMANDS.get(argv[0] if argv else "", ("", ""))[0]
    added: set[str] = set()
    for name, (module, line) in COMMANDS.items():
        if wanted is not None and module != wanted:
            sub.add_parser(name, help=line, add_help=False)
        elif module not in added:
            added.add(module)
            importlib.import_module(f"dustoptics.cli.{module}").add_parser(sub)
    return parser
