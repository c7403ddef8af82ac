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

Channels
--------
Either three wavelengths (``channels_nm``, any order) or three colour channels
(``colour="cie1931-xyz"`` or ``colour="linear-srgb-astmg173"``), all made by
:func:`dustoptics.colour.channel_weights`:

- A channel wavelength that is on the table's grid takes the table's row
  unchanged; one between two grid wavelengths takes the linear interpolation
  in wavelength of the two rows (a convex combination, so it stays a
  nonnegative, normalized phase function, and cross-sections and g are
  interpolated the same way).  A wavelength outside the table's range is an
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

import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._validation import check_choice, check_positive
from dustoptics.colour import CHANNEL_MODES, DEFAULT_CHANNELS_NM, channel_phase, channel_weights
from dustoptics.io import register_format
from dustoptics.io._atomic import write_files
from dustoptics.io.texture import _safe_stem
from dustoptics.scattering.phase import sphere_integral
from dustoptics.table import PHASE_NORMALIZATION

__all__ = [
    "ACOS_AS4446",
    "ACOS_METHODS",
    "DEFAULT_CHANNELS_NM",
    "DEFAULT_RESOLUTION_DEG",
    "GLSLChannels",
    "glsl_channels",
    "glsl_float",
    "glsl_snippet",
    "write_glsl",
]

#: The seed shader's channels R, G, B. [nm]

#: The seed shader's angular step (721 samples over 0..180 deg). [deg]
DEFAULT_RESOLUTION_DEG = 0.25

# Colour modes of ``colour=`` (the three-wavelength mode is ``channels_nm``).
_COLOUR_MODES = tuple(m for m in CHANNEL_MODES if m != "wavelengths")

#: How the snippet computes acos: its own polynomial (default) or GLSL's builtin.
ACOS_METHODS = ("polynomial", "builtin")

#: Coefficients a0..a7 of acos(x) = sqrt(1 - x) (a0 + a1 x + ... + a7 x^7), 0 <= x <= 1,
#: absolute error <= 2e-8 rad: M. Abramowitz and I. A. Stegun, Handbook of Mathematical
#: Functions (1964), formula 4.4.46 (after C. Hastings, 1955).
ACOS_AS4446 = (
    1.5707963050,
    -0.2145988016,
    0.0889789874,
    -0.0501743046,
    0.0308918810,
    -0.0170881256,
    0.0066700901,
    -0.0012624911,
)

_UM2_TO_M2 = 1e-12

_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")

# Keywords and reserved words of GLSL 4.60 (section 3.6) that an identifier of
# ours could collide with; names with "__" or starting "gl_" are reserved too.
_GLSL_KEYWORDS = frozenset(
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


@dataclass(frozen=True)
class GLSLChannels:
    """The three channels a GLSL snippet holds, before formatting.

    Attributes
    ----------
    mode : str
        One of :data:`dustoptics.colour.CHANNEL_MODES`.
    wavelength_nm : numpy.ndarray, shape (3,)
        The channel wavelengths, or each band's weighted mean wavelength. [nm]
    descriptions : tuple of str
        How each channel was made from the table (grid member, interpolated
        between two wavelengths with their weights, or band weighting).
    weights : numpy.ndarray, shape (3, n_wavelength)
        Weights over the table's wavelengths, rows summing to 1 (nonnegative
        except for linear sRGB): every channel cross-section and g is
        ``weights @`` the table's rows; the phase function is weighted by
        scattering as well (:func:`dustoptics.colour.channel_phase`). [-]
    theta_deg : numpy.ndarray, shape (n_angles,)
        The uniform angle grid of the array, 0 to 180. [deg]
    phase : numpy.ndarray of float32, shape (n_angles, 3)
        The constant array as the shader holds it. [sr^-1]
    sphere_integral : numpy.ndarray, shape (3,)
        2 pi int P dmu of each channel of ``phase`` read by linear
        interpolation in angle (what the shader computes); 1 up to resampling
        and float32 rounding. [-]
    g : numpy.ndarray, shape (3,)
        Asymmetry parameter of each channel (channel weights applied to the
        table's g). [-]
    cext_m2, csca_m2 : numpy.ndarray or None, shape (3,)
        Mean cross-sections per particle, or None for a phase-only table. [m^2]
    number_density_per_m3 : float or None
        Number density of the table's beta coefficients. [m^-3]
    """

    mode: str
    wavelength_nm: np.ndarray
    descriptions: tuple[str, ...]
    weights: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray
    sphere_integral: np.ndarray
    g: np.ndarray
    cext_m2: np.ndarray | None
    csca_m2: np.ndarray | None
    number_density_per_m3: float | None


def glsl_float(value: Any) -> str:
    """GLSL literal of ``value`` rounded to float32, reading back to that float32 exactly.

    The shortest decimal that identifies the float32 (numpy's Dragon4 with
    ``unique=True``), always in exponent form with a decimal point, so GLSL
    reads a float (never an int).

    >>> glsl_float(1.0), glsl_float(0.1), glsl_float(-2.5e-13)
    ('1.0e+00', '1.0e-01', '-2.5e-13')
    """
    with np.errstate(over="ignore"):
        x = np.float32(value)
    if not np.isfinite(x):
        raise ValueError(f"value must be finite as float32 to be written to GLSL; got {value!r}")
    return np.format_float_scientific(x, unique=True, trim="0", exp_digits=2)


def _check_identifier(name: str, value: Any) -> str:
    if (
        not isinstance(value, str)
        or not _IDENTIFIER.match(value)
        or "__" in value
        or value.startswith("gl_")
        or value in _GLSL_KEYWORDS
    ):
        raise ValueError(
            f"{name} must be a valid GLSL identifier (letters, digits and '_', not starting with "
            f"a digit or 'gl_', no '__', not a GLSL keyword); got {value!r}"
        )
    return value


def _grid_count(resolution_deg: Any) -> int:
    step = check_positive("resolution_deg", resolution_deg, unit="deg")
    intervals = 180.0 / step
    n = round(intervals)
    if n < 1 or abs(intervals - n) > 1e-9 * n:
        raise ValueError(
            f"resolution_deg must divide 180 deg into a whole number of steps "
            f"(e.g. 0.1, 0.25, 0.5, 1); got {resolution_deg!r} ({intervals:g} steps)"
        )
    return n + 1


def _fmt_nm(x: float) -> str:
    return f"{x:g}"


def glsl_channels(
    table: Any,
    *,
    channels_nm: Any = None,
    colour: str | None = None,
    resolution_deg: float = DEFAULT_RESOLUTION_DEG,
    min_band_coverage: float = 0.99,
) -> GLSLChannels:
    """The channel data of :func:`glsl_snippet`, as arrays.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    channels_nm : sequence of 3 floats, optional
        Channel wavelengths in vec3 order, within the table's wavelength
        range; default (680, 550, 440) (the seed's R, G, B) unless ``colour``
        is given. [nm]
    colour : {"cie1931-xyz", "linear-srgb-astmg173"}, optional
        Colour channels instead of wavelengths (see
        :func:`dustoptics.colour.channel_weights`).
        Not together with ``channels_nm``.
    resolution_deg : float
        Angular step of the array; must divide 180. Default 0.25. [deg]
    min_band_coverage : float
        For ``colour``: smallest fraction of each colour-matching function's
        integral over 360-830 nm the table's range must hold. [-]

    Returns
    -------
    GLSLChannels
    """
    if colour is not None and channels_nm is not None:
        raise ValueError(
            f"give either channels_nm (wavelengths) or colour (bands), not both; got "
            f"channels_nm={channels_nm!r} and colour={colour!r}"
        )
    n_angles = _grid_count(resolution_deg)
    wavelength = np.asarray(table.wavelength_nm, dtype=np.float64)
    if colour is not None:
        check_choice("colour", colour, _COLOUR_MODES)
        chosen = channel_weights(wavelength, mode=colour, min_coverage=min_band_coverage)
    else:
        chosen = channel_weights(
            wavelength,
            mode="wavelengths",
            channels_nm=DEFAULT_CHANNELS_NM if channels_nm is None else channels_nm,
        )
    weights = np.array(chosen.weights)
    centres = np.array(chosen.centroid_nm)
    descriptions = chosen.descriptions
    mode = chosen.mode
    theta = np.linspace(0.0, 180.0, n_angles)
    # Scattering-weighted channels when the table has cross-sections, so that
    # csca_c * P_c is the channel of csca * P (see dustoptics.colour.channel_phase).
    phase64 = channel_phase(
        chosen, np.asarray(table.phase_at(theta), dtype=np.float64), csca_um2=table.csca_um2
    )
    phase32 = np.ascontiguousarray(phase64.T.astype(np.float32))
    integral = np.asarray(sphere_integral(phase32.T.astype(np.float64), theta_deg=theta))
    g = channel_phase(
        chosen, np.asarray(table.g, dtype=np.float64)[:, None], csca_um2=table.csca_um2
    )[:, 0]
    cext = csca = None
    if table.cext_um2 is not None:
        cext = weights @ np.asarray(table.cext_um2, dtype=np.float64) * _UM2_TO_M2
        csca = weights @ np.asarray(table.csca_um2, dtype=np.float64) * _UM2_TO_M2
    for array in (weights, centres, theta, phase32, integral, g, cext, csca):
        if array is not None:
            array.setflags(write=False)
    return GLSLChannels(
        mode=mode,
        wavelength_nm=centres,
        descriptions=descriptions,
        weights=weights,
        theta_deg=theta,
        phase=phase32,
        sphere_integral=integral,
        g=g,
        cext_m2=cext,
        csca_m2=csca,
        number_density_per_m3=table.number_density_per_m3 if cext is not None else None,
    )


def _vec3(values: Any) -> str:
    return "vec3(" + ", ".join(glsl_float(v) for v in values) + ")"


def _const(kind: str, name: str, value: str, comment: str) -> str:
    """One constant declaration with its unit comment."""
    return f"const {kind} {name} = {value};  // {comment}"


def _text(value: Any) -> str:
    """One-line ASCII rendering of free text for a comment (quoted, escaped)."""
    return json.dumps(str(value), ensure_ascii=True)


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
) -> str:
    """GLSL source: the phase function as a constant array and its lookup function.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    channels_nm : sequence of 3 floats, optional
        Channel wavelengths in vec3 order (.x, .y, .z), each on the table's
        grid (its row is used as it is) or between two grid wavelengths
        (linear interpolation in wavelength); default (680, 550, 440), the
        seed's R, G, B. [nm]
    colour : {"cie1931-xyz", "linear-srgb-astmg173"}, optional
        Colour bands instead: averages over wavelength weighted by the CIE
        1931 2-degree observer (:func:`dustoptics.colour.channel_weights`).
    resolution_deg : float
        Angular step of the array; must divide 180.  Default 0.25 (721
        samples, the seed's). [deg]
    prefix : str
        Prefix of the constants (``<prefix>_PHASE_N``, ``<prefix>_PHASE``,
        ``<prefix>_G``, ...), so two snippets can share a shader.  Default
        ``"MIE"``.
    function_name : str
        Name of the lookup function; default ``"MiePhaseFunction"`` (the seed's).
    min_band_coverage : float
        With ``colour``: smallest accepted fraction of each colour-matching
        function's 360-830 nm integral within the table's range. [-]
    acos : {"polynomial", "builtin"}
        How the lookup computes the angle from ``nu``: ``"polynomial"``
        (default), Abramowitz & Stegun 4.4.46 evaluated in float32 (error
        2.5e-7 rad, measured against float64 over [-1, 1]), the same on every
        driver; or ``"builtin"``, GLSL's ``acos`` as the seed shader, whose
        precision the GL specification leaves to the driver (Mesa llvmpipe:
        errors up to 1.6e-4 rad, 0.04 of a 0.25 deg step, measured).

    Returns
    -------
    str
        GLSL source (ASCII, ``\\n`` line ends) with no ``#version`` line, valid
        in GLSL 3.30 and later (and GLSL ES 3.00): a comment header, then

        - ``const int <prefix>_PHASE_N``: number of samples N;
        - ``const vec3 <prefix>_PHASE[N]``: phase function [sr^-1] at
          ``theta_j = 180 j / (N - 1)`` deg, channel per component;
        - ``const vec3 <prefix>_WAVELENGTH_NM``: channel wavelengths (band
          mean wavelengths in colour mode) [nm];
        - ``const vec3 <prefix>_G``: asymmetry parameter [-];
        - with cross-sections: ``<prefix>_CEXT_M2``, ``<prefix>_CSCA_M2``,
          ``<prefix>_CABS_M2`` [m^2] and ``<prefix>_SSA`` [-];
        - with a number density as well: ``<prefix>_NUMBER_DENSITY_PER_M3``
          (float) [m^-3] and ``<prefix>_BETA_EXT_PER_M``,
          ``<prefix>_BETA_SCA_PER_M``, ``<prefix>_BETA_ABS_PER_M`` [m^-1];
        - ``vec3 <function_name>(float nu)``: the phase function [sr^-1] at
          ``nu = cos(theta)``.

    Raises
    ------
    ValueError
        A channel wavelength outside the table's range, both ``channels_nm``
        and ``colour``, a resolution that does not divide 180 deg, an invalid
        identifier, or too little band coverage; the message names the
        parameter, the value and what is allowed.

    Notes
    -----
    The lookup computes ``x = acos(clamp(nu, -1, 1)) * (N - 1) / pi``
    (``acos`` per the ``acos`` option),
    ``i = min(int(x), N - 2)``, ``f = x - i`` and returns
    ``P[i] (1 - f) + P[i + 1] f``.  The clamp of ``nu`` (and of ``x`` to
    [0, N - 1]) is numerical safety only: a cosine computed as a dot product
    of unit vectors can exceed 1 in magnitude by rounding, where ``acos`` is
    undefined.  Since ``x`` is linear in ``theta``, the shader interpolates
    linearly in angle, as :meth:`~dustoptics.table.Table.phase_at` does; the
    seed divides by pi after multiplying, this multiplies by the float32 of
    (N - 1)/pi (a difference of float32 rounding).

    Examples
    --------
    >>> src = glsl_snippet(table)                                        # doctest: +SKIP
    >>> src_colour = glsl_snippet(table, colour="cie1931-xyz", prefix="DUST_RGB",
    ...                           function_name="DustPhase")              # doctest: +SKIP
    """
    from dustoptics import __version__

    check_choice("acos", acos, ACOS_METHODS)
    prefix = _check_identifier("prefix", prefix)
    function_name = _check_identifier("function_name", function_name)
    names = {
        key: _check_identifier("prefix", f"{prefix}_{key}")
        for key in (
            "PHASE_N",
            "PHASE",
            "PHASE_INDEX_PER_RAD",
            "WAVELENGTH_NM",
            "G",
            "CEXT_M2",
            "CSCA_M2",
            "CABS_M2",
            "SSA",
            "NUMBER_DENSITY_PER_M3",
            "BETA_EXT_PER_M",
            "BETA_SCA_PER_M",
            "BETA_ABS_PER_M",
        )
    }
    if function_name in names.values():
        raise ValueError(
            f"function_name must differ from the constants' names; got {function_name!r}"
        )
    ch = glsl_channels(
        table,
        channels_nm=channels_nm,
        colour=colour,
        resolution_deg=resolution_deg,
        min_band_coverage=min_band_coverage,
    )
    n = ch.theta_deg.size
    step = 180.0 / (n - 1)
    source_angles = np.asarray(table.theta_deg)
    same_grid = source_angles.size == n and np.array_equal(source_angles, ch.theta_deg)
    resampling = (
        f"the table's own {n} angles (no resampling)"
        if same_grid
        else f"the table's {source_angles.size} angles read by linear interpolation in angle "
        "(Table.phase_at)"
    )
    if ch.mode == "wavelengths":
        channel_line = (
            "channels (.x, .y, .z): "
            + ", ".join(f"{_fmt_nm(w)} nm" for w in ch.wavelength_nm)
            + " (wavelengths)"
        )
    else:
        channel_line = f"channels (.x, .y, .z): {ch.mode} (dustoptics.colour.channel_weights)"
    lines = [
        f"// dustoptics {__version__}: phase function of table {_text(table.name)} for GLSL.",
        f"// input_hash (SHA-256 of the table's inputs): {table.provenance.input_hash}",
        f"// {channel_line}",
    ]
    lines += [f"//   .{axis}: {desc}" for axis, desc in zip("xyz", ch.descriptions)]
    sources = ", ".join(_text(s.name) for s in table.provenance.sources) or "none recorded"
    lines += [
        f"// sources: {sources}",
        "// units: phase function [sr^-1]; nu = cos(scattering angle) [-], nu = 1 forward;",
        "//   wavelengths [nm]; cross-sections [m^2]; beta coefficients [m^-1]",
        f"// normalization: {PHASE_NORMALIZATION}",
        f"// resolution: {step:g} deg, {n} samples theta_j = 180 j / {n - 1} deg, j = 0..{n - 1}",
        f"// resampling: {resampling}, then rounded to float32",
        "//   (each literal is the shortest decimal that reads back as that float32)",
        "// sphere integral 2 pi int P dmu of each channel as interpolated below: "
        + ", ".join(f"{v:.7f}" for v in ch.sphere_integral),
        f"// lookup: x = ({n - 1}) acos(nu) / pi, linear interpolation between samples",
        "//   floor(x) and floor(x) + 1 (linear in angle, as Table.phase_at); acos: "
        + ("GLSL builtin" if acos == "builtin" else "Abramowitz & Stegun 4.4.46 polynomial"),
        "",
        f"const int {names['PHASE_N']} = {n};",
        _const(
            "float",
            names["PHASE_INDEX_PER_RAD"],
            glsl_float((n - 1) / math.pi),
            "(N - 1) / pi [rad^-1]",
        ),
        _const(
            "vec3",
            names["WAVELENGTH_NM"],
            _vec3(ch.wavelength_nm),
            "[nm]" if ch.mode == "wavelengths" else "weighted mean wavelengths [nm]",
        ),
        _const("vec3", names["G"], _vec3(ch.g), "asymmetry parameter [-]"),
    ]
    if ch.cext_m2 is not None and ch.csca_m2 is not None:
        cabs = ch.cext_m2 - ch.csca_m2
        lines += [
            _const(
                "vec3",
                names["CEXT_M2"],
                _vec3(ch.cext_m2),
                "mean extinction cross-section per particle [m^2]",
            ),
            _const(
                "vec3",
                names["CSCA_M2"],
                _vec3(ch.csca_m2),
                "mean scattering cross-section per particle [m^2]",
            ),
            _const(
                "vec3",
                names["CABS_M2"],
                _vec3(cabs),
                "mean absorption cross-section per particle [m^2]",
            ),
            _const(
                "vec3",
                names["SSA"],
                _vec3(ch.csca_m2 / ch.cext_m2),
                "single-scattering albedo csca / cext [-]",
            ),
        ]
        if ch.number_density_per_m3 is not None:
            density = ch.number_density_per_m3
            lines += [
                _const(
                    "float",
                    names["NUMBER_DENSITY_PER_M3"],
                    glsl_float(density),
                    "number density of the beta coefficients [m^-3]",
                ),
                _const(
                    "vec3",
                    names["BETA_EXT_PER_M"],
                    _vec3(density * ch.cext_m2),
                    "extinction coefficient [m^-1]",
                ),
                _const(
                    "vec3",
                    names["BETA_SCA_PER_M"],
                    _vec3(density * ch.csca_m2),
                    "scattering coefficient [m^-1]",
                ),
                _const(
                    "vec3",
                    names["BETA_ABS_PER_M"],
                    _vec3(density * cabs),
                    "absorption coefficient [m^-1]",
                ),
            ]
    lines += [
        "",
        f"// Phase function [sr^-1] at theta_j = 180 j / {n - 1} deg, j = 0..{n - 1}.",
        f"const vec3 {names['PHASE']}[{names['PHASE_N']}] = vec3[](",
    ]
    rows = [f"    {_vec3(row)}" for row in ch.phase]
    lines += [row + "," for row in rows[:-1]] + [rows[-1], ");"]
    lines += [
        "",
        "// Phase function [sr^-1] at nu = cos(scattering angle) [-], nu = 1 forward.",
        f"vec3 {function_name}(float nu)",
        "{",
        "    // Numerical safety only: a cosine computed by rounding (e.g. a dot product of",
        "    // unit vectors) can exceed 1 in magnitude, where acos is undefined.",
        "    float c = clamp(nu, -1.0, 1.0);",
    ]
    if acos == "builtin":
        lines += ["    float theta = acos(c);  // [rad]"]
    else:
        lines += [
            "    // theta = acos(c) [rad]: Abramowitz & Stegun 4.4.46 (|error| <= 2e-8 rad in exact",
            "    // arithmetic), for a result independent of the driver's acos precision.",
            "    float a = abs(c);",
            f"    float p = {glsl_float(ACOS_AS4446[-1])};",
        ]
        lines += [f"    p = p * a + {glsl_float(coef)};" for coef in ACOS_AS4446[-2::-1]]
        lines += [
            "    float theta = sqrt(1.0 - a) * p;",
            f"    if (c < 0.0) theta = {glsl_float(math.pi)} - theta;",
        ]
    lines += [
        f"    float x = clamp(theta * {names['PHASE_INDEX_PER_RAD']}, 0.0, float({names['PHASE_N']} - 1));",
        f"    int i = min(int(x), {names['PHASE_N']} - 2);",
        "    float f = x - float(i);",
        f"    return {names['PHASE']}[i] * (1.0 - f) + {names['PHASE']}[i + 1] * f;",
        "}",
    ]
    return "\n".join(lines) + "\n"


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
) -> list[Path]:
    """Write :func:`glsl_snippet` to a file, atomically.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    out_dir_or_path : path-like
        A path ending in ``.glsl`` is the file to write; anything else is a
        directory (created if missing) that receives
        ``<table name>_phase.glsl`` (characters other than letters, digits,
        ``.``, ``_`` and ``-`` replaced by ``_``).
    overwrite : bool
        Replace an existing file.  Default False.
    channels_nm, colour, resolution_deg, prefix, function_name, min_band_coverage, acos
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
    source = glsl_snippet(
        table,
        channels_nm=channels_nm,
        colour=colour,
        resolution_deg=resolution_deg,
        prefix=prefix,
        function_name=function_name,
        min_band_coverage=min_band_coverage,
        acos=acos,
    )
    out = Path(out_dir_or_path)
    target = out if out.suffix == ".glsl" else out / f"{_safe_stem(table.name)}_phase.glsl"
    return write_files({target: source.encode("ascii")}, overwrite=overwrite)


register_format("glsl", write_glsl)
