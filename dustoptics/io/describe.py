"""What a file dustoptics writes holds and how it was made, as text (``dustoptics info``).

- :func:`describe_table`: a table's grids, ranges, provenance and inputs;
- :func:`describe_path`: any file or folder dustoptics writes, each format
  read by its own describer (``_describe_*``, one per format).

Both say everything by default; ``full=False`` gives a summary of a dozen
lines per table (what it holds, what it was made from, its accuracy and input
hash), leaving out the software versions, the citations, the notes and the
inputs as JSON (``dustoptics info`` shows the summary, ``info --full`` all).

The text is safe to print: every line is passed through
:func:`dustoptics.io._text.printable`, so control characters and escape
sequences read from a file are shown escaped, never sent to the terminal.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from typing import TYPE_CHECKING, Any

from dustoptics._files import load_json
from dustoptics.atmosphere.build import SET_PROVENANCE_SUFFIX
from dustoptics.io._atomic import FormatError, whole_set
from dustoptics.io._text import printable
from dustoptics.io.csv.cosmoscout import check_cosmoscout_set, read_cosmoscout_constituent
from dustoptics.io.csv.seed import EXTINCTION_FILENAME, PHASE_FILENAME, SUMMARY_FILENAME
from dustoptics.io.describe_formats import _range, describer_of, inputs_lines, read_limit
from dustoptics.io.outputs import TABLE_SUFFIXES, read_table
from dustoptics.io.textures.raw import read_texture

if TYPE_CHECKING:
    from dustoptics.table import Table

__all__ = ["describe_path", "describe_table"]

#: A CosmoScout VR constituent's files: ``<name>_phase.csv``, ...
_COSMOSCOUT_FILE = re.compile(r"(?P<name>.+)_(phase|scattering|absorption|density)\.csv")

#: The ``format`` of a texture's JSON sidecar starts with this.
_TEXTURE_FORMAT = "dustoptics-phase-texture/"

#: The file of an atmosphere set's settings, beside CosmoScout VR's CSV files.
_SETTINGS_SUFFIX = "_settings.json"

#: What ``info`` reads, for the refusal of anything else.
_WHAT_INFO_READS = (
    "netCDF/HDF5 tables .nc/.h5/.hdf5, seed CSV, GLSL/HLSL/WGSL, texture .raw/.npy/.json, "
    ".exr, .ktx2, CosmoScout VR CSV, set settings or provenance, Bruneton .json/.h, DISORT .txt, "
    "libRadtran .dat, fit .json, the sky's .nc and .png"
)

#: The last line of a summary (``full=False``): what the full description adds, and how.
_MORE = "more:            "
_FULL = "(full=True; dustoptics info --full)"


def _printable_lines(text: str) -> str:

    return "\n".join(printable(line) for line in text.split("\n"))


def describe_table(table: Table, *, full: bool = True) -> str:
    """What a table holds and how it was made, as text.

    Parameters
    ----------
    table : Table
    full : bool, optional
        Everything (default), or a summary: the lines up to the error
        estimates, what the table was made from (material, sizes, phase
        model) on one line each, the sources' names, the input hash and
        what ``full=True`` adds.

    Returns
    -------
    str
        Lines ``key: value`` (name, grids, ranges of g, the cross-sections
        and the single-scattering albedo, number density, error estimates,
        the expansion coefficients' orders and the scattering matrix when the
        table holds them, with their error estimates, input hash, software, sources, notes), then the provenance inputs as
        indented JSON.  Control characters from the table's text are escaped.

    Examples
    --------
    >>> import dustoptics as do
    >>> t = do.compute_optics(1.5, do.Monodisperse(radius_um=0.5), [550.0], [0.0, 180.0])
    >>> print(describe_table(t, full=False))  # doctest: +ELLIPSIS
    name:            table
    wavelengths:     1, 550 .. 550 nm
    angles:          2, 0 .. 180 deg
    phase function:  [sr^-1], 2 pi int P dmu = 1
    g:               ...
    cext_um2:        ...
    ssa:             1 .. 1
    error estimate:  phase <= ... (relative)
                     cross-sections, g <= ...
    domain:          inside the validated domain (x 5.712 .. 5.712, n 1.5 .. 1.5, k 0 .. 0)
    material:        constant m = (1.5+0j)
    sizes:           monodisperse(radius_um=0.5)
    phase model:     mie, scattering-weighted
    sources:         constant m = (1.5+0j), monodisperse
    input hash:      ...
    more:            software, 2 citations and every input (full=True; dustoptics info --full)
    """
    prov = table.provenance
    wl, theta = table.wavelength_nm, table.theta_deg
    lines = [
        f"name:            {table.name}",
        f"wavelengths:     {wl.size}, {wl[0]:g} .. {wl[-1]:g} nm",
        f"angles:          {theta.size}, {theta[0]:g} .. {theta[-1]:g} deg",
        "phase function:  [sr^-1], 2 pi int P dmu = 1",
        f"g:               {table.g.min():.6g} .. {table.g.max():.6g}",
    ]
    cext = table.quantity("cext_um2")
    if cext is not None:  # table.has_cross_sections
        lines += [
            f"cext_um2:        {cext.min():.6g} .. {cext.max():.6g}",
            f"ssa:             {table.ssa.min():.6g} .. {table.ssa.max():.6g}",
        ]
    else:
        lines.append("cross-sections:  none (phase function only)")
    if table.cross_sections is not None and table.cross_sections.number_density_per_m3 is not None:
        lines.append(f"number density:  {table.cross_sections.number_density_per_m3:.6g} m^-3")
    if table.quadrature is not None:
        lines.append(
            f"error estimate:  phase <= {table.quadrature.error_estimate.max():.2e} (relative)"
        )
    if table.quadrature is not None and table.quadrature.cross_section_error_estimate is not None:
        lines.append(
            f"                 cross-sections, g <= {table.quadrature.cross_section_error_estimate.max():.2e}"
        )
    lines += _domain_lines(prov.quadrature)
    lines += _components(table)
    if not full:
        lines += _made_from(prov.to_dict()["inputs"])
        if prov.sources:
            names = [s.name if len(s.name) <= 30 else s.name[:27] + "..." for s in prov.sources]
            rest = f" and {len(names) - 4} more" if len(names) > 4 else ""
            lines.append(f"sources:         {', '.join(names[:4])}{rest}")
        lines.append(f"input hash:      {prov.input_hash}")
        more = ["software", f"{len(prov.sources)} citations"] if prov.sources else ["software"]
        more += [f"{len(prov.notes)} notes"] if prov.notes else []
        lines.append(f"{_MORE}{', '.join(more)} and every input {_FULL}")
        return _printable_lines("\n".join(lines))
    lines.append(f"input hash:      {prov.input_hash}")
    lines.append(
        "software:        " + ", ".join(f"{k} {v}" for k, v in sorted(prov.software.items()))
    )
    if prov.sources:
        lines.append("sources:")
        lines += [f"  - {s.name} ({s.role}): {s.citation}" for s in prov.sources]
    if prov.notes:
        lines.append("notes:")
        lines += [f"  - {n}" for n in prov.notes]
    lines += inputs_lines(prov.to_dict()["inputs"])
    # Names, citations and notes come from the file: escape what a terminal would obey.
    return _printable_lines("\n".join(lines))


def _domain_lines(quadrature: Any) -> list[str]:
    """Whether the spheres stayed inside the validated domain
    (:mod:`dustoptics.scattering.domain`), from the provenance's record."""
    record = quadrature.get("domain") if isinstance(quadrature, dict) else None
    if not isinstance(record, dict):
        if quadrature:
            return ["domain:          not recorded (computed before domain checks)"]
        return []
    try:
        x, n, k = (record[key] for key in ("size_parameter", "n", "k"))
        span = f"x {x[0]:.4g} .. {x[1]:.4g}, n {n[0]:.4g} .. {n[1]:.4g}, k {k[0]:.3g} .. {k[1]:.3g}"
    except (KeyError, TypeError, IndexError, ValueError):
        return [f"domain:          {record!r}"]
    if record.get("inside") is True:
        return [f"domain:          inside the validated domain ({span})"]
    return [
        f"domain:          OUTSIDE the validated domain ({span}; validated: "
        f"{record.get('validated', '?')}): accuracy not verified"
    ]


def _components(table: Table) -> list[str]:
    """The expansion coefficients and the scattering matrix, when the table holds them."""
    lines = []
    if table.expansion is not None:
        e = table.expansion
        error = e.expansion_error_estimate
        lines.append(
            f"expansion:       alpha1-4, beta1-2, orders l = 0 .. {e.n_order - 1}"
            + ("" if error is None else f", error <= {error.max():.2e} (of each / (2 l + 1))")
        )
    if table.matrix is not None:
        error = table.matrix.matrix_error_estimate
        lines.append(
            "matrix:          F12, F33, F34 beside F11"
            + ("" if error is None else f", error <= {error.max():.2e} (relative to F11)")
        )
    return lines


def _compact(value: Any) -> str:
    """A value of the inputs on one line: ``model(key=value, ...)``, long lists counted."""
    if isinstance(value, dict):
        params = value.get("parameters")
        if not isinstance(params, dict):
            params = {k: v for k, v in value.items() if k not in ("model", "citation", "derived")}
        inner = ", ".join(f"{k}={_compact(v)}" for k, v in params.items())
        if "model" not in value:
            return "{" + inner + "}"
        return f"{value['model']}({inner})" if inner else str(value["model"])
    if isinstance(value, list):
        if len(value) > 4 and not any(isinstance(v, (dict, list)) for v in value):
            return f"[{len(value)} values]"
        return "[" + ", ".join(_compact(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _made_from(inputs: dict[str, Any]) -> list[str]:
    """What a table was made from, one line each, for a summary."""
    lines = []
    material, index = inputs.get("material"), inputs.get("refractive_index")
    if isinstance(material, dict):
        lines.append(f"material:        {_compact(material)}")
    elif isinstance(index, dict) and "description" in index:
        lines.append(f"material:        {index['description']}")
    sizes = inputs.get("size_distribution")
    if isinstance(sizes, dict) and "model" in sizes:
        lines.append(f"sizes:           {_compact(sizes)}")
    phase, optics = inputs.get("phase"), inputs.get("optics")
    weighting = optics.get("weighting") if isinstance(optics, dict) else inputs.get("weighting")
    # compute_optics records no phase model: its tables are Mie's.
    model = [_compact(phase) if isinstance(phase, dict) else "mie"]
    model += [f"{weighting}-weighted"] if isinstance(weighting, str) else []
    lines.append(f"phase model:     {', '.join(model)}")
    return lines


def describe_path(
    path: str | os.PathLike[str], *, full: bool = True, max_bytes: int | None = None
) -> str:
    """What any file or folder dustoptics writes holds, as text.

    Parameters
    ----------
    path : path-like
        Any file that ``build``, ``export``, ``fit``, ``sky`` and ``sweep`` write:
        a table (``.nc``, ``.h5``, ``.hdf5``; the seed CSVs or their
        ``table_summary.json``), a shader (GLSL, HLSL, WGSL: the table's, a
        fit's, Bruneton's phase snippet), a texture (``.raw`` or ``.npy`` with
        its JSON sidecar, ``.exr``, ``.ktx2``), a DISORT or libRadtran file, a
        CosmoScout VR constituent file, Bruneton's JSON and C++ header, an
        atmosphere set's ``<name>_settings.json`` or ``<name>_provenance.json``,
        a fit's JSON, the sky's netCDF and images, a sweep's netCDF file
        (:mod:`dustoptics.io.describe_formats` for all but tables and sets).
        A folder: a sweep's Zarr store, or every output found in it
        (``build``'s ``DIR/NAME/``, a set from ``build mars``), one section each.
    full : bool, optional
        Everything (default), or a summary (:func:`describe_table`); the
        summary of a set or a texture leaves out their inputs as JSON.
    max_bytes : int, optional
        Most bytes read or decompressed from one file, as its header declares them (a sky,
        a sweep's coordinates, a texture's pixels); None:
        :data:`~dustoptics.io.describe_formats.MAX_READ_BYTES` (256 MiB). [bytes]

    Returns
    -------
    str
        The description; control characters read from the files are escaped.

    Raises
    ------
    FileNotFoundError
        No such file or folder.
    dustoptics.io.FormatError
        A damaged file, nothing dustoptics writes, or a set that a killed
        write left incomplete (:func:`dustoptics.io._atomic.whole_set`).
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such file or directory: {str(p)!r}")
    with read_limit(max_bytes), whole_set(p):  # a set a killed write left incomplete is refused
        if p.is_dir() and (describer := describer_of(p)) is not None:  # a sweep's store
            text = describer(p, full)
        elif p.is_dir():
            text = _describe_directory(p, full)
        else:
            text = _describe_file(p, full)
    return _printable_lines(text)


def _describe_file(p: Path, full: bool = True) -> str:
    """One file, by its name (and for JSON and netCDF its contents): the describer of its format."""
    name, suffix = p.name, p.suffix.lower()
    if not stat.S_ISREG(os.stat(p).st_mode):  # recognisers open files: a FIFO would block them
        raise FormatError(f"{str(p)!r}: not a regular file (a FIFO, device or socket); refused")
    describer = describer_of(p)
    if describer is not None:
        return describer(p, full)
    if suffix in TABLE_SUFFIXES or name in (SUMMARY_FILENAME, PHASE_FILENAME, EXTINCTION_FILENAME):
        return describe_table(read_table(p if suffix != ".csv" else p.parent), full=full)
    for ending in (SET_PROVENANCE_SUFFIX, _SETTINGS_SUFFIX):
        if name.endswith(ending):
            return _describe_set(p.parent, name[: -len(ending)], full)
    if suffix in (".json", ".raw", ".npy"):
        sidecar = p.with_suffix(".json")
        if sidecar.is_file() and _is_texture_sidecar(sidecar):
            return _describe_texture(sidecar, full)
    match = _COSMOSCOUT_FILE.fullmatch(name)
    if match:
        return _describe_constituent(p.parent, match["name"])
    raise FormatError(f"{str(p)!r}: not a file dustoptics writes ({_WHAT_INFO_READS})")


def _is_texture_sidecar(path: Path) -> bool:

    try:
        data = load_json(path)  # bounded in size and depth
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and str(data.get("format", "")).startswith(_TEXTURE_FORMAT)


def _describe_directory(root: Path, full: bool = True) -> str:
    """Every output found in ``root``, one section each."""
    sections: list[tuple[str, str]] = []
    files = sorted(q for q in root.iterdir() if q.is_file())
    set_names = [
        q.name[: -len(suffix)]
        for q in files
        for suffix in (SET_PROVENANCE_SUFFIX, _SETTINGS_SUFFIX)
        if q.name.endswith(suffix)
    ]
    in_sets: set[str] = set()
    for name in dict.fromkeys(set_names):
        sections.append((f"{name} (atmosphere set)", _describe_set(root, name, full)))
        in_sets.add(name)
    constituents = sorted({m["name"] for q in files if (m := _COSMOSCOUT_FILE.fullmatch(q.name))})
    for name in constituents:
        if not any(name.startswith(f"{s}_") for s in in_sets):
            sections.append((f"{name} (CosmoScout VR)", _describe_constituent(root, name)))
    for q in files:
        if q.suffix.lower() in TABLE_SUFFIXES and describer_of(q) is None:
            sections.append((q.name, describe_table(read_table(q), full=full)))
    if (root / SUMMARY_FILENAME).is_file():
        table = read_table(root)
        sections.append((f"{SUMMARY_FILENAME} (seed CSV)", describe_table(table, full=full)))
    for q in files:
        describer = describer_of(q)
        if describer is not None:
            sections.append((q.name, describer(q, full)))
        elif q.suffix.lower() == ".json" and _is_texture_sidecar(q):
            sections.append((q.name, _describe_texture(q, full)))
    if not sections:
        raise FormatError(f"{str(root)!r}: holds no file dustoptics writes")
    if len(sections) == 1:
        return sections[0][1]
    return "\n\n".join(f"== {title} ==\n{text}" for title, text in sections)


def _describe_constituent(root: Path, name: str) -> str:
    """A CosmoScout VR constituent: its four CSV files in ``root``."""

    c = read_cosmoscout_constituent(root, name)
    wl_nm = c.wavelength_m * 1e9
    lines = [
        f"constituent:     {c.name} (CosmoScout VR CSV set in {root})",
        f"wavelengths:     {wl_nm.size}, {_range(wl_nm, 'nm')}",
    ]
    if c.phase is not None and c.theta_deg is not None:
        lines.append(f"phase function:  {c.theta_deg.size} angles, {_range(c.phase, 'sr^-1')}")
    else:
        lines.append("phase function:  none (does not scatter)")
    if c.beta_sca_per_m is not None:
        lines.append(f"beta_sca:        {_range(c.beta_sca_per_m, 'm^-1')} (at density 1)")
    lines.append(f"beta_abs:        {_range(c.beta_abs_per_m, 'm^-1')} (at density 1)")
    lines.append(f"density:         {c.density.size} altitudes, {_range(c.density, '')}")
    return "\n".join(lines)


def _describe_set(root: Path, name: str, full: bool = True) -> str:
    """An atmosphere set: its settings, provenance record and constituents."""

    try:
        return _set_text(root, name, full)
    except FormatError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise FormatError(
            f"{root / name}: the set's settings or provenance record is damaged "
            f"({type(exc).__name__}: {exc})"
        ) from None


def _set_text(root: Path, name: str, full: bool) -> str:

    lines = [f"atmosphere set:  {name} (CosmoScout VR, in {root})"]
    settings = root / f"{name}{_SETTINGS_SUFFIX}"
    if settings.is_file():
        data = load_json(settings)
        lines.append(
            f"radii:           planet {data['minAltitude']:.6g} m, atmosphere top "
            f"{data['maxAltitude']:.6g} m; sun distance {data['sunDistance']:.6g} m"
        )
    record_path = root / f"{name}{SET_PROVENANCE_SUFFIX}"
    record = None
    if record_path.is_file():
        record = load_json(record_path)
        lines.append(f"input hash:      {record['input_hash']}")
    members = [c for c in check_cosmoscout_set(root) if c.startswith(f"{name}_")]
    for member in members:
        lines.append("")
        lines.append(_describe_constituent(root, member))
        role = member[len(name) + 1 :]
        if record is not None and role in record["constituents"]:
            entry = record["constituents"][role]
            lines.append(
                f"table:           {entry['table']}, input hash {entry['provenance']['input_hash']}"
            )
            if entry["number_density_per_m3"] is not None:
                lines.append(f"number density:  {entry['number_density_per_m3']:.6g} m^-3")
    if record is not None and not full:
        given = {k: v for k, v in record["inputs"].items() if k != "constituents"}
        lines += ["", f"made from:       {_compact(given)[1:-1]}", f"{_MORE}every input {_FULL}"]
    elif record is not None:
        lines += ["", *inputs_lines(record["inputs"])]
    return "\n".join(lines)


def _describe_texture(sidecar: Path, full: bool = True) -> str:
    """A texture, from its JSON sidecar (the raw file it names is read and checked too)."""

    t = read_texture(sidecar)
    meta = t.metadata
    lines = [
        f"texture:         {meta['file']} ({meta['dtype']}, "
        f"{meta.get('byte_order', 'little-endian')}), sidecar "
        f"{sidecar.name}",
        f"table:           {meta['table']}",
        f"shape:           {t.phase.shape[0]} wavelengths x {t.phase.shape[1]} angles",
        f"wavelengths:     {_range(t.wavelength_nm, 'nm')}",
        f"sampling:        {meta.get('sampling_description', meta.get('sampling_rule'))}",
        f"values:          {_range(t.phase, meta['unit'])}, {meta['normalization']}",
        "sphere integral of the samples: "
        + ", ".join(f"{v:.6g}" for v in meta["sphere_integral_of_samples"]),
        f"input hash:      {meta['input_hash']}",
        f"written by:      {meta['written_by']}",
    ]
    if not full:
        return "\n".join([*lines, f"{_MORE}every input {_FULL}"])
    return "\n".join([*lines, *inputs_lines(meta["provenance"]["inputs"])])
