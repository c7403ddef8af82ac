"""A self-contained GLSL snippet with the phase function as a constant array.

The snippet follows the seed shader: a constant array of ``vec3`` (three
channels, by default R, G, B = 680, 550, 440 nm) sampled uniformly over
0..180 deg, and ``vec3 MiePhaseFunction(float nu)`` that takes the cosine of
the scattering angle, computes ``x = (N - 1) acos(nu) / pi`` and interpolates
linearly between samples ``floor(x)`` and ``floor(x) + 1``.  By default
``acos`` is computed by a polynomial in the snippet (Abramowitz & Stegun
4.4.46, error 2.5e-7 rad in float32), because GLSL leaves the builtin's
precision to the driver (Mesa llvmpipe's is off by up to 1.6e-4 rad);
``acos="builtin"`` keeps the seed's call.  Per-channel
constants give the asymmetry parameter and, when the table has them, the
cross-sections, single-scattering albedo and volume coefficients.

Versions
--------
The snippet is include-ready (no ``#version`` line) and its header states
the versions it needs: GLSL 1.30 or later, or GLSL ES 3.00 or later
(``version="130"``, the default).  ``version="100"`` gives the GLSL ES 1.00
(WebGL 1) variant, without arrays (see :mod:`dustoptics.io.shaders.common`).

The generator is shared with HLSL and WGSL in :mod:`dustoptics.io.shaders.common`
(:func:`~dustoptics.io.shaders.common.shader_source`); this module keeps the GLSL
names.

Channels
--------
Either three wavelengths (``channels_nm``, any order) or three colour channels
(``colour="cie1931-xyz"`` or ``colour="linear-srgb-astmg173"``), all made by
:func:`dustoptics.colour.channel_weights`:

- A channel wavelength that is on the table's grid takes the table's row
  unchanged; one between two grid wavelengths takes the linear interpolation
  in wavelength of the two rows.  A wavelength outside the table's range is an
  error: nothing is extrapolated.
- ``"cie1931-xyz"`` averages the table over wavelength with the CIE 1931
  2-degree colour-matching functions x̄, ȳ, z̄ (the CIE's 1 nm table) as
  weights, in the channel order x, y, z (long, middle, short wavelengths: the
  roles of R, G, B); ``"linear-srgb-astmg173"`` gives linear sRGB channels of
  the table lit by the ASTM G173 sun, white-balanced to the sun, so that a
  renderer with a white sun reproduces the spectral single-scattering colour.
- With cross-sections in the table, each channel's phase function is
  weighted by the scattering cross-section
  (:func:`dustoptics.colour.channel_phase`).

Angles
------
The table is resampled to ``N = 180 / resolution_deg + 1`` angles by linear
interpolation in angle (:meth:`dustoptics.table.Table.phase_at`, the
interpolation the shader also applies), then each value is rounded to float32
and written as the shortest decimal literal that reads back as that float32.
The header records the sphere integral of each channel as the shader
interpolates it, so a user sees what resampling did to the normalization.

Everything is deterministic: the same table and options give the same bytes.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dustoptics._validation import check_choice
from dustoptics.io import register_format
from dustoptics.io.shaders.common import (
    ACOS_AS4446,
    ACOS_METHODS,
    DEFAULT_CHANNELS_NM,
    DEFAULT_RESOLUTION_DEG,
    ShaderChannels,
    float_literal,
    shader_channels,
    shader_source,
    write_shader,
)

__all__ = [
    "ACOS_AS4446",
    "ACOS_METHODS",
    "DEFAULT_CHANNELS_NM",
    "DEFAULT_RESOLUTION_DEG",
    "GLSL_VERSIONS",
    "GLSLChannels",
    "glsl_channels",
    "glsl_float",
    "glsl_snippet",
    "write_glsl",
]

#: GLSL variants: "130" (GLSL 1.30+ and ES 3.00+) and "100" (GLSL ES 1.00, WebGL 1).
GLSL_VERSIONS = ("130", "100")

_LANGUAGE = {"130": "glsl", "100": "glsl100"}

#: The three channels a snippet holds (the shared :class:`~dustoptics.io.shaders.common.ShaderChannels`).
GLSLChannels = ShaderChannels

#: The channel data of :func:`glsl_snippet` (:func:`~dustoptics.io.shaders.common.shader_channels`).
glsl_channels = shader_channels


def glsl_float(value: Any) -> str:
    """GLSL literal of ``value`` rounded to float32, reading back to that float32 exactly.

    The shortest decimal that identifies the float32 (numpy's Dragon4 with
    ``unique=True``), always in exponent form with a decimal point, so GLSL
    reads a float (never an int).

    >>> glsl_float(1.0), glsl_float(0.1), glsl_float(-2.5e-13)
    ('1.0e+00', '1.0e-01', '-2.5e-13')
    """
    return float_literal(value)


def glsl_snippet(
    table: Any,
    *,
    channels_nm: Any = None,
    colour: str | None = None,
    resolution_deg: float = DEFAULT_RESOLUTION_DEG,
    prefix: str = "MIE",
    function_name: str = "MiePhaseFunction",
    min_band_coverage: float = 0.99,
    acos: str = "polynomial",
    version: str = "130",
) -> str:
    """GLSL source: the phase function as a constant array and its lookup function.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    channels_nm, colour, resolution_deg, prefix, function_name, min_band_coverage, acos
        As :func:`dustoptics.io.shaders.common.shader_source`.
    version : {"130", "100"}
        ``"130"`` (default): GLSL 1.30 and later, GLSL ES 3.00 and later, a
        ``const vec3`` array and ``vec3 MiePhaseFunction(float nu)``.
        ``"100"``: GLSL ES 1.00 (WebGL 1), the samples returned by a function
        (ES 1.00 has no array initializers), every declaration ``highp``.

    Returns
    -------
    str
        GLSL source (ASCII, ``\\n`` line ends) with no ``#version`` line; its
        header's ``// requires:`` line states the versions it compiles with.

    Raises
    ------
    ValueError
        As :func:`~dustoptics.io.shaders.common.shader_source`, or an unknown ``version``.

    Examples
    --------
    >>> src = glsl_snippet(table)                                        # doctest: +SKIP
    >>> webgl1 = glsl_snippet(table, version="100", prefix="DUST",
    ...                       function_name="DustPhase")                  # doctest: +SKIP
    """
    check_choice("version", version, GLSL_VERSIONS)
    return shader_source(
        table,
        language=_LANGUAGE[version],
        channels_nm=channels_nm,
        colour=colour,
        resolution_deg=resolution_deg,
        prefix=prefix,
        function_name=function_name,
        min_band_coverage=min_band_coverage,
        acos=acos,
    )


def write_glsl(
    table: Any,
    out_dir_or_path: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    channels_nm: Any = None,
    colour: str | None = None,
    resolution_deg: float = DEFAULT_RESOLUTION_DEG,
    prefix: str = "MIE",
    function_name: str = "MiePhaseFunction",
    min_band_coverage: float = 0.99,
    acos: str = "polynomial",
    version: str = "130",
) -> list[Path]:
    """Write :func:`glsl_snippet` to a file, atomically.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    out_dir_or_path : path-like
        A path ending in ``.glsl`` is the file to write; anything else is a
        directory (created if missing) that receives
        ``<table name>_phase.glsl`` (``version="100"``:
        ``<table name>_phase_es100.glsl``; characters other than letters,
        digits, ``.``, ``_`` and ``-`` replaced by ``_``).
    overwrite : bool
        Replace an existing file.  Default False.
    channels_nm, colour, resolution_deg, prefix, function_name, min_band_coverage, acos, version
        As in :func:`glsl_snippet`.

    Returns
    -------
    list of pathlib.Path
        The written file.

    Raises
    ------
    FileExistsError
        The file exists and ``overwrite`` is False (nothing is written).
    ValueError
        As :func:`glsl_snippet`.
    """
    check_choice("version", version, GLSL_VERSIONS)
    return write_shader(
        table,
        out_dir_or_path,
        language=_LANGUAGE[version],
        overwrite=overwrite,
        channels_nm=channels_nm,
        colour=colour,
        resolution_deg=resolution_deg,
        prefix=prefix,
        function_name=function_name,
        min_band_coverage=min_band_coverage,
        acos=acos,
    )


register_format("glsl", write_glsl)
