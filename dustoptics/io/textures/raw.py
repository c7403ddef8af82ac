"""Raw float32 2-D phase-function texture with a JSON sidecar.

For engines that upload the phase function as a texture rather than compile
it into a shader: :func:`write_texture` writes two files,

``<stem>.raw``
    The phase function [sr^-1] as little-endian IEEE-754 float32, no header,
    C order of an array of shape ``(n_wavelength, n_angles)``: one row per
    wavelength (in the table's increasing order), the angle index fastest.
    Uploaded as it is, it is a GL texture of width ``n_angles`` and height
    ``n_wavelength`` (``GL_R32F``, format ``GL_RED``, type ``GL_FLOAT``,
    unpack alignment 4).  Texel ``(j, i)`` is angle sample ``j`` at
    wavelength ``i``; with texel centres at ``(j + 0.5) / n_angles``.
``<stem>.json``
    The sidecar: shape, dtype ``"<f4"``, byte order, memory order, the axes
    with their coordinate values and units, the sampling, the normalization,
    the table's name, input hash and provenance, and the SHA-256 of the raw
    file, which :func:`read_texture` checks.

Two samplings of the angle axis:

``"theta"``
    Uniform in scattering angle: ``theta_j = 180 j / (n_angles - 1)`` deg,
    ``j = 0 .. n_angles - 1``, both ends included (0 = forward).  Values are
    ``table.phase_at(theta_j)``, the table read by linear interpolation in
    angle (at the table's own angles, its stored values).
``"cos"``
    Uniform in ``mu = cos(theta)`` from ``mu_0 = 1`` (forward) to
    ``mu_{N-1} = -1`` (backward), both ends included: ``mu_j = 1 - 2 j /
    (n_angles - 1)`` as computed by :func:`numpy.linspace`, for engines that
    index by ``nu = cos(theta)``.  Values are
    ``table.phase_at(degrees(arccos(mu_j)))``.

Both files go through the package's one atomic-write mechanism
(:func:`dustoptics.io._atomic.write_files`): an existing output is not
replaced unless ``overwrite=True``, and a failed call leaves nothing partial.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics._validation import MAX_GRID_POINTS, check_choice
from dustoptics.io._atomic import FormatError, safe_stem, write_files
from dustoptics.io._text import load_json, read_checked
from dustoptics.io.registry import Format, option, register
from dustoptics.scattering.tabulated_phase import sphere_integral
from dustoptics.table import PHASE_NORMALIZATION

__all__ = [
    "DEFAULT_N_ANGLES",
    "NORMALIZATION_TOLERANCE",
    "PHASE_TEXTURE_FORMAT",
    "SAMPLINGS",
    "TEXTURE_FORMAT",
    "TextureData",
    "TextureNormalizationWarning",
    "read_texture",
    "texture_values",
    "write_texture",
]

#: Format name and version in the metadata of the engines' textures
#: (:mod:`dustoptics.io.textures.phase_texture`; their ``.npy`` sidecars are read here too).
PHASE_TEXTURE_FORMAT = "dustoptics-phase-texture/2"

#: Format name and version written in every sidecar and required by the reader.
TEXTURE_FORMAT = "dustoptics-phase-texture/1"

#: Angle samplings :func:`write_texture` knows.
SAMPLINGS = ("theta", "cos")

#: Default number of angle samples: the seed shader's 0.25 deg over 0..180 deg.
DEFAULT_N_ANGLES = 721


@dataclass(frozen=True)
class TextureData:
    """A texture read back by :func:`read_texture`.

    Attributes
    ----------
    phase : numpy.ndarray of float32, shape (n_wavelength, n_angles)
        The texture, read-only. [sr^-1]
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Row coordinates. [nm]
    theta_deg : numpy.ndarray, shape (n_angles,)
        Column coordinates as angles (for ``"cos"``: ``degrees(arccos(mu))``). [deg]
    mu : numpy.ndarray or None, shape (n_angles,)
        Column coordinates as cosines for the ``"cos"`` sampling, else None. [-]
    sampling : str
        ``"theta"`` or ``"cos"``.
    metadata : dict
        The whole sidecar.
    """

    phase: np.ndarray
    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    mu: np.ndarray | None
    sampling: str
    metadata: dict[str, Any]


def _check_n_angles(n_angles: Any) -> int:
    if isinstance(n_angles, bool) or not isinstance(n_angles, (int, np.integer)) or n_angles < 2:
        raise ValueError(
            f"n_angles must be an integer >= 2 (both ends are sampled); got {n_angles!r}"
        )
    if n_angles > MAX_GRID_POINTS:
        raise ValueError(
            f"n_angles must be <= {MAX_GRID_POINTS} (samples of one texture row); got {n_angles!r}"
        )
    return int(n_angles)


def _sampling_grid(sampling: str, n_angles: int) -> tuple[np.ndarray, np.ndarray | None]:
    """Angles [deg] of the samples, and their cosines for the ``"cos"`` sampling."""
    if sampling == "theta":
        return np.linspace(0.0, 180.0, n_angles), None
    mu = np.linspace(1.0, -1.0, n_angles)
    # degrees(arccos(-1)) is exactly 180 in IEEE arithmetic; the clip only guards
    # a libm that rounds it up, which phase_at would reject.
    theta = np.minimum(np.degrees(np.arccos(mu)), 180.0)
    return theta, mu


def texture_values(
    table: Any, *, sampling: str = "theta", n_angles: int = DEFAULT_N_ANGLES
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The texture :func:`write_texture` writes, in memory.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    sampling : {"theta", "cos"}
        Uniform in angle or in its cosine (see the module docstring).
    n_angles : int
        Number of angle samples, both ends included (>= 2).

    Returns
    -------
    phase : numpy.ndarray of float32, shape (n_wavelength, n_angles)
        The phase function at the samples, rounded to float32. [sr^-1]
    theta_deg : numpy.ndarray, shape (n_angles,)
        The sample angles. [deg]
    mu : numpy.ndarray or None
        The sample cosines (``"cos"`` sampling), else None. [-]
    """
    check_choice("sampling", sampling, SAMPLINGS)
    n_angles = _check_n_angles(n_angles)
    theta, mu = _sampling_grid(sampling, n_angles)
    values = np.asarray(table.phase_at(theta), dtype=np.float64)
    with np.errstate(over="raise"):
        phase = values.astype("<f4")
    return phase, theta, mu


#: Largest ``|sphere integral of a texture's samples - 1|`` written without a
#: :class:`TextureNormalizationWarning` [-]: the tolerance ``dustoptics sky --angles`` refuses
#: beyond (:mod:`dustoptics.sky.approximations`).
NORMALIZATION_TOLERANCE: Final = 0.005


class TextureNormalizationWarning(UserWarning):
    """A texture's samples, read as the renderer interpolates them, lose the phase function's
    normalization by more than :data:`NORMALIZATION_TOLERANCE`."""


def _normalization_check(
    phase32: np.ndarray, theta: np.ndarray, mu: np.ndarray | None, table: Any
) -> list[float]:
    """2 pi int P dmu of each row, read the way the sampling is meant to be interpolated.

    Warns (:class:`TextureNormalizationWarning`) when a row is more than
    :data:`NORMALIZATION_TOLERANCE` from 1, saying whether the texture's sampling or the
    table's own angle grid (its phase function, linear between its angles) loses it.
    """
    p = phase32.astype(np.float64)
    if mu is None:  # linear in theta between samples: integrated exactly
        integrals = np.atleast_1d(sphere_integral(p, theta_deg=theta))
    else:  # linear in mu between samples: the trapezoid rule is exact (mu decreasing)
        integrals = (
            2.0 * math.pi * np.sum(0.5 * (p[:, 1:] + p[:, :-1]) * (mu[:-1] - mu[1:]), axis=1)
        )
    error = np.abs(integrals - 1.0)
    worst = int(np.argmax(error))
    if error[worst] > NORMALIZATION_TOLERANCE:
        own = np.atleast_1d(sphere_integral(table.phase, theta_deg=table.theta_deg))
        own_worst = int(np.argmax(np.abs(own - 1.0)))
        if abs(own[own_worst] - 1.0) > NORMALIZATION_TOLERANCE:
            advice = (
                f"the table's own {np.asarray(table.theta_deg).size} angles already integrate to "
                f"{own[own_worst]:.4g}: compute it on more angles (n_theta)"
            )
        elif mu is None:
            advice = "use more angles (--n-angles)"
        else:
            advice = (
                "use sampling 'theta' or more angles (the forward peak falls between the "
                "first cos samples)"
            )
        sampling = "theta" if mu is None else "cos"
        warnings.warn(
            f"the texture's samples ({sampling} sampling, {theta.size} angles) integrate over "
            f"the sphere to {integrals[worst]:.4g} (row {worst}), not 1 within "
            f"{NORMALIZATION_TOLERANCE:g}: read by a renderer, the phase function is off by "
            f"{100 * error[worst]:.2g} %; {advice}",
            TextureNormalizationWarning,
            stacklevel=3,
        )
    return integrals.tolist()


def _sidecar(
    table: Any,
    *,
    raw_name: str,
    raw_bytes: bytes,
    phase32: np.ndarray,
    theta: np.ndarray,
    mu: np.ndarray | None,
    sampling: str,
) -> bytes:
    from dustoptics import __version__

    n_wl, n_angles = phase32.shape
    if sampling == "theta":
        angle_axis: dict[str, Any] = {
            "name": "theta_deg",
            "unit": "deg",
            "meaning": "scattering angle, 0 = forward",
            "values": theta.tolist(),
        }
        description = (
            f"uniform in theta_deg from 0 (forward, column 0) to 180 (backward, column "
            f"{n_angles - 1}), both included: theta_j = 180 j / {n_angles - 1}"
        )
        interpolation = "linear in theta between columns reproduces the table's own interpolation"
    else:
        angle_axis = {
            "name": "mu",
            "unit": "1",
            "meaning": "cosine of the scattering angle nu = cos(theta), 1 = forward",
            "values": mu.tolist() if mu is not None else [],
            "theta_deg": theta.tolist(),
        }
        description = (
            f"uniform in mu = cos(theta) from 1 (forward, column 0) to -1 (backward, column "
            f"{n_angles - 1}), both included: mu_j = 1 - 2 j / {n_angles - 1}; value_j = "
            "table.phase_at(degrees(arccos(mu_j)))"
        )
        interpolation = (
            "linear in mu between columns (GL linear filtering), which differs from the "
            "table's linear-in-theta interpolation between samples"
        )
    provenance = table.provenance.to_dict()
    document = {
        "format": TEXTURE_FORMAT,
        "file": raw_name,
        "sha256": hashlib.sha256(raw_bytes).hexdigest(),
        "size_bytes": len(raw_bytes),
        "dtype": "<f4",
        "byte_order": "little-endian",
        "shape": [n_wl, n_angles],
        "order": (
            "C (row-major): row i = wavelength index, column j = angle index (fastest); "
            "byte offset of (i, j) = 4 (i n_angles + j)"
        ),
        "gl": {
            "width": n_angles,
            "height": n_wl,
            "internal_format": "GL_R32F",
            "format": "GL_RED",
            "type": "GL_FLOAT",
            "texel_centre": "u = (j + 0.5) / width, v = (i + 0.5) / height",
        },
        "axes": [
            {
                "name": "wavelength_nm",
                "unit": "nm",
                "meaning": "vacuum wavelength, increasing",
                "values": np.asarray(table.wavelength_nm, dtype=np.float64).tolist(),
            },
            angle_axis,
        ],
        "sampling": sampling,
        "sampling_description": description,
        "interpolation": interpolation,
        "quantity": "phase function",
        "unit": "sr^-1",
        "normalization": PHASE_NORMALIZATION,
        "sphere_integral_of_samples": _normalization_check(phase32, theta, mu, table),
        "source_angles": int(np.asarray(table.theta_deg).size),
        "table": table.name,
        "input_hash": table.provenance.input_hash,
        "provenance": provenance,
        "written_by": f"dustoptics {__version__}",
    }
    text = json.dumps(document, indent=2, sort_keys=True, allow_nan=False, ensure_ascii=True)
    return (text + "\n").encode("ascii")


def write_texture(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    sampling: str = "theta",
    n_angles: int = DEFAULT_N_ANGLES,
    overwrite: bool = False,
    stem: str | None = None,
) -> list[Path]:
    """Write the phase function as a raw float32 texture and its JSON sidecar.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table; every wavelength becomes one row of the texture.
    out_dir : path-like
        Output directory; created with its parents if missing.
    sampling : {"theta", "cos"}
        ``"theta"``: uniform in angle from 0 to 180 deg; ``"cos"``: uniform
        in ``mu = cos(theta)`` from 1 to -1.  Both ends are samples.
    n_angles : int
        Number of angle samples (texture width), >= 2.  Default 721: the seed
        shader's 0.25 deg step in ``"theta"``.  In ``"cos"`` sampling the first
        interval spans theta = arccos(1 - 2 / (n_angles - 1)) (4.3 deg for
        721): dust's forward peak needs many more samples, and the sidecar's
        ``sphere_integral_of_samples`` shows how much of the normalization the
        sampling keeps.
    overwrite : bool
        Replace existing files.  Default False: if either file exists, nothing
        is written.
    stem : str, optional
        File-name stem; default ``"<table name>_phase_<sampling>"`` with
        characters other than letters, digits, ``.``, ``_`` and ``-`` replaced
        by ``_``.

    Returns
    -------
    list of pathlib.Path
        ``[<stem>.raw, <stem>.json]``.

    Raises
    ------
    ValueError
        Unknown ``sampling`` or invalid ``n_angles`` or ``stem``.
    FileExistsError
        An output exists and ``overwrite`` is False.

    Examples
    --------
    >>> paths = write_texture(table, "out", sampling="cos", n_angles=2048)  # doctest: +SKIP
    >>> [p.name for p in paths]                                              # doctest: +SKIP
    ['mars-dust_phase_cos.raw', 'mars-dust_phase_cos.json']
    """
    phase32, theta, mu = texture_values(table, sampling=sampling, n_angles=n_angles)
    if stem is None:
        stem = safe_stem(f"{table.name}_phase_{sampling}")
    elif not isinstance(stem, str) or safe_stem(stem) != stem:
        raise ValueError(
            f"stem must be a non-empty file-name stem of letters, digits, '.', '_' and '-' "
            f"not starting with '.'; got {stem!r}"
        )
    root = Path(out_dir)
    raw_path = root / f"{stem}.raw"
    json_path = root / f"{stem}.json"
    raw_bytes = np.ascontiguousarray(phase32, dtype="<f4").tobytes(order="C")
    sidecar = _sidecar(
        table,
        raw_name=raw_path.name,
        raw_bytes=raw_bytes,
        phase32=phase32,
        theta=theta,
        mu=mu,
        sampling=sampling,
    )
    return write_files({raw_path: raw_bytes, json_path: sidecar}, overwrite=overwrite)


def read_texture(sidecar_path: str | os.PathLike[str]) -> TextureData:
    """Read a texture written by :func:`write_texture` or :func:`~dustoptics.io.textures.npy.write_npy`.

    Both write a JSON sidecar beside the array file: :data:`TEXTURE_FORMAT`
    (this module's ``.raw`` file) or
    :data:`~dustoptics.io.textures.raw.PHASE_TEXTURE_FORMAT` (a
    ``.npy`` file).  The sidecar is checked whole (every entry the format
    defines, of its type), the array file's size against the sidecar's shape
    before it is read, and its SHA-256.

    Parameters
    ----------
    sidecar_path : path-like
        The ``.json`` sidecar; the array file is the one it names, in the same
        directory.

    Returns
    -------
    TextureData
        The texture as float32 (read-only), one row per wavelength, with its
        coordinates and the sidecar.  An RGB ``.npy`` texture (one row, three
        channels) gives one row per channel, at the channels' wavelengths
        (their centroids for colour bands).

    Raises
    ------
    FormatError
        The sidecar is not JSON, not a texture sidecar of these formats, or
        has a missing or malformed entry; the array file is missing, shorter
        or longer than the sidecar's shape needs (e.g. a truncated download),
        or its SHA-256 differs from the sidecar's.
    """
    path = Path(sidecar_path)
    try:
        meta = load_json(path)
    except FormatError as exc:
        detail = str(exc).removeprefix(f"{path}: ")
        raise FormatError(f"{path}: cannot read the texture sidecar as JSON: {detail}") from None
    formats = (TEXTURE_FORMAT, PHASE_TEXTURE_FORMAT)
    if not isinstance(meta, dict) or meta.get("format") not in formats:
        found = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
        raise FormatError(
            f"{path}: not a texture sidecar of {' or '.join(map(repr, formats))} (format {found!r})"
        )
    try:
        if meta["format"] == TEXTURE_FORMAT:
            return _read_raw(path, meta)
        return _read_npy(path, meta)
    except FormatError:
        raise
    except (KeyError, TypeError, ValueError, OverflowError, IndexError, AttributeError) as exc:
        raise FormatError(
            f"{path}: texture sidecar has a missing or malformed entry "
            f"({type(exc).__name__}: {exc})"
        ) from None


def _text_entries(path: Path, meta: dict[str, Any], keys: tuple[str, ...]) -> None:
    for key in keys:
        if not isinstance(meta[key], str):
            raise FormatError(f"{path}: sidecar entry {key!r} must be a string; got {meta[key]!r}")
    provenance = meta["provenance"]
    if not isinstance(provenance, dict) or not isinstance(provenance.get("inputs"), dict):
        raise FormatError(f"{path}: sidecar entry 'provenance' must hold the table's inputs")
    integrals = meta["sphere_integral_of_samples"]
    if not isinstance(integrals, list) or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in integrals
    ):
        raise FormatError(f"{path}: sidecar entry 'sphere_integral_of_samples' must be numbers")


def _axis(path: Path, key: str, values: Any, n: int) -> np.ndarray:
    """An axis of ``n`` finite float coordinates from the sidecar, read-only."""
    if not isinstance(values, list) or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in values
    ):
        raise FormatError(f"{path}: sidecar axis {key!r} must be a list of numbers")
    out = np.asarray(values, dtype=np.float64)
    if out.shape != (n,) or not np.all(np.isfinite(out)):
        raise FormatError(
            f"{path}: sidecar axis {key!r} has {out.size} values; the shape needs {n} finite ones"
        )
    out.setflags(write=False)
    return out


def _shape(path: Path, value: Any, ndim: int) -> tuple[int, ...]:
    if (
        not isinstance(value, list)
        or len(value) != ndim
        or not all(type(n) is int and 1 <= n <= MAX_GRID_POINTS for n in value)
    ):
        raise FormatError(
            f"{path}: texture shape {value!r} must be {ndim} integers in [1, {MAX_GRID_POINTS}]"
        )
    return tuple(value)


def _array_file(
    path: Path, meta: dict[str, Any], least: int, most: int, kind: str
) -> tuple[Path, bytes]:
    """The array file the sidecar names: its size in [least, most] before reading, its digest."""
    raw_name = meta["file"]
    if not isinstance(raw_name, str) or not raw_name or Path(raw_name).name != raw_name:
        raise FormatError(f"{path}: array file name {raw_name!r} must be a plain file name")
    raw_path = path.parent / raw_name
    try:
        size = raw_path.stat().st_size
    except (OSError, ValueError) as exc:
        raise FormatError(f"{path}: cannot read the array file {raw_path}: {exc}") from None
    # Sizes compared before reading: a sidecar's shape cannot make the reader
    # allocate more than the file holds.
    if not least <= size <= most:
        what = "truncated" if size < least else "longer than expected"
        need = f"{least} bytes" if least == most else f"{least} to {most} bytes"
        number = {"<f4": "float32", "<f2": "float16"}[meta["dtype"]]
        raise FormatError(
            f"{raw_path}: {kind} is {what}: {size} bytes, but shape "
            f"{list(meta['shape'])} of {number} needs {need}"
        )
    data = read_checked(raw_path, limit=most)
    actual = hashlib.sha256(data).hexdigest()
    if actual != meta["sha256"]:
        raise FormatError(
            f"{raw_path}: SHA-256 {actual} differs from the sidecar's {meta['sha256']!r}: the "
            "file was altered or damaged"
        )
    return raw_path, data


def _read_raw(path: Path, meta: dict[str, Any]) -> TextureData:
    """A :data:`TEXTURE_FORMAT` sidecar and its ``.raw`` file."""
    dtype, sampling = meta["dtype"], meta["sampling"]
    if dtype != "<f4" or sampling not in SAMPLINGS:
        raise FormatError(
            f"{path}: unsupported texture (dtype {dtype!r}, sampling {sampling!r}); "
            f"this reader reads dtype '<f4', 2-D, sampling one of {SAMPLINGS}"
        )
    shape = _shape(path, meta["shape"], 2)
    _text_entries(
        path,
        meta,
        ("table", "input_hash", "written_by", "unit", "normalization", "sampling_description"),
    )
    wl_axis, angle_axis = meta["axes"]
    wavelength = _axis(path, "wavelength_nm", wl_axis["values"], shape[0])
    mu = None
    if sampling == "theta":
        theta = _axis(path, "theta_deg", angle_axis["values"], shape[1])
    else:
        mu = _axis(path, "mu", angle_axis["values"], shape[1])
        theta = _axis(path, "theta_deg", angle_axis["theta_deg"], shape[1])
    expected = 4 * shape[0] * shape[1]
    _, data = _array_file(path, meta, expected, expected, "raw texture")
    phase = np.frombuffer(data, dtype="<f4").reshape(shape).copy()
    phase.setflags(write=False)
    return TextureData(
        phase=phase,
        wavelength_nm=wavelength,
        theta_deg=theta,
        mu=mu,
        sampling=sampling,
        metadata=meta,
    )


#: Most bytes of a ``.npy`` header (format 1.0 pads it to a multiple of 64).
_NPY_HEADER_MAX = 4096


def _read_npy(path: Path, meta: dict[str, Any]) -> TextureData:
    """A :data:`~dustoptics.io.textures.raw.PHASE_TEXTURE_FORMAT` sidecar and its ``.npy``."""
    dtype, sampling, layout = meta["dtype"], meta["sampling"], meta["layout"]
    if (
        dtype not in ("<f4", "<f2")
        or sampling not in SAMPLINGS
        or layout not in ("wavelength", "rgb")
    ):
        raise FormatError(
            f"{path}: unsupported texture (dtype {dtype!r}, sampling {sampling!r}, layout "
            f"{layout!r}); this reader reads dtype '<f4' or '<f2', sampling one of {SAMPLINGS}, "
            "layout 'wavelength' or 'rgb'"
        )
    height, width, channels = _shape(path, meta["shape"], 3)
    if not (
        (layout == "rgb" and (height, channels) == (1, 3))
        or (layout == "wavelength" and channels == 1)
    ):
        raise FormatError(
            f"{path}: a {layout!r} texture of shape {[height, width, channels]}: expected "
            "(1, width, 3) for 'rgb', (n_wavelength, width, 1) for 'wavelength'"
        )
    _text_entries(path, meta, ("table", "input_hash", "written_by", "unit", "normalization"))
    columns = meta["axes"]["columns"]
    mu = None
    if sampling == "theta":
        theta = _axis(path, "theta_deg", columns["values"], width)
    else:
        mu = _axis(path, "mu", columns["values"], width)
        theta = _axis(path, "theta_deg", columns["theta_deg"], width)
    if layout == "rgb":
        wavelength = _axis(path, "channels.wavelength_nm", meta["channels"]["wavelength_nm"], 3)
    else:
        wavelength = _axis(path, "wavelength_nm", meta["axes"]["rows"]["values"], height)
    itemsize = 4 if dtype == "<f4" else 2
    nbytes = height * width * channels * itemsize
    _, data = _array_file(path, meta, nbytes, nbytes + _NPY_HEADER_MAX, ".npy array")
    # The header's declared shape and type are checked before numpy allocates them (a
    # header may declare 112 GiB in a file of a few hundred bytes).
    try:
        buffer = io.BytesIO(data)
        version = np.lib.format.read_magic(buffer)
        read_header = (
            np.lib.format.read_array_header_1_0
            if version == (1, 0)
            else np.lib.format.read_array_header_2_0
        )
        shape, _, declared = read_header(buffer, max_header_size=_NPY_HEADER_MAX)
    except (ValueError, OSError, EOFError, SyntaxError) as exc:
        raise FormatError(f"{path}: the array file is not a NumPy .npy array ({exc})") from None
    if declared != np.dtype(dtype) or tuple(shape) != (height, width, channels):
        raise FormatError(
            f"{path}: the array file holds {declared.str} of shape {list(shape)}; the "
            f"sidecar says {dtype} of shape {[height, width, channels]}"
        )
    try:
        pixels = np.load(io.BytesIO(data), allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise FormatError(f"{path}: the array file is not a NumPy .npy array ({exc})") from None
    rows = pixels[0].T if layout == "rgb" else pixels[:, :, 0]
    phase = np.ascontiguousarray(rows, dtype=np.float32)
    phase.setflags(write=False)
    return TextureData(
        phase=phase,
        wavelength_nm=wavelength,
        theta_deg=theta,
        mu=mu,
        sampling=sampling,
        metadata=meta,
    )


@dataclass(frozen=True)
class SamplingOptions:
    """How a texture samples the angle (formats texture, ktx2, exr, npy); None leaves the
    writer's default.

    Attributes
    ----------
    sampling : str, optional
        ``"theta"`` (default) or ``"cos"``.
    n_angles : int, optional
        Samples along the angle axis (default :data:`DEFAULT_N_ANGLES`).
    """

    sampling: str | None = option(
        help="uniform in angle or in cos(angle) (default theta)", choices=["theta", "cos"]
    )
    n_angles: int | None = option(
        help="samples along the angle axis (default 721)", type="positive_int", metavar="N"
    )


RECORD = register(
    Format(
        name="texture",
        summary="NAME_phase_theta.raw: float32 texture, JSON sidecar",
        write=write_texture,
        suffixes=(".raw", ".json"),
        options=SamplingOptions,
    )
)
