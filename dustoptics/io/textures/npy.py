"""The phase-function texture as a NumPy ``.npy`` array with a JSON sidecar.

``<stem>.npy``: NumPy's format 1.0, little-endian float32 (``<f4``) or float16
(``<f2``), C order, shape (height, width, channels) (row, angle column,
channel).  The ``.npy`` header holds only dtype, order and shape, so the
sampling rule, axes, units, accuracy and provenance go into ``<stem>.json``
beside it (the texture metadata of :mod:`~dustoptics.io.textures.phase_texture`, plus
the array file's name and SHA-256).  Both files are written together, or
neither.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import Content
from dustoptics.io.registry import Format, register
from dustoptics.io.textures.phase_texture import (
    PhaseTexture,
    TextureOptions,
    write_container,
)

__all__ = ["write_npy"]


def _files(texture: PhaseTexture, npy_path: Path) -> dict[Path, Content]:
    """The ``.npy`` file of ``texture`` at ``npy_path`` and its ``.json`` sidecar beside it."""
    buffer = io.BytesIO()
    np.save(buffer, texture.pixels, allow_pickle=False)
    array_bytes = buffer.getvalue()
    sidecar = dict(texture.metadata)
    sidecar.update(
        {
            "file": npy_path.name,
            "sha256": hashlib.sha256(array_bytes).hexdigest(),
            "dtype": texture.pixels.dtype.str,
            "shape": list(texture.pixels.shape),
            "order": "C: (row, angle column, channel), channel fastest",
            "channel_names": list(texture.channel_names),
        }
    )
    text = json.dumps(sidecar, indent=2, sort_keys=True, allow_nan=False, ensure_ascii=True) + "\n"
    return {npy_path: array_bytes, npy_path.with_suffix(".json"): text.encode("ascii")}


def write_npy(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    **options: Any,
) -> list[Path]:
    """Write the phase-function texture as ``<stem>.npy`` and its ``<stem>.json`` sidecar in
    ``out_dir``, atomically, as :func:`~dustoptics.io.textures.phase_texture.write_container`
    (``**options``: the fields of :class:`~dustoptics.io.textures.phase_texture.TextureOptions`)."""
    return write_container(
        table,
        out_dir,
        suffix=".npy",
        encode=_files,
        overwrite=overwrite,
        accept_file_path=False,
        **options,
    )


RECORD = register(
    Format(
        name="npy",
        summary="NAME_phase_*.npy: the phase texture as NumPy .npy, JSON sidecar",
        write=write_npy,
        suffixes=(".npy", ".json"),
        options=TextureOptions,
    )
)
