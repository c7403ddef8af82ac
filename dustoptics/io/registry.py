"""The formats a table is written in: one record per format, gathered in one registry.

Modelled on xarray's backend entry points.  A format module defines one
:class:`Format` record (its fields say what a format gives) and registers it
(:func:`register`) when imported.

Everything else reads :data:`FORMATS`: the command line's ``--format`` list,
its option groups and needs check, ``info``, :class:`FormatOptions` and the
documentation's format table (:func:`format_table`).  Adding a format is one
module and one line that names it (:data:`dustoptics.io.FORMAT_MODULES`); the
first look at :data:`FORMATS` imports those modules (:func:`load_formats`).
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable, Iterable, Iterator, Mapping, MutableMapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "FORMATS",
    "NEEDS",
    "Format",
    "FormatOptions",
    "Need",
    "Writer",
    "cli_fields",
    "format_table",
    "formats_needing",
    "load_formats",
    "option",
    "option_groups",
    "register",
    "with_export",
    "write",
]

#: A writer of one table into a directory: ``(table, out_dir, *, overwrite, **keywords) -> paths``.
Writer = Callable[..., list[Path]]

#: A describer of one file for ``dustoptics info``: ``(path, full) -> text``.
Describer = Callable[[Path, bool], str]


@dataclass(frozen=True)
class Need:
    """Something a format needs from the table.

    Attributes
    ----------
    key : str
        The name formats give in ``needs``.
    what : str
        What it is, for messages (``"cross-sections"``).
    present : callable
        ``present(table) -> bool``: whether a table holds it.
    """

    key: str
    what: str
    present: Callable[[Any], bool]


#: What a format may need from the table, by key.
NEEDS: dict[str, Need] = {
    need.key: need
    for need in (
        Need("cross_sections", "cross-sections", lambda t: t.cross_sections is not None),
        Need(
            "number_density",
            "a number density",
            lambda t: (
                t.cross_sections is not None and t.cross_sections.number_density_per_m3 is not None
            ),
        ),
        Need(
            "expansion",
            "the phase function's expansion coefficients",
            lambda t: t.expansion is not None,
        ),
        Need(
            "matrix",
            "the scattering matrix's expansion coefficients",
            lambda t: t.expansion is not None,
        ),
    )
}


def option(*, help: str, default: Any = None, **argparse_keywords: Any) -> Any:
    """A field of a format's options dataclass that is a command-line option.

    Parameters
    ----------
    help : str
        The option's ``--help`` line.
    default : optional
        The field's default; None leaves the writer's.
    **argparse_keywords
        Given to :meth:`argparse.ArgumentParser.add_argument` (``type``,
        ``choices``, ``metavar``).

    Returns
    -------
    dataclasses.Field
    """
    return dataclasses.field(
        default=default, metadata={"help": help, "argparse": argparse_keywords}
    )


@dataclass(frozen=True)
class Format:
    """One output format: what it writes, its options, what it needs, how ``info`` reads it.

    Attributes
    ----------
    name : str
        ``--format NAME``.
    summary : str
        One line: the files and what they are for.
    write : callable
        ``write(table, out_dir, *, overwrite=False, **keywords) -> list[Path]``.
    suffixes : tuple of str
        Suffixes of the files it writes.
    options : type, optional
        A frozen dataclass of its options; None: no options.  Each field made with
        :func:`option` is a command-line option (``--NAME-WITH-DASHES``) and None
        means "the writer's default".  The dataclass may define ``keywords()`` (the
        writer's keywords; default: the fields given), ``recorded()`` (what the
        files record in their provenance; default: the keywords) and
        ``check(wavelength_nm)`` (refuse before the table is computed).
    needs : frozenset of str
        Keys of :data:`NEEDS`.
    recognise : callable, optional
        ``recognise(path) -> bool``: whether ``path`` is a file of this format.
    describe : callable, optional
        ``describe(path, full) -> str`` for ``dustoptics info``.
    plain_name : bool
        Its files are named by the table's name as it is (letters, digits,
        ``.``, ``_``, ``-``).
    inputs_file : callable, optional
        ``inputs_file(table_name) -> file name``: the file that records the
        table's inputs (compared before it is replaced).
    """

    name: str
    summary: str
    write: Writer
    suffixes: tuple[str, ...] = ()
    options: type | None = None
    needs: frozenset[str] = frozenset()
    recognise: Callable[[Path], bool] | None = None
    describe: Describer | None = None
    plain_name: bool = False
    inputs_file: Callable[[str], str] | None = None

    def __post_init__(self) -> None:
        unknown = sorted(set(self.needs) - NEEDS.keys())
        if unknown:
            raise ValueError(f"format {self.name!r}: needs {unknown} are not among {sorted(NEEDS)}")
        if self.options is not None and not dataclasses.is_dataclass(self.options):
            raise TypeError(f"format {self.name!r}: options must be a dataclass")
        if (self.recognise is None) != (self.describe is None):
            raise ValueError(f"format {self.name!r}: give both recognise and describe, or neither")

    def make_options(self, values: Mapping[str, Any]) -> Any:
        """Its options dataclass made of the ``values`` that are its fields; None if it has none."""
        if self.options is None:
            return None
        names = {f.name for f in dataclasses.fields(self.options)}
        return self.options(**{k: v for k, v in values.items() if k in names})

    def keywords(self, values: Mapping[str, Any]) -> dict[str, Any]:
        """The writer's keywords for the option ``values`` (the options' ``keywords()``, or
        the fields given)."""
        opts = self.make_options(values)
        if opts is None:
            return {}
        if hasattr(opts, "keywords"):
            return dict(opts.keywords())
        return {
            f.name: getattr(opts, f.name)
            for f in dataclasses.fields(opts)
            if getattr(opts, f.name) is not None
        }

    def recorded(self, values: Mapping[str, Any]) -> dict[str, Any]:
        """The options its files record in their provenance: the options' ``recorded()``, or
        the writer's keywords (JSON-serializable: tuples as lists, None left out)."""
        opts = self.make_options(values)
        if opts is None:
            return {}
        found = opts.recorded() if hasattr(opts, "recorded") else self.keywords(values)
        return {
            k: list(v) if isinstance(v, tuple) else v for k, v in found.items() if v is not None
        }


class _Formats(MutableMapping[str, Format]):
    """Format name -> record, the format modules imported on the first look
    (:func:`load_formats`); :func:`register` adds to it without looking."""

    def __init__(self) -> None:
        self.records: dict[str, Format] = {}
        self.loaded = False

    def __getitem__(self, name: str) -> Format:
        return load_formats()[name]

    def __setitem__(self, name: str, fmt: Format) -> None:
        self.records[name] = fmt

    def __delitem__(self, name: str) -> None:
        del self.records[name]

    def __iter__(self) -> Iterator[str]:
        return iter(load_formats())

    def __len__(self) -> int:
        return len(load_formats())

    def __contains__(self, name: object) -> bool:
        return name in load_formats()

    def __repr__(self) -> str:
        return repr(load_formats())


#: Format name -> record; filled by each format module when it is imported
#: (:data:`dustoptics.io.FORMAT_MODULES`, imported on the first look).
FORMATS = _Formats()


def load_formats() -> dict[str, Format]:
    """Every registered record by name, the format modules imported first (once).

    The modules of :data:`dustoptics.io.FORMAT_MODULES` register their records when
    imported; they are imported here, on the first look at :data:`FORMATS`, so that
    importing this module (or one format's) imports no other format's writer.
    """
    if not FORMATS.loaded:
        FORMATS.loaded = True
        for module in importlib.import_module("dustoptics.io").FORMAT_MODULES:
            importlib.import_module(module)
    return FORMATS.records


def register(fmt: Format) -> Format:
    """Add ``fmt`` to :data:`FORMATS` (names are unique) and return it."""
    known = FORMATS.records.get(fmt.name)
    if known is not None and known is not fmt:
        raise ValueError(f"format {fmt.name!r} is already registered")
    FORMATS[fmt.name] = fmt
    return fmt


def _check_names(formats: Iterable[str]) -> None:
    unknown = [name for name in formats if name not in FORMATS]
    if unknown:
        raise ValueError(
            f"format must be one of {', '.join(map(repr, sorted(FORMATS)))}; got {unknown[0]!r}"
        )


def write(
    table: Any, out_dir: Any, *, format: str, overwrite: bool = False, **keywords: Any
) -> list[Path]:
    """Write ``table`` into ``out_dir`` in the named format (see :data:`FORMATS`).

    The options given (``**keywords``) are recorded in the provenance of the table the writer
    gets (:func:`with_export`), as the command line records them: a file's ``input_hash`` is
    the same whether this function or ``dustoptics build``/``export`` wrote it.

    Raises
    ------
    ValueError
        Unknown format (the message lists the valid names).
    """
    _check_names([format])
    fmt = FORMATS[format]
    return fmt.write(with_export(table, fmt, keywords), out_dir, overwrite=overwrite, **keywords)


def with_export(table: Any, fmt: Format, keywords: Mapping[str, Any]) -> Any:
    """``table`` with the writer ``keywords`` given recorded under ``"export"`` in its
    provenance inputs, so that a file's ``input_hash`` means one thing whoever wrote it (the
    command line or :func:`write`): the SHA-256 of the inputs of its numbers, the table's and
    the export options given.  Formats whose options record something else (``recorded()``)
    are recorded by :func:`dustoptics.io.outputs.write_formats`."""
    given = {
        k: np.asarray(v).tolist() if isinstance(v, (tuple, list, np.ndarray)) else v
        for k, v in keywords.items()
        if v is not None
    }
    if not given or fmt.options is None or hasattr(fmt.options, "recorded"):
        return table
    prov = table.provenance
    inputs = {**prov.inputs, "export": {"format": fmt.name, **given}}
    return table.replace(provenance=dataclasses.replace(prov, inputs=inputs))


def formats_needing(need: str | tuple[str, ...], formats: Iterable[str]) -> list[str]:
    """The names among ``formats`` whose records need ``need`` (a key of :data:`NEEDS`, or any
    of several), sorted."""
    needs = {need} if isinstance(need, str) else set(need)
    return sorted(name for name in set(formats) if needs & FORMATS[name].needs)


def cli_fields(fmt: Format) -> tuple[dataclasses.Field[Any], ...]:
    """The fields of a format's options that are command-line options (made by :func:`option`)."""
    if fmt.options is None:
        return ()
    return tuple(f for f in dataclasses.fields(fmt.options) if "help" in f.metadata)


def option_groups() -> list[tuple[tuple[str, ...], list[dataclasses.Field[Any]]]]:
    """The command-line options of every format, grouped by the formats that take them.

    Returns
    -------
    list of (formats, fields)
        Each option once (the first format's field, in name order), in groups of the
        options that the same formats take; groups ordered by their first option.
    """
    takers: dict[str, list[str]] = {}
    first: dict[str, dataclasses.Field[Any]] = {}
    for name in sorted(FORMATS):
        for f in cli_fields(FORMATS[name]):
            takers.setdefault(f.name, []).append(name)
            first.setdefault(f.name, f)
    groups: dict[tuple[str, ...], list[dataclasses.Field[Any]]] = {}
    for field_name, names in takers.items():
        groups.setdefault(tuple(names), []).append(first[field_name])
    return list(groups.items())


class FormatOptions:
    """The format options given (the command line's), each format taking its own.

    Parameters
    ----------
    **values
        Fields of the registered formats' options dataclasses; None (or not
        given) leaves a writer's default.

    Raises
    ------
    TypeError
        A name that no format's options have (the message lists them).

    Examples
    --------
    >>> FormatOptions(n_angles=181).recorded("texture")
    {'n_angles': 181}
    """

    def __init__(self, **values: Any) -> None:
        known = {
            f.name
            for fmt in FORMATS.values()
            if fmt.options is not None
            for f in dataclasses.fields(fmt.options)
        }
        unknown = sorted(set(values) - known)
        if unknown:
            raise TypeError(f"no format has the options {unknown}; known: {sorted(known)}")
        self.values: dict[str, Any] = {k: v for k, v in values.items() if v is not None}

    def __repr__(self) -> str:
        return f"FormatOptions({', '.join(f'{k}={v!r}' for k, v in self.values.items())})"

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, FormatOptions)
            and self.values.keys() == other.values.keys()
            and all(_same(self.values[k], other.values[k]) for k in self.values)
        )

    __hash__ = None  # type: ignore[assignment]

    def replace(self, **values: Any) -> FormatOptions:
        """These options with ``values`` added or replaced."""
        return FormatOptions(**{**self.values, **values})

    def for_format(self, name: str) -> dict[str, Any]:
        """Keyword options for the writer of format ``name`` (empty for formats without options)."""
        _check_names([name])
        return FORMATS[name].keywords(self.values)

    def recorded(self, name: str) -> dict[str, Any]:
        """The options given for format ``name`` that its files record (key ``"export"`` of the
        table's provenance inputs, :func:`dustoptics.io.outputs.write_formats`), so that their
        input hash changes with them.  Writers' defaults are stated in the files themselves."""
        _check_names([name])
        return FORMATS[name].recorded(self.values)

    def check(self, formats: Sequence[str], *, wavelength_nm: Any) -> None:
        """Each format's own check of its options against a wavelength grid [nm], before the
        table is computed (the options' ``check``, where they define one)."""
        _check_names(formats)
        for name in formats:
            opts = FORMATS[name].make_options(self.values)
            if opts is not None and hasattr(opts, "check"):
                opts.check(wavelength_nm)


def _same(a: Any, b: Any) -> bool:
    try:
        return bool(a == b)
    except ValueError:  # arrays
        return a is b


def format_table() -> str:
    """The formats as a reStructuredText list table (the documentation's format table).

    Returns
    -------
    str
        One row per registered format: name, files, what it is, what it needs
        from the table, its command-line options.
    """
    lines = [
        ".. list-table::",
        "   :header-rows: 1",
        "",
        "   * - ``--format``",
        "     - files",
        "     - what",
        "     - needs",
        "     - options",
    ]
    for name in sorted(FORMATS):
        fmt = FORMATS[name]
        cells = [
            f"``{name}``",
            ", ".join(f"``{s}``" for s in fmt.suffixes) or "none",
            fmt.summary,
            ", ".join(NEEDS[n].what for n in sorted(fmt.needs)) or "none",
            ", ".join(f"``--{f.name.replace('_', '-')}``" for f in cli_fields(fmt)) or "none",
        ]
        lines.append(f"   * - {cells[0]}")
        lines += [f"     - {cell}" for cell in cells[1:]]
    return "\n".join(lines) + "\n"
