"""Readers and writers of :class:`dustoptics.table.Table` in renderers' formats.

One module per format; each writes atomically (a temporary file in the target
directory, renamed into place; :mod:`dustoptics.io._atomic`) and refuses to
replace existing files unless asked to (``overwrite=True``).  Readers raise
:class:`FormatError` (a :class:`ValueError`) naming the file and the problem.

- :mod:`~dustoptics.io.netcdf`: one CF-1.10 netCDF-4 file (``.nc``, or the same
  bytes as ``.h5``), verified when read (:func:`open_table`, :func:`write_netcdf`,
  :func:`read_netcdf`; :meth:`dustoptics.table.Table.save`).
- :mod:`~dustoptics.io.seed_csv`: the seed framework's CSV files with a JSON
  provenance sidecar (:func:`write_seed_csv`, :func:`read_seed_csv`).
- :mod:`~dustoptics.io.cosmoscout`: CosmoScout VR's per-constituent CSV set
  (:func:`write_cosmoscout_constituent`, :func:`write_cosmoscout_set`,
  :func:`read_cosmoscout_constituent`, :func:`check_cosmoscout_set`).
- :mod:`~dustoptics.io.shader`: the phase function as shader source, one
  generator for GLSL (1.30+ and ES 1.00), HLSL and WGSL, each with the seed's
  lookup ``MiePhaseFunction(nu)`` (:func:`shader_source`, :func:`write_shader`;
  formats ``hlsl`` and ``wgsl``).
- :mod:`~dustoptics.io.glsl`: the GLSL snippet (format ``glsl``:
  :func:`glsl_snippet`, :func:`write_glsl`).
- :mod:`~dustoptics.io.texture`: a raw little-endian float32 texture (angle x
  wavelength) with a JSON sidecar (:func:`write_texture`, :func:`read_texture`).
- :mod:`~dustoptics.io.phase_texture`: the texture engines load (angle x
  wavelength or angle x RGB, theta or cos(theta) columns, float32 or float16)
  with its metadata, written by :mod:`~dustoptics.io.ktx2` (KTX 2.0, the
  sampling rule in its key/value data), :mod:`~dustoptics.io.exr` (OpenEXR,
  in a header attribute; the ``textures`` extra) and :mod:`~dustoptics.io.npy`
  (``.npy`` with a JSON sidecar): formats ``ktx2``, ``exr``, ``npy``.
- :mod:`~dustoptics.io.bruneton`: the parameters of Bruneton's precomputed
  atmospheric scattering (2017) for a whole atmosphere
  (:func:`~dustoptics.io.bruneton.write_bruneton`) or, as the ``bruneton``
  format, one aerosol table's Mie part and phase-function snippet.
- :mod:`~dustoptics.io.rt_text`: what radiative-transfer codes read, as plain
  text: DISORT's phase-function moments with ssa and extinction (format
  ``disort``) and libRadtran's ``aerosol_file explicit`` layer files (format
  ``libradtran``); both need ``compute_optics(expansion=...)``.

:data:`FORMATS` maps a format name (the command line's ``--format``) to a
writer ``writer(table, out_dir, *, overwrite=False, **options) -> list[Path]``
that writes one table into a directory.  Each format module registers its
writer here when imported; this package imports them all.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from dustoptics.io._atomic import FormatError

#: A writer of one table into a directory: ``(table, out_dir, *, overwrite, **options) -> paths``.
Writer = Callable[..., list[Path]]

#: Format name -> writer; filled by each format module when it is imported.
FORMATS: dict[str, Writer] = {}


def register_format(name: str, writer: Writer) -> None:
    """Register ``writer`` under ``name`` in :data:`FORMATS` (names are unique)."""
    if name in FORMATS and FORMATS[name] is not writer:
        raise ValueError(f"format {name!r} is already registered (to {FORMATS[name].__qualname__})")
    FORMATS[name] = writer


def write(
    table: Any, out_dir: Any, *, format: str, overwrite: bool = False, **options: Any
) -> list[Path]:
    """Write ``table`` into ``out_dir`` in the named format (see :data:`FORMATS`).

    Raises
    ------
    ValueError
        Unknown format (the message lists the valid names).
    """
    if format not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(map(repr, FORMATS))}; got {format!r}")
    return FORMATS[format](table, out_dir, overwrite=overwrite, **options)


from dustoptics.io import (
    bruneton,
    cosmoscout,
    exr,
    glsl,
    ktx2,
    npy,
    phase_texture,
    rt_text,
    seed_csv,
    shader,
    tables,
    texture,
)
from dustoptics.io.cosmoscout import (
    CosmoScoutConstituent,
    check_cosmoscout_set,
    read_cosmoscout_constituent,
    write_cosmoscout_constituent,
    write_cosmoscout_set,
)
from dustoptics.io.exr import write_exr
from dustoptics.io.glsl import glsl_snippet, write_glsl
from dustoptics.io.ktx2 import write_ktx2
from dustoptics.io.npy import write_npy
from dustoptics.io.seed_csv import read_seed_csv, write_seed_csv
from dustoptics.io.shader import shader_source, write_shader
from dustoptics.io.tables import open_table, read_hdf5, read_netcdf, write_hdf5, write_netcdf
from dustoptics.io.texture import read_texture, write_texture

__all__ = [
    "FORMATS",
    "CosmoScoutConstituent",
    "FormatError",
    "Writer",
    "bruneton",
    "check_cosmoscout_set",
    "cosmoscout",
    "exr",
    "glsl",
    "glsl_snippet",
    "ktx2",
    "npy",
    "open_table",
    "phase_texture",
    "read_cosmoscout_constituent",
    "read_hdf5",
    "read_netcdf",
    "read_seed_csv",
    "read_texture",
    "register_format",
    "rt_text",
    "seed_csv",
    "shader",
    "shader_source",
    "tables",
    "texture",
    "write",
    "write_cosmoscout_constituent",
    "write_cosmoscout_set",
    "write_exr",
    "write_glsl",
    "write_hdf5",
    "write_ktx2",
    "write_netcdf",
    "write_npy",
    "write_seed_csv",
    "write_shader",
    "write_texture",
]
