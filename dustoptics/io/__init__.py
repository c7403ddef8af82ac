"""Readers and writers of :class:`dustoptics.table.Table` in renderers' formats.

One module per format, grouped in subpackages; each writes atomically (a
temporary file in the target directory, renamed into place;
:mod:`dustoptics.io._atomic`) and refuses to replace existing files unless asked
to (``overwrite=True``).  Readers raise :class:`FormatError` (a
:class:`ValueError`) naming the file and the problem.

Formats, grouped by what they are for (each subpackage lists its modules):

- :mod:`~dustoptics.io.tables`: the table file, CF-1.10 netCDF-4 (``.nc``, or the
  same bytes as ``.h5``), verified when read (:func:`open_table`,
  :func:`write_netcdf`, :func:`read_netcdf`; :meth:`dustoptics.table.Table.save`).
- :mod:`~dustoptics.io.csv`: CSV sets renderers read: the seed framework's files
  with a JSON provenance sidecar (:func:`write_seed_csv`, :func:`read_seed_csv`) and
  CosmoScout VR's per-constituent set (:func:`write_cosmoscout_constituent`,
  :func:`write_cosmoscout_set`, :func:`read_cosmoscout_constituent`,
  :func:`check_cosmoscout_set`).
- :mod:`~dustoptics.io.shaders`: the phase function as shader source, one
  generator and one module per language, each with the seed's lookup
  ``MiePhaseFunction(nu)`` (:func:`shader_source`, :func:`write_shader`): GLSL
  1.30+ and ES 1.00 (format ``glsl``: :func:`glsl_snippet`, :func:`write_glsl`),
  HLSL and WGSL (formats ``hlsl`` and ``wgsl``).
- :mod:`~dustoptics.io.textures`: the phase function as a texture: raw float32
  with a JSON sidecar (format ``texture``: :func:`write_texture`,
  :func:`read_texture`) and the texture engines load (angle x wavelength or angle
  x RGB, theta or cos(theta) columns, float32 or float16) in KTX 2.0, OpenEXR (the
  ``textures`` extra) or ``.npy`` (formats ``ktx2``, ``exr``, ``npy``).
- :mod:`~dustoptics.io.rt`: what radiative-transfer codes read, as plain text:
  DISORT's phase-function moments with ssa and extinction (format ``disort``) and
  libRadtran's ``aerosol_file explicit`` layer files (format ``libradtran``); both
  need ``compute_optics(expansion=...)``.
- :mod:`~dustoptics.io.engines`: parameters of engines' own models: Bruneton's
  precomputed atmospheric scattering (2017; as the ``bruneton`` format, one aerosol
  table's Mie part) and fitted analytic phase functions as JSON and constants.
- :mod:`~dustoptics.io.gcm`: the dust files of Mars GCMs, over a grid of radii: the LMD
  Mars PCM's visible and infrared files (formats ``lmd-dustvis``, ``lmd-dustir``) and the
  NASA Ames Mars GCM's band files (formats ``ames-dustvis``, ``ames-dustir``).
- :mod:`~dustoptics.io.outputs` (a table in several formats into ``OUT/NAME/``,
  beside what is there; :func:`read_table` of any table file) and
  :mod:`~dustoptics.io.describe` (what any file dustoptics writes holds).

:data:`FORMATS` maps a format name (the command line's ``--format``) to its record
(:class:`~dustoptics.io.registry.Format`): writer, options, needs, and how ``info``
reads its files.  Each format module registers its record when imported;
:data:`FORMAT_MODULES` below is the registration (adding a format: its module and one
line there), imported on the first look at :data:`FORMATS`.  The package's names are
imported on first use: writing one format imports that format's module only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.io import (
        csv,
        describe,
        engines,
        gcm,
        outputs,
        rt,
        shaders,
        tables,
        textures,
    )
    from dustoptics.io._atomic import FormatError
    from dustoptics.io.csv import (
        check_cosmoscout_set,
        read_cosmoscout_constituent,
        read_seed_csv,
        write_cosmoscout_constituent,
        write_cosmoscout_set,
        write_seed_csv,
    )
    from dustoptics.io.csv.cosmoscout import CosmoScoutConstituent
    from dustoptics.io.describe import describe_path, describe_table
    from dustoptics.io.outputs import (
        Placement,
        place_outputs,
        place_table,
        read_table,
        with_inputs,
        write_atmosphere_set,
        write_formats,
    )
    from dustoptics.io.registry import FORMATS, Format, FormatOptions, Writer, register, write
    from dustoptics.io.shaders import glsl_snippet, shader_source, write_glsl, write_shader
    from dustoptics.io.tables import open_table, read_hdf5, read_netcdf, write_hdf5, write_netcdf
    from dustoptics.io.textures import (
        read_texture,
        write_exr,
        write_ktx2,
        write_npy,
        write_texture,
    )

#: The modules that register the formats, one line each (adding a format: its module and
#: its line here).  The registry imports them on the first look at :data:`FORMATS`
#: (:func:`dustoptics.io.registry.load_formats`), not before: importing the package, or one
#: of its modules, imports no format's module.
FORMAT_MODULES = (
    "dustoptics.io.shaders.glsl",
    "dustoptics.io.shaders.hlsl",
    "dustoptics.io.shaders.wgsl",
    "dustoptics.io.textures.raw",
    "dustoptics.io.textures.exr",
    "dustoptics.io.textures.ktx2",
    "dustoptics.io.textures.npy",
    "dustoptics.io.engines.bruneton",
    "dustoptics.io.csv.cosmoscout",
    "dustoptics.io.csv.seed",
    "dustoptics.io.rt.disort",
    "dustoptics.io.rt.libradtran",
    "dustoptics.io.rt.libradtran_netcdf",
    "dustoptics.io.tables.netcdf",
    "dustoptics.io.gcm.ames",
    "dustoptics.io.gcm.lmd",
)

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.io._atomic": ("FormatError",),
    "dustoptics.io.csv": (
        "check_cosmoscout_set",
        "read_cosmoscout_constituent",
        "read_seed_csv",
        "write_cosmoscout_constituent",
        "write_cosmoscout_set",
        "write_seed_csv",
    ),
    "dustoptics.io.csv.cosmoscout": ("CosmoScoutConstituent",),
    "dustoptics.io.describe": ("describe_path", "describe_table"),
    "dustoptics.io.outputs": (
        "Placement",
        "place_outputs",
        "place_table",
        "read_table",
        "with_inputs",
        "write_atmosphere_set",
        "write_formats",
    ),
    "dustoptics.io.registry": ("FORMATS", "Format", "FormatOptions", "Writer", "register", "write"),
    "dustoptics.io.shaders": ("glsl_snippet", "shader_source", "write_glsl", "write_shader"),
    "dustoptics.io.tables": (
        "open_table",
        "read_hdf5",
        "read_netcdf",
        "write_hdf5",
        "write_netcdf",
    ),
    "dustoptics.io.textures": (
        "read_texture",
        "write_exr",
        "write_ktx2",
        "write_npy",
        "write_texture",
    ),
}


__all__ = [
    "FORMATS",
    "FORMAT_MODULES",
    "CosmoScoutConstituent",
    "Format",
    "FormatError",
    "FormatOptions",
    "Placement",
    "Writer",
    "check_cosmoscout_set",
    "csv",
    "describe",
    "describe_path",
    "describe_table",
    "engines",
    "gcm",
    "glsl_snippet",
    "open_table",
    "outputs",
    "place_outputs",
    "place_table",
    "read_cosmoscout_constituent",
    "read_hdf5",
    "read_netcdf",
    "read_seed_csv",
    "read_table",
    "read_texture",
    "register",
    "rt",
    "shader_source",
    "shaders",
    "tables",
    "textures",
    "with_inputs",
    "write",
    "write_atmosphere_set",
    "write_cosmoscout_constituent",
    "write_cosmoscout_set",
    "write_exr",
    "write_formats",
    "write_glsl",
    "write_hdf5",
    "write_ktx2",
    "write_netcdf",
    "write_npy",
    "write_seed_csv",
    "write_shader",
    "write_texture",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)
