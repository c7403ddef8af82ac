"""A phase-function texture as engines load it: layout, angle sampling, precision, metadata.

:func:`phase_texture` turns a table into an image and the metadata that says
how to read it; the container modules write it (:mod:`~dustoptics.io.textures.ktx2`,
:mod:`~dustoptics.io.textures.exr`, :mod:`~dustoptics.io.textures.npy`), each
through :func:`write_container` (the texture, the file's name, one atomic write)
with its own encoder.

Layouts
-------
``"wavelength"``
    angle x wavelength: one row per table wavelength (row 0 = the first,
    shortest), one column per angle sample, one channel (R).
``"rgb"``
    angle x RGB: one row, one column per angle sample, channels R, G, B made
    from the table's wavelengths as the shaders make them
    (:func:`dustoptics.io.shaders.common.choose_channels`: three wavelengths, CIE
    1931 XYZ bands or linear sRGB lit by the sun).  Containers whose GPU
    formats have no filterable three-channel float format (KTX2) add A = 1.

Samplings
---------
``"theta"``
    column ``j`` at ``theta_j = 180 j / (W - 1)`` deg (``W`` columns, 0 =
    forward); a renderer reads ``u = (theta / 180 (W - 1) + 0.5) / W`` with
    linear filtering, which interpolates linearly in angle.  With the table's
    own angles (``W`` = the table's count on its uniform grid), that is
    exactly the table's interpolation (:meth:`~dustoptics.table.Table.phase_at`).
``"cos"``
    column ``j`` at ``mu_j = 1 - 2 j / (W - 1)`` (mu = cos(theta), 1 =
    forward), the value ``phase_at(degrees(arccos(mu_j)))``; a renderer reads
    ``u = ((1 - mu) / 2 (W - 1) + 0.5) / W``: linear in mu between columns,
    which differs from the table's linear-in-angle interpolation between
    samples (the forward peak needs many more columns).

Precision
---------
``"float32"`` or ``"float16"`` (IEEE binary16: 11 significant bits, largest
65504; a value above it is an error, never clamped).  The metadata give the
largest relative rounding error of the samples and the sphere integral of
each row as the sampling is meant to be interpolated.

Limits
------
Each side of the image at most ``max_dimension`` texels (default 4096,
Vulkan's guaranteed ``maxImageDimension2D``; WebGPU guarantees 8192,
Direct3D 11-12 and OpenGL 4.1+ 16384) and at most the container's own limit.
Everything is checked before anything is written.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._validation import check_choice
from dustoptics.colour import channel_phase
from dustoptics.io._atomic import Content, safe_stem, write_files
from dustoptics.io.registry import option
from dustoptics.io.shaders.common import ChannelOptions, choose_channels
from dustoptics.io.textures.raw import (
    DEFAULT_N_ANGLES,
    PHASE_TEXTURE_FORMAT,
    SAMPLINGS,
    SamplingOptions,
    _normalization_check,
    _sampling_grid,
)
from dustoptics.table import PHASE_NORMALIZATION

__all__ = [
    "DEFAULT_MAX_DIMENSION",
    "LAYOUTS",
    "PRECISIONS",
    "PhaseTexture",
    "check_dimensions",
    "metadata_json",
    "phase_texture",
    "write_container",
]

#: Image layouts :func:`phase_texture` makes.
LAYOUTS = ("wavelength", "rgb")

#: Sample precisions: IEEE binary32 and binary16.
PRECISIONS = ("float32", "float16")

#: Default largest side [texels]: Vulkan's guaranteed maxImageDimension2D.
DEFAULT_MAX_DIMENSION = 4096

_DTYPES: dict[str, np.dtype[Any]] = {"float32": np.dtype("<f4"), "float16": np.dtype("<f2")}


@dataclass(frozen=True)
class PhaseTexture:
    """A phase-function image and the metadata that says how to read it.

    Attributes
    ----------
    pixels : numpy.ndarray, shape (height, width, channels)
        Little-endian float32 or float16, read-only; row 0 first. [sr^-1]
    layout : str
        ``"wavelength"`` or ``"rgb"``.
    sampling : str
        ``"theta"`` or ``"cos"``.
    precision : str
        ``"float32"`` or ``"float16"``.
    theta_deg : numpy.ndarray, shape (width,)
        Angle of each column. [deg]
    mu : numpy.ndarray or None, shape (width,)
        Cosine of each column for the ``"cos"`` sampling, else None. [-]
    channel_names : tuple of str
        Name of each channel (``("R",)`` or ``("R", "G", "B")``).
    metadata : dict
        JSON-ready: the sampling rule, axes, units, normalization, accuracy
        and provenance (what containers store in their own metadata).
    """

    pixels: np.ndarray
    layout: str
    sampling: str
    precision: str
    theta_deg: np.ndarray
    mu: np.ndarray | None
    channel_names: tuple[str, ...]
    metadata: dict[str, Any]

    @property
    def height(self) -> int:
        return int(self.pixels.shape[0])

    @property
    def width(self) -> int:
        return int(self.pixels.shape[1])


def _check_size(name: str, value: Any, *, low: int, high: int, what: str) -> int:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, np.integer))
        or not low <= value <= high
    ):
        raise ValueError(f"{name} must be an integer from {low} to {high} ({what}); got {value!r}")
    return int(value)


def check_dimensions(
    width: int, height: int, *, max_dimension: int, container: str, container_limit: int
) -> None:
    """Refuse an image larger than ``max_dimension`` or than the container allows."""
    for side, size in (("width (angle samples)", width), ("height (rows)", height)):
        if size > container_limit:
            raise ValueError(
                f"texture {side} = {size} exceeds the {container} container's limit of "
                f"{container_limit} texels"
            )
        if size > max_dimension:
            raise ValueError(
                f"texture {side} = {size} exceeds max_dimension = {max_dimension} texels (default "
                f"{DEFAULT_MAX_DIMENSION}, Vulkan's guaranteed maxImageDimension2D); use fewer "
                "samples or raise max_dimension for engines that allow more"
            )


def phase_texture(
    table: Any,
    *,
    layout: str = "rgb",
    sampling: str = "theta",
    n_angles: int = DEFAULT_N_ANGLES,
    precision: str = "float32",
    channels_nm: Any = None,
    colour: str | None = None,
    min_band_coverage: float = 0.99,
    max_dimension: int = DEFAULT_MAX_DIMENSION,
) -> PhaseTexture:
    """The texture of a table's phase function (see the module docstring).

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    layout : {"rgb", "wavelength"}
        Angle x RGB (one row, three channels) or angle x wavelength (one row
        per wavelength, one channel).
    sampling : {"theta", "cos"}
        Columns uniform in angle or in its cosine.
    n_angles : int
        Number of columns (>= 2); default 721 (0.25 deg in ``"theta"``).
    precision : {"float32", "float16"}
        Sample type.
    channels_nm, colour, min_band_coverage
        RGB layout only: the channels (:func:`dustoptics.io.shaders.common.choose_channels`).
    max_dimension : int
        Largest accepted side [texels]; default 4096.

    Returns
    -------
    PhaseTexture

    Raises
    ------
    ValueError
        An unknown layout, sampling or precision; channel options with the
        wavelength layout; a side above ``max_dimension``; a value above
        float16's 65504 with ``precision="float16"``.
    """
    from dustoptics import __version__

    check_choice("layout", layout, LAYOUTS)
    check_choice("sampling", sampling, SAMPLINGS)
    check_choice("precision", precision, PRECISIONS)
    max_dimension = _check_size(
        "max_dimension", max_dimension, low=2, high=2**31 - 1, what="texels"
    )
    n_angles = _check_size(
        "n_angles", n_angles, low=2, high=2**31 - 1, what="columns, both ends sampled"
    )
    height = 1 if layout == "rgb" else int(np.asarray(table.wavelength_nm).size)
    check_dimensions(
        n_angles,
        height,
        max_dimension=max_dimension,
        container="requested",
        container_limit=2**31 - 1,
    )
    theta, mu = _sampling_grid(sampling, n_angles)
    rows = np.asarray(table.phase_at(theta), dtype=np.float64)  # (n_wavelength, n_angles)
    channel_info: dict[str, Any]
    if layout == "rgb":
        chosen = choose_channels(
            table, channels_nm=channels_nm, colour=colour, min_band_coverage=min_band_coverage
        )
        exact = channel_phase(chosen, rows, csca_um2=table.quantity("csca_um2"))  # (3, n_angles)
        image64 = exact.T[None, :, :]  # (1, n_angles, 3)
        names: tuple[str, ...] = ("R", "G", "B")
        channel_info = {
            "mode": chosen.mode,
            "names": list(chosen.names),
            "wavelength_nm": chosen.centroid_nm.tolist(),
            "descriptions": list(chosen.descriptions),
            "weights_over_table_wavelengths": chosen.weights.tolist(),
            "scattering_weighted": table.cross_sections is not None,
        }
    else:
        if channels_nm is not None or colour is not None:
            raise ValueError(
                "channels_nm and colour choose the RGB layout's channels; with layout='wavelength' "
                f"every wavelength is a row (got channels_nm={channels_nm!r}, colour={colour!r})"
            )
        image64 = rows[:, :, None]  # (n_wavelength, n_angles, 1)
        names = ("R",)
        channel_info = {"mode": "one row per wavelength", "names": ["R"]}
    dtype = _DTYPES[precision]
    largest = float(np.max(np.abs(image64)))
    limit = float(np.finfo(dtype).max)
    if largest > limit:
        raise ValueError(
            f"precision='{precision}' cannot hold the phase function's largest value {largest:.6g} "
            f"sr^-1 (largest {precision} {limit:g}); use precision='float32'"
        )
    pixels = np.ascontiguousarray(image64.astype(dtype))
    pixels.setflags(write=False)
    stored = pixels.astype(np.float64)
    nonzero = image64 != 0
    rounding = (
        float(np.max(np.abs(stored - image64)[nonzero] / np.abs(image64[nonzero])))
        if nonzero.any()
        else 0.0
    )
    integral_rows = stored[0].T if layout == "rgb" else stored[:, :, 0]
    if sampling == "theta":
        rule = (
            f"column j (0..{n_angles - 1}) at theta_j = 180 j / {n_angles - 1} deg, 0 = forward; "
            f"u = (theta_deg / 180 * {n_angles - 1} + 0.5) / {n_angles} with linear filtering "
            "interpolates linearly in angle"
        )
        angle_axis: dict[str, Any] = {
            "name": "theta_deg",
            "unit": "degree",
            "values": theta.tolist(),
        }
    else:
        rule = (
            f"column j (0..{n_angles - 1}) at mu_j = 1 - 2 j / {n_angles - 1}, mu = cos(theta), "
            f"1 = forward, value = phase_at(degrees(arccos(mu_j))); u = ((1 - mu) / 2 * "
            f"{n_angles - 1} + 0.5) / {n_angles} with linear filtering interpolates linearly in mu"
        )
        angle_axis = {
            "name": "mu",
            "unit": "1",
            "values": mu.tolist() if mu is not None else [],
            "theta_deg": theta.tolist(),
        }
    if layout == "rgb":
        row_axis: dict[str, Any] = {
            "name": "row",
            "meaning": "one row: channels R, G, B",
            "values": [0],
        }
        row_rule = "one row; v = 0.5"
    else:
        row_axis = {
            "name": "wavelength_nm",
            "unit": "nm",
            "values": np.asarray(table.wavelength_nm, dtype=np.float64).tolist(),
        }
        row_rule = (
            f"row i (0..{height - 1}) at the table's wavelength i (increasing); v = (i + 0.5) / "
            f"{height} reads row i"
        )
    metadata: dict[str, Any] = {
        "format": PHASE_TEXTURE_FORMAT,
        "quantity": "phase function",
        "unit": "sr^-1",
        "normalization": PHASE_NORMALIZATION,
        "layout": layout,
        "sampling": sampling,
        "sampling_rule": rule,
        "row_rule": row_rule,
        "width": n_angles,
        "height": height,
        "channels": channel_info,
        "precision": precision,
        "max_relative_rounding_error": rounding,
        "sphere_integral_of_samples": _normalization_check(integral_rows, theta, mu, table),
        "axes": {"columns": angle_axis, "rows": row_axis},
        "table": table.name,
        "input_hash": table.provenance.input_hash,
        "provenance": table.provenance.to_dict(),
        "written_by": f"dustoptics {__version__}",
    }
    for array in (theta, mu):
        if array is not None:
            array.setflags(write=False)
    return PhaseTexture(
        pixels=pixels,
        layout=layout,
        sampling=sampling,
        precision=precision,
        theta_deg=theta,
        mu=mu,
        channel_names=names,
        metadata=metadata,
    )


def metadata_json(texture: PhaseTexture) -> str:
    """The metadata as canonical JSON text (sorted keys, ASCII, no NaN)."""
    return json.dumps(texture.metadata, sort_keys=True, allow_nan=False, ensure_ascii=True)


@dataclass(frozen=True)
class TextureOptions(SamplingOptions, ChannelOptions):
    """The keywords of the container writers (formats ktx2, exr, npy), once for all three: the
    keyword arguments of :func:`phase_texture`.  None leaves :func:`phase_texture`'s default.

    Attributes
    ----------
    layout : str, optional
        ``"rgb"`` (angle x three channels, default) or ``"wavelength"``.
    precision : str, optional
        ``"float32"`` (default) or ``"float16"``.
    sampling, n_angles
        As :class:`~dustoptics.io.textures.raw.SamplingOptions`.
    channels_nm, colour
        As :class:`~dustoptics.io.shaders.common.ChannelOptions`.
    min_band_coverage : float, optional
        As :func:`choose_channels` (not a command-line option).
    max_dimension : int, optional
        Largest texture side (not a command-line option).
    """

    layout: str | None = option(
        help="angle x RGB (default) or angle x wavelength",
        choices=["rgb", "wavelength"],
    )
    precision: str | None = option(
        help="sample type (default float32)", choices=["float32", "float16"]
    )
    min_band_coverage: float | None = None
    max_dimension: int | None = None

    def keywords(self) -> dict[str, Any]:
        """The keywords given (not None), for :func:`phase_texture`."""
        out: dict[str, Any] = {"channels_nm": self.channels_nm, "colour": self.colour}
        keys = ("layout", "sampling", "n_angles", "precision", "min_band_coverage", "max_dimension")
        for key in keys:
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        return out


def write_container(
    table: Any,
    out_dir_or_path: str | os.PathLike[str],
    *,
    suffix: str,
    encode: Callable[[PhaseTexture, Path], Mapping[Path, Content]],
    overwrite: bool,
    accept_file_path: bool = True,
    **options: Any,
) -> list[Path]:
    """Write a table's phase texture into a container's files, atomically.

    What every container writer does (:func:`~dustoptics.io.textures.ktx2.write_ktx2`,
    :func:`~dustoptics.io.textures.exr.write_exr`, :func:`~dustoptics.io.textures.npy.write_npy`):
    make the texture with :func:`phase_texture` (so its errors come before anything is
    written), name the file ``<table name>_phase_<layout>_<sampling>_<precision><suffix>`` (with
    ``colour``, its name after ``_phase``),
    let the container encode it, and write every file in one atomic step
    (:func:`dustoptics.io._atomic.write_files`).

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    out_dir_or_path : path-like
        Directory (created if missing) that receives the named file; with
        ``accept_file_path``, a path ending in ``suffix`` is the file itself.
    suffix : str
        The container's file-name suffix, with its dot (``".ktx2"``).
    encode : callable
        ``encode(texture, path) -> {path: content}``: the container's files, given the
        texture and the main file's path; a content is the file's bytes or a callable
        that writes the file at the path it is given.
    overwrite : bool
        Replace existing files.
    accept_file_path : bool, default True
        Whether ``out_dir_or_path`` may name the file itself.
    **options
        The fields of :class:`TextureOptions` (the keyword arguments of
        :func:`phase_texture`); an unknown name is a TypeError.

    Returns
    -------
    list of pathlib.Path
        The written files, in the order ``encode`` gives them.

    Raises
    ------
    ValueError
        As :func:`phase_texture` (before anything is written).
    FileExistsError
        A file exists and ``overwrite`` is False (nothing is written).
    """
    texture = phase_texture(table, **TextureOptions(**options).keywords())
    out = Path(out_dir_or_path)
    # Each colour mode its own file (as the shaders'): the modes' numbers differ.
    mode = f"_{options['colour']}" if options.get("colour") else ""
    name = (
        f"{safe_stem(table.name)}_phase{mode}_{texture.layout}_{texture.sampling}_"
        f"{texture.precision}"
    )
    target = out if accept_file_path and out.suffix == suffix else out / f"{name}{suffix}"
    return write_files(encode(texture, target), overwrite=overwrite)
