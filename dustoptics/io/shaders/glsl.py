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
the versions it needs (its ``// requires:`` line):

``version="130"`` (language ``"glsl"``, the default)
    GLSL 1.30 and later, GLSL ES 3.00 and later: ``const vec3`` array and
    ``vec3 MiePhaseFunction(float nu)``, each version tested with
    glslangValidator in a full shader.
``version="100"`` (language ``"glsl100"``)
    GLSL ES 1.00 (WebGL 1).  That language has no array initializers and
    its Appendix A only guarantees array indexing by constant or loop index
    in fragment shaders, so a constant array cannot be indexed by a computed
    angle.  The samples are returned instead by a function,
    ``<prefix>_PHASE_SAMPLE(i)``, a balanced binary tree of comparisons on
    ``i`` whose leaves return the literals (ceil(log2 N) comparisons per
    call, no array, no loop, no texture).  Every declaration is ``highp``:
    the lookup needs float32 (fragment shaders must have
    ``GL_FRAGMENT_PRECISION_HIGH``; vertex shaders always do).

The content is the same in every language (:mod:`dustoptics.io.shaders.common`,
:func:`~dustoptics.io.shaders.common.shader_source`); this module spells it in
GLSL (:class:`GLSLSyntax`, :class:`GLSL100Syntax`) and keeps the GLSL names.

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

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._validation import check_choice
from dustoptics.io.registry import option, register
from dustoptics.io.shaders.common import (
    ACOS_AS4446,
    ACOS_METHODS,
    DEFAULT_CHANNELS_NM,
    DEFAULT_RESOLUTION_DEG,
    LOOKUP_COMMENT,
    SAFETY_COMMENT,
    ShaderChannels,
    ShaderOptions,
    ShaderSyntax,
    float_literal,
    register_syntax,
    shader_channels,
    shader_format,
    shader_source,
    write_shader,
)

__all__ = [
    "ACOS_AS4446",
    "ACOS_METHODS",
    "DEFAULT_CHANNELS_NM",
    "DEFAULT_RESOLUTION_DEG",
    "GLSL_VERSIONS",
    "GLSL100Syntax",
    "GLSLChannels",
    "GLSLSyntax",
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

# Keywords and reserved words an identifier of ours could collide with.
# GLSL 4.60 section 3.6 (with ES 1.00's and 3.x's); names with "__" or starting
# "gl_" are reserved too.
GLSL_KEYWORDS = frozenset(
    [
        "attribute",
        "const",
        "uniform",
        "varying",
        "buffer",
        "shared",
        "coherent",
        "volatile",
        "restrict",
        "readonly",
        "writeonly",
        "atomic_uint",
        "layout",
        "centroid",
        "flat",
        "smooth",
        "noperspective",
        "patch",
        "sample",
        "invariant",
        "precise",
        "break",
        "continue",
        "do",
        "for",
        "while",
        "switch",
        "case",
        "default",
        "if",
        "else",
        "subroutine",
        "in",
        "out",
        "inout",
        "int",
        "void",
        "bool",
        "true",
        "false",
        "float",
        "double",
        "discard",
        "return",
        "vec2",
        "vec3",
        "vec4",
        "ivec2",
        "ivec3",
        "ivec4",
        "bvec2",
        "bvec3",
        "bvec4",
        "uint",
        "uvec2",
        "uvec3",
        "uvec4",
        "dvec2",
        "dvec3",
        "dvec4",
        "mat2",
        "mat3",
        "mat4",
        "mat2x2",
        "mat2x3",
        "mat2x4",
        "mat3x2",
        "mat3x3",
        "mat3x4",
        "mat4x2",
        "mat4x3",
        "mat4x4",
        "dmat2",
        "dmat3",
        "dmat4",
        "lowp",
        "mediump",
        "highp",
        "precision",
        "sampler1D",
        "sampler2D",
        "sampler3D",
        "samplerCube",
        "struct",
        "common",
        "partition",
        "active",
        "asm",
        "class",
        "union",
        "enum",
        "typedef",
        "template",
        "this",
        "resource",
        "goto",
        "inline",
        "noinline",
        "public",
        "static",
        "extern",
        "external",
        "interface",
        "long",
        "short",
        "half",
        "fixed",
        "unsigned",
        "superp",
        "input",
        "output",
        "hvec2",
        "hvec3",
        "hvec4",
        "fvec2",
        "fvec3",
        "fvec4",
        "filter",
        "sizeof",
        "cast",
        "namespace",
        "using",
        "sampler3DRect",
        "texture",
        "main",
    ]
)


class GLSLSyntax(ShaderSyntax):
    """GLSL 1.30+ and GLSL ES 3.00+: ``const vec3`` array, C-style statements."""

    language = "glsl"
    label = "GLSL"
    extension = ".glsl"
    requirements = (
        "GLSL 1.30 or later (#version 130), or GLSL ES 3.00 or later (#version 300 es); "
        "include-ready (no #version line)"
    )
    keywords = GLSL_KEYWORDS
    vec3 = "vec3"

    def const_declaration(self, type_name: str, name: str, value: str) -> str:
        return f"const {type_name} {name} = {value};"

    def array_declaration(self, name: str, n_samples: int, count_name: str) -> tuple[str, str]:
        return f"const vec3 {name}[{count_name}] = vec3[](", ");"

    def float_array(self, name: str, values: Any) -> str:
        """A constant float array (GLSL 1.20 or GLSL ES 3.00 and later)."""
        n = len(values)
        items = ", ".join(self.lit(v) for v in values)
        return f"const float {name}[{n}] = float[{n}]({items});"


class GLSL100Syntax(GLSLSyntax):
    """GLSL ES 1.00 (WebGL 1): no arrays (a sample function instead), ``highp`` floats."""

    language = "glsl100"
    label = "GLSL ES 1.00"
    file_tail = "_phase_es100"
    requirements = (
        "GLSL ES 1.00 (#version 100, WebGL 1) and later; highp float in the calling stage "
        "(fragment shaders: GL_FRAGMENT_PRECISION_HIGH); no arrays, loops or textures "
        "(ES 1.00 Appendix A)"
    )
    precision = "highp "

    def array_lines(self, ch: ShaderChannels, names: Mapping[str, str]) -> list[str]:
        """None: the samples are :meth:`lookup_lines`' sample function."""
        return []

    def float_array(self, name: str, values: Any) -> str:
        """Refused (ValueError): GLSL ES 1.00 has no array initializers."""
        raise ValueError(f"{self.label} has no array initializers; got an array for {name!r}")

    def sample_tree(self, phase: np.ndarray, lo: int, hi: int, depth: int) -> list[str]:
        """Leaves that return the sample whose index equals i, by bisection on i."""
        indent = "    " * depth
        if lo == hi:
            return [f"{indent}return {self.vec(phase[lo])};"]
        mid = (lo + hi) // 2
        return (
            [f"{indent}if (i < {float(mid) + 0.5:.1f}) {{"]
            + self.sample_tree(phase, lo, mid, depth + 1)
            + [f"{indent}}}"]
            + self.sample_tree(phase, mid + 1, hi, depth)
        )

    def lookup_lines(
        self, ch: ShaderChannels, names: Mapping[str, str], function_name: str, acos: str
    ) -> list[str]:
        """The sample function ``<prefix>_PHASE_SAMPLE(i)``, then the lookup reading it."""
        n_name, k_name = names["PHASE_N"], names["PHASE_INDEX_PER_RAD"]
        sample = names["PHASE_SAMPLE"]
        n = ch.phase.shape[0]
        return [
            f"// Sample i (0 <= i <= {n - 1}, a whole number) of the phase function [sr^-1]:",
            f"// bisection on i, {math.ceil(math.log2(n))} comparisons (GLSL ES 1.00 has no constant arrays).",
            f"highp vec3 {sample}(highp float i)",
            "{",
            *self.sample_tree(ch.phase, 0, n - 1, 1),
            "}",
            "",
            LOOKUP_COMMENT,
            *self.function_open(function_name),
            *SAFETY_COMMENT,
            "    highp float c = clamp(nu, -1.0, 1.0);",
            *self.acos_lines(acos, names),
            f"    highp float x = clamp(theta * {k_name}, 0.0, float({n_name} - 1));",
            f"    highp float i = min(floor(x), float({n_name} - 2));",
            "    highp float f = x - i;",
            f"    return {sample}(i) * (1.0 - f) + {sample}(i + 1.0) * f;",
            "}",
        ]


register_syntax(GLSLSyntax())
register_syntax(GLSL100Syntax())


def glsl_float(value: Any) -> str:
    """GLSL literal of ``value`` rounded to float32, reading back to that float32 exactly.

    The shortest decimal that identifies the float32 (numpy's Dragon4 with
    ``unique=True``), always in exponent form with a decimal point, so GLSL
    reads a float (never an int).

    >>> glsl_float(1.0), glsl_float(0.1), glsl_float(-2.5e-13)
    ('1.0e+00', '1.0e-01', '-2.5e-13')
    """
    return float_literal(value)


def glsl_snippet(table: Any, *, version: str = "130", **options: Any) -> str:
    """GLSL source: the phase function as a constant array and its lookup function.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    **options
        The keywords of :func:`dustoptics.io.shaders.common.shader_source` but ``language``
        (``channels_nm``, ``colour``, ``resolution_deg``, ``prefix``, ``function_name``,
        ``min_band_coverage``, ``acos``).
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
    return shader_source(table, language=_LANGUAGE[version], **options)


def write_glsl(
    table: Any,
    out_dir_or_path: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    version: str = "130",
    **options: Any,
) -> list[Path]:
    """Write :func:`glsl_snippet` (:func:`~dustoptics.io.shaders.common.write_shader` with the
    ``language`` of ``version``, ``"130"`` or ``"100"``: ``<table name>_phase_es100.glsl``)."""
    check_choice("version", version, GLSL_VERSIONS)
    return write_shader(
        table, out_dir_or_path, language=_LANGUAGE[version], overwrite=overwrite, **options
    )


@dataclass(frozen=True)
class GLSLOptions(ShaderOptions):
    """The glsl format's options: :class:`~dustoptics.io.shaders.common.ShaderOptions` and the
    language version (None: ``"130"``)."""

    glsl_version: str | None = option(
        help="130 = GLSL 1.30+ and ES 3.00+ (default); 100 = GLSL ES 1.00 (WebGL 1)",
        choices=list(GLSL_VERSIONS),
    )

    def keywords(self) -> dict[str, Any]:
        """The keywords of :func:`write_glsl`."""
        out = super().keywords()
        if self.glsl_version is not None:
            out["version"] = self.glsl_version
        return out


RECORD = register(
    shader_format(
        "glsl",
        summary="NAME_phase.glsl: MiePhaseFunction(nu), GLSL 1.30+ or ES 1.00",
        write=write_glsl,
        options=GLSLOptions,
    )
)
