"""The ``dustoptics`` command line: thin, the library does the work.

Usage::

    dustoptics build [NAME_OR_CONFIG] [--out DIR] [--format FMT[,FMT...]] [--force] [--quiet]
    dustoptics build mars|earth [--out DIR] [--dust PRESET] [--optical-depth TAU] [--force]
    dustoptics export FILE --out DIR --format FMT[,FMT...] [--force]
    dustoptics info FILE_OR_FOLDER
    dustoptics plot FILE --kind {phase,polar,map,spectra} [--wavelengths-nm LIST] --out FIG.png|.svg
    dustoptics presets [--show NAME]
    dustoptics materials
    dustoptics sweep CONFIG --out STORE [--scheduler ADDRESS] [--workers N] [--quiet]
    dustoptics --version

``build`` computes a preset (``dustoptics presets``) or a TOML configuration
file (:mod:`dustoptics.models.config`; copy a preset with ``presets --show NAME``)
and writes it into ``DIR/NAME/`` in each format of :data:`dustoptics.io.FORMATS`
(``hdf5``, ``csv``, ``cosmoscout``, ``glsl``, ``hlsl``, ``wgsl``, ``texture``,
``ktx2``, ``exr``, ``npy``, ...); ``build mars`` and
``build earth`` write CosmoScout VR's whole atmosphere set (molecules,
aerosols, ozone, densities and the settings JSON).  ``export`` turns
an HDF5 table into other formats in ``DIR``; ``info`` says what a table file
holds and how it was made; ``plot`` draws it (needs the ``plot`` extra).
``sweep`` computes a configuration over the axes of its ``[sweep]`` table
into a resumable Zarr store (or a ``.nc`` file) on Dask (needs the ``sweep``
extra; :func:`dustoptics.sweep.sweep`).

Exit status: 0 on success, 1 on failure (an output exists without ``--force``,
a damaged input file, an input the physics rejects), 2 on a usage error
(unknown preset, format or option value).  Errors are printed as
``dustoptics: error: <message>`` on stderr, without a traceback.  A closed
output pipe (``dustoptics info f.h5 | head``) is not an error.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn, TextIO

import numpy as np

__all__ = [
    "Placement",
    "SkyJob",
    "TableBuilder",
    "build_atmosphere",
    "main",
    "place_outputs",
    "read_table",
]

PROG = "dustoptics"

#: Formats written by ``build`` when ``--format`` is not given.
DEFAULT_FORMATS = ("hdf5", "csv")

#: About how long the first build compiles the kernels: 12 s of CPU time measured
#: on a 2-core machine (``/usr/bin/time`` of a first ``dustoptics build`` with an
#: empty ``NUMBA_CACHE_DIR``, minus a warm build's), longer on a busy machine. [s]
COMPILE_ESTIMATE_S = "10-15"


class UsageError(ValueError):
    """A command-line usage error (exit status 2)."""


# ---------------------------------------------------------------------- library side


def read_table(path: str | os.PathLike[str]) -> Any:
    """Read a table from an HDF5 file (``.h5``/``.hdf5``/``.nc``), a seed-CSV
    directory or its ``table_summary.json``.

    Raises
    ------
    dustoptics.io.FormatError
        A damaged or unrecognized file.
    FileNotFoundError
        No such file.
    """
    from dustoptics.io import FormatError, read_hdf5, read_seed_csv
    from dustoptics.io.seed_csv import SUMMARY_FILENAME

    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such file or directory: {str(p)!r}")
    if p.is_dir() or p.name == SUMMARY_FILENAME:
        return read_seed_csv(p if p.is_dir() else p.parent)
    if p.suffix.lower() in (".h5", ".hdf5", ".nc"):
        return read_hdf5(p)
    raise FormatError(
        f"{str(p)!r}: not a table file; give an HDF5 file (.h5, .hdf5, .nc), a seed-CSV "
        f"directory or its {SUMMARY_FILENAME}"
    )


@dataclass(frozen=True)
class FormatOptions:
    """Options of the individual formats, as the command line gives them."""

    channels_nm: tuple[float, ...] | None = None
    colour: str | None = None
    resolution_deg: float | None = None
    sampling: str | None = None
    n_angles: int | None = None
    density: np.ndarray | None = None
    prefix: str | None = None
    glsl_version: str | None = None
    layout: str | None = None
    precision: str | None = None
    #: The density profile's parameters (cosmoscout), as recorded in provenance.
    profile: dict[str, Any] | None = None

    def recorded(self, name: str) -> dict[str, Any]:
        """The options given for format ``name`` that change the numbers it writes.

        :func:`write_formats` adds them to the table's provenance inputs (key
        ``"export"``), so that the input hash a file records changes with them.
        Writers' defaults are stated in the files themselves and not repeated.
        """
        if name == "cosmoscout":
            return dict(self.profile or {})
        return {
            key: list(value) if isinstance(value, tuple) else value
            for key, value in self.for_format(name).items()
            if value is not None
        }

    def for_format(self, name: str) -> dict[str, Any]:
        """Keyword options for the writer of format ``name``."""
        if name in ("glsl", "hlsl", "wgsl"):
            out: dict[str, Any] = {"channels_nm": self.channels_nm, "colour": self.colour}
            if self.resolution_deg is not None:
                out["resolution_deg"] = self.resolution_deg
            if self.prefix is not None:
                # Every identifier prefixed, the lookup too (MIE keeps the seed's names).
                out["prefix"] = self.prefix
                if self.prefix != "MIE":
                    out["function_name"] = f"{self.prefix}_MiePhaseFunction"
            if name == "glsl" and self.glsl_version is not None:
                out["version"] = self.glsl_version
            return out
        if name in ("ktx2", "exr", "npy"):
            out = {"channels_nm": self.channels_nm, "colour": self.colour}
            for key in ("layout", "sampling", "n_angles", "precision"):
                if getattr(self, key) is not None:
                    out[key] = getattr(self, key)
            return out
        if name == "texture":
            out = {}
            if self.sampling is not None:
                out["sampling"] = self.sampling
            if self.n_angles is not None:
                out["n_angles"] = self.n_angles
            return out
        if name == "cosmoscout":
            return {"density": self.density}
        return {}


class TableBuilder:
    """Builds the table of a configuration, reporting progress per wavelength.

    Parameters
    ----------
    config : dustoptics.models.config.BuildConfig
        A validated configuration.
    progress : TextIO or None
        Where to report progress (None: silent).
    """

    def __init__(
        self, config: Any, *, progress: TextIO | None = None, allow_large: bool = False
    ) -> None:
        self.config = config
        self.progress = progress
        self.allow_large = allow_large

    @classmethod
    def from_name(cls, name_or_config: str, *, progress: TextIO | None = None) -> TableBuilder:
        """A builder for a preset name or the path of a TOML configuration file."""
        from dustoptics.models import config, presets

        if (
            name_or_config.endswith(".toml")
            or os.sep in name_or_config
            or Path(name_or_config).is_file()
        ):
            return cls(config.load_config(name_or_config), progress=progress)
        try:
            return cls(presets.load_preset(name_or_config), progress=progress)
        except ValueError as exc:
            raise UsageError(str(exc)) from None

    @property
    def name(self) -> str:
        return self.config.name

    def build(self) -> Any:
        """Compute the table, reporting progress per wavelength."""
        from dustoptics import _numba_cache
        from dustoptics.models import config

        start = time.perf_counter()
        tty = self.progress is not None and self.progress.isatty()
        compiling = self.config.phase.uses_mie and not _numba_cache.kernels_compiled()
        if compiling and self.progress is not None:
            print(
                f"{PROG}: compiling the Mie kernels (once per install, about "
                f"{COMPILE_ESTIMATE_S} s; cached in {_numba_cache.cache_dir()}) ...",
                file=self.progress,
            )
            self.progress.flush()

        def report(done: int, total: int) -> None:
            if self.progress is None:
                return
            if tty or done in (0, total):
                end = "\n" if done == total else ("\r" if tty else "\n")
                elapsed = time.perf_counter() - start
                print(
                    f"{self.name}: {done}/{total} wavelengths, {elapsed:.1f} s",
                    end=end,
                    file=self.progress,
                )
                self.progress.flush()

        table = config.build_table(self.config, progress=report, allow_large=self.allow_large)
        if compiling:
            _numba_cache.mark_compiled()
            if self.progress is not None:
                print(
                    f"{PROG}: this first build took {time.perf_counter() - start:.1f} s; later "
                    "builds load the compiled kernels from the cache",
                    file=self.progress,
                )
        return table


#: Names ``build`` treats as whole CosmoScout VR atmosphere sets.
ATMOSPHERES = ("mars", "earth", "earth-kobe2026")


def build_atmosphere(
    name: str,
    *,
    dust: str = "blue-moons",
    optical_depth: float = 0.5,
    reference_wavelength_nm: float = 550.0,
    ozone_csv: str | os.PathLike[str] | None = None,
    wavelength_nm: tuple[float, ...] | None = None,
    progress: TextIO | None = None,
) -> Any:
    """The atmosphere set ``name`` ("mars", "earth" or "earth-kobe2026").

    ``wavelength_nm`` replaces CosmoScout VR's 15 wavelengths of "mars" and
    "earth" (Kobe's set has his three only).

    Mars: CO2 molecules (Costa et al. 2021 corrected to Martian conditions)
    and the dust of preset or configuration ``dust``, computed at CosmoScout
    VR's 15 wavelengths with angles every 0.1 deg (a superset of the files'
    1 deg), its number density set by the vertical ``optical_depth`` at
    ``reference_wavelength_nm`` (<C_ext> computed there exactly).
    Earth: standard air (Penndorf 1957, King factor), Kobe's aerosols and the
    shipped ozone spectrum (Serdyuchenko et al. 2014) in Bruneton's layer on
    CosmoScout VR's 15 wavelengths; ``ozone_csv``
    (:func:`dustoptics.atmosphere.gases.read_ozone_csv`) replaces the ozone
    spectrum.  "earth-kobe2026": Kobe 2026's air, aerosols and ozone on his
    three wavelengths.
    """
    from dataclasses import replace

    from dustoptics.atmosphere import gases
    from dustoptics.atmosphere import sets as atmosphere
    from dustoptics.table import Table

    grid_nm = atmosphere.COSMOSCOUT_WAVELENGTHS_NM if wavelength_nm is None else wavelength_nm
    if name == "earth-kobe2026":
        if wavelength_nm is not None:
            raise UsageError(
                "earth-kobe2026 has Kobe's three wavelengths only; drop --wavelengths-nm"
            )
        return atmosphere.earth_atmosphere_kobe2026()
    if name == "earth":
        ozone = "serdyuchenko2014" if ozone_csv is None else gases.read_ozone_csv(ozone_csv)
        return atmosphere.earth_atmosphere(wavelength_nm=grid_nm, ozone=ozone)
    builder = TableBuilder.from_name(dust, progress=progress)
    cfg = builder.config
    if not cfg.phase.uses_mie:
        raise UsageError(
            f"dust {dust!r} has no cross-sections (a phase-function-only model); choose a Mie preset"
        )
    grid = replace(
        cfg,
        optics=replace(cfg.optics, wavelengths_nm=tuple(float(w) for w in grid_nm), n_theta=1801),
    )
    dust_table: Table = TableBuilder(grid, progress=progress).build()
    reference = replace(
        cfg, optics=replace(cfg.optics, wavelengths_nm=(float(reference_wavelength_nm),), n_theta=2)
    )
    cext = TableBuilder(reference).build().cext_um2[0]
    return atmosphere.mars_atmosphere(
        dust_table=dust_table,
        optical_depth=optical_depth,
        reference_wavelength_nm=reference_wavelength_nm,
        reference_cext_um2=float(cext),
    )


def write_formats(
    table: Any,
    out_dir: Path,
    formats: Sequence[str],
    *,
    overwrite: bool,
    options: FormatOptions,
    root: Path | None = None,
) -> list[Path]:
    """Write ``table`` into ``out_dir`` in every format, as one set; returns the paths written.

    The options that change a format's numbers (:meth:`FormatOptions.recorded`)
    are added to the provenance inputs of the table that format's writer gets,
    under ``"export"``: the files record them, and their input hash changes
    with them.  Every path must stay inside ``root`` (default ``out_dir``);
    the set is written whole or not at all
    (:func:`dustoptics.io._atomic.file_set`).
    """
    from dustoptics.io import write
    from dustoptics.io._atomic import file_set

    written: list[Path] = []
    # One set: every format is prepared, then all are moved into place together.
    with file_set(root if root is not None else out_dir, overwrite=overwrite):
        for name in formats:
            recorded = options.recorded(name)
            table_for_format = (
                with_inputs(table, export={"format": name, **recorded}) if recorded else table
            )
            written.extend(
                write(
                    table_for_format,
                    out_dir,
                    format=name,
                    overwrite=overwrite,
                    **options.for_format(name),
                )
            )
    return written


def with_inputs(table: Any, *, note: str | None = None, **inputs: Any) -> Any:
    """``table`` with ``inputs`` added to its provenance inputs (hence a new input hash),
    and ``note`` added to its notes.  For the command line's own inputs."""
    from dataclasses import replace

    prov = table.provenance
    notes = prov.notes if note is None else (*prov.notes, note)
    return table.replace(provenance=replace(prov, inputs={**prov.inputs, **inputs}, notes=notes))


@dataclass(frozen=True)
class Placement:
    """What :func:`place_outputs` did: files written, and files left as they were."""

    written: tuple[Path, ...]
    unchanged: tuple[Path, ...]


def _same_table(existing: Path, staged: Path) -> bool:
    """Both HDF5 files hold the same table (:func:`dustoptics.compare.table_differences`)."""
    from dustoptics.compare import table_differences
    from dustoptics.io import FormatError, read_hdf5

    if existing.suffix.lower() not in (".h5", ".hdf5", ".nc"):
        return False
    try:
        return not table_differences(read_hdf5(existing), read_hdf5(staged))
    except (FormatError, OSError):
        return False


def place_outputs(
    render: Callable[[Path], Sequence[Path]], out_dir: Path, *, force: bool
) -> Placement:
    """Write the files ``render(directory)`` writes, into ``out_dir``, as ``build`` and ``export`` do.

    ``render`` writes into an empty temporary directory; each of its files is
    then compared with the file of the same name in ``out_dir``:

    - none there: the file is written;
    - the same bytes, or an HDF5 file that holds the same table (same inputs
      and grids, numbers equal to 1e-9 relative; only the recorded software
      versions differ): the existing file is left untouched ("up to date");
    - anything else: replaced with ``force``, otherwise :class:`FileExistsError`
      naming every such file, before anything is written.

    The new files appear together or not at all (:mod:`dustoptics.io._atomic`).
    Other files in ``out_dir`` are left alone.
    """
    from dustoptics.io._atomic import write_files

    with tempfile.TemporaryDirectory(prefix="dustoptics-") as tmp:
        staging = Path(tmp).resolve()
        contents: dict[Path, bytes] = {}
        unchanged: list[Path] = []
        conflicts: list[Path] = []
        for path in render(staging):
            target = out_dir / Path(path).resolve().relative_to(staging)
            data = Path(path).read_bytes()
            if target.is_file():
                if target.read_bytes() == data or _same_table(target, Path(path)):
                    unchanged.append(target)
                    continue
                conflicts.append(target)
            contents[target] = data
        if conflicts and not force:
            raise FileExistsError(
                "these files exist and differ from the new ones; use --force to replace them: "
                + ", ".join(repr(str(c)) for c in conflicts)
            )
        written = write_files(contents, overwrite=force) if contents else []
    return Placement(written=tuple(written), unchanged=tuple(unchanged))


def _report_placement(
    args: argparse.Namespace, name: str, out_dir: Path, placed: Placement
) -> None:
    if placed.written:
        _say(args, f"{name}: wrote {len(placed.written)} files to {out_dir}")
        for path in placed.written:
            _say(args, f"  {path}")
    if placed.unchanged:
        _say(
            args, f"{name}: {len(placed.unchanged)} files up to date in {out_dir} (left untouched)"
        )
        for path in placed.unchanged:
            _say(args, f"  {path}")


def describe(table: Any) -> str:
    """What a table holds and how it was made, as text for ``info``.

    Every line is passed through :func:`dustoptics.io._text.printable`:
    control characters and escape sequences read from a file are shown
    escaped, never sent to the terminal.
    """
    from dustoptics.io._text import printable

    prov = table.provenance
    wl, theta = table.wavelength_nm, table.theta_deg
    lines = [
        f"name:            {table.name}",
        f"wavelengths:     {wl.size}, {wl[0]:g} .. {wl[-1]:g} nm",
        f"angles:          {theta.size}, {theta[0]:g} .. {theta[-1]:g} deg",
        "phase function:  [sr^-1], 2 pi int P dmu = 1",
        f"g:               {table.g.min():.6g} .. {table.g.max():.6g}",
    ]
    if table.has_cross_sections:
        lines += [
            f"cext_um2:        {table.cext_um2.min():.6g} .. {table.cext_um2.max():.6g}",
            f"ssa:             {table.ssa.min():.6g} .. {table.ssa.max():.6g}",
        ]
    else:
        lines.append("cross-sections:  none (phase function only)")
    if table.number_density_per_m3 is not None:
        lines.append(f"number density:  {table.number_density_per_m3:.6g} m^-3")
    if table.error_estimate is not None:
        lines.append(f"error estimate:  phase <= {table.error_estimate.max():.2e} (relative)")
    if table.cross_section_error_estimate is not None:
        lines.append(
            f"                 cross-sections, g <= {table.cross_section_error_estimate.max():.2e}"
        )
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
    lines.append("inputs:")
    lines += [
        "  " + line
        for line in json.dumps(prov.to_dict()["inputs"], indent=2, sort_keys=True).splitlines()
    ]
    # Names, citations and notes come from the file: escape what a terminal would obey.
    return "\n".join(printable(line) for line in lines)


_COSMOSCOUT_FILE = re.compile(r"(?P<name>.+)_(phase|scattering|absorption|density)\.csv")
_TEXTURE_FORMAT = "dustoptics-phase-texture/"


def describe_path(path: str | os.PathLike[str]) -> str:
    """What any file or folder dustoptics writes holds, as text for ``info``.

    Files: HDF5 (``.h5``, ``.hdf5``, ``.nc``), the seed CSVs or their
    ``table_summary.json``, a GLSL snippet, a texture (its JSON sidecar or
    ``.raw`` file), a CosmoScout VR constituent file, an atmosphere set's
    ``<name>_settings.json`` or ``<name>_provenance.json``.  Folders: every
    output found in them (``build``'s ``DIR/NAME/``, a set from ``build mars``).

    Raises
    ------
    FileNotFoundError
        No such file or folder.
    dustoptics.io.FormatError
        A damaged file, or nothing dustoptics writes.
    """
    from dustoptics.io import FormatError
    from dustoptics.io.seed_csv import EXTINCTION_FILENAME, PHASE_FILENAME, SUMMARY_FILENAME

    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such file or directory: {str(p)!r}")
    if p.is_dir():
        return _describe_directory(p)
    name, suffix = p.name, p.suffix.lower()
    if suffix in (".h5", ".hdf5", ".nc") or name in (
        SUMMARY_FILENAME,
        PHASE_FILENAME,
        EXTINCTION_FILENAME,
    ):
        return describe(read_table(p if suffix != ".csv" else p.parent))
    for ending in (SET_PROVENANCE_SUFFIX, "_settings.json"):
        if name.endswith(ending):
            return _describe_set(p.parent, name[: -len(ending)])
    if suffix == ".glsl":
        return _describe_glsl(p)
    if suffix in (".json", ".raw"):
        sidecar = p.with_suffix(".json")
        if sidecar.is_file() and _is_texture_sidecar(sidecar):
            return _describe_texture(sidecar)
    match = _COSMOSCOUT_FILE.fullmatch(name)
    if match:
        return _describe_constituent(p.parent, match["name"])
    raise FormatError(
        f"{str(p)!r}: not a file dustoptics writes (HDF5 .h5/.hdf5/.nc, seed CSV, GLSL "
        "snippet, texture sidecar or .raw, CosmoScout VR CSV, set settings or provenance)"
    )


def _is_texture_sidecar(path: Path) -> bool:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and str(data.get("format", "")).startswith(_TEXTURE_FORMAT)


def _describe_directory(root: Path) -> str:
    """Every output found in ``root``, one section each."""
    from dustoptics.io import FormatError
    from dustoptics.io.seed_csv import SUMMARY_FILENAME

    sections: list[tuple[str, str]] = []
    files = sorted(q for q in root.iterdir() if q.is_file())
    set_names = [
        q.name[: -len(suffix)]
        for q in files
        for suffix in (SET_PROVENANCE_SUFFIX, "_settings.json")
        if q.name.endswith(suffix)
    ]
    in_sets: set[str] = set()
    for name in dict.fromkeys(set_names):
        sections.append((f"{name} (atmosphere set)", _describe_set(root, name)))
        in_sets.add(name)
    constituents = sorted({m["name"] for q in files if (m := _COSMOSCOUT_FILE.fullmatch(q.name))})
    for name in constituents:
        if not any(name.startswith(f"{s}_") for s in in_sets):
            sections.append((f"{name} (CosmoScout VR)", _describe_constituent(root, name)))
    for q in files:
        if q.suffix.lower() in (".h5", ".hdf5", ".nc"):
            sections.append((q.name, describe(read_table(q))))
    if (root / SUMMARY_FILENAME).is_file():
        sections.append((f"{SUMMARY_FILENAME} (seed CSV)", describe(read_table(root))))
    for q in files:
        if q.suffix.lower() == ".glsl":
            sections.append((q.name, _describe_glsl(q)))
        elif q.suffix.lower() == ".json" and _is_texture_sidecar(q):
            sections.append((q.name, _describe_texture(q)))
    if not sections:
        raise FormatError(f"{str(root)!r}: holds no file dustoptics writes")
    if len(sections) == 1:
        return sections[0][1]
    return "\n\n".join(f"== {title} ==\n{text}" for title, text in sections)


def _range(values: Any, unit: str) -> str:
    values = np.asarray(values, dtype=float)
    return f"{values.min():.6g} .. {values.max():.6g} {unit}".rstrip()


def _describe_constituent(root: Path, name: str) -> str:
    from dustoptics.io.cosmoscout import read_cosmoscout_constituent

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


def _describe_set(root: Path, name: str) -> str:
    from dustoptics.io.cosmoscout import check_cosmoscout_set

    lines = [f"atmosphere set:  {name} (CosmoScout VR, in {root})"]
    settings = root / f"{name}_settings.json"
    if settings.is_file():
        data = json.loads(settings.read_text(encoding="utf-8"))
        lines.append(
            f"radii:           planet {data['minAltitude']:.6g} m, atmosphere top "
            f"{data['maxAltitude']:.6g} m; sun distance {data['sunDistance']:.6g} m"
        )
    record_path = root / f"{name}{SET_PROVENANCE_SUFFIX}"
    record = None
    if record_path.is_file():
        record = json.loads(record_path.read_text(encoding="utf-8"))
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
    if record is not None:
        lines.append("")
        lines.append("inputs:")
        lines += [
            "  " + line
            for line in json.dumps(record["inputs"], indent=2, sort_keys=True).splitlines()
        ]
    return "\n".join(lines)


def _describe_glsl(path: Path) -> str:
    """The snippet's header: what the shader must assume, the table's input hash."""
    from dustoptics.io import FormatError

    text = path.read_text(encoding="utf-8")
    header = []
    for line in text.splitlines():
        if not line.startswith("//"):
            break
        header.append(line[2:].strip())
    if not header or not header[0].startswith("dustoptics"):
        raise FormatError(f"{str(path)!r}: not a GLSL snippet written by dustoptics")
    lines = [f"GLSL snippet:    {path.name}"]
    lines += [f"  {h}" for h in header]
    lines.append("constants:")
    for line in text.splitlines():
        if line.startswith("const "):
            declaration = line.split(" = vec")[0] if "[" in line.split("=")[0] else line
            lines.append(f"  {declaration}")
    return "\n".join(lines)


def _describe_texture(sidecar: Path) -> str:
    from dustoptics.io import read_texture

    t = read_texture(sidecar)
    meta = t.metadata
    lines = [
        f"texture:         {meta['file']} ({meta['dtype']}, {meta['byte_order']}), sidecar "
        f"{sidecar.name}",
        f"table:           {meta['table']}",
        f"shape:           {t.phase.shape[0]} wavelengths x {t.phase.shape[1]} angles",
        f"wavelengths:     {_range(t.wavelength_nm, 'nm')}",
        f"sampling:        {meta['sampling_description']}",
        f"values:          {_range(t.phase, meta['unit'])}, {meta['normalization']}",
        "sphere integral of the samples: "
        + ", ".join(f"{v:.6g}" for v in meta["sphere_integral_of_samples"]),
        f"input hash:      {meta['input_hash']}",
        f"written by:      {meta['written_by']}",
        "inputs:",
    ]
    lines += [
        "  " + line
        for line in json.dumps(meta["provenance"]["inputs"], indent=2, sort_keys=True).splitlines()
    ]
    return "\n".join(lines)


# ---------------------------------------------------------------------- argument parsing


def _formats(text: str) -> tuple[str, ...]:
    from dustoptics.io import FORMATS

    names = tuple(part.strip() for part in text.split(",") if part.strip())
    unknown = [n for n in names if n not in FORMATS]
    if not names or unknown:
        raise argparse.ArgumentTypeError(
            f"unknown format {', '.join(map(repr, unknown)) or repr(text)}; "
            f"choose from {', '.join(sorted(FORMATS))} (comma-separated)"
        )
    return tuple(dict.fromkeys(names))


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


def _add_format_options(p: argparse.ArgumentParser, *, default: str | None, required: bool) -> None:
    help_default = f" (default {default})" if default else ""
    p.add_argument(
        "--format",
        type=_formats,
        default=None,
        required=required,
        metavar="FMT[,FMT...]",
        help=f"output formats: netcdf (.nc), hdf5 (.h5, the same format), csv, cosmoscout, glsl, hlsl, wgsl, texture, disort, libradtran{help_default}",
    )
    p.add_argument("--force", action="store_true", help="replace existing output files")
    p.add_argument(
        "--allow-large",
        action="store_true",
        help="go ahead beyond the memory (2 GiB) and work (about ten minutes) budget",
    )
    g = p.add_argument_group("glsl, hlsl, wgsl")
    g.add_argument(
        "--channels-nm",
        type=_float_list,
        metavar="R,G,B",
        help="wavelengths of the three channels [nm] (default 680,550,440)",
    )
    g.add_argument(
        "--colour",
        choices=["cie1931-xyz", "linear-srgb-astmg173"],
        help="colour channels instead of three wavelengths: CIE 1931 XYZ bands, or linear sRGB of the "
        "table lit by the ASTM G173 sun (a renderer with a white sun reproduces the spectral colour)",
    )
    g.add_argument(
        "--resolution-deg",
        type=_positive_float,
        metavar="DEG",
        help="angular step of the constant array [deg] (default 0.25)",
    )
    g.add_argument(
        "--prefix",
        metavar="NAME",
        help="prefix of every identifier: NAME_PHASE, ..., NAME_MiePhaseFunction (default MIE, "
        "with the seed's MiePhaseFunction)",
    )
    g.add_argument(
        "--glsl-version",
        choices=["130", "100"],
        help="glsl: 130 = GLSL 1.30+ and ES 3.00+ (default); 100 = GLSL ES 1.00 (WebGL 1)",
    )
    g = p.add_argument_group("texture, ktx2, exr, npy (channels: --channels-nm, --colour)")
    g.add_argument(
        "--sampling",
        choices=["theta", "cos"],
        help="uniform in angle or in cos(angle) (default theta)",
    )
    g.add_argument(
        "--n-angles",
        type=_positive_int,
        metavar="N",
        help="samples along the angle axis (default 721)",
    )
    g.add_argument(
        "--layout",
        choices=["rgb", "wavelength"],
        help="ktx2, exr, npy: angle x RGB (default) or angle x wavelength",
    )
    g.add_argument(
        "--precision",
        choices=["float32", "float16"],
        help="ktx2, exr, npy: sample type (default float32)",
    )
    g = p.add_argument_group("cosmoscout (beta in m^-1 needs a number density)")
    g.add_argument(
        "--number-density-per-m3",
        type=_positive_float,
        metavar="N0",
        help="number density at the surface [m^-3] (overrides the configuration's; recorded "
        "in the table's provenance)",
    )
    g.add_argument(
        "--scale-height-m",
        type=_positive_float,
        default=10_000.0,
        metavar="H",
        help="exponential density profile's scale height [m] (default 10000, the seeds' Mars dust)",
    )
    g.add_argument(
        "--top-altitude-m",
        type=_positive_float,
        default=120_000.0,
        metavar="Z",
        help="atmosphere top above the surface [m] (default 120000, Mars 3510 - 3390 km)",
    )
    g.add_argument(
        "--n-altitudes",
        type=_positive_int,
        default=1024,
        metavar="N",
        help="density samples (default 1024)",
    )


_FIT_MODEL_HELP = (
    "henyey-greenstein (hg), dhg-costa2021 (dhg), dhg-kobe2026 (dhg-kobe), cornette-shanks1992 (cs), "
    "hg-draine-jendersie-deon2023 (hg-draine), two-term-hg-hapke2012 (tthg)"
)


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors on one line: ``dustoptics: error: <message>``."""

    def error(self, message: str) -> NoReturn:
        from dustoptics.io._text import printable

        self.exit(2, f"{PROG}: error: {printable(message)} (see '{self.prog} --help')\n")


def _parser() -> argparse.ArgumentParser:
    from dustoptics import __version__
    from dustoptics.models.presets import DEFAULT_PRESET

    parser = _Parser(
        prog=PROG,
        description="Exact, reproducible optics of atmospheric dust and lookup tables for renderers.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser("build", help="compute a preset or configuration file and write its tables")
    p.add_argument(
        "name",
        nargs="?",
        default=DEFAULT_PRESET,
        metavar="NAME_OR_CONFIG",
        help=f"preset name (see 'presets'), TOML configuration file, or an atmosphere set "
        f"({', '.join(ATMOSPHERES)}) (default {DEFAULT_PRESET})",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("tables"),
        metavar="DIR",
        help="output directory; files go to DIR/NAME/ (default ./tables); files that "
        "already hold the same table are left untouched",
    )
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")
    _add_format_options(p, default=",".join(DEFAULT_FORMATS), required=False)
    g = p.add_argument_group(
        "atmosphere sets ('build mars', 'build earth': CosmoScout VR's full set)"
    )
    g.add_argument(
        "--dust",
        default=None,
        metavar="PRESET_OR_CONFIG",
        help="Mars dust model (default blue-moons)",
    )
    g.add_argument(
        "--optical-depth",
        type=_positive_float,
        metavar="TAU",
        help="vertical optical depth: of the Mars dust (default 0.5; clear seasons 0.3-1), or, "
        "for one preset with --format cosmoscout, sets its number density (recorded in the provenance)",
    )
    g.add_argument(
        "--reference-wavelength-nm",
        type=_positive_float,
        default=550.0,
        metavar="NM",
        help="wavelength of that optical depth [nm] (default 550)",
    )
    g.add_argument(
        "--wavelengths-nm",
        type=_float_list,
        metavar="L1,L2,...",
        help="wavelengths of the mars and earth sets [nm] (default CosmoScout VR's 15, 360-830)",
    )
    g.add_argument(
        "--ozone-csv",
        type=Path,
        metavar="FILE",
        help="Earth: ozone cross-sections (see dustoptics.atmosphere.gases.read_ozone_csv) in Bruneton's layer",
    )

    p = sub.add_parser("export", help="convert a table file into other formats")
    p.add_argument(
        "file", type=Path, metavar="FILE", help="HDF5 file, seed-CSV directory or its summary"
    )
    p.add_argument(
        "--out",
        type=Path,
        required=True,
        metavar="DIR",
        help="output directory; files go to DIR/NAME/, NAME the table's name (as for build)",
    )
    p.add_argument("--quiet", action="store_true", help="no summary output")
    _add_format_options(p, default=None, required=True)

    p = sub.add_parser("info", help="what a table file holds and how it was made")
    p.add_argument(
        "file",
        type=Path,
        metavar="FILE",
        help="any file or folder dustoptics writes: HDF5, seed CSV, GLSL, texture (sidecar or "
        ".raw), CosmoScout VR CSV, an atmosphere set's folder or files",
    )

    p = sub.add_parser("plot", help="plot a table (needs the 'plot' extra: matplotlib)")
    p.add_argument("file", type=Path, metavar="FILE")
    p.add_argument(
        "--kind",
        choices=["phase", "polar", "map", "spectra"],
        default="phase",
        help="phase function (log scale), polar, wavelength x angle map, or spectra",
    )
    p.add_argument(
        "--wavelengths-nm",
        type=_float_list,
        metavar="LIST",
        help="wavelengths to draw for phase/polar [nm] (must be on the table's grid)",
    )
    p.add_argument(
        "--out", type=Path, required=True, metavar="FIG", help="output file, .png or .svg"
    )
    p.add_argument("--force", action="store_true", help="replace an existing figure")

    p = sub.add_parser("presets", help="list the presets, or print one's configuration file")
    p.add_argument("--show", metavar="NAME", help="print the TOML of preset NAME (copy it to edit)")

    sub.add_parser("materials", help="list the refractive-index catalogue")

    p = sub.add_parser("fit", help="fit an analytic phase function (HG, double HG, ...) to a table")
    p.add_argument("table", metavar="NAME_OR_FILE", help="a preset name or a table file")
    p.add_argument(
        "--model", default="dhg", help="model or alias (default dhg): " + _FIT_MODEL_HELP
    )
    p.add_argument(
        "--colour",
        choices=["wavelengths", "cie1931-xyz", "linear-srgb-astmg173"],
        help="fit three renderer channels instead of every wavelength",
    )
    p.add_argument(
        "--channels",
        type=_float_list,
        metavar="R,G,B",
        help="channel wavelengths with --colour wavelengths [nm] (default 680,550,440)",
    )
    p.add_argument(
        "--forward-cutoff",
        type=float,
        default=0.0,
        metavar="DEG",
        help="leave angles below DEG out of the loss (default 0)",
    )
    p.add_argument("--prefix", default="DUST", help="name prefix of the shader constants")
    p.add_argument("--out", type=Path, metavar="DIR", help="write JSON, GLSL, HLSL and WGSL there")
    p.add_argument("--force", action="store_true", help="replace existing files")

    p = sub.add_parser(
        "sweep",
        help="compute a configuration over its [sweep] axes on Dask (needs the 'sweep' extra)",
    )
    p.add_argument(
        "config",
        metavar="CONFIG",
        help="TOML configuration file with a [sweep] table, or a preset name",
    )
    p.add_argument(
        "--out",
        type=Path,
        required=True,
        metavar="STORE",
        help="Zarr store directory (resumed if it exists), or FILE.nc for netCDF",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="dask.distributed scheduler, tcp://HOST:PORT (default: a local cluster)",
    )
    p.add_argument(
        "--workers",
        type=_worker_count,
        metavar="N",
        help="worker processes of the local cluster (default: all cores)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress or summary output")
    _add_sky_parser(sub)
    return parser


def _add_sky_parser(sub: Any) -> None:
    p = sub.add_parser(
        "sky", help="render the sky an atmosphere makes: images, data and the thesis's comparisons"
    )
    skies = p.add_subparsers(dest="sky_command", metavar="{mars,earth,compare}", required=True)
    for planet in ("mars", "earth"):
        q = skies.add_parser(
            planet, help=f"spectral sky of {planet} over an observer near the ground"
        )
        if planet == "mars":
            q.add_argument(
                "--dust",
                default="hybrid",
                metavar="PRESET",
                help="dust model (a preset: collienne, costa, blue-moons, hybrid, ...; default hybrid)",
            )
            q.add_argument(
                "--optical-depth",
                type=_positive_float,
                default=0.5,
                metavar="TAU",
                help="vertical dust optical depth at 550 nm (default 0.5)",
            )
        q.add_argument(
            "--sun-elevation",
            type=float,
            default=10.0 if planet == "mars" else 45.0,
            metavar="DEG",
            help="Sun elevation [degree], -10 .. 90",
        )
        q.add_argument(
            "--albedo",
            type=float,
            default=0.2,
            metavar="A",
            help="Lambertian ground albedo (default 0.2)",
        )
        q.add_argument(
            "--size", type=_positive_int, default=512, metavar="PX", help="fisheye size [pixels]"
        )
        q.add_argument(
            "--exposure",
            type=_positive_float,
            metavar="E",
            help="display white at Y * E = 1 (default: the 99th percentile of the sky is white)",
        )
        q.add_argument(
            "--sunset",
            action="store_true",
            help="also a sunset sequence, Sun elevation 20 to -2 degree, at one exposure",
        )
        q.add_argument(
            "--space",
            action="store_true",
            help="also the limb seen from space, Sun in quadrature (NAME_limb.png, its own "
            "exposure unless --exposure)",
        )
        q.add_argument("--out", type=Path, required=True, metavar="DIR", help="output directory")
        q.add_argument("--force", action="store_true", help="replace existing files")
        q.add_argument("--quiet", action="store_true", help="no summary output")
    q = skies.add_parser("compare", help="the seed thesis's comparisons of the Mars dust models")
    q.add_argument(
        "--models",
        type=lambda t: tuple(x.strip() for x in t.split(",") if x.strip()),
        default=None,
        metavar="LIST",
        help="presets (default collienne,costa,blue-moons,hybrid)",
    )
    q.add_argument(
        "--optical-depth",
        type=_positive_float,
        default=0.5,
        metavar="TAU",
        help="vertical dust optical depth at 550 nm (default 0.5)",
    )
    q.add_argument(
        "--sun-elevation",
        type=float,
        default=10.0,
        metavar="DEG",
        help="Sun elevation of the radiance and luminance comparisons [degree]",
    )
    q.add_argument("--out", type=Path, required=True, metavar="DIR", help="output directory")
    q.add_argument("--force", action="store_true", help="replace existing files")
    q.add_argument("--quiet", action="store_true", help="no summary output")


#: Sun elevations of ``sky --sunset``. [degree]
_SUNSET_ELEVATIONS_DEG = (20.0, 10.0, 5.0, 2.0, 0.0, -2.0)


class SkyJob:
    """The ``sky`` command's work: atmosphere, sky, pictures and data, as files."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args

    @property
    def name(self) -> str:
        """File-name stem: the atmosphere's name, or ``mars-comparison``."""
        if self.args.sky_command == "compare":
            return "mars-comparison"
        return f"mars-{self.args.dust}" if self.args.sky_command == "mars" else "earth"

    def targets(self) -> list[Path]:
        """Every file the job writes (known before any work)."""
        out, stem = self.args.out, self.name
        if self.args.sky_command == "compare":
            kinds = ["radiance", "luminance", "chromaticity", "transmittance"]
            return [out / f"{stem}.nc"] + [out / f"{stem}_{k}.png" for k in kinds]
        names = [f"{stem}_sky.nc", f"{stem}_fisheye.png", f"{stem}_panorama.png"]
        if self.args.sunset:
            names += [f"{stem}_sunset_{e:+05.1f}.png" for e in _SUNSET_ELEVATIONS_DEG]
        if self.args.space:
            names.append(f"{stem}_limb.png")
        return [out / n for n in names]

    def atmosphere(self) -> Any:
        from dustoptics.atmosphere import sets
        from dustoptics.sky.compare import mars_sky_atmosphere

        if self.args.sky_command == "mars":
            return mars_sky_atmosphere(self.args.dust, optical_depth=self.args.optical_depth)
        return sets.earth_atmosphere()

    def files(self) -> dict[Path, bytes]:
        from dustoptics.sky import Medium
        from dustoptics.sky.scene import png_bytes, sky_radiance

        a = self.args
        if not (-10.0 <= a.sun_elevation <= 90.0):
            raise UsageError(
                f"--sun-elevation must be within [-10, 90] degree; got {a.sun_elevation!r}"
            )
        if not (0.0 <= a.albedo <= 1.0):
            raise UsageError(f"--albedo must be within [0, 1]; got {a.albedo!r}")
        atm = self.atmosphere()
        medium = Medium.from_atmosphere(atm)
        sky = sky_radiance(medium, sun_elevation_deg=a.sun_elevation, ground_albedo=a.albedo)
        exposure = a.exposure if a.exposure is not None else sky.default_exposure()
        stem = a.out / atm.name
        out = {
            stem.with_name(f"{atm.name}_sky.nc"): bytes(sky.to_xarray().to_netcdf(engine="scipy")),
            stem.with_name(f"{atm.name}_fisheye.png"): png_bytes(
                sky.fisheye(size=a.size, exposure=exposure)
            ),
            stem.with_name(f"{atm.name}_panorama.png"): png_bytes(sky.panorama(exposure=exposure)),
        }
        if a.sunset:
            for elev in _SUNSET_ELEVATIONS_DEG:
                s = sky_radiance(medium, sun_elevation_deg=elev, ground_albedo=a.albedo)
                out[stem.with_name(f"{atm.name}_sunset_{elev:+05.1f}.png")] = png_bytes(
                    s.panorama(exposure=exposure)
                )
        if a.space:
            from dustoptics.sky.space import limb_radiance

            limb = limb_radiance(medium, ground_albedo=a.albedo)
            out[stem.with_name(f"{atm.name}_limb.png")] = png_bytes(limb.image(exposure=a.exposure))
        return out

    def comparison_files(self) -> dict[Path, bytes]:
        import io as _io

        from dustoptics.sky.compare import MARS_MODELS, compare_mars_models, plot_comparison

        a = self.args
        ds = compare_mars_models(
            models=a.models or MARS_MODELS,
            optical_depth=a.optical_depth,
            sun_elevation_deg=a.sun_elevation,
        )
        out = {a.out / "mars-comparison.nc": bytes(ds.to_netcdf(engine="scipy"))}
        for name, fig in plot_comparison(ds).items():
            buf = _io.BytesIO()
            fig.savefig(buf, format="png", dpi=110, metadata={"Software": None})
            out[a.out / f"mars-comparison_{name}.png"] = buf.getvalue()
        return out


def _cmd_sky(args: argparse.Namespace) -> int:
    from dustoptics.io._atomic import check_targets, write_files

    job = SkyJob(args)
    check_targets(job.targets(), overwrite=args.force)  # before any work
    files = job.comparison_files() if args.sky_command == "compare" else job.files()
    assert sorted(files) == sorted(job.targets())
    for path in write_files(files, overwrite=args.force):
        _say(args, f"wrote {path}")
    return 0


# ---------------------------------------------------------------------- commands


def _say(args: argparse.Namespace, text: str) -> None:
    if not getattr(args, "quiet", False):
        print(text)


def _format_options(
    args: argparse.Namespace, table: Any, formats: Sequence[str]
) -> tuple[Any, FormatOptions]:
    """The table and the writers' options."""
    density = None
    profile_inputs = None
    if "cosmoscout" in formats:
        from dustoptics.atmosphere.column import ExponentialProfile, sample_profile

        tau = getattr(args, "optical_depth", None)
        if tau is not None and args.number_density_per_m3 is not None:
            raise UsageError("give --optical-depth or --number-density-per-m3, not both")
        profile = ExponentialProfile(scale_height_m=args.scale_height_m)
        if tau is not None:
            from dustoptics.atmosphere.sets import with_optical_depth

            table = with_optical_depth(
                table,
                optical_depth=tau,
                reference_wavelength_nm=args.reference_wavelength_nm,
                profile=profile,
                top_altitude_m=args.top_altitude_m,
            )
        if table.number_density_per_m3 is None:
            raise UsageError(
                "the cosmoscout format needs a number density for beta [m^-1]: give "
                "--optical-depth (with --reference-wavelength-nm), --number-density-per-m3 or "
                "number_density_per_m3 in the configuration"
            )
        samples = sample_profile(
            profile, top_altitude_m=args.top_altitude_m, n_altitudes=args.n_altitudes
        )
        density = samples.relative_density
        profile_inputs = {
            "density_profile": "exponential",
            "scale_height_m": args.scale_height_m,
            "top_altitude_m": args.top_altitude_m,
            "n_altitudes": args.n_altitudes,
        }
    options = FormatOptions(
        profile=profile_inputs,
        channels_nm=args.channels_nm,
        colour=args.colour,
        resolution_deg=args.resolution_deg,
        sampling=args.sampling,
        n_angles=args.n_angles,
        density=density,
        prefix=args.prefix,
        glsl_version=args.glsl_version,
        layout=args.layout,
        precision=args.precision,
    )
    return table, options


def _cmd_build_atmosphere(args: argparse.Namespace) -> int:
    from dustoptics.atmosphere import sets as atmosphere

    if args.format is not None and not set(args.format) <= {"cosmoscout", "bruneton"}:
        raise UsageError(
            f"'build {args.name}' writes CosmoScout VR's atmosphere set (format cosmoscout), and "
            f"with --format bruneton also Bruneton's model parameters; --format "
            f"{','.join(args.format)} is not available for a set. Build a table "
            "('dustoptics build PRESET --format ...') to get the other formats"
        )
    atm = build_atmosphere(
        args.name,
        dust="blue-moons" if args.dust is None else args.dust,
        optical_depth=0.5 if args.optical_depth is None else args.optical_depth,
        reference_wavelength_nm=args.reference_wavelength_nm,
        ozone_csv=args.ozone_csv,
        wavelength_nm=args.wavelengths_nm,
        progress=None if args.quiet else sys.stderr,
    )
    record = set_provenance(atm, set_inputs(args))
    out_dir = args.out / args.name

    def render(directory: Path) -> list[Path]:
        from dustoptics.io._atomic import write_files

        written = atmosphere.write_atmosphere(atm, directory)
        if args.format is not None and "bruneton" in args.format:
            from dustoptics.io.bruneton import write_bruneton

            written += write_bruneton(atm, directory)
        path = directory / f"{atm.name}{SET_PROVENANCE_SUFFIX}"
        return written + write_files({path: record.encode("utf-8")})

    placed = place_outputs(render, out_dir, force=args.force)
    _report_placement(args, f"{args.name} (CosmoScout VR set)", out_dir, placed)
    return 0


#: File of a set's provenance, beside CosmoScout VR's files: ``<name>_provenance.json``.
SET_PROVENANCE_SUFFIX = "_provenance.json"


def set_inputs(args: argparse.Namespace) -> dict[str, Any]:
    """The command-line inputs of ``build mars|earth`` that change the set's numbers."""
    import hashlib

    inputs: dict[str, Any] = {"set": args.name}
    if getattr(args, "wavelengths_nm", None) is not None:
        inputs["wavelengths_nm"] = list(args.wavelengths_nm)
    if args.name == "mars":
        inputs.update(
            dust="blue-moons" if args.dust is None else args.dust,
            optical_depth=0.5 if args.optical_depth is None else args.optical_depth,
            reference_wavelength_nm=args.reference_wavelength_nm,
        )
    elif args.ozone_csv is not None:
        data = Path(args.ozone_csv).read_bytes()
        inputs["ozone_csv"] = {
            "path": str(args.ozone_csv),
            "sha256": hashlib.sha256(data).hexdigest(),
        }
    return inputs


def set_provenance(atm: Any, inputs: dict[str, Any]) -> str:
    """JSON record of a set: the command's inputs, each constituent's table provenance
    and number density, and an input hash over the inputs and the constituents' hashes."""
    import hashlib

    from dustoptics.table import canonical_json

    constituents = {
        c.role: {
            "table": c.table.name,
            "number_density_per_m3": c.table.number_density_per_m3,
            "provenance": c.table.provenance.to_dict(),
        }
        for c in atm.constituents
    }
    hashed = {
        **inputs,
        "constituents": {role: c["provenance"]["input_hash"] for role, c in constituents.items()},
        "number_densities_per_m3": {
            role: c["number_density_per_m3"] for role, c in constituents.items()
        },
    }
    record = {
        "format": "dustoptics atmosphere set provenance",
        "set": atm.name,
        "inputs": hashed,
        "input_hash": hashlib.sha256(canonical_json(hashed).encode("utf-8")).hexdigest(),
        "constituents": constituents,
    }
    return json.dumps(record, indent=2, sort_keys=True, allow_nan=False) + "\n"


#: Options of ``build`` that only a table's formats use, and those only a set uses.
_TABLE_OPTIONS = (
    "channels_nm",
    "colour",
    "resolution_deg",
    "sampling",
    "n_angles",
    "number_density_per_m3",
    "prefix",
    "glsl_version",
    "layout",
    "precision",
)
_SET_OPTIONS = ("dust", "ozone_csv", "wavelengths_nm")


def _refuse_unused_options(args: argparse.Namespace) -> None:
    """An option given where it changes nothing is a usage error, never silently ignored."""

    def given(names: Sequence[str]) -> list[str]:
        return ["--" + n.replace("_", "-") for n in names if getattr(args, n, None) is not None]

    if args.name in ATMOSPHERES:
        unused = given(_TABLE_OPTIONS)
        unused += given(("dust", "optical_depth") if args.name == "earth" else ("ozone_csv",))
        where = f"'build {args.name}' (an atmosphere set)"
    else:
        unused = given(_SET_OPTIONS)
        if args.optical_depth is not None and "cosmoscout" not in (args.format or ()):
            unused.append("--optical-depth")
        where = f"'build {args.name}' with --format {','.join(args.format or DEFAULT_FORMATS)}"
    if unused:
        raise UsageError(f"{', '.join(unused)} changes nothing in {where}; remove it")


def _cmd_build(args: argparse.Namespace) -> int:
    _refuse_unused_options(args)
    if args.name in ATMOSPHERES:
        return _cmd_build_atmosphere(args)
    from dataclasses import replace

    from dustoptics.models.config import PresetCopyWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        builder = TableBuilder.from_name(args.name, progress=None if args.quiet else sys.stderr)
        if args.number_density_per_m3 is not None:
            # An input of the table: recorded in its provenance like the configuration's own.
            builder.config = replace(
                builder.config, number_density_per_m3=args.number_density_per_m3
            )
        builder.allow_large = args.allow_large
        _check_build_request(args, builder)
        table = builder.build()
    for w in caught:
        print(f"{PROG}: warning: {w.message}", file=sys.stderr)
        if issubclass(w.category, PresetCopyWarning):
            table = with_inputs(table, note=f"warning: {w.message}")
    return _write_table(args, table, args.format or DEFAULT_FORMATS)


def _check_build_request(args: argparse.Namespace, builder: TableBuilder) -> None:
    """What the formats need and where the files go, checked before the table is computed."""
    from dustoptics._validation import check_file_name, check_inside

    rt_formats = sorted({"disort", "libradtran"} & set(args.format or DEFAULT_FORMATS))
    if rt_formats:
        # Configurations compute no expansion coefficients: refuse before computing.
        raise UsageError(
            f"--format {','.join(rt_formats)} needs the phase function's Legendre moments, which "
            "a configuration does not compute: compute the table with "
            "compute_optics(..., expansion=True), save it (table.save) and run "
            f"'{PROG} export FILE --format {','.join(rt_formats)}'"
        )
    if "cosmoscout" in (args.format or DEFAULT_FORMATS):
        # What _format_options needs, checked before the table is computed.
        from dustoptics.atmosphere.column import ExponentialProfile, sample_profile

        if (
            getattr(args, "optical_depth", None) is None
            and args.number_density_per_m3 is None
            and builder.config.number_density_per_m3 is None
        ):
            raise UsageError(
                "the cosmoscout format needs a number density for beta [m^-1]: give "
                "--optical-depth (with --reference-wavelength-nm), --number-density-per-m3 or "
                "number_density_per_m3 in the configuration"
            )
        sample_profile(
            ExponentialProfile(scale_height_m=args.scale_height_m),
            top_altitude_m=args.top_altitude_m,
            n_altitudes=args.n_altitudes,
        )
    if {"glsl", "hlsl", "wgsl"} & set(args.format or DEFAULT_FORMATS):
        from dustoptics.io.shader import DEFAULT_RESOLUTION_DEG, check_shader_options

        check_shader_options(
            builder.config.wavelengths_nm,
            channels_nm=args.channels_nm,
            colour=args.colour,
            resolution_deg=args.resolution_deg or DEFAULT_RESOLUTION_DEG,
        )
    # Where the files go is checked before any work, too.
    check_inside(args.out, args.out / check_file_name("name", builder.name))


def _write_table(args: argparse.Namespace, table: Any, formats: Sequence[str]) -> int:
    """``build`` and ``export``: the table's files go into ``--out DIR`` / the table's name."""
    from dustoptics._validation import check_file_name, check_inside

    table, options = _format_options(args, table, formats)
    # The name may come from a file (export): it must not choose where files go.
    out_dir = args.out / check_file_name("name", table.name)
    check_inside(args.out, out_dir)
    placed = place_outputs(
        lambda directory: write_formats(
            table, directory, formats, overwrite=False, options=options
        ),
        out_dir,
        force=args.force,
    )
    _report_placement(args, table.name, out_dir, placed)
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    table = read_table(args.file)
    if args.number_density_per_m3 is not None:
        table = with_inputs(
            table.replace(number_density_per_m3=args.number_density_per_m3),
            number_density_per_m3=args.number_density_per_m3,
        )
    return _write_table(args, table, args.format)


def _cmd_info(args: argparse.Namespace) -> int:
    from dustoptics.io._text import printable

    # What a file says is shown, never obeyed: control characters and escape
    # sequences are printed escaped, line by line.
    print("\n".join(printable(line) for line in describe_path(args.file).split("\n")))
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    from dustoptics import plot

    table = read_table(args.file)
    if args.kind in ("phase", "polar"):
        figure = plot.phase_function(
            table, wavelengths_nm=args.wavelengths_nm, polar=args.kind == "polar"
        )
    elif args.kind == "map":
        figure = plot.phase_map(table)
    else:
        figure = plot.spectra(table)
    path = plot.save(figure, args.out, overwrite=args.force)
    print(f"wrote {path}")
    return 0


def _cmd_presets(args: argparse.Namespace) -> int:
    from dustoptics.models import presets

    if args.show is not None:
        try:
            text = presets.preset_text(args.show)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        sys.stdout.write(text)
        return 0
    for name in presets.list_presets():
        description = (presets.load_preset(name).description.splitlines() or [""])[0]
        marker = " (default)" if name == presets.DEFAULT_PRESET else ""
        print(f"{name:18s} {description}{marker}")
    return 0


def _cmd_materials(args: argparse.Namespace) -> int:
    from dustoptics.particles.materials import get_material, list_materials

    for name in list_materials():
        material = get_material(name)
        lo, hi = material.wavelength_range_nm
        print(f"{name:36s} {lo:8.1f} - {hi:8.1f} nm  {material.citation}")
    return 0


def _cmd_fit(args: argparse.Namespace) -> int:
    from dustoptics.io.fit import write_fit
    from dustoptics.scattering.fit import fit_table

    source = Path(args.table)
    if source.exists() and source.suffix.lower() != ".toml":
        table = read_table(source)
    else:
        table = TableBuilder.from_name(args.table).build()
    result = fit_table(
        table,
        model=args.model,
        colour=args.colour,
        channels_nm=args.channels,
        forward_cutoff_deg=args.forward_cutoff,
    )
    print(f"{table.name}: {result.model}, {result.formula}")
    print(f"  loss: {result.loss}")
    names = "  ".join(f"{n:>10s}" for n in result.parameter_names)
    print(f"  {'row':>10s}  {names}  {'max rel':>9s}  {'median':>9s}  {'g error':>9s}")
    for i, label in enumerate(result.labels):
        values = "  ".join(f"{v:10.6f}" for v in result.parameters[i])
        print(
            f"  {label:>10s}  {values}  {result.max_relative_error[i]:9.3g}  "
            f"{result.median_relative_error[i]:9.3g}  {result.g_error[i]:+9.2e}"
        )
    if args.out is not None:
        for path in write_fit(
            result, args.out, stem=table.name, prefix=args.prefix, overwrite=args.force
        ):
            print(f"wrote {path}")
    return 0


def _worker_count(text: str) -> int:
    """``--workers``: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer; got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1; got {text!r}")
    return value


def _cmd_sweep(args: argparse.Namespace) -> int:
    from dustoptics.sweep import sweep

    ds = sweep(
        args.config,
        out=args.out,
        client=args.scheduler,
        workers=args.workers,
        progress=None if args.quiet else sys.stderr,
    )
    _say(args, f"sweep: {dict(ds.sizes)} in {args.out}")
    return 0


_COMMANDS = {
    "fit": _cmd_fit,
    "build": _cmd_build,
    "export": _cmd_export,
    "info": _cmd_info,
    "plot": _cmd_plot,
    "presets": _cmd_presets,
    "materials": _cmd_materials,
    "sweep": _cmd_sweep,
    "sky": _cmd_sky,
}


def _silence_stdout() -> None:
    """After a broken pipe, send further output to devnull so exit is quiet."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def _one_line(exc: BaseException) -> str:
    """An error message on one line (h5py's span several), control characters escaped."""
    from dustoptics.io._text import printable

    return printable(" ".join(str(exc).split()))


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 1 failure, 2 usage).

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default ``sys.argv[1:]``).
    """
    from dustoptics.models.config import ConfigError

    try:
        try:
            args = _parser().parse_args(argv)
        except SystemExit as exc:  # argparse: --help/--version (0) or usage (2)
            return int(exc.code or 0)
        return _COMMANDS[args.command](args)
    except BrokenPipeError:
        _silence_stdout()
        return 0
    except (UsageError, ConfigError) as exc:
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except (OSError, ValueError, TypeError, ImportError) as exc:
        # FormatError is a ValueError; FileExistsError/PermissionError are OSErrors.
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
