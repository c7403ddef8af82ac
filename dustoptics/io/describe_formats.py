"""Describers of the files that are not tables: shaders, engine and radiative-transfer files,
textures in containers, fits, skies and images (``dustoptics info``, one concept: describing).

Each ``describe_*`` function reads one kind of file dustoptics writes and returns lines of text:
what it holds, units, how it was made (the input hash of the table it came from), and, for
shaders and textures, the sampling rule.  :mod:`dustoptics.io.describe` chooses the describer by
the file's name and contents (:func:`describer_of`: the format records' ``recognise``, then
:data:`KINDS`) and escapes what it prints.

Every read is bounded (:func:`dustoptics._files.read_checked`, :func:`~dustoptics._files.load_json`)
and a file that is not what its name says is refused with :class:`dustoptics.io.FormatError`.
"""

from __future__ import annotations

import contextvars
import json
import math
import os
import stat
import struct
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._files import load_json, read_checked
from dustoptics.io._atomic import FormatError
from dustoptics.io.registry import FORMATS, Describer

__all__ = [
    "KINDS",
    "MAX_READ_BYTES",
    "SHADER_LANGUAGES",
    "check_classic_netcdf",
    "check_hdf5_sizes",
    "check_zarr_store",
    "describe_bruneton",
    "describe_fit",
    "describe_image",
    "describe_rt_text",
    "describe_shader",
    "describe_sky",
    "describe_sweep",
    "describe_texture",
    "describer_of",
    "is_bruneton",
    "is_rt_text",
    "is_shader",
    "limit_of",
    "read_limit",
    "register_store_verifier",
    "regular_size",
]

#: Shading languages by file suffix.
SHADER_LANGUAGES = {".glsl": "GLSL", ".hlsl": "HLSL", ".wgsl": "WGSL"}

#: First line of the radiative-transfer text files, and what each is.
_RT_FIRST_LINES = {
    "# dustoptics DISORT moments file": "DISORT phase-function moments",
    "# dustoptics libRadtran aerosol optical properties": "libRadtran aerosol optical properties",
    "# dustoptics libRadtran aerosol species profile": "libRadtran aerosol species profile",
}

#: The ``model`` of every Bruneton JSON file.
_BRUNETON_MODEL = "E. Bruneton, precomputed_atmospheric_scattering (2017)"

#: The file that makes a folder a sweep's Zarr store (``dustoptics.sweep.store.IDENTITY``; this
#: layer does not import the sweep's).
_SWEEP_IDENTITY = "sweep-identity.json"
#: The folder of a store's chunk completion markers (``dustoptics.sweep.store.MARKERS``).
_SWEEP_MARKERS = "sweep-done"

#: The check of every chunk of a sweep store (:func:`dustoptics.sweep.store.verify_store`,
#: registered by that module: this layer does not import the sweep's).
_store_verifiers: list[Callable[[Path], int]] = []


def register_store_verifier(verify: Callable[[Path], int]) -> None:
    """Set the function that checks a sweep store's every chunk before ``info`` calls it
    complete (``verify(path) -> chunks checked``, raising :class:`FormatError`)."""
    _store_verifiers[:] = [verify]


#: The attributes of a sky file its summary shows.
_SKY_SUMMARY = (
    "sun_zenith_angle_degree",
    "sun_elevation_deg",
    "observer_altitude_m",
    "n_streams",
    "orders_of_scattering",
    "radiance_relative_error_max",
    "radiance_error_domain",
    "illuminant",
    "source",
)

#: Most bytes ``info`` reads or decompresses from one file, as its header declares them, by
#: default (``describe_path(max_bytes=...)``, ``dustoptics info --max-bytes``): 256 MiB, a
#: 1,024 x 1,024 sky at 32 wavelengths in float64, a sweep's coordinates and error estimates
#: of 3 x 10^7 values, 20 times the largest texture (16,384 x 48 RGBA float32).  What xarray
#: reads it may copy once or twice: ``info`` then peaks near 3 times the limit. [bytes]
MAX_READ_BYTES = 256 * 1024**2

#: Most chunks one array of a Zarr store may declare (xarray and Dask keep a tuple per chunk):
#: a sweep of 10^6 chunks is 10^6 tasks, beyond what a sweep computes. [-]
MAX_ZARR_CHUNKS = 10**6

#: Most bytes deflate can expand one stored byte to (its format's limit is about 1032:1).
_MAX_DEFLATE_RATIO = 1100

#: The limit the describers use when the caller gives none (set by :func:`read_limit`).
_read_limit: contextvars.ContextVar[int | None] = contextvars.ContextVar(
    "dustoptics_read_limit", default=None
)


@contextmanager
def read_limit(max_bytes: int | None) -> Iterator[int]:
    """Within the block, the describers read at most ``max_bytes`` bytes of a file (None:
    :data:`MAX_READ_BYTES`); yields the limit.

    Raises
    ------
    ValueError
        ``max_bytes`` is not an integer >= 1.
    """
    limit = limit_of(max_bytes)
    token = _read_limit.set(limit)
    try:
        yield limit
    finally:
        _read_limit.reset(token)


def limit_of(max_bytes: int | None) -> int:
    """``max_bytes`` checked (an integer >= 1), or the describers' limit when None."""
    if max_bytes is None:
        return _read_limit.get(None) or MAX_READ_BYTES
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, int) or max_bytes < 1:
        raise ValueError(f"max_bytes must be an integer >= 1 [bytes]; got {max_bytes!r}")
    return max_bytes


def _too_large(path: Path, what: str, declared: int, limit: int) -> FormatError:
    return FormatError(
        f"{str(path)!r}: {what} declares {declared} bytes, beyond the {limit}-byte limit of "
        "this reader; refused before reading (max_bytes=, or dustoptics info --max-bytes, "
        "raises it)"
    )


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _format_error(path: Path, what: str) -> Exception:
    return FormatError(f"{str(path)!r}: {what}")


def _text(path: Path) -> str:
    try:
        return read_checked(path).decode("utf-8")
    except UnicodeDecodeError:
        raise _format_error(path, "not UTF-8 text") from None


def _kv(key: Any, value: Any) -> str:
    """``key:`` padded to the column of the other describers, then the value."""
    return f"{str(key) + ':':<16} {value}"


def _range(values: Any, unit: str = "") -> str:
    values = np.asarray(values, dtype=float)
    return f"{np.nanmin(values):.6g} .. {np.nanmax(values):.6g} {unit}".rstrip()


def inputs_lines(inputs: Any) -> list[str]:
    """``inputs:`` and then ``inputs`` as JSON (sorted keys), indented."""
    return [
        "inputs:",
        *("  " + s for s in json.dumps(inputs, indent=2, sort_keys=True).splitlines()),
    ]


@contextmanager
def damaged(path: Path, what: str) -> Iterator[None]:
    """A KeyError, TypeError or ValueError while reading ``path`` becomes a FormatError
    that names ``what`` and the error."""
    try:
        yield
    except (KeyError, TypeError, ValueError) as exc:
        raise _format_error(path, f"{what} ({type(exc).__name__}: {exc})") from None


# --- Declared sizes, checked before reading ---------------------------------------------------

#: netCDF classic external types: size in bytes (NC_BYTE .. NC_DOUBLE).
_NC_TYPE_SIZES = {1: 1, 2: 1, 3: 2, 4: 4, 5: 4, 6: 8}
_NC_DIMENSION, _NC_VARIABLE, _NC_ATTRIBUTE = 10, 11, 12


def regular_size(path: Path, limit: int) -> int:
    """The size of ``path`` [bytes], refused (FileNotFoundError, FormatError) unless a regular
    file of at most ``limit`` bytes: never opened if a FIFO or a device."""
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise FileNotFoundError(f"{str(path)!r}: no such file") from None
    if not stat.S_ISREG(info.st_mode):
        raise _format_error(path, "not a regular file (a FIFO, device, socket or directory)")
    if info.st_size > limit:
        raise _format_error(
            path,
            f"{info.st_size} bytes, larger than the {limit}-byte limit of this reader; refused "
            "before reading (max_bytes=, or dustoptics info --max-bytes, raises it)",
        )
    return info.st_size


class _Header:
    """A netCDF classic header read field by field, every length checked against the file."""

    def __init__(self, path: Path, handle: Any, size: int, offset_bytes: int) -> None:
        self.path, self.handle, self.size, self.offset_bytes = path, handle, size, offset_bytes

    def take(self, n: int, what: str) -> bytes:
        if n < 0 or n > self.size - self.handle.tell():
            raise _format_error(
                self.path, f"its header declares {n} bytes for {what}, beyond the file's end"
            )
        return bytes(self.handle.read(n))

    def integer(self, what: str, n: int = 4) -> int:
        return int.from_bytes(self.take(n, what), "big", signed=n == 4)

    def name(self, what: str) -> str:
        n = self.integer(f"the length of a {what} name")
        raw = self.take(n + (-n % 4), f"a {what} name")[:n]
        return raw.decode("utf-8", "replace")

    def values(self, what: str) -> None:
        kind, count = self.integer(f"the type of {what}"), self.integer(f"the length of {what}")
        if kind not in _NC_TYPE_SIZES:
            raise _format_error(self.path, f"{what} has the unknown netCDF type {kind}")
        n = count * _NC_TYPE_SIZES[kind]
        self.take(n + (-n % 4), what)

    def variable(self, n_dims: int) -> tuple[str, list[int], int, int]:
        """A variable's name, dimension ids, type and offset (its attributes skipped)."""
        name = self.name("variable")
        rank = self.integer(f"the rank of variable {name!r}")
        ids = [self.integer(f"a dimension of variable {name!r}") for _ in range(max(rank, 0))]
        if rank < 0 or any(not 0 <= i < n_dims for i in ids):
            raise _format_error(self.path, f"variable {name!r} names an unknown dimension")
        self.attributes(f"variable {name!r}")
        kind = self.integer(f"the type of variable {name!r}")
        self.integer(f"the size of variable {name!r}")
        begin = self.integer(f"the offset of variable {name!r}", self.offset_bytes)
        if kind not in _NC_TYPE_SIZES:
            raise _format_error(self.path, f"variable {name!r} has the unknown netCDF type {kind}")
        return name, ids, kind, begin & ((1 << (8 * self.offset_bytes)) - 1)

    def attributes(self, owner: str) -> None:
        tag, count = self.integer("an attribute list"), self.integer("an attribute count")
        if tag not in (0, _NC_ATTRIBUTE):
            raise _format_error(self.path, f"not a netCDF classic header ({owner}'s attributes)")
        for _ in range(count):
            self.values(f"attribute {self.name('attribute')!r} of {owner}")


def check_classic_netcdf(path: Path, *, max_bytes: int | None = None) -> dict[str, int]:
    """The bytes each variable of a netCDF classic file (``CDF\\x01``, ``CDF\\x02``) declares,
    from its header, refused before anything is read if the file is not a regular file of at
    most ``max_bytes`` (None: the describers' limit, :data:`MAX_READ_BYTES`), or if a name,
    attribute or variable declares more bytes than the file holds (Unidata, "The NetCDF
    Classic Format Specification").

    Raises
    ------
    FileNotFoundError
        No such file.
    dustoptics.io.FormatError
        The refusal, naming the file, the variable or attribute and the size.
    """
    limit = limit_of(max_bytes)
    size = regular_size(path, limit)
    with open(path, "rb") as handle:
        magic = handle.read(4)
        if magic not in (b"CDF\x01", b"CDF\x02"):
            raise _format_error(path, "not a netCDF classic or 64-bit offset file")
        h = _Header(path, handle, size, 4 if magic == b"CDF\x01" else 8)
        numrecs = h.integer("the number of records", 4) & 0xFFFFFFFF
        tag, n_dims = h.integer("the dimension list"), h.integer("the dimension count")
        if tag not in (0, _NC_DIMENSION) or n_dims < 0:
            raise _format_error(path, "not a netCDF classic header (dimensions)")
        dims = []
        for _ in range(n_dims):
            h.name("dimension")
            dims.append(h.integer("a dimension length") & 0xFFFFFFFF)
        h.attributes("the file")
        tag, n_vars = h.integer("the variable list"), h.integer("the variable count")
        if tag not in (0, _NC_VARIABLE) or n_vars < 0:
            raise _format_error(path, "not a netCDF classic header (variables)")
        declared: dict[str, int] = {}
        for _ in range(n_vars):
            name, ids, kind, begin = h.variable(len(dims))
            shape = [numrecs if dims[i] == 0 else dims[i] for i in ids]
            nbytes = math.prod(shape) * _NC_TYPE_SIZES[kind]
            if nbytes > limit:
                raise _too_large(path, f"variable {name!r} (shape {tuple(shape)})", nbytes, limit)
            record = bool(ids) and dims[ids[0]] == 0
            if not record and begin + nbytes > size:
                raise _format_error(
                    path,
                    f"variable {name!r} (shape {tuple(shape)}) declares {nbytes} bytes at offset "
                    f"{begin}, beyond the file's {size} bytes (truncated or crafted); refused "
                    "before reading",
                )
            declared[name] = nbytes
    total = sum(declared.values())
    if total > size:
        raise _format_error(
            path,
            f"its variables declare {total} bytes, more than the file's {size} bytes "
            "(truncated or crafted); refused before reading",
        )
    return declared


def check_hdf5_sizes(
    path: Path, f: Any, *, max_bytes: int | None = None, read: Callable[[str], bool] | None = None
) -> dict[str, int]:
    """The bytes each dataset of an open HDF5 (netCDF-4) file ``f`` declares, refused before
    a value is read if one that is read whole (``read(name)``; None: all) declares more than
    ``max_bytes`` (None: :data:`MAX_READ_BYTES`), or if any declares more than its stored
    bytes can hold: all of them without compression, at most deflate's limit (about 1032:1)
    with it; so a compressed bomb is refused from its metadata.

    Raises
    ------
    dustoptics.io.FormatError
        The refusal, naming the file, the dataset and the size.
    """
    limit = limit_of(max_bytes)
    declared: dict[str, int] = {}

    def visit(name: str, obj: Any) -> None:
        if not hasattr(obj, "dtype") or not hasattr(obj, "shape") or obj.shape is None:
            return
        nbytes = math.prod(int(n) for n in obj.shape) * int(obj.dtype.itemsize)
        if nbytes > limit and (read is None or read(name)):
            raise _too_large(path, f"variable {name!r} (shape {tuple(obj.shape)})", nbytes, limit)
        stored = int(obj.id.get_storage_size())
        compressed = obj.compression is not None or bool(obj.id.get_create_plist().get_nfilters())
        capacity = _MAX_DEFLATE_RATIO * stored if compressed else stored
        if nbytes > capacity and (compressed or obj.chunks is not None):
            raise _format_error(
                path,
                f"variable {name!r} (shape {tuple(obj.shape)}) declares {nbytes} bytes but "
                f"stores {stored}, which cannot hold them (chunks missing, or a crafted "
                "file); refused before reading",
            )
        declared[name] = nbytes

    f.visititems(visit)
    return declared


def _zarr_metadata(path: Path) -> dict[str, Any]:
    """Every array's metadata in a Zarr (v2) store, from ``.zmetadata`` and each ``.zarray``
    (read within bounds), keyed by where it was read and the array's name."""
    metas: dict[str, Any] = {}
    consolidated = path / ".zmetadata"
    if consolidated.exists() or consolidated.is_symlink():
        data = load_json(consolidated)
        entries = data.get("metadata") if isinstance(data, dict) else None
        if not isinstance(entries, dict):
            raise _format_error(path, ".zmetadata holds no metadata object (damaged)")
        for key, meta in entries.items():
            if str(key).endswith("/.zarray"):
                metas[f".zmetadata: {str(key)[: -len('/.zarray')]}"] = meta
    for entry in sorted(path.iterdir()):
        zarray = entry / ".zarray"
        if entry.is_dir() and (zarray.exists() or zarray.is_symlink()):
            metas[f"{entry.name}/.zarray: {entry.name}"] = load_json(zarray)
    return metas


def check_zarr_store(path: Path, *, max_bytes: int | None = None) -> dict[str, int]:
    """The bytes each array of a Zarr (v2) store declares, from its ``.zmetadata`` and
    ``.zarray`` files (read within bounds), refused before a chunk is read if an array
    declares more than ``max_bytes`` (None: :data:`MAX_READ_BYTES`) in one chunk, more than
    :data:`MAX_ZARR_CHUNKS` chunks, or a shape, chunk shape or type that is not one.

    Raises
    ------
    dustoptics.io.FormatError
        The refusal, naming the store, the array and the size.
    """
    limit = limit_of(max_bytes)
    declared: dict[str, int] = {}
    for where, meta in _zarr_metadata(path).items():
        name = where.split(": ", 1)[1]
        try:
            shape = [int(n) for n in meta["shape"]]
            chunks = [int(n) for n in meta["chunks"]]
            itemsize = np.dtype(meta["dtype"]).itemsize if isinstance(meta["dtype"], str) else 8
        except (KeyError, TypeError, ValueError, OverflowError) as exc:
            raise _format_error(
                path, f"{where} is not Zarr array metadata ({type(exc).__name__}: {exc})"
            ) from None
        if len(chunks) != len(shape) or min(shape, default=0) < 0 or min(chunks, default=1) < 1:
            raise _format_error(
                path, f"{where}: shape {shape} and chunks {chunks} are not an array's (damaged)"
            )
        chunk_bytes = math.prod(chunks) * max(itemsize, 1)
        if chunk_bytes > limit:
            raise _too_large(path, f"{where}: a chunk (shape {tuple(chunks)})", chunk_bytes, limit)
        n_chunks = math.prod(-(-n // c) for n, c in zip(shape, chunks, strict=True))
        if n_chunks > MAX_ZARR_CHUNKS:
            raise _format_error(
                path,
                f"{where}: shape {tuple(shape)} in chunks {tuple(chunks)} declares {n_chunks} "
                f"chunks, more than the {MAX_ZARR_CHUNKS} a store of dustoptics holds; refused "
                "before reading",
            )
        declared[name] = math.prod(shape) * max(itemsize, 1)
    return declared


# --- What a file is ---------------------------------------------------------------------------


def describer_of(path: Path) -> Describer | None:
    """The describer of ``path``: the first format record (:data:`dustoptics.io.FORMATS`) or
    other kind of file (:data:`KINDS`) that recognises it; None when none does."""
    for fmt in FORMATS.values():
        if fmt.recognise is not None and fmt.describe is not None and fmt.recognise(path):
            return fmt.describe
    for recognise, describe in KINDS:
        if recognise(path):
            return describe
    return None


def is_shader(path: Path, extension: str) -> bool:
    """Whether ``path`` is named as a shader file of the language with file ``extension``."""
    return path.suffix.lower() == extension


def is_rt_text(path: Path) -> bool:
    """Whether ``path`` is a DISORT or libRadtran text file dustoptics wrote (its first line)."""
    return path.suffix.lower() in (".txt", ".dat") and _first_line(path) in _RT_FIRST_LINES


def is_bruneton(path: Path) -> bool:
    """Whether ``path`` is one of Bruneton's (2017) files: a C++ header or a JSON file."""
    suffix = path.suffix.lower()
    if suffix == ".h":
        return path.name.endswith("_bruneton_parameters.h")
    if suffix != ".json":
        return False
    data = _json_or_none(path)
    return isinstance(data, dict) and str(data.get("model", "")).startswith(_BRUNETON_MODEL)


def _is_fit(path: Path) -> bool:
    if path.suffix.lower() != ".json":
        return False
    data = _json_or_none(path)
    return isinstance(data, dict) and {"model", "formula", "rows"} <= data.keys()


def _is_sweep(path: Path) -> bool:
    if path.is_dir():
        return (path / _SWEEP_IDENTITY).is_file()
    return path.suffix.lower() == ".nc" and _is_sweep_file(path)


def _first_line(path: Path) -> str:
    try:
        with open(path, "rb") as f:
            head = f.read(200).split(b"\n", 1)[0].decode("utf-8", "replace")
    except OSError:
        return ""
    return head.split(",", 1)[0].strip()


def _json_or_none(path: Path) -> Any:
    try:
        return load_json(path)
    except (OSError, ValueError):
        return None


def _is_sweep_file(path: Path) -> bool:
    import h5py  # here: h5py adds ~0.06 s to `import dustoptics` (python -X importtime)

    try:
        with h5py.File(path, "r") as f:
            return "sweep" in f.attrs and str(_attr(f.attrs.get("title", ""))).startswith(
                "dustoptics sweep"
            )
    except (OSError, ValueError):
        return False


def _is_sky(path: Path) -> bool:
    # The sky writes netCDF-3 (classic or 64-bit offset); tables are netCDF-4 (HDF5).
    if path.suffix.lower() != ".nc":
        return False
    try:
        with open(path, "rb") as f:
            return f.read(4) in (b"CDF\x01", b"CDF\x02")
    except OSError:
        return False


# --- Shaders ----------------------------------------------------------------------------------


def describe_shader(path: Path, full: bool = True) -> str:
    """A GLSL, HLSL or WGSL file: its header comment and its constants' declarations.

    The table snippets (``build --format glsl,hlsl,wgsl``), the fits' shaders (``fit``) and
    Bruneton's phase snippet all open with comment lines that name what they hold, the language
    version they need, the table's input hash, the channels and the sampling rule.
    """
    language = SHADER_LANGUAGES[path.suffix.lower()]
    text = _text(path)
    header = []
    for line in text.splitlines():
        if not line.startswith("//"):
            break
        header.append(line[2:].strip())
    if not any(h.startswith("dustoptics") for h in header):
        raise _format_error(path, f"not a {language} snippet written by dustoptics")
    lines = [f"{language} snippet:    {path.name}"]
    lines += [f"  {h}" for h in header]
    declarations = []
    for line in text.splitlines():
        code = line.split("//", 1)[0].strip()
        if code.startswith(("const ", "static const ")):
            name = code.split("=", 1)[0].strip()
            declarations.append(f"  {name}" if "[" in name or "array<" in code else f"  {code}")
    if declarations:
        lines.append("constants:")
        lines += declarations
    return "\n".join(lines)


# --- Radiative-transfer text files ------------------------------------------------------------


def _shortened(line: str, limit: int = 300) -> str:
    """A long header line (a DISORT file's ``mu_phase:`` list) cut to its start and a count."""
    if len(line) <= limit:
        return line
    return f"{line[:limit].rsplit(' ', 1)[0]} ... ({len(line.split())} words)"


def describe_rt_text(path: Path, full: bool = True) -> str:
    """A DISORT moments file or a libRadtran aerosol file: its header and its rows.

    The layer list of libRadtran (``NAME_aerosol_explicit.dat``: altitude [km] and the layer's
    file) is told as layers; the optical-property files as rows of a wavelength [nm] each.
    """
    text = _text(path)
    what = _RT_FIRST_LINES.get(text.split("\n", 1)[0].split(",", 1)[0].strip())
    if what is None:
        raise _format_error(path, "not a DISORT or libRadtran file written by dustoptics")
    header = [line[1:].strip() for line in text.splitlines() if line.startswith("#")]
    rows = [line.split() for line in text.splitlines() if line.strip() and line[0] != "#"]
    lines = [f"{what}: {path.name}", *[f"  {_shortened(h)}" for h in header[1:]]]
    try:
        first = np.array([float(r[0]) for r in rows])
    except (ValueError, IndexError):
        raise _format_error(path, "a data row does not start with a number") from None
    if rows and what == "libRadtran aerosol species profile":
        lines.append(f"levels:          {len(rows)}, altitudes {_range(first, 'km')}")
    elif rows and all(len(r) == 2 for r in rows) and rows[0][1] == "NULL":
        files = [r[1] for r in rows[1:]]
        lines.append(
            f"layers:          {len(files)}, altitudes {_range(first, 'km')}: {', '.join(files)}"
        )
    elif rows:
        lines.append(f"wavelengths:     {len(rows)}, {_range(first, 'nm')}")
        lines.append(f"values per row:  {len(rows[0])}")
    return "\n".join(lines)


# --- Engines ----------------------------------------------------------------------------------


def describe_bruneton(path: Path, full: bool = True) -> str:
    """Bruneton's (2017) files: a table's ``NAME_bruneton_mie.json`` or a set's
    ``NAME_bruneton.json`` and ``NAME_bruneton_parameters.h``."""
    if path.suffix.lower() == ".h":
        json_path = path.with_name(path.name.replace("_parameters.h", ".json"))
        header = [line[2:].strip() for line in _text(path).splitlines() if line.startswith("//")][
            :6
        ]
        lines = [f"Bruneton C++ header: {path.name}", *[f"  {h}" for h in header]]
        if json_path.is_file():
            lines.append(f"the same numbers, with units and provenance: {json_path.name}")
        return "\n".join(lines)
    data = load_json(path)
    with damaged(path, "a damaged Bruneton file"):
        lines = _bruneton_lines(path, data, full)
    return "\n".join(lines)


def _bruneton_lines(path: Path, data: dict[str, Any], full: bool) -> list[str]:
    wl = np.asarray(data["wavelengths"], dtype=float)
    lines = [
        f"Bruneton (2017): {path.name}",
        f"model:           {data['model']}",
        f"wavelengths:     {wl.size}, {_range(wl, 'nm')}",
        f"mie_scattering:  {_range(data['mie_scattering'], 'm^-1')}",
        f"mie_extinction:  {_range(data['mie_extinction'], 'm^-1')}",
        f"mie g:           {float(data['mie_phase_function_g']):.6g} (Cornette-Shanks fallback)",
    ]
    if "name" in data:  # a whole atmosphere
        lines[0] = f"Bruneton (2017) atmosphere {data['name']!r}: {path.name}"
        lines += [
            f"radii:           bottom {float(data['bottom_radius']):.6g} m, "
            f"top {float(data['top_radius']):.6g} m",
            f"solar irradiance: {_range(data['solar_irradiance'], 'W m-2 nm-1')}",
            f"ground albedo:   {_range(data['ground_albedo'])}",
        ]
        pre = data.get("precomputation", {})
        sizes = pre.get("constants.h", {})
        if sizes:
            lines.append(
                "texture sizes:   "
                + ", ".join(f"{k} {v}" for k, v in sizes.items() if not k.startswith("_"))
            )
        for key, value in pre.items():
            if key != "constants.h" and not isinstance(value, (dict, list)):
                lines.append(_kv(key, value))
        for role, entry in data.get("provenance", {}).items():
            if isinstance(entry, dict) and "input_hash" in entry:
                lines.append(
                    _kv(role, f"table {entry.get('table')}, input hash {entry['input_hash']}")
                )
    else:
        lines.append(f"number density:  {float(data['number_density_per_m3']):.6g} m^-3")
        lines.append(f"input hash:      {data['input_hash']}")
    if full:
        lines.append("units:")
        lines += [f"  {k}: {v}" for k, v in data.get("units", {}).items()]
    return lines


# --- Textures in containers -------------------------------------------------------------------


def describe_texture(path: Path, meta: dict[str, Any], container: str, full: bool = True) -> str:
    """An OpenEXR or KTX2 phase texture, from the metadata inside it (key ``dustoptics``, read
    by the container's module)."""
    with damaged(path, "damaged texture metadata"):
        lines = _texture_lines(path, meta, container, full)
    return "\n".join(lines)


def _texture_lines(path: Path, meta: dict[str, Any], container: str, full: bool) -> list[str]:
    lines = [
        f"texture:         {path.name} ({container}, {meta['precision']}, layout {meta['layout']})",
        f"table:           {meta['table']}",
        f"size:            {meta['width']} x {meta['height']} texels",
        f"sampling:        {meta.get('sampling_rule')}",
        f"rows:            {meta.get('row_rule')}",
        f"values:          [{meta['unit']}], {meta['normalization']}",
        "sphere integral of the samples: "
        + ", ".join(f"{float(v):.6g}" for v in meta["sphere_integral_of_samples"]),
        f"rounding error:  <= {float(meta['max_relative_rounding_error']):.3g} (relative)",
        f"input hash:      {meta['input_hash']}",
    ]
    if full and isinstance(meta.get("provenance"), dict):
        lines += inputs_lines(meta["provenance"].get("inputs", {}))
    return lines


# --- Fits -------------------------------------------------------------------------------------


def describe_fit(path: Path, full: bool = True) -> str:
    """A fit's JSON (``dustoptics fit``): the model, its formula and citation, each row's
    parameters and errors."""
    data = load_json(path)
    with damaged(path, "a damaged fit file"):
        lines = [
            f"phase-function fit: {path.name}",
            f"model:           {data['model']}: {data['formula']}",
            f"citation:        {data['citation']}",
            f"normalization:   {data['normalization']}",
            f"loss:            {data['loss']}",
            f"continuous:      {data.get('continuous')} (parameters continuous in wavelength)",
            "rows:",
        ]
        for row in data["rows"]:
            params = ", ".join(f"{k} {float(v):.6g}" for k, v in row["parameters"].items())
            lines.append(
                f"  {row['label']}: {params}; relative error max "
                f"{float(row['max_relative_error']):.3g}, median "
                f"{float(row['median_relative_error']):.3g}"
            )
    return "\n".join(lines)


# --- Skies and images -------------------------------------------------------------------------


def describe_sky(path: Path, full: bool = True, *, max_bytes: int | None = None) -> str:
    """The sky's netCDF (``dustoptics sky``: ``NAME_sky.nc``, ``mars-comparison.nc``): its
    grids, what it holds with units, its accuracy and how it was made (the global attributes).

    A file larger than ``max_bytes`` (None: :data:`MAX_READ_BYTES`, or the limit of
    :func:`read_limit`), or whose header declares more than the file holds, is refused
    (:func:`check_classic_netcdf`) before a value is read.
    """
    import xarray as xr  # here: xarray adds ~0.7 s to `import dustoptics` (-X importtime)

    # Every variable's declared size against the file and the limit, from the header, before
    # xarray reads any of it (a header declaring 2**31 values is refused, not allocated).
    check_classic_netcdf(path, max_bytes=max_bytes)
    try:
        ds = xr.open_dataset(path, engine="scipy", decode_times=False, cache=False)
    except Exception as exc:  # the scipy reader raises TypeError/ValueError/OSError on damage
        raise _format_error(path, f"a damaged netCDF file ({type(exc).__name__}: {exc})") from None
    with ds:
        lines = [f"sky:             {path.name}: {ds.attrs.get('title', '(no title)')}"]
        for name in ds.dims:
            if name in ds.coords:
                unit = ds[name].attrs.get("units", "")
                lines.append(_kv(name, f"{ds.sizes[name]}, {_range(ds[name].values, unit)}"))
            else:
                lines.append(_kv(name, ds.sizes[name]))
        for name, var in ds.data_vars.items():
            unit = var.attrs.get("units", "")
            rng = _range(var.values, unit) if var.dtype.kind == "f" and var.size else ""
            lines.append(f"  {name} ({', '.join(map(str, var.dims))}): {rng}".rstrip(": "))
        attrs = {k: _attr(v) for k, v in ds.attrs.items() if k != "title"}
    shown = attrs if full else {k: v for k, v in attrs.items() if k in _SKY_SUMMARY}
    lines += [_kv(k, v) for k, v in shown.items()]
    if not full and len(shown) < len(attrs):
        lines.append(
            f"more:            {len(attrs) - len(shown)} attributes (full=True; dustoptics info --full)"
        )
    return "\n".join(lines)


def describe_sweep(path: Path, full: bool = True, *, max_bytes: int | None = None) -> str:
    """A sweep (``dustoptics sweep``): its Zarr store or netCDF file: the axes and their values,
    the variables, each point's accuracy, and for a store how many chunks are done.

    Reads the metadata and the small variables; a store whose chunks are all marked done is
    called complete only after :func:`dustoptics.sweep.verify_store` (registered by
    :mod:`dustoptics.sweep.store`) has checked every chunk against its digests.

    What it reads whole (the coordinates and the error estimates) may declare at most
    ``max_bytes`` (None: :data:`MAX_READ_BYTES`, or the limit of :func:`read_limit`), every
    chunk too; a compressed dataset that declares more than its stored bytes can hold is
    refused (:func:`check_zarr_store`, :func:`check_hdf5_sizes`) before a value is read.
    """
    import xarray as xr  # here: xarray adds ~0.7 s to `import dustoptics` (-X importtime)

    store = path.is_dir()
    _check_sweep_sizes(path, store, max_bytes)
    try:
        if store:
            ds = xr.open_zarr(path, consolidated=None, decode_times=False)
        else:
            ds = xr.open_dataset(path, decode_times=False, cache=False)
    except Exception as exc:  # the backends raise many kinds on damage
        raise _format_error(path, f"a damaged sweep ({type(exc).__name__}: {exc})") from None
    with ds:
        axes = [d for d in ds["phase"].dims if d not in ("wavelength_nm", "theta_deg")]
        lines = [_kv("sweep", f"{path.name}: {ds.attrs.get('title', '')}")]
        lines.append(_kv("points", f"{int(np.prod([ds.sizes[a] for a in axes]))}"))
        for name in (*axes, "wavelength_nm", "theta_deg"):
            values = ds[name].values
            shown = ", ".join(f"{v:g}" for v in values) if values.size <= 6 else _range(values)
            lines.append(_kv(name, f"{values.size}: {shown}"))
        lines.append(_kv("variables", ", ".join(sorted(map(str, ds.data_vars)))))
        if "error_estimate" in ds:
            err = ds["error_estimate"].values
            lines.append(_kv("error estimate", f"phase <= {np.nanmax(err):.2e} (relative)"))
        lines.append(_kv("method", ds.attrs.get("method", "")))
        lines.append(_kv("source", ds.attrs.get("source", "")))
        if store:
            n_chunks = int(np.prod([len(c) for c in (ds["phase"].chunks or ())]))
            done = len(list((path / _SWEEP_MARKERS).glob("*")))
            lines.append(
                _kv("chunks", f"{done} of {n_chunks} done ({_store_state(path, done, n_chunks)})")
            )
        if full:
            lines += [_kv(k, _attr(v)) for k, v in sorted(ds.attrs.items()) if k != "title"]
    return "\n".join(lines)


#: The variables of a sweep ``info`` does not read whole (it reads their metadata only).
_SWEEP_LAZY = frozenset({"phase", "cext_um2", "csca_um2", "g", "provenance", "n_nodes"})


def _check_sweep_sizes(path: Path, store: bool, max_bytes: int | None) -> None:
    """Refuse a sweep whose metadata declares more than :func:`describe_sweep` may read."""
    limit = limit_of(max_bytes)
    if store:
        declared = check_zarr_store(path, max_bytes=limit)
    else:
        import h5py  # here: h5py adds ~0.06 s to `import dustoptics` (python -X importtime)

        regular_size(path, max(limit, _MAX_DEFLATE_RATIO * limit))
        try:
            with h5py.File(path, "r") as f:
                declared = check_hdf5_sizes(
                    path, f, max_bytes=limit, read=lambda name: name not in _SWEEP_LAZY
                )
        except OSError as exc:
            raise _format_error(path, f"a damaged sweep ({exc})") from None
    read = {k: v for k, v in declared.items() if k not in _SWEEP_LAZY}
    total = sum(read.values())
    if total > limit:
        name = max(read, key=lambda k: read[k])
        raise _too_large(path, f"its coordinates and estimates (largest {name!r})", total, limit)


def _store_state(path: Path, done: int, n_chunks: int) -> str:
    """Whether a store is complete: every chunk marked done and, checked against its digests,
    whole (a damaged chunk is a :class:`FormatError`, not "complete")."""
    if done != n_chunks:
        return "incomplete: resume with the same command"
    if not _store_verifiers:
        return "every chunk marked done; dustoptics.sweep.verify_store(path) checks them"
    _store_verifiers[0](path)
    return "complete: every chunk checked against its digests"


def _attr(value: Any) -> Any:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        return value.reshape(()).item()
    if isinstance(value, np.generic):
        return value.item()
    return value


def describe_image(path: Path, full: bool = True) -> str:
    """A PNG image dustoptics wrote (a sky's fisheye, panorama, sunset or limb, a plot): its size,
    and the data file it shows where one lies beside it."""
    data = _png_header(path)
    width, height, depth, colour = data
    kinds = {2: "RGB", 6: "RGBA", 0: "grey", 4: "grey + alpha", 3: "palette"}
    lines = [
        f"image:           {path.name}, PNG {width} x {height}, {kinds.get(colour, colour)}, "
        f"{depth} bit"
    ]
    stem = path.stem
    for ending in ("_fisheye", "_panorama", "_limb"):
        if stem.endswith(ending):
            stem = stem[: -len(ending)]
    stem = stem.split("_sunset_")[0]
    sky = path.with_name(f"{stem}_sky.nc")
    if sky.is_file():
        lines.append(f"shows:           the sky in {sky.name} (dustoptics info {sky.name})")
    return "\n".join(lines)


def _png_header(path: Path) -> tuple[int, int, int, int]:
    with open(path, "rb") as f:
        head = f.read(33)
    if len(head) < 33 or head[:8] != _PNG_SIGNATURE or head[12:16] != b"IHDR":
        raise _format_error(path, "not a PNG image")
    width, height, depth, colour = struct.unpack(">IIBB", head[16:26])
    return width, height, depth, colour


#: The files ``info`` reads that no format writes, as ``(recognise, describe)``: a fit's JSON,
#: the sky's netCDF and images, a sweep's store or file.
KINDS: tuple[tuple[Callable[[Path], bool], Describer], ...] = (
    (lambda path: path.suffix.lower() == ".png", describe_image),
    (_is_fit, describe_fit),
    (_is_sky, describe_sky),
    (_is_sweep, describe_sweep),
)
