"""The phase-function texture as an OpenEXR image (film and game pipelines).

Written with the OpenEXR library's own Python binding (``OpenEXR`` on PyPI,
the ``textures`` extra): scanline image, ZIP compression (lossless), pixel
type FLOAT (float32) or HALF (float16), channels ``R`` (wavelength layout) or
``R``, ``G``, ``B`` (RGB layout).  The sampling rule, axes, units, accuracy and
provenance are the header's string attribute ``dustoptics`` (canonical JSON).
Same table and options, same bytes.

Reference: Academy Software Foundation, "OpenEXR File Layout",
https://openexr.com/en/latest/OpenEXRFileLayout.html.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import FormatError
from dustoptics.io.describe_formats import describe_texture, limit_of, regular_size
from dustoptics.io.registry import Format, register
from dustoptics.io.textures.phase_texture import (
    PhaseTexture,
    TextureOptions,
    check_dimensions,
    metadata_json,
    write_container,
)

__all__ = ["encode_exr", "read_exr_metadata", "write_exr"]

# The data window is stored as int32 coordinates.
_CONTAINER_LIMIT = 2**31 - 1

#: Most bytes ZIP (deflate) can expand one stored byte to (deflate's limit is about 1032:1).
_MAX_ZIP_RATIO = 1100


def _openexr() -> Any:
    try:
        import OpenEXR
    except ImportError:
        raise ImportError(
            "the exr format needs the OpenEXR package, a dependency of dustoptics: "
            "pip install 'OpenEXR>=3.3'"
        ) from None
    return OpenEXR


def _writer(texture: PhaseTexture) -> Any:
    """A callback that writes the EXR file of ``texture`` at a given path."""
    openexr = _openexr()
    check_dimensions(
        texture.width,
        texture.height,
        max_dimension=_CONTAINER_LIMIT,
        container="OpenEXR",
        container_limit=_CONTAINER_LIMIT,
    )
    header = {
        "compression": openexr.ZIP_COMPRESSION,
        "type": openexr.scanlineimage,
        "dustoptics": metadata_json(texture),
    }
    channels = {
        name: texture.pixels[:, :, k].copy() for k, name in enumerate(texture.channel_names)
    }

    def write(path: Path) -> None:
        with openexr.File(header, channels) as image:
            image.write(str(path))

    return write


def encode_exr(
    channels: Mapping[str, np.ndarray],
    *,
    attributes: Mapping[str, Any] | None = None,
    metadata: Mapping[str, Any] | None = None,
) -> bytes:
    """An OpenEXR image as bytes: scanlines, ZIP compression (lossless), deterministic.

    The encoder behind the phase textures, for any other image the package
    writes (the sky's environment maps, :mod:`dustoptics.sky.hdr`).

    Parameters
    ----------
    channels : mapping of str to numpy.ndarray
        Channel name to pixels, shape (height, width) or (height, width, k)
        (``"RGB"`` with k = 3 gives channels R, G, B), dtype float16 (HALF) or
        float32 (FLOAT).
    attributes : mapping, optional
        Further header attributes, as the OpenEXR binding takes them (standard
        ones such as ``chromaticities`` and ``whiteLuminance``; a Python float
        is written as a float attribute, a str as a string).
    metadata : mapping, optional
        Written as the string attribute ``dustoptics`` (canonical JSON: sorted
        keys, ASCII, no NaN), read back by :func:`read_exr_metadata`.

    Returns
    -------
    bytes

    Raises
    ------
    ImportError
        OpenEXR is not installed.
    ValueError
        A channel neither float16 nor float32.
    """
    openexr = _openexr()
    for name, pixels in channels.items():
        if pixels.dtype not in (np.float16, np.float32):
            raise ValueError(
                f"channels[{name!r}] must be float16 (half) or float32 (float); got {pixels.dtype}"
            )
    header: dict[str, Any] = {
        "compression": openexr.ZIP_COMPRESSION,
        "type": openexr.scanlineimage,
        **(attributes or {}),
    }
    if metadata is not None:
        header["dustoptics"] = json.dumps(
            dict(metadata), sort_keys=True, allow_nan=False, ensure_ascii=True
        )
    with tempfile.TemporaryDirectory(prefix="dustoptics-exr-") as tmp:
        target = Path(tmp) / "image.exr"
        with openexr.File(header, {k: np.ascontiguousarray(v) for k, v in channels.items()}) as f:
            f.write(str(target))
        return target.read_bytes()


def write_exr(
    table: Any,
    out_dir_or_path: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    **options: Any,
) -> list[Path]:
    """Write the phase function as an OpenEXR image, atomically: the ``.exr`` file
    ``out_dir_or_path`` or a file in that directory, as
    :func:`~dustoptics.io.textures.phase_texture.write_container` (``**options``: the fields of
    :class:`~dustoptics.io.textures.phase_texture.TextureOptions`).

    Raises
    ------
    ImportError
        OpenEXR is not installed (the message names the ``textures`` extra).
    """
    return write_container(
        table,
        out_dir_or_path,
        suffix=".exr",
        encode=lambda texture, target: {target: _writer(texture)},
        overwrite=overwrite,
        **options,
    )


def read_exr_metadata(
    path: str | os.PathLike[str], *, max_bytes: int | None = None
) -> dict[str, Any]:
    """The ``dustoptics`` header attribute (sampling rule, axes, units, provenance) of an EXR
    texture, read with the OpenEXR library.

    Before the library opens it, the file must be a regular file of at most ``max_bytes``
    (None: :data:`~dustoptics.io.describe_formats.MAX_READ_BYTES`); then the pixels its data
    window declares (at 4 bytes a channel) must fit in ``max_bytes`` and in what its bytes can
    hold (ZIP: deflate's limit of about 1032:1), and the metadata's width and height must be
    the data window's.

    Raises
    ------
    ImportError
        OpenEXR is not installed (the ``textures`` extra).
    dustoptics.io.FormatError
        Not an OpenEXR file, a crafted or damaged one, or one without dustoptics' metadata;
        the message names the file and the size.
    """
    openexr = _openexr()
    p = Path(path)
    limit = limit_of(max_bytes)
    size = regular_size(p, limit)
    try:
        with openexr.File(str(p), header_only=True) as image:
            header = image.header()
            text = header.get("dustoptics")
            low, high = (tuple(int(v) for v in corner) for corner in header["dataWindow"])
            n_channels = len(header["channels"])
    except Exception as exc:  # OpenEXR raises plain Exception/RuntimeError on damage
        raise FormatError(f"{str(p)!r}: not a readable OpenEXR file ({exc})") from None
    width, height = high[0] - low[0] + 1, high[1] - low[1] + 1
    declared = max(width, 0) * max(height, 0) * n_channels * 4
    if width < 1 or height < 1 or declared > min(limit, _MAX_ZIP_RATIO * size):
        raise FormatError(
            f"{str(p)!r}: its data window declares {width} x {height} pixels of {n_channels} "
            f"channels ({declared} bytes) in a file of {size} bytes, beyond what it can hold "
            f"or the {limit}-byte limit (max_bytes=); refused before reading"
        )
    if not isinstance(text, str):
        raise FormatError(f"{str(p)!r}: an OpenEXR file without dustoptics' metadata")
    try:
        meta = json.loads(text)
    except (ValueError, RecursionError):
        raise FormatError(f"{str(p)!r}: its dustoptics metadata is not JSON (damaged)") from None
    if not isinstance(meta, dict):
        raise FormatError(f"{str(p)!r}: its dustoptics metadata is not a JSON object")
    if (meta.get("width"), meta.get("height")) != (width, height):
        raise FormatError(
            f"{str(p)!r}: its metadata says {meta.get('width')!r} x {meta.get('height')!r} "
            f"texels, its data window {width} x {height} (damaged or crafted)"
        )
    return meta


def describe_exr(path: Path, full: bool = True) -> str:
    """What an OpenEXR phase texture holds, from its metadata (``dustoptics info``)."""
    return describe_texture(path, read_exr_metadata(path), "OpenEXR", full)


RECORD = register(
    Format(
        name="exr",
        summary="NAME_phase_*.exr: the phase texture as OpenEXR",
        write=write_exr,
        suffixes=(".exr",),
        options=TextureOptions,
        recognise=lambda path: path.suffix.lower() == ".exr",
        describe=describe_exr,
    )
)
