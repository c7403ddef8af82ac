"""The phase-function texture as a KTX 2.0 file (Khronos; Vulkan, WebGPU, three.js).

One uncompressed 2-D image, one mip level, no supercompression, in
``VK_FORMAT_R32G32B32A32_SFLOAT`` / ``VK_FORMAT_R16G16B16A16_SFLOAT`` (RGB
layout, A = 1) or ``VK_FORMAT_R32_SFLOAT`` / ``VK_FORMAT_R16_SFLOAT``
(wavelength layout), linear transfer, BT.709 primaries.  The sampling rule,
axes, units, accuracy and provenance are the key/value entry ``dustoptics``
(canonical JSON, NUL-terminated UTF-8), beside ``KTXwriter``.

Why the container is written here: ``pyktx`` (PyPI) binds libktx, which must
be built from KTX-Software's sources (PyPI has no wheel and Debian 12 no
package).  An uncompressed one-level 2-D KTX2 file is a fixed header, a level
index, a Data Format Descriptor and key/value data (KTX 2.0 specification,
sections 3-4; Khronos Data Format specification 1.3, section 5), written
below field by field with the DFD that KTX-Software's ``vk2dfd`` makes for
these formats.  The tests read the files with an independent parser,
``ktx-parse`` (npm; the reader of three.js's KTX2Loader and glTF-Transform),
check that it serializes them back to the same bytes, and upload its pixels
to OpenGL.

References
----------
Khronos Group, "KTX File Format Specification, version 2.0" (2021),
https://registry.khronos.org/KTX/specs/2.0/ktxspec.v2.html; Khronos Group,
"Khronos Data Format Specification 1.3" (2020).
"""

from __future__ import annotations

import json
import math
import os
import struct
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

__all__ = ["KTX2_IDENTIFIER", "VK_FORMATS", "ktx2_bytes", "read_ktx2_metadata", "write_ktx2"]

#: The 12-byte file identifier: «KTX 20»\r\n\x1A\n.
KTX2_IDENTIFIER = bytes([0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A])

#: vkFormat of (channels, precision): Vulkan's VkFormat enumerants.
VK_FORMATS = {
    (4, "float32"): 109,  # VK_FORMAT_R32G32B32A32_SFLOAT
    (4, "float16"): 97,  # VK_FORMAT_R16G16B16A16_SFLOAT
    (1, "float32"): 100,  # VK_FORMAT_R32_SFLOAT
    (1, "float16"): 76,  # VK_FORMAT_R16_SFLOAT
}

# pixelWidth and pixelHeight are uint32.
_CONTAINER_LIMIT = 2**32 - 1

# Data Format Descriptor fields (Khronos Data Format 1.3, khr_df.h).
_KHR_DF_VERSIONNUMBER_1_3 = 2
_KHR_DF_MODEL_RGBSDA = 1
_KHR_DF_PRIMARIES_BT709 = 1
_KHR_DF_TRANSFER_LINEAR = 1
_KHR_DF_SAMPLE_DATATYPE_FLOAT = 0x80
_KHR_DF_SAMPLE_DATATYPE_SIGNED = 0x40
_CHANNEL_IDS = (0, 1, 2, 15)  # R, G, B, A
_FLOAT_ONE = struct.unpack("<I", struct.pack("<f", 1.0))[0]
_FLOAT_MINUS_ONE = struct.unpack("<I", struct.pack("<f", -1.0))[0]


def _dfd(n_channels: int, bytes_per_channel: int) -> bytes:
    """The basic Data Format Descriptor of an unpacked little-endian SFLOAT format."""
    block_size = 24 + 16 * n_channels
    words = [
        0,  # vendorId KHRONOS (0), descriptorType BASICFORMAT (0)
        _KHR_DF_VERSIONNUMBER_1_3 | (block_size << 16),
        _KHR_DF_MODEL_RGBSDA | (_KHR_DF_PRIMARIES_BT709 << 8) | (_KHR_DF_TRANSFER_LINEAR << 16),
        0,  # texelBlockDimension0..3 = 1x1x1x1, stored as n - 1
        n_channels * bytes_per_channel,  # bytesPlane0; planes 1-3 zero
        0,  # bytesPlane4..7
    ]
    for k in range(n_channels):
        channel_type = (
            _CHANNEL_IDS[k] | _KHR_DF_SAMPLE_DATATYPE_FLOAT | _KHR_DF_SAMPLE_DATATYPE_SIGNED
        )
        bits = 8 * bytes_per_channel
        words += [
            (k * bits) | ((bits - 1) << 16) | (channel_type << 24),
            0,  # sample position
            _FLOAT_MINUS_ONE,  # sampleLower: -1.0f for SFLOAT (as KTX-Software's vk2dfd)
            _FLOAT_ONE,  # sampleUpper: 1.0f
        ]
    body = struct.pack(f"<{len(words)}I", *words)
    return struct.pack("<I", 4 + len(body)) + body


def _key_value(entries: dict[str, bytes]) -> bytes:
    """Key/value data: entries sorted by key, each padded to 4 bytes."""
    out = bytearray()
    for key in sorted(entries, key=lambda k: k.encode("utf-8")):
        kv = key.encode("utf-8") + b"\0" + entries[key]
        out += struct.pack("<I", len(kv)) + kv
        out += b"\0" * (-len(kv) % 4)
    return bytes(out)


def ktx2_bytes(texture: PhaseTexture) -> bytes:
    """The KTX2 file of ``texture`` (see the module docstring)."""
    from dustoptics import __version__

    check_dimensions(
        texture.width,
        texture.height,
        max_dimension=_CONTAINER_LIMIT,
        container="KTX2",
        container_limit=_CONTAINER_LIMIT,
    )
    pixels = texture.pixels
    if pixels.shape[2] == 3:  # no filterable RGB float format in Vulkan/WebGPU: RGBA with A = 1
        alpha = np.ones(pixels.shape[:2] + (1,), dtype=pixels.dtype)
        pixels = np.concatenate([pixels, alpha], axis=2)
    n_channels = pixels.shape[2]
    type_size = pixels.dtype.itemsize
    level = np.ascontiguousarray(pixels).tobytes(order="C")
    dfd = _dfd(n_channels, type_size)
    kvd = _key_value(
        {
            "KTXwriter": f"dustoptics {__version__}".encode() + b"\0",
            "dustoptics": metadata_json(texture).encode("utf-8") + b"\0",
        }
    )
    header_size = 12 + 9 * 4 + 4 * 4 + 2 * 8
    level_index_size = 24
    dfd_offset = header_size + level_index_size
    kvd_offset = dfd_offset + len(dfd)
    texel = n_channels * type_size
    alignment = math.lcm(texel, 4)
    data_start = kvd_offset + len(kvd)
    data_offset = data_start + (-data_start % alignment)
    out = bytearray(KTX2_IDENTIFIER)
    out += struct.pack(
        "<9I",
        VK_FORMATS[(n_channels, texture.precision)],
        type_size,
        texture.width,
        texture.height,
        0,  # pixelDepth: 2-D
        0,  # layerCount: not an array
        1,  # faceCount
        1,  # levelCount
        0,  # supercompressionScheme: none
    )
    out += struct.pack("<4I2Q", dfd_offset, len(dfd), kvd_offset, len(kvd), 0, 0)
    out += struct.pack("<3Q", data_offset, len(level), len(level))
    out += dfd + kvd
    out += b"\0" * (data_offset - len(out))
    out += level
    return bytes(out)


def write_ktx2(
    table: Any,
    out_dir_or_path: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    **options: Any,
) -> list[Path]:
    """Write the phase function as a KTX2 texture, atomically: the ``.ktx2`` file
    ``out_dir_or_path`` or a file in that directory, as
    :func:`~dustoptics.io.textures.phase_texture.write_container` (``**options``: the fields of
    :class:`~dustoptics.io.textures.phase_texture.TextureOptions`)."""
    return write_container(
        table,
        out_dir_or_path,
        suffix=".ktx2",
        encode=lambda texture, target: {target: ktx2_bytes(texture)},
        overwrite=overwrite,
        **options,
    )


def read_ktx2_metadata(
    path: str | os.PathLike[str], *, max_bytes: int | None = None
) -> dict[str, Any]:
    """The ``dustoptics`` metadata (sampling rule, axes, units, provenance) of a KTX2 texture.

    Reads the file's header, level index and key/value data only (Khronos KTX 2.0
    specification, sections 3 and 3.11).  Before anything else is read, the file must be a
    regular file of at most ``max_bytes`` (None:
    :data:`~dustoptics.io.describe_formats.MAX_READ_BYTES`); the header's format, its
    pixel size and count of levels, layers and faces, and the level index must describe one
    level of a format dustoptics writes whose bytes lie inside the file; and the metadata's
    width and height must be the header's.

    Raises
    ------
    dustoptics.io.FormatError
        Not a KTX2 file, a damaged or crafted one, or one without dustoptics' metadata; the
        message names the file, the field and the size.
    """
    p = Path(path)
    size = regular_size(p, limit_of(max_bytes))
    with open(p, "rb") as f:
        head = f.read(104)
        if len(head) < 80 or head[:12] != KTX2_IDENTIFIER:
            raise FormatError(f"{str(p)!r}: not a KTX2 file")
        width, height = _check_ktx2_header(p, head, size)
        kvd_offset, kvd_length = struct.unpack("<2I", head[56:64])
        if kvd_offset + kvd_length > size or kvd_length > 64 * 1024**2:
            raise FormatError(f"{str(p)!r}: its key/value data lies beyond the file (damaged)")
        f.seek(kvd_offset)
        kvd = f.read(kvd_length)
    entries, i = {}, 0
    while i + 4 <= len(kvd):
        (n,) = struct.unpack("<I", kvd[i : i + 4])
        entry = kvd[i + 4 : i + 4 + n]
        key, _, value = entry.partition(b"\0")
        entries[key.decode("utf-8", "replace")] = value.rstrip(b"\0")
        i += 4 + n + (-n % 4)
    if "dustoptics" not in entries:
        raise FormatError(f"{str(p)!r}: a KTX2 file without dustoptics' metadata")
    try:
        meta = json.loads(entries["dustoptics"].decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise FormatError(f"{str(p)!r}: its dustoptics metadata is not JSON (damaged)") from None
    if not isinstance(meta, dict):
        raise FormatError(f"{str(p)!r}: its dustoptics metadata is not a JSON object")
    if (meta.get("width"), meta.get("height")) != (width, height):
        raise FormatError(
            f"{str(p)!r}: its metadata says {meta.get('width')!r} x {meta.get('height')!r} "
            f"texels, its header {width} x {height} (damaged or crafted)"
        )
    return meta


def _check_ktx2_header(p: Path, head: bytes, size: int) -> tuple[int, int]:
    """(width, height) of a KTX2 header that describes one level of a format dustoptics
    writes, its bytes inside a file of ``size`` bytes; else FormatError."""
    vk_format, type_size, width, height, depth, layers, faces, levels, scheme = struct.unpack(
        "<9I", head[12:48]
    )
    channels = {fmt: n for (n, _), fmt in VK_FORMATS.items()}.get(vk_format)
    if channels is None or type_size not in (2, 4):
        raise FormatError(
            f"{str(p)!r}: vkFormat {vk_format} with typeSize {type_size} is not a format "
            "dustoptics writes (R/RGBA, 16- or 32-bit float)"
        )
    if (depth, layers, faces, levels, scheme) != (0, 0, 1, 1, 0) or len(head) < 104:
        raise FormatError(
            f"{str(p)!r}: declares depth {depth}, {layers} layers, {faces} faces, {levels} "
            f"levels, supercompression {scheme}: not the one 2-D level dustoptics writes"
        )
    offset, length, uncompressed = struct.unpack("<3Q", head[80:104])
    declared = width * height * channels * type_size
    if width < 1 or height < 1 or declared != uncompressed or length != uncompressed:
        raise FormatError(
            f"{str(p)!r}: its level declares {length} bytes ({uncompressed} uncompressed) for "
            f"{width} x {height} texels of {channels * type_size} bytes ({declared}): damaged "
            "or crafted"
        )
    if offset + length > size:
        raise FormatError(
            f"{str(p)!r}: its {width} x {height} level declares {length} bytes at offset "
            f"{offset}, beyond the file's {size} bytes (truncated or crafted); refused"
        )
    return width, height


def describe_ktx2(path: Path, full: bool = True) -> str:
    """What an KTX2 phase texture holds, from its metadata (``dustoptics info``)."""
    return describe_texture(path, read_ktx2_metadata(path), "KTX2", full)


RECORD = register(
    Format(
        name="ktx2",
        summary="NAME_phase_*.ktx2: the phase texture as KTX2",
        write=write_ktx2,
        suffixes=(".ktx2",),
        options=TextureOptions,
        recognise=lambda path: path.suffix.lower() == ".ktx2",
        describe=describe_ktx2,
    )
)
