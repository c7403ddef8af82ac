"""What every shading language's phase-function source holds, made once.

:func:`shader_source` writes the same content in every language of
:data:`LANGUAGES`; each language module says how it is spelled
(:class:`ShaderSyntax`): :mod:`~dustoptics.io.shaders.glsl` (GLSL 1.30+ and
GLSL ES 1.00), :mod:`~dustoptics.io.shaders.hlsl`,
:mod:`~dustoptics.io.shaders.wgsl`.  The content:

- three channels of the table (:func:`shader_channels`: three wavelengths, or
  colour bands; :func:`choose_channels`), sampled uniformly over 0..180 deg and
  rounded to float32;
- per-channel constants (g, cross-sections, beta coefficients);
- the seed shader's lookup ``MiePhaseFunction(nu)``: it takes the cosine of the
  scattering angle ``nu`` and returns the three channels, interpolated linearly
  in angle between samples (:meth:`ShaderSyntax.lookup_lines`).

Every identifier a snippet declares at module scope begins with ``prefix``
(default ``"MIE"``: ``MIE_PHASE_N``, ``MIE_PHASE``, ``MIE_G``, ...) except the
lookup, named by ``function_name`` (default the seed's ``MiePhaseFunction``),
so two snippets with different prefixes and function names share a shader.

Numbers: each value is rounded to float32 and written as the shortest decimal
that reads back as that float32 (:func:`float_literal`; HLSL and WGSL with the
``f`` suffix, so the compiler rounds the decimal to float32 once, not through a
double).  The lookup computes ``acos`` with the polynomial of Abramowitz &
Stegun 4.4.46 (error 2.5e-7 rad in float32), the same in every driver, unless
``acos="builtin"`` (the language's own ``acos``, whose precision the shading
languages leave to the implementation).

Everything is deterministic: the same table and options give the same bytes.
"""

from __future__ import annotations

import json
import math
import os
import re
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any, ClassVar

import numpy as np

from dustoptics._validation import MAX_GRID_POINTS, check_choice, check_positive
from dustoptics.colour import (
    CHANNEL_MODES,
    DEFAULT_CHANNELS_NM,
    ChannelWeights,
    channel_phase,
    channel_weights,
)
from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io.describe_formats import describe_shader, is_shader
from dustoptics.io.registry import Format, option
from dustoptics.scattering.tabulated_phase import sphere_integral
from dustoptics.table import PHASE_NORMALIZATION

__all__ = [
    "ACOS_AS4446",
    "ACOS_METHODS",
    "COLOUR_MODES",
    "DEFAULT_CHANNELS_NM",
    "DEFAULT_RESOLUTION_DEG",
    "LANGUAGES",
    "ShaderChannels",
    "ShaderSyntax",
    "check_shader_options",
    "choose_channels",
    "float_literal",
    "register_syntax",
    "shader_channels",
    "shader_source",
    "shader_syntax",
    "write_shader",
]

#: Colour modes of ``colour=`` (the three-wavelength mode is ``channels_nm``).
COLOUR_MODES = tuple(m for m in CHANNEL_MODES if m != "wavelengths")

#: The seed shader's angular step (721 samples over 0..180 deg). [deg]
DEFAULT_RESOLUTION_DEG = 0.25

#: How the lookup computes acos: its own polynomial (default) or the language's builtin.
ACOS_METHODS = ("polynomial", "builtin")

#: Shader languages :func:`shader_source` writes, each spelled by its module's
#: :class:`ShaderSyntax` (registered with :func:`register_syntax`).
LANGUAGES = ("glsl", "glsl100", "hlsl", "wgsl")

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

# Suffixes of the constants every snippet declares (after "<prefix>_").
_CONSTANT_KEYS = (
    "PHASE_N",
    "PHASE",
    "PHASE_SAMPLE",
    "PHASE_INDEX_PER_RAD",
    "PI",
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


# ---------------------------------------------------------------------- channels


@dataclass(frozen=True)
class ShaderChannels:
    """The three channels a shader snippet holds, before formatting.

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
        except for linear sRGB): every channel cross-section is ``weights @``
        the table's rows; the phase function and g are weighted by scattering
        as well (:func:`dustoptics.colour.channel_phase`). [-]
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


def _fmt_nm(x: float) -> str:
    return f"{x:g}"


def choose_channels(
    table: Any,
    *,
    channels_nm: Any = None,
    colour: str | None = None,
    min_band_coverage: float = 0.99,
) -> ChannelWeights:
    """The three channels (R, G, B roles) of a table, as weights over its wavelengths.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    channels_nm : sequence of 3 floats, optional
        Channel wavelengths in (R, G, B) order within the table's range;
        default (680, 550, 440), the seed's, unless ``colour`` is given. [nm]
    colour : {"cie1931-xyz", "linear-srgb-astmg173"}, optional
        Colour channels instead (:func:`dustoptics.colour.channel_weights`).
        Not together with ``channels_nm``.
    min_band_coverage : float
        With ``colour``: smallest fraction of each weighting function's
        integral over 360-830 nm the table's range must hold. [-]

    Returns
    -------
    dustoptics.colour.ChannelWeights
    """
    if colour is not None and channels_nm is not None:
        raise ValueError(
            f"give either channels_nm (wavelengths) or colour (bands), not both; got "
            f"channels_nm={channels_nm!r} and colour={colour!r}"
        )
    wavelength = np.asarray(table.wavelength_nm, dtype=np.float64)
    if colour is not None:
        check_choice("colour", colour, COLOUR_MODES)
        return channel_weights(wavelength, mode=colour, min_coverage=min_band_coverage)
    return channel_weights(
        wavelength,
        mode="wavelengths",
        channels_nm=DEFAULT_CHANNELS_NM if channels_nm is None else channels_nm,
    )


def _channel_line(ch: ShaderChannels) -> str:
    """One line saying what the three channels are (for a file's header)."""
    if ch.mode == "wavelengths":
        return (
            "channels (.x, .y, .z): "
            + ", ".join(f"{_fmt_nm(w)} nm" for w in ch.wavelength_nm)
            + " (wavelengths)"
        )
    return f"channels (.x, .y, .z): {ch.mode} (dustoptics.colour.channel_weights)"


def _grid_count(resolution_deg: Any) -> int:
    step = check_positive("resolution_deg", resolution_deg, unit="deg")
    intervals = 180.0 / step
    if intervals + 1 > MAX_GRID_POINTS:
        raise ValueError(
            f"resolution_deg must give at most {MAX_GRID_POINTS} samples over 0-180 deg; got "
            f"{resolution_deg!r} ({intervals + 1:.3g} samples)"
        )
    n = round(intervals)
    if n < 1 or abs(intervals - n) > 1e-9 * n:
        raise ValueError(
            f"resolution_deg must divide 180 deg into a whole number of steps "
            f"(e.g. 0.1, 0.25, 0.5, 1); got {resolution_deg!r} ({intervals:g} steps)"
        )
    return n + 1


def check_shader_options(
    wavelength_nm: Any,
    *,
    channels_nm: Any = None,
    colour: str | None = None,
    resolution_deg: float = DEFAULT_RESOLUTION_DEG,
    min_band_coverage: float = 0.99,
) -> None:
    """Check a snippet's options against a table's wavelengths, before the table exists.

    The command line calls it with a configuration's wavelength grid before
    computing the table, so that options :func:`shader_channels` would refuse
    (channels outside the grid, a colour mode whose bands the grid does not
    cover, a resolution that does not divide 180 deg or gives more than
    :data:`dustoptics._validation.MAX_GRID_POINTS` samples) fail before any work.

    Raises
    ------
    ValueError
        What :func:`shader_channels` would raise for these options.
    """
    _grid_count(resolution_deg)
    grid = SimpleNamespace(wavelength_nm=np.asarray(wavelength_nm, dtype=np.float64))
    choose_channels(
        grid, channels_nm=channels_nm, colour=colour, min_band_coverage=min_band_coverage
    )


@dataclass(frozen=True)
class ChannelOptions:
    """The three channels of a snippet or a texture (formats glsl, hlsl, wgsl, ktx2, exr, npy).

    Attributes
    ----------
    channels_nm : tuple of float, optional
        The three channels' wavelengths; None: 680, 550, 440. [nm]
    colour : str, optional
        Colour channels instead of wavelengths (:data:`COLOUR_MODES`).
    """

    channels_nm: tuple[float, ...] | None = option(
        help="wavelengths of the three channels [nm] (default 680,550,440)",
        type="floats",
        metavar="R,G,B",
    )
    colour: str | None = option(
        help="colour channels instead of three wavelengths: CIE 1931 XYZ bands, or linear sRGB of "
        "the table lit by the ASTM G173 sun (a renderer with a white sun reproduces the spectral "
        "colour)",
        choices=["cie1931-xyz", "linear-srgb-astmg173"],
    )


@dataclass(frozen=True)
class ShaderOptions(ChannelOptions):
    """The options of the hlsl and wgsl formats (glsl: :class:`GLSLOptions`); None leaves
    :func:`shader_source`'s default.

    Attributes
    ----------
    resolution_deg : float, optional
        Angular step of the constant array. [deg]
    prefix : str, optional
        Prefix of every identifier; a prefix other than ``MIE`` also names the lookup
        ``PREFIX_MiePhaseFunction``.
    """

    resolution_deg: float | None = option(
        help="angular step of the constant array [deg] (default 0.25)",
        type="positive_float",
        metavar="DEG",
    )
    prefix: str | None = option(
        help="prefix of every identifier: NAME_PHASE, ..., NAME_MiePhaseFunction (default MIE, "
        "with the seed's MiePhaseFunction)",
        metavar="NAME",
    )

    def keywords(self) -> dict[str, Any]:
        """The keywords of :func:`write_shader`."""
        out: dict[str, Any] = {"channels_nm": self.channels_nm, "colour": self.colour}
        if self.resolution_deg is not None:
            out["resolution_deg"] = self.resolution_deg
        if self.prefix is not None:
            # Every identifier prefixed, the lookup too (MIE keeps the seed's names).
            out["prefix"] = self.prefix
            if self.prefix != "MIE":
                out["function_name"] = f"{self.prefix}_MiePhaseFunction"
        return out

    def check(self, wavelength_nm: Any) -> None:
        """:func:`check_shader_options` for a wavelength grid [nm], before the table exists."""
        check_shader_options(
            wavelength_nm,
            channels_nm=self.channels_nm,
            colour=self.colour,
            resolution_deg=self.resolution_deg or DEFAULT_RESOLUTION_DEG,
        )


def shader_format(
    language: str, *, summary: str, write: Callable[..., list[Path]], options: type[ShaderOptions]
) -> Format:
    """The record of a shading language's format (its module registers it).

    Parameters
    ----------
    language : str
        The format's name and the language (:data:`LANGUAGES`).
    summary : str
        One line for ``--help`` and the documentation's format table.
    write : callable
        The language's writer.
    options : type
        :class:`ShaderOptions` or a subclass.

    Returns
    -------
    Format
    """
    extension = shader_syntax(language).extension
    return Format(
        name=language,
        summary=summary,
        write=write,
        suffixes=(extension,),
        options=options,
        recognise=lambda path: is_shader(path, extension),
        describe=describe_shader,
    )


def shader_channels(
    table: Any,
    *,
    channels_nm: Any = None,
    colour: str | None = None,
    resolution_deg: float = DEFAULT_RESOLUTION_DEG,
    min_band_coverage: float = 0.99,
) -> ShaderChannels:
    """The channel data of :func:`shader_source`, as arrays.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    channels_nm, colour, min_band_coverage
        As in :func:`choose_channels`.
    resolution_deg : float
        Angular step of the array; must divide 180. Default 0.25. [deg]

    Returns
    -------
    ShaderChannels
    """
    n_angles = _grid_count(resolution_deg)
    chosen = choose_channels(
        table, channels_nm=channels_nm, colour=colour, min_band_coverage=min_band_coverage
    )
    weights = np.array(chosen.weights)
    theta = np.linspace(0.0, 180.0, n_angles)
    # Scattering-weighted channels when the table has cross-sections, so that
    # csca_c * P_c is the channel of csca * P (see dustoptics.colour.channel_phase).
    phase64 = channel_phase(
        chosen,
        np.asarray(table.phase_at(theta), dtype=np.float64),
        csca_um2=table.quantity("csca_um2"),
    )
    phase32 = np.ascontiguousarray(phase64.T.astype(np.float32))
    integral = np.asarray(sphere_integral(phase32.T.astype(np.float64), theta_deg=theta))
    g = channel_phase(
        chosen, np.asarray(table.g, dtype=np.float64)[:, None], csca_um2=table.quantity("csca_um2")
    )[:, 0]
    cext = csca = None
    if table.cross_sections is not None:
        cext = weights @ np.asarray(table.cross_sections.cext_um2, dtype=np.float64) * _UM2_TO_M2
        csca = weights @ np.asarray(table.cross_sections.csca_um2, dtype=np.float64) * _UM2_TO_M2
    for array in (weights, theta, phase32, integral, g, cext, csca):
        if array is not None:
            array.setflags(write=False)
    return ShaderChannels(
        mode=chosen.mode,
        wavelength_nm=chosen.centroid_nm,
        descriptions=chosen.descriptions,
        weights=weights,
        theta_deg=theta,
        phase=phase32,
        sphere_integral=integral,
        g=g,
        cext_m2=cext,
        csca_m2=csca,
        number_density_per_m3=table.cross_sections.number_density_per_m3
        if cext is not None
        else None,
    )


# ---------------------------------------------------------------------- formatting


def float_literal(value: Any, *, suffix: str = "") -> str:
    """Shader literal of ``value`` rounded to float32, reading back to that float32 exactly.

    The shortest decimal that identifies the float32 (numpy's Dragon4 with
    ``unique=True``), always in exponent form with a decimal point, so every
    shading language reads a float (never an int); ``suffix="f"`` for HLSL
    and WGSL, where it makes the literal a float32 (not a double or an
    abstract float rounded twice).

    >>> float_literal(1.0), float_literal(0.1, suffix="f"), float_literal(-2.5e-13)
    ('1.0e+00', '1.0e-01f', '-2.5e-13')
    """
    with np.errstate(over="ignore"):
        x = np.float32(value)
    if not np.isfinite(x):
        raise ValueError(
            f"value must be finite as float32 to be written to a shader; got {value!r}"
        )
    return np.format_float_scientific(x, unique=True, trim="0", exp_digits=2) + suffix


def _text(value: Any) -> str:
    """One-line ASCII rendering of free text for a comment (quoted, escaped)."""
    return json.dumps(str(value), ensure_ascii=True)


# ---------------------------------------------------------------------- syntax

#: The comment above every lookup function.
LOOKUP_COMMENT = "// Phase function [sr^-1] at nu = cos(scattering angle) [-], nu = 1 forward."

#: The comment on the clamp of ``nu`` in every lookup function.
SAFETY_COMMENT = (
    "    // Numerical safety only: a cosine computed by rounding (e.g. a dot product of",
    "    // unit vectors) can exceed 1 in magnitude, where acos is undefined.",
)


class ShaderSyntax(ABC):
    """How one shading language spells what every snippet holds.

    Each language module defines a subclass, registers one instance
    (:func:`register_syntax`) and writes its files with :func:`write_shader`.
    The defaults are the C family's spelling (GLSL, HLSL); a language that
    spells a construct otherwise overrides its method.

    Attributes
    ----------
    language : str
        Its name in :data:`LANGUAGES`.
    label : str
        Its name in headers and messages.
    extension : str
        File-name extension.
    file_tail : str
        What follows the table's name in a file name (``"_phase"``).
    requirements : str
        The versions that compile the source (the header's ``// requires:`` line).
    keywords : frozenset of str
        Keywords and reserved words no identifier of ours may be.
    max_samples : int or None
        Most samples the language holds in one constant array; None: no limit.
    max_samples_reason : str
        What sets ``max_samples``.
    float_type, int_type, vec3 : str
        Names of the scalar types (casts) and of the three-component vector
        (type and constructor).
    precision : str
        Qualifier before every float declaration (``"highp "`` in GLSL ES 1.00).
    float_suffix : str
        Suffix of float literals (``"f"``: a float32, not a double or an
        abstract float).
    """

    language: ClassVar[str]
    label: ClassVar[str]
    extension: ClassVar[str]
    file_tail: ClassVar[str] = "_phase"
    requirements: ClassVar[str]
    keywords: ClassVar[frozenset[str]]
    max_samples: ClassVar[int | None] = None
    max_samples_reason: ClassVar[str] = ""
    float_type: ClassVar[str] = "float"
    int_type: ClassVar[str] = "int"
    vec3: ClassVar[str]
    precision: ClassVar[str] = ""
    float_suffix: ClassVar[str] = ""

    # ---------------------------------------------------------- numbers and names

    def lit(self, value: Any) -> str:
        """A float literal (:func:`float_literal` with the language's suffix)."""
        return float_literal(value, suffix=self.float_suffix)

    def vec(self, values: Any) -> str:
        """A three-component vector of float literals."""
        return f"{self.vec3}(" + ", ".join(self.lit(v) for v in values) + ")"

    def type_name(self, kind: str) -> str:
        """The declared type of ``kind`` (``"float"``, ``"int"`` or ``"vec3"``)."""
        if kind == "int":
            return self.int_type
        return self.precision + {"float": self.float_type, "vec3": self.vec3}[kind]

    def cast(self, kind: str, expression: str) -> str:
        """``expression`` converted to ``kind`` (``"float"`` or ``"int"``)."""
        scalar = self.float_type if kind == "float" else self.int_type
        return f"{scalar}({expression})"

    def check_identifier(self, name: str, value: Any) -> str:
        """``value`` if it is an identifier of ours in this language, else a ValueError."""
        if (
            not isinstance(value, str)
            or not _IDENTIFIER.match(value)
            or "__" in value
            or value.startswith("gl_")
            or value in self.keywords
        ):
            raise ValueError(
                f"{name} must be a valid {self.label} identifier (letters, digits and '_', not "
                f"starting with a digit or 'gl_', no '__', not a {self.label} keyword); got "
                f"{value!r}"
            )
        return value

    # ---------------------------------------------------------- declarations

    @abstractmethod
    def const_declaration(self, type_name: str, name: str, value: str) -> str:
        """A module-scope constant of type ``type_name`` (:meth:`type_name`)."""

    def const(self, kind: str, name: str, value: str, comment: str) -> str:
        """One module-scope constant (kind: "float", "int" or "vec3") with its comment, if any."""
        tail = f"  // {comment}" if comment else ""
        return self.const_declaration(self.type_name(kind), name, value) + tail

    @abstractmethod
    def array_declaration(self, name: str, n_samples: int, count_name: str) -> tuple[str, str]:
        """The lines that open and close the constant array of ``n_samples`` vectors."""

    def array_lines(self, ch: ShaderChannels, names: Mapping[str, str]) -> list[str]:
        """The constant array of samples ``names["PHASE"]``, one vector per line."""
        n = ch.phase.shape[0]
        header = f"// Phase function [sr^-1] at theta_j = 180 j / {n - 1} deg, j = 0..{n - 1}."
        rows = [f"    {self.vec(row)}" for row in ch.phase]
        body = [row + "," for row in rows[:-1]] + [rows[-1]]
        opening, closing = self.array_declaration(names["PHASE"], n, names["PHASE_N"])
        return ["", header, opening, *body, closing]

    @abstractmethod
    def float_array(self, name: str, values: Any) -> str:
        """A module-scope constant array of floats (the fitted parameters per wavelength)."""

    # ---------------------------------------------------------- statements

    def local(self, kind: str, name: str, value: str, *, mutable: bool = False) -> str:
        """A local variable (``mutable`` when it is assigned again)."""
        return f"{self.type_name(kind)} {name} = {value};"

    def if_then(self, condition: str, statement: str) -> str:
        """``statement`` when ``condition`` holds."""
        return f"if ({condition}) {statement}"

    def function_open(self, function_name: str) -> list[str]:
        """The lookup's signature, ``nu`` in, three channels out, and its opening brace."""
        return [f"{self.type_name('vec3')} {function_name}({self.type_name('float')} nu)", "{"]

    def acos_lines(self, acos: str, names: Mapping[str, str], indent: str = "    ") -> list[str]:
        """Statements that set ``theta = acos(c)`` [rad] from ``c``."""
        if acos == "builtin":
            return [f"{indent}{self.local('float', 'theta', 'acos(c)')}  // [rad]"]
        lines = [
            f"{indent}// theta = acos(c) [rad]: Abramowitz & Stegun 4.4.46 (|error| <= 2e-8 rad "
            "in exact",
            f"{indent}// arithmetic), for a result independent of the driver's acos precision.",
            f"{indent}{self.local('float', 'a', 'abs(c)')}",
            f"{indent}{self.local('float', 'p', self.lit(ACOS_AS4446[-1]), mutable=True)}",
        ]
        lines += [f"{indent}p = p * a + {self.lit(coef)};" for coef in ACOS_AS4446[-2::-1]]
        theta = f"sqrt({self.lit(1.0)} - a) * p"
        lines.append(f"{indent}{self.local('float', 'theta', theta, mutable=True)}")
        flip = f"theta = {names['PI']} - theta;"
        lines.append(f"{indent}{self.if_then(f'c < {self.lit(0.0)}', flip)}")
        return lines

    def lookup_lines(
        self, ch: ShaderChannels, names: Mapping[str, str], function_name: str, acos: str
    ) -> list[str]:
        """The lookup function ``function_name(nu)`` (see :func:`shader_source`, Notes)."""
        one, zero = self.lit(1.0), self.lit(0.0)
        n_name, p_name, k_name = names["PHASE_N"], names["PHASE"], names["PHASE_INDEX_PER_RAD"]
        c = f"clamp(nu, -{one}, {one})"
        x = f"clamp(theta * {k_name}, {zero}, {self.cast('float', n_name + ' - 1')})"
        i = f"min({self.cast('int', 'x')}, {n_name} - 2)"
        f = f"x - {self.cast('float', 'i')}"
        return [
            LOOKUP_COMMENT,
            *self.function_open(function_name),
            *SAFETY_COMMENT,
            f"    {self.local('float', 'c', c)}",
            *self.acos_lines(acos, names),
            f"    {self.local('float', 'x', x)}",
            f"    {self.local('int', 'i', i)}",
            f"    {self.local('float', 'f', f)}",
            f"    return {p_name}[i] * ({one} - f) + {p_name}[i + 1] * f;",
            "}",
        ]


_SYNTAXES: dict[str, ShaderSyntax] = {}


def register_syntax(syntax: ShaderSyntax) -> None:
    """Make ``syntax`` the spelling of its language (each language module registers one)."""
    check_choice("language", syntax.language, LANGUAGES)
    if syntax.language in _SYNTAXES and type(_SYNTAXES[syntax.language]) is not type(syntax):
        raise ValueError(f"language {syntax.language!r} already has a syntax")
    _SYNTAXES[syntax.language] = syntax


def shader_syntax(language: str) -> ShaderSyntax:
    """The :class:`ShaderSyntax` of ``language`` (one of :data:`LANGUAGES`)."""
    check_choice("language", language, LANGUAGES)
    return _SYNTAXES[language]


# ---------------------------------------------------------------------- source


def shader_source(
    table: Any,
    *,
    language: str = "glsl",
    channels_nm: Any = None,
    colour: str | None = None,
    resolution_deg: float = DEFAULT_RESOLUTION_DEG,
    prefix: str = "MIE",
    function_name: str = "MiePhaseFunction",
    min_band_coverage: float = 0.99,
    acos: str = "polynomial",
) -> str:
    """Shader source: the phase function as constants and its lookup function.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    language : {"glsl", "glsl100", "hlsl", "wgsl"}
        Shading language: GLSL 1.30+/ES 3.00+, GLSL ES 1.00 (WebGL 1)
        (:mod:`~dustoptics.io.shaders.glsl`), HLSL
        (:mod:`~dustoptics.io.shaders.hlsl`), WGSL (:mod:`~dustoptics.io.shaders.wgsl`).
    channels_nm : sequence of 3 floats, optional
        Channel wavelengths in vector order (.x, .y, .z), each on the table's
        grid or between two grid wavelengths (linear interpolation in
        wavelength); default (680, 550, 440), the seed's R, G, B. [nm]
    colour : {"cie1931-xyz", "linear-srgb-astmg173"}, optional
        Colour channels instead (:func:`choose_channels`).
    resolution_deg : float
        Angular step of the samples; must divide 180.  Default 0.25 (721
        samples, the seed's). [deg]
    prefix : str
        Prefix of every module-scope identifier except the lookup
        (``<prefix>_PHASE_N``, ``<prefix>_PHASE``, ``<prefix>_G``, ...), so two
        snippets can share a shader.  Default ``"MIE"``.
    function_name : str
        Name of the lookup; default ``"MiePhaseFunction"`` (the seed's).
    min_band_coverage : float
        With ``colour``: smallest accepted fraction of each colour-matching
        function's 360-830 nm integral within the table's range. [-]
    acos : {"polynomial", "builtin"}
        How the lookup computes the angle from ``nu``: ``"polynomial"``
        (default), Abramowitz & Stegun 4.4.46 evaluated in float32 (error
        2.5e-7 rad, measured against float64 over [-1, 1]), the same on every
        driver; or ``"builtin"``, the language's ``acos``, whose precision the
        specifications leave to the implementation (Mesa llvmpipe's GLSL acos:
        errors up to 1.6e-4 rad, 0.04 of a 0.25 deg step, measured).

    Returns
    -------
    str
        Source (ASCII, ``\\n`` line ends), include-ready (no ``#version``
        line): a comment header, then

        - ``<prefix>_PHASE_N`` (int): number of samples N;
        - ``<prefix>_PHASE``: N three-component vectors, the phase function
          [sr^-1] at ``theta_j = 180 j / (N - 1)`` deg, channel per component
          (GLSL ES 1.00: the function ``<prefix>_PHASE_SAMPLE(float i)``);
        - ``<prefix>_PHASE_INDEX_PER_RAD`` (float): (N - 1) / pi [rad^-1];
          ``<prefix>_PI`` (float): pi in float32;
        - ``<prefix>_WAVELENGTH_NM``: channel wavelengths (band mean
          wavelengths in colour mode) [nm]; ``<prefix>_G``: asymmetry
          parameter [-];
        - with cross-sections: ``<prefix>_CEXT_M2``, ``<prefix>_CSCA_M2``,
          ``<prefix>_CABS_M2`` [m^2] and ``<prefix>_SSA`` [-];
        - with a number density as well: ``<prefix>_NUMBER_DENSITY_PER_M3``
          (float) [m^-3] and ``<prefix>_BETA_EXT_PER_M``,
          ``<prefix>_BETA_SCA_PER_M``, ``<prefix>_BETA_ABS_PER_M`` [m^-1];
        - the lookup ``function_name(nu)``: the phase function [sr^-1] at
          ``nu = cos(theta)``, three components.

    Raises
    ------
    ValueError
        An unknown language, a channel wavelength outside the table's range,
        both ``channels_nm`` and ``colour``, a resolution that does not divide
        180 deg (or, for HLSL, gives more than 4096 samples), an invalid
        identifier, or too little band coverage; the message names the
        parameter, the value and what is allowed.

    Notes
    -----
    The lookup computes ``x = acos(clamp(nu, -1, 1)) * (N - 1) / pi``
    (``acos`` per the ``acos`` option), ``i = min(floor(x), N - 2)``,
    ``f = x - i`` and returns ``P[i] (1 - f) + P[i + 1] f``.  The clamp of
    ``nu`` (and of ``x`` to [0, N - 1]) is numerical safety only: a cosine
    computed as a dot product of unit vectors can exceed 1 in magnitude by
    rounding, where ``acos`` is undefined.  Since ``x`` is linear in
    ``theta``, the shader interpolates linearly in angle, as
    :meth:`~dustoptics.table.Table.phase_at` does; the seed divides by pi
    after multiplying, this multiplies by the float32 of (N - 1)/pi (a
    difference of float32 rounding).

    Examples
    --------
    >>> src = shader_source(table, language="wgsl")                      # doctest: +SKIP
    >>> two = shader_source(table, language="hlsl", prefix="DUST",
    ...                     function_name="DustPhase")                    # doctest: +SKIP
    """
    from dustoptics import __version__

    sx = shader_syntax(language)
    check_choice("acos", acos, ACOS_METHODS)
    prefix = sx.check_identifier("prefix", prefix)
    function_name = sx.check_identifier("function_name", function_name)
    names = {key: sx.check_identifier("prefix", f"{prefix}_{key}") for key in _CONSTANT_KEYS}
    if function_name in names.values():
        raise ValueError(
            f"function_name must differ from the constants' names; got {function_name!r}"
        )
    n_samples = _grid_count(resolution_deg)
    limit = sx.max_samples
    if limit is not None and n_samples > limit:
        raise ValueError(
            f"resolution_deg = {resolution_deg!r} gives {n_samples} samples, more than {language}'s "
            f"{limit} ({sx.max_samples_reason}); choose resolution_deg >= "
            f"{180.0 / (limit - 1):.6g}"
        )
    ch = shader_channels(
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
    title = f"phase function of table {_text(table.name)} for {sx.label}"
    lines = [
        f"// dustoptics {__version__}: {title}.",
        f"// requires: {sx.requirements}",
        f"// input_hash (SHA-256 of the table's inputs): {table.provenance.input_hash}",
        f"// {_channel_line(ch)}",
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
        + (
            "the language's builtin"
            if acos == "builtin"
            else "Abramowitz & Stegun 4.4.46 polynomial"
        ),
        "",
    ]
    wavelength_note = "[nm]" if ch.mode == "wavelengths" else "weighted mean wavelengths [nm]"
    constants = [  # (kind, key, value, comment)
        ("int", "PHASE_N", str(n), ""),  # N, the number of samples
        ("float", "PHASE_INDEX_PER_RAD", sx.lit((n - 1) / math.pi), "(N - 1) / pi [rad^-1]"),
        ("float", "PI", sx.lit(math.pi), "pi in float32"),
        ("vec3", "WAVELENGTH_NM", sx.vec(ch.wavelength_nm), wavelength_note),
        ("vec3", "G", sx.vec(ch.g), "asymmetry parameter [-]"),
    ]
    if ch.cext_m2 is not None and ch.csca_m2 is not None:
        cabs = ch.cext_m2 - ch.csca_m2
        ssa = ch.csca_m2 / ch.cext_m2
        per_particle = "cross-section per particle [m^2]"
        constants += [
            ("vec3", "CEXT_M2", sx.vec(ch.cext_m2), f"mean extinction {per_particle}"),
            ("vec3", "CSCA_M2", sx.vec(ch.csca_m2), f"mean scattering {per_particle}"),
            ("vec3", "CABS_M2", sx.vec(cabs), f"mean absorption {per_particle}"),
            ("vec3", "SSA", sx.vec(ssa), "single-scattering albedo csca / cext [-]"),
        ]
        if ch.number_density_per_m3 is not None:
            n0 = ch.number_density_per_m3
            n0_note = "number density of the beta coefficients [m^-3]"
            per_m = "coefficient [m^-1]"
            constants += [
                ("float", "NUMBER_DENSITY_PER_M3", sx.lit(n0), n0_note),
                ("vec3", "BETA_EXT_PER_M", sx.vec(n0 * ch.cext_m2), f"extinction {per_m}"),
                ("vec3", "BETA_SCA_PER_M", sx.vec(n0 * ch.csca_m2), f"scattering {per_m}"),
                ("vec3", "BETA_ABS_PER_M", sx.vec(n0 * cabs), f"absorption {per_m}"),
            ]
    lines += [sx.const(kind, names[key], value, note) for kind, key, value, note in constants]
    lines += sx.array_lines(ch, names)
    lines += [""] + sx.lookup_lines(ch, names, function_name, acos)
    return "\n".join(lines) + "\n"


def write_shader(
    table: Any,
    out_dir_or_path: str | os.PathLike[str],
    *,
    language: str = "glsl",
    overwrite: bool = False,
    **options: Any,
) -> list[Path]:
    """Write :func:`shader_source` to a file, atomically.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    out_dir_or_path : path-like
        A path ending in the language's extension (``.glsl``, ``.hlsl``,
        ``.wgsl``) is the file to write; anything else is a directory
        (created if missing) that receives ``<table name>_phase<ext>``
        (GLSL ES 1.00: ``<table name>_phase_es100.glsl``; with ``colour``, its name
        follows ``_phase``: ``<table name>_phase_cie1931-xyz.glsl``), with characters
        other than letters, digits, ``.``, ``_`` and ``-`` replaced by ``_``.
    language : {"glsl", "glsl100", "hlsl", "wgsl"}
        Shading language.
    overwrite : bool
        Replace an existing file.  Default False.
    **options
        As :func:`shader_source` (``channels_nm``, ``colour``,
        ``resolution_deg``, ``prefix``, ``function_name``,
        ``min_band_coverage``, ``acos``).

    Returns
    -------
    list of pathlib.Path
        The written file.

    Raises
    ------
    FileExistsError
        The file exists and ``overwrite`` is False (nothing is written).
    ValueError
        As :func:`shader_source`.
    """
    sx = shader_syntax(language)
    source = shader_source(table, language=language, **options)
    ext = sx.extension
    out = Path(out_dir_or_path)
    # Each colour mode its own file: the modes' numbers differ, their files must not collide.
    tail = (
        sx.file_tail.replace("_phase", f"_phase_{options['colour']}", 1)
        if options.get("colour")
        else sx.file_tail
    )
    target = out if out.suffix == ext else out / f"{safe_stem(table.name)}{tail}{ext}"
    return write_files({target: source.encode("ascii")}, overwrite=overwrite)
