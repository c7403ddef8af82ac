"""The output formats on the command line: ``--format`` and the options of each format.

All generated from the format records (:data:`dustoptics.io.FORMATS`):
:func:`add_format_options` adds ``--format`` (:func:`parse_formats`), with one
line per format in ``--help`` (:func:`format_lines`), ``--force``,
``--allow-large``, ``--number-density-per-m3`` and each format's options, in
groups of the options the same formats take (:func:`dustoptics.io.registry.option_groups`).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from typing import Any

from dustoptics.cli.parser import _float_list, _positive_float, _positive_int, detail_group
from dustoptics.io import FORMATS
from dustoptics.io.registry import option_groups

__all__ = [
    "add_format_options",
    "format_lines",
    "format_option_names",
    "parse_formats",
    "unused_format_options",
]

#: The command line's parsers of the option types the format records name.
_TYPES: dict[str, Callable[[str], Any]] = {
    "floats": _float_list,
    "positive_float": _positive_float,
    "positive_int": _positive_int,
}


def format_lines(default: Sequence[str] = ()) -> str:
    """One line per format of :data:`dustoptics.io.FORMATS`, for ``--help``.

    Parameters
    ----------
    default : sequence of str, optional
        The formats written when ``--format`` is not given, marked ``(default)``.

    Returns
    -------
    str
        ``"NAME  summary"`` lines, names sorted.
    """
    width = max(map(len, FORMATS))
    lines = []
    for name in sorted(FORMATS):
        mark = " (default)" if name in default else ""
        lines.append(f"{name:<{width}}  {FORMATS[name].summary}{mark}")
    return "\n".join(lines)


def parse_formats(text: str) -> tuple[str, ...]:
    """``--format``: comma-separated names of :data:`dustoptics.io.FORMATS`, each once."""
    names = tuple(part.strip() for part in text.split(",") if part.strip())
    unknown = [n for n in names if n not in FORMATS]
    if not names or unknown:
        raise argparse.ArgumentTypeError(
            f"unknown format {', '.join(map(repr, unknown)) or repr(text)}; "
            f"choose from {', '.join(sorted(FORMATS))} (comma-separated)"
        )
    return tuple(dict.fromkeys(names))


def format_option_names(*, defaults: bool = True) -> list[str]:
    """The destinations of every format's command-line options (``channels_nm``, ...).

    Parameters
    ----------
    defaults : bool, optional
        Also the options with a default of their own (``scale_height_m``); False: only
        those that are None unless given.
    """
    return [
        f.name for _, fields in option_groups() for f in fields if defaults or f.default is None
    ]


def add_format_options(
    p: argparse.ArgumentParser, *, default: Sequence[str], required: bool
) -> None:
    """Add ``--format``, ``--force``, ``--allow-large``, ``--number-density-per-m3`` and every
    format's options to ``p``."""
    g = p.add_argument_group(
        "formats (--format FMT[,FMT...], from dustoptics.io.FORMATS)", format_lines(default)
    )
    help_default = f" (default {','.join(default)})" if default else ""
    g.add_argument(
        "--format",
        type=parse_formats,
        default=None,
        required=required,
        metavar="FMT[,FMT...]",
        help=f"output formats, comma-separated: one or more of the formats listed here{help_default}",
    )
    p.add_argument("--force", action="store_true", help="replace existing output files")
    p.add_argument(
        "--allow-large",
        action="store_true",
        help="go ahead beyond the memory (2 GiB) and work (about ten minutes) budget",
    )
    needing = sorted(n for n, fmt in FORMATS.items() if "number_density" in fmt.needs)
    g = p.add_argument_group(f"number density ({', '.join(needing)}: coefficients N C [m^-1])")
    g.add_argument(
        "--number-density-per-m3",
        type=_positive_float,
        metavar="N0",
        help="number density at the surface [m^-3] (overrides the configuration's; recorded "
        "in the table's provenance)",
    )
    for names, fields in option_groups():
        g = detail_group(p, ", ".join(names))
        for f in fields:
            keywords = dict(f.metadata["argparse"])
            if "type" in keywords:
                keywords["type"] = _TYPES[keywords["type"]]
            # None unless given (each format's dataclass default applies), so that an option
            # that no format asked for takes is refused (:func:`unused_format_options`).
            g.add_argument(
                "--" + f.name.replace("_", "-"),
                default=None,
                help=f.metadata["help"],
                **keywords,
            )


def unused_format_options(args: argparse.Namespace, formats: Sequence[str]) -> list[str]:
    """The format options given (``--scale-height-m``, ...) that none of ``formats`` takes.

    Returns
    -------
    list of str
        ``"--name (taken by fmt, ...)"`` for each, in the options' order.
    """
    out = []
    for names, fields in option_groups():
        if set(names) & set(formats):
            continue
        for f in fields:
            if getattr(args, f.name, None) is not None:
                out.append(f"--{f.name.replace('_', '-')} (taken by {', '.join(names)})")
    return out
