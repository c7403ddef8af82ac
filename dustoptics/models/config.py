"""Build configurations: the TOML schema of a dust model, parsed and validated.

A configuration file says everything a table is made from: the material, the
size distribution, the grids and tolerances, the phase-function model, and the
sources and choices behind them.  The package's presets
(:mod:`dustoptics.models.presets`) are such files; a user copies one
(``dustoptics.models.presets.preset_text(name)``), edits it, reads it with
:func:`dustoptics.models.files.load_config` and builds it with
:func:`dustoptics.models.compute.build_table`.  :func:`parse_config` reads the
text with the standard library's :mod:`tomllib` and validates it key by key:
unknown keys, wrong types and out-of-range values raise :class:`ConfigError`,
which names the key (``size_distribution.modes[1].r_eff_um``), the line of the
file and what is allowed.  Nothing is clamped or ignored.  The result, a
:class:`BuildConfig`, is plain data: this module computes nothing and knows no
preset.

Schema
------
Top level (before any ``[section]``)::

    name = "blue-moons"                  # required: table name
    description = "..."                  # required: one line
    choices = ["...", "..."]             # optional: choices the sources left open
    number_density_per_m3 = 1.0e8        # optional, Mie models only [m^-3]

    [[sources]]                          # optional, repeated: name, role, citation
    name = "meyran2022"
    role = "dust model"
    citation = "T. Meyran, ..."

``[material]`` (Mie and hybrid models only), ``model`` one of

- ``"mars_dust"`` (:func:`dustoptics.particles.mixing.mars_dust`): ``hematite_fraction``
  [0, 1] (default 0.03), ``host_index`` (a number n, ``{n = 1.5, k = 0.0}``, or a
  catalogue name such as ``"marsdust-wolff2009"``; default 1.5), ``hematite`` (default ``"querry-extraordinary"``), ``rule``
  (default ``"maxwell_garnett"``);
- ``"catalogue"``: ``name``, a catalogue material (:func:`dustoptics.list_materials`);
- ``"constant"``: ``n`` > 0 and ``k`` >= 0 (default 0).

``[size_distribution]`` (Mie and hybrid models only), ``model`` any family of
:data:`dustoptics.particles.sizedist.SIZE_DISTRIBUTIONS` (or one of its aliases,
recorded under the family's name) with its constructor's parameters as keys, each
checked against the range its class declares (:attr:`SizeDistribution.parameters
<dustoptics.particles.sizedist.SizeDistribution.parameters>`) and then by the class
(``"modified_gamma"``: ``r_eff_um`` > 0, ``v_eff`` in (0, 0.5); ``"tabulated"``:
arrays; ``"truncated"``: ``parent``, an inline table describing another
distribution), or ``"multimodal"`` with one
``[[size_distribution.modes]]`` table per mode, each a model above plus
``relative_number_density`` > 0
(:class:`dustoptics.particles.custom_sizedist.MultiModal`).  Only
``"density_function"`` (a Python callable) cannot be written in TOML.

``[optics]``: ``wavelengths_nm`` (a list, or ``{start = 360, stop = 830, step
= 10}``, the default), angles as ``n_theta`` evenly spaced from 0 to 180 deg
inclusive (default 1801) or ``theta_step_deg`` (must divide 180); for Mie and
hybrid models also ``weighting`` (``"scattering"``, the default, or
``"number"``), ``rtol`` (default 1e-4) and ``cross_section_rtol`` (default
``rtol / 100``), as in :func:`dustoptics.scattering.optics.compute_optics`;
for ``phase.model = "mie"`` also ``expansion``: ``true`` for the expansion
coefficients in generalized spherical functions of every order the spheres
need, or an integer N for orders 0..N (default ``false``, none), which the
DISORT and libRadtran formats need (``dustoptics build CONFIG --format
disort,libradtran``), and ``polarization``: ``true`` for the scattering matrix
F12, F33, F34 beside the phase function (default ``false``).

``[phase]``: ``model`` one of

- ``"mie"`` (the default): the polydisperse Mie phase function;
- ``"hybrid"``: Meyran 2022's blend ``renormalize((1 - w) P_mie + w P_analytic)``
  (:func:`dustoptics.scattering.tabulated_phase.hybrid`) with ``weight`` w in [0, 1] (default 0.5)
  and ``analytic``, an analytic model below (default ``"costa2021_mars_dhg"``)
  with its parameters;
- an analytic model alone: ``"costa2021_mars_dhg"`` (Costa et al.'s Mars DHG
  spectrum, :func:`dustoptics.scattering.phase.costa2021_mars_dhg`, with ``outside``:
  ``"quadratic"`` (default), ``"clamp"`` or ``"error"``), or any name of
  :data:`dustoptics.scattering.phase.ANALYTIC_MODELS` with its parameters as keys
  (``cornette_shanks1992`` with ``g``, ``henyey_greenstein`` with ``g``,
  ``dhg_costa2021`` with ``g1``, ``g2``, ``alpha``, ...), the same at every
  wavelength.  Analytic-only tables carry no cross-sections.
"""

from __future__ import annotations

import itertools
import math
import re
import tomllib
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Final

import numpy as np

from dustoptics._validation import (
    MAX_GRID_POINTS,
    check_file_name,
    check_wavelength_unit,
)
from dustoptics.particles.catalogue import get_material, list_materials
from dustoptics.particles.custom_sizedist import MultiModal
from dustoptics.particles.mixing import MARS_DUST_HEMATITE, MIXING_RULES, mars_dust
from dustoptics.particles.sizedist import (
    SIZE_DISTRIBUTION_ALIASES,
    SIZE_DISTRIBUTIONS,
    SizeDistribution,
    SizeParameter,
)
from dustoptics.scattering import phase as _phase
from dustoptics.scattering.optics import WEIGHTINGS
from dustoptics.table import Source

__all__ = [
    "SCHEMA",
    "BuildConfig",
    "ConfigError",
    "MaterialConfig",
    "ModeConfig",
    "OpticsConfig",
    "PhaseConfig",
    "SizeDistributionConfig",
    "parse_config",
]

#: Schema identifier recorded in every table's inputs.
SCHEMA: Final = "dustoptics-config-1"

_DEFAULT_WAVELENGTHS: Final = {"start": 360.0, "stop": 830.0, "step": 10.0}
_DEFAULT_N_THETA: Final = 1801
_DEFAULT_RTOL: Final = 1e-4
_DEFAULT_HYBRID_WEIGHT: Final = 0.5
_DEFAULT_ANALYTIC: Final = "costa2021_mars_dhg"
_COSTA_SPECTRUM: Final = "costa2021_mars_dhg"
_COSTA_OUTSIDE: Final = ("quadratic", "clamp", "error")
_MIE_MODELS: Final = ("mie", "hybrid")

_MATERIAL_KEYS: Final[Mapping[str, tuple[str, ...]]] = {
    "mars_dust": ("model", "hematite_fraction", "host_index", "hematite", "rule"),
    "catalogue": ("model", "name"),
    "constant": ("model", "n", "k"),
}

#: Size-distribution models a TOML file cannot name: a Python function is no TOML value.
_NOT_IN_TOML: Final = ("density_function",)
_MULTIMODAL: Final = "multimodal"


def _size_models(*, in_mixture: bool) -> tuple[str, ...]:
    """The size-distribution models (and aliases) ``model =`` accepts: the registry's.

    A mode of a mixture (or the parent of a truncation) is any model but a mixture;
    ``multimodal`` itself is written with ``[[size_distribution.modes]]``.
    """
    names = tuple(n for n in SIZE_DISTRIBUTIONS if n not in (*_NOT_IN_TOML, _MULTIMODAL))
    aliases = tuple(a for a, n in SIZE_DISTRIBUTION_ALIASES.items() if n in names)
    return (*names, *aliases) if in_mixture else (*names, _MULTIMODAL, *aliases)


# --------------------------------------------------------------------- errors


class ConfigError(ValueError):
    """A configuration file or text that does not follow the schema.

    The message reads ``<source>:<line>: <key>: <what is wrong>``, e.g.
    ``my.toml:12: size_distribution.v_eff: must be in the open interval (0, 0.5); got 0.7``.

    Attributes
    ----------
    key : str or None
        Dotted path of the offending key, with list indices
        (``size_distribution.modes[1].r_eff_um``); None for a syntax error.
    line : int or None
        1-based line of the key (or of its table header) in the text, or None
        when the key is absent and has no header (a missing top-level key).
    source : str
        The file's path, or ``"<string>"``.
    reason : str
        What is wrong, without the location.
    """

    def __init__(self, reason: str, *, key: str | None, line: int | None, source: str) -> None:
        self.reason = reason
        self.key = key
        self.line = line
        self.source = source
        where = source if line is None else f"{source}:{line}"
        super().__init__(f"{where}: {key}: {reason}" if key else f"{where}: {reason}")


# ----------------------------------------------------------- line locations


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _split_key(text: str) -> list[str] | None:
    """Components of a (possibly dotted, possibly quoted) TOML key, or None."""
    parts: list[str] = []
    rest = text.strip()
    while rest:
        if rest[0] in "\"'":
            end = rest.find(rest[0], 1)
            if end < 0:
                return None
            parts.append(rest[1:end])
            rest = rest[end + 1 :].strip()
        else:
            match = _BARE_KEY.match(rest)
            if not match:
                return None
            parts.append(match.group())
            rest = rest[match.end() :].strip()
        if rest.startswith("."):
            rest = rest[1:].strip()
        elif rest:
            return None
    return parts or None


def _scan(line: str, state: dict[str, Any]) -> int:
    """Update the multi-line string state and return the bracket depth change.

    Skips strings (basic, literal, multi-line) and comments, so that brackets
    inside them do not count.
    """
    depth = 0
    i = 0
    n = len(line)
    while i < n:
        delim = state["string"]
        if delim is not None:
            if delim in ('"', '"""') and line[i] == "\\":
                i += 2
                continue
            if line.startswith(delim, i):
                state["string"] = None
                i += len(delim)
                continue
            i += 1
            continue
        c = line[i]
        if c == "#":
            break
        if line.startswith('"""', i) or line.startswith("'''", i):
            state["string"] = line[i : i + 3]
            i += 3
            continue
        if c in "\"'":
            state["string"] = c
            i += 1
            continue
        if c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        i += 1
    if state["string"] in ('"', "'"):  # single-line strings end with the line
        state["string"] = None
    return depth


def _key_lines(text: str) -> dict[str, int]:
    """Line (1-based) of every table header and ``key =`` line, by dotted path.

    Array-of-tables elements are indexed, ``modes[1].r_eff_um``; keys inside
    inline tables and multi-line arrays map to their parent key's line by the
    fallback in :meth:`_Context.line`.
    """
    lines: dict[str, int] = {}
    counts: dict[str, int] = {}
    current = ""
    depth = 0
    state: dict[str, Any] = {"string": None}
    for number, raw in enumerate(text.splitlines(), start=1):
        in_string = state["string"] is not None
        stripped = raw.strip()
        if not in_string and depth == 0 and stripped.startswith("["):
            array = stripped.startswith("[[")
            close = stripped.find("]]" if array else "]")
            parts = _split_key(stripped[2 if array else 1 : close]) if close > 0 else None
            if parts:
                path = ""
                for part in parts:
                    path = f"{path}.{part}" if path else part
                    if path in counts and not (array and path == ".".join(parts)):
                        path = f"{path}[{counts[path] - 1}]"
                if array:
                    base = path
                    index = counts.get(base, 0)
                    counts[base] = index + 1
                    lines.setdefault(base, number)
                    path = f"{base}[{index}]"
                current = path
                lines.setdefault(path, number)
        elif not in_string and depth == 0 and "=" in stripped and not stripped.startswith("#"):
            parts = _split_key(stripped.split("=", 1)[0])
            if parts:
                path = current
                for part in parts:
                    path = f"{path}.{part}" if path else part
                    lines.setdefault(path, number)
        depth += _scan(raw, state)
    return lines


class _Context:
    """Where errors point: the source's name and its key lines."""

    def __init__(self, text: str, source: str) -> None:
        self.source = source
        self.lines = _key_lines(text)

    def line(self, key: str) -> int | None:
        """Line of ``key``, or of its nearest enclosing key or header present."""
        path = key
        while path:
            if path in self.lines:
                return self.lines[path]
            cut = max(path.rfind("."), path.rfind("["))
            path = path[:cut] if cut > 0 else ""
        return None

    def error(self, key: str, reason: str) -> ConfigError:
        return ConfigError(reason, key=key, line=self.line(key), source=self.source)


# ------------------------------------------------------------- value checks


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


def _type_name(value: Any) -> str:
    return {
        bool: "boolean",
        int: "integer",
        float: "number",
        str: "string",
        list: "array",
        dict: "table",
    }.get(type(value), type(value).__name__)


def _number(ctx: _Context, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ctx.error(key, f"must be a number; got {value!r} ({_type_name(value)})")
    try:
        out = float(value)
    except OverflowError:  # an integer beyond the float range (10**400)
        out = math.inf
    if not math.isfinite(out):
        shown = "an integer beyond the float range" if isinstance(value, int) else repr(value)
        raise ctx.error(key, f"must be a finite number; got {shown}")
    return out


def _positive(ctx: _Context, key: str, value: Any, unit: str = "") -> float:
    out = _number(ctx, key, value)
    if out <= 0.0:
        raise ctx.error(key, f"must be > 0{' ' + unit if unit else ''}; got {value!r}")
    return out


def _open(ctx: _Context, key: str, value: Any, low: float, high: float) -> float:
    out = _number(ctx, key, value)
    if not low < out < high:
        raise ctx.error(key, f"must be in the open interval ({low:g}, {high:g}); got {value!r}")
    return out


def _closed(ctx: _Context, key: str, value: Any, low: float, high: float) -> float:
    out = _number(ctx, key, value)
    if not low <= out <= high:
        raise ctx.error(key, f"must be in the closed interval [{low:g}, {high:g}]; got {value!r}")
    return out


def _integer(ctx: _Context, key: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.error(key, f"must be an integer; got {value!r} ({_type_name(value)})")
    if value < minimum:
        raise ctx.error(key, f"must be an integer >= {minimum}; got {value!r}")
    return value


def _string(ctx: _Context, key: str, value: Any) -> str:
    if not isinstance(value, str):
        raise ctx.error(key, f"must be a string; got {value!r} ({_type_name(value)})")
    if not value.strip():
        raise ctx.error(key, "must be a non-empty string")
    return value


def _choice(ctx: _Context, key: str, value: Any, choices: tuple[str, ...] | list[str]) -> str:
    text = _string(ctx, key, value)
    if text not in choices:
        valid = ", ".join(repr(c) for c in choices)
        raise ctx.error(key, f"must be one of {valid}; got {value!r}")
    return text


def _table(ctx: _Context, key: str, value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ctx.error(
            key, f"must be a table ([{key}] or {{...}}); got {value!r} ({_type_name(value)})"
        )
    return value


def _array(ctx: _Context, key: str, value: Any) -> list[Any]:
    if not isinstance(value, list):
        raise ctx.error(key, f"must be an array [...]; got {value!r} ({_type_name(value)})")
    return value


def _known_keys(
    ctx: _Context,
    prefix: str,
    table: Mapping[str, Any],
    allowed: tuple[str, ...],
    context: str = "",
) -> None:
    """Raise for the first key of ``table`` not in ``allowed`` (listing them)."""
    for key in table:
        if key not in allowed:
            where = f" {context}" if context else ""
            raise ctx.error(
                _join(prefix, key),
                f"unknown key{where}; allowed keys: {', '.join(allowed)}",
            )


def _required(ctx: _Context, prefix: str, table: Mapping[str, Any], key: str) -> Any:
    if key not in table:
        raise ctx.error(_join(prefix, key), "missing required key")
    return table[key]


def _not_used(ctx: _Context, key: str, model: str) -> ConfigError:
    return ctx.error(
        key,
        f"not used by phase.model = {model!r} (an analytic phase function has no material, "
        "size distribution, quadrature or cross-sections); remove it",
    )


# ------------------------------------------------------------ configuration


def _frozen(mapping: Mapping[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(dict(mapping))


@dataclass(frozen=True)
class MaterialConfig:
    """The refractive index m = n + i k of the particles.

    Attributes
    ----------
    model : str
        ``"mars_dust"``, ``"catalogue"`` or ``"constant"``.
    parameters : Mapping
        The model's parameters with defaults filled in: for ``"mars_dust"``
        ``hematite_fraction`` [-], ``host_index`` (``{"n", "k"}`` [-] or a
        catalogue name),
        ``hematite`` (full catalogue name) and ``rule``; for ``"catalogue"``
        ``name``; for ``"constant"`` ``n`` and ``k`` [-].
    """

    model: str
    parameters: Mapping[str, Any]

    def build(self) -> Any:
        """The refractive-index object for :func:`dustoptics.scattering.optics.compute_optics`."""
        p = self.parameters
        if self.model == "mars_dust":
            host_index = p["host_index"]
            host = (
                host_index
                if isinstance(host_index, str)
                else complex(host_index["n"], host_index["k"])
            )
            return mars_dust(
                hematite_fraction=p["hematite_fraction"],
                host_index=host,
                hematite=p["hematite"],
                rule=p["rule"],
            )
        if self.model == "catalogue":
            return get_material(p["name"])
        return complex(p["n"], p["k"])

    def to_inputs(self) -> dict[str, Any]:
        """JSON-ready parameters."""
        return {
            "model": self.model,
            **{k: (dict(v) if isinstance(v, Mapping) else v) for k, v in self.parameters.items()},
        }


def _input_value(value: Any) -> Any:
    """A mode's parameter as plain data (a nested mode as its dict, numbers as a list)."""
    if isinstance(value, ModeConfig):
        return value.to_inputs()
    if isinstance(value, tuple):
        return list(value)
    return value


@dataclass(frozen=True)
class ModeConfig:
    """One size mode: a distribution model and its parameters.

    Attributes
    ----------
    model : str
        A key of :data:`~dustoptics.particles.sizedist.SIZE_DISTRIBUTIONS`
        (``"modified_gamma"``, ...).
    parameters : Mapping
        Its parameters (radii in [um], the rest dimensionless): numbers, tuples
        of numbers, or a nested :class:`ModeConfig` (a truncation's parent).
    relative_number_density : float or None
        Weight in a multimodal distribution (only ratios matter); None for a
        single distribution. [-]
    """

    model: str
    parameters: Mapping[str, Any]
    relative_number_density: float | None = None

    def build(self) -> SizeDistribution:
        """The :class:`~dustoptics.particles.sizedist.SizeDistribution`."""
        cls = SIZE_DISTRIBUTIONS[self.model]
        return cls(
            **{
                k: (v.build() if isinstance(v, ModeConfig) else v)
                for k, v in self.parameters.items()
            }
        )

    def to_inputs(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "model": self.model,
            **{k: _input_value(v) for k, v in self.parameters.items()},
        }
        if self.relative_number_density is not None:
            out["relative_number_density"] = self.relative_number_density
        return out


@dataclass(frozen=True)
class SizeDistributionConfig:
    """The number size distribution n(r).

    Attributes
    ----------
    model : str
        A size-distribution model or ``"multimodal"``.
    modes : tuple of ModeConfig
        One mode for a single distribution (its ``relative_number_density``
        None), one per mode for ``"multimodal"``.
    """

    model: str
    modes: tuple[ModeConfig, ...]

    def build(self) -> SizeDistribution:
        """The :class:`~dustoptics.particles.sizedist.SizeDistribution` (a MultiModal for several modes)."""
        if self.model != "multimodal":
            return self.modes[0].build()
        return MultiModal(
            modes=tuple(m.build() for m in self.modes),
            relative_number_densities=tuple(
                float(m.relative_number_density or 0.0) for m in self.modes
            ),
        )

    def to_inputs(self) -> dict[str, Any]:
        if self.model != "multimodal":
            return self.modes[0].to_inputs()
        return {"model": "multimodal", "modes": [m.to_inputs() for m in self.modes]}


@dataclass(frozen=True)
class OpticsConfig:
    """Grids and quadrature settings.

    Attributes
    ----------
    wavelengths_nm : tuple of float
        Strictly increasing vacuum wavelengths. [nm]
    n_theta : int
        Number of scattering angles, evenly spaced from 0 to 180 deg inclusive.
    weighting : str or None
        ``"scattering"`` or ``"number"``; None for analytic-only models.
    rtol, cross_section_rtol : float or None
        Quadrature tolerances [-]; None for analytic-only models.
    expansion : bool, int or None
        ``True`` (every order needed) or the highest order N of the expansion
        coefficients (``compute_optics(expansion=...)``); None for none.
    polarization : bool
        Whether the scattering matrix F12, F33, F34 is computed
        (``compute_optics(polarization=...)``).
    """

    wavelengths_nm: tuple[float, ...]
    n_theta: int
    weighting: str | None = None
    rtol: float | None = None
    cross_section_rtol: float | None = None
    expansion: bool | int | None = None
    polarization: bool = False

    @property
    def theta_deg(self) -> np.ndarray:
        """Scattering angles ``linspace(0, 180, n_theta)``. [deg]"""
        return np.linspace(0.0, 180.0, self.n_theta)

    def to_inputs(self) -> dict[str, Any]:
        out: dict[str, Any] = {"wavelengths_nm": list(self.wavelengths_nm), "n_theta": self.n_theta}
        if self.weighting is not None:
            out.update(
                weighting=self.weighting, rtol=self.rtol, cross_section_rtol=self.cross_section_rtol
            )
        if self.expansion is not None:  # recorded only when asked: other tables' inputs unchanged
            out["expansion"] = self.expansion
        if self.polarization:  # likewise
            out["polarization"] = True
        return out


@dataclass(frozen=True)
class PhaseConfig:
    """The phase-function model.

    Attributes
    ----------
    model : str
        ``"mie"``, ``"hybrid"``, ``"costa2021_mars_dhg"`` or a name of
        :data:`dustoptics.scattering.phase.ANALYTIC_MODELS`.
    analytic : str or None
        The analytic model (the model itself when analytic-only, the blended
        one for ``"hybrid"``, None for ``"mie"``).
    parameters : Mapping
        The analytic model's parameters (``outside`` for the Costa spectrum,
        ``g`` for Cornette-Shanks, ...).
    weight : float or None
        Hybrid weight w of the analytic table, in [0, 1]; None unless hybrid. [-]
    """

    model: str
    analytic: str | None = None
    parameters: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    weight: float | None = None

    @property
    def uses_mie(self) -> bool:
        """Whether the table needs a Mie computation (``"mie"`` or ``"hybrid"``)."""
        return self.model in _MIE_MODELS

    def to_inputs(self) -> dict[str, Any]:
        out: dict[str, Any] = {"model": self.model}
        if self.model == "hybrid":
            out.update(weight=self.weight, analytic=self.analytic)
        out.update(self.parameters)
        return out


@dataclass(frozen=True)
class BuildConfig:
    """A validated build configuration (see the module docstring for the schema).

    Attributes
    ----------
    name : str
        Table name.
    description : str
        One-line description.
    sources : tuple of Source
        Sources the configuration cites.
    choices : tuple of str
        Choices the sources left open, as made here.
    material : MaterialConfig or None
        None for analytic-only models.
    size_distribution : SizeDistributionConfig or None
        None for analytic-only models.
    optics : OpticsConfig
        Grids and quadrature settings.
    phase : PhaseConfig
        Phase-function model.
    number_density_per_m3 : float or None
        Number density for the table's ``beta_*`` coefficients. [m^-3]
    source : str
        Where the configuration was read from (a path or ``"<string>"``).
    """

    name: str
    description: str
    sources: tuple[Source, ...]
    choices: tuple[str, ...]
    material: MaterialConfig | None
    size_distribution: SizeDistributionConfig | None
    optics: OpticsConfig
    phase: PhaseConfig
    number_density_per_m3: float | None = None
    source: str = "<string>"

    @property
    def wavelengths_nm(self) -> np.ndarray:
        """The wavelength grid. [nm]"""
        return np.array(self.optics.wavelengths_nm, dtype=np.float64)

    @property
    def theta_deg(self) -> np.ndarray:
        """The angle grid. [deg]"""
        return self.optics.theta_deg

    def to_inputs(self) -> dict[str, Any]:
        """Every computational parameter, defaults filled in, JSON-ready.

        This is what :func:`dustoptics.models.compute.build_table` stores as
        ``Provenance.inputs`` (and
        hashes).  The name, description, sources and choices label the table
        and are not part of it.
        """
        return {
            "schema": SCHEMA,
            "material": None if self.material is None else self.material.to_inputs(),
            "size_distribution": (
                None if self.size_distribution is None else self.size_distribution.to_inputs()
            ),
            "optics": self.optics.to_inputs(),
            "phase": self.phase.to_inputs(),
            "number_density_per_m3": self.number_density_per_m3,
        }


# ------------------------------------------------------------------ parsing

_TOP_KEYS: Final = (
    "name",
    "description",
    "choices",
    "number_density_per_m3",
    "sources",
    "material",
    "size_distribution",
    "optics",
    "phase",
)


def _parse_sources(ctx: _Context, value: Any) -> tuple[Source, ...]:
    out = []
    for i, item in enumerate(_array(ctx, "sources", value)):
        key = f"sources[{i}]"
        entry = _table(ctx, key, item)
        _known_keys(ctx, key, entry, ("name", "role", "citation"))
        out.append(
            Source(
                **{
                    k: _string(ctx, f"{key}.{k}", _required(ctx, key, entry, k))
                    for k in ("name", "role", "citation")
                }
            )
        )
    return tuple(out)


def _parse_material(ctx: _Context, value: Any) -> MaterialConfig:
    sec = _table(ctx, "material", value)
    model = _choice(
        ctx, "material.model", _required(ctx, "material", sec, "model"), tuple(_MATERIAL_KEYS)
    )
    _known_keys(ctx, "material", sec, _MATERIAL_KEYS[model], f"for material.model = {model!r}")
    if model == "catalogue":
        names = list_materials()
        name = _choice(ctx, "material.name", _required(ctx, "material", sec, "name"), names)
        return MaterialConfig(model, _frozen({"name": name}))
    if model == "constant":
        n = _positive(ctx, "material.n", _required(ctx, "material", sec, "n"))
        k = _number(ctx, "material.k", sec.get("k", 0.0))
        if k < 0:
            raise ctx.error("material.k", f"must be >= 0 (absorption); got {sec['k']!r}")
        return MaterialConfig(model, _frozen({"n": n, "k": k}))
    fraction = _closed(
        ctx, "material.hematite_fraction", sec.get("hematite_fraction", 0.03), 0.0, 1.0
    )
    host = sec.get("host_index", 1.5)
    host_value: Any
    if isinstance(host, str):
        host_value = _choice(ctx, "material.host_index", host, list_materials())
    elif isinstance(host, dict):
        _known_keys(ctx, "material.host_index", host, ("n", "k"))
        host_n = _positive(
            ctx, "material.host_index.n", _required(ctx, "material.host_index", host, "n")
        )
        host_k = _number(ctx, "material.host_index.k", host.get("k", 0.0))
        if host_k < 0:
            raise ctx.error(
                "material.host_index.k", f"must be >= 0 (absorption); got {host['k']!r}"
            )
    else:
        try:
            host_n = _positive(ctx, "material.host_index", host)
        except ConfigError:
            raise ctx.error(
                "material.host_index",
                f"must be a number n > 0 or a table {{n = ..., k = ...}}; got {host!r}",
            ) from None
        host_k = 0.0
    if not isinstance(host, str):
        host_value = _frozen({"n": host_n, "k": host_k})
    hematite = _choice(
        ctx,
        "material.hematite",
        sec.get("hematite", "querry-extraordinary"),
        (*MARS_DUST_HEMATITE, *MARS_DUST_HEMATITE.values()),
    )
    rule = _choice(ctx, "material.rule", sec.get("rule", "maxwell_garnett"), MIXING_RULES)
    return MaterialConfig(
        model,
        _frozen(
            {
                "hematite_fraction": fraction,
                "host_index": host_value,
                "hematite": MARS_DUST_HEMATITE.get(hematite, hematite),
                "rule": rule,
            }
        ),
    )


def _parameter_value(ctx: _Context, key: str, raw: Any, param: SizeParameter) -> Any:
    """One size-distribution parameter from TOML, checked against its registry record."""
    if param.kind == "distribution":
        return _parse_mode(ctx, key, _table(ctx, key, raw), in_mixture=True, weighted=False)
    if param.kind == "numbers":
        return tuple(_number(ctx, f"{key}[{i}]", v) for i, v in enumerate(_array(ctx, key, raw)))
    if param.low == 0.0 and param.high == math.inf:
        return _positive(ctx, key, raw, "um" if param.name.endswith("_um") else "")
    if param.low == -math.inf and param.high == math.inf:
        return _number(ctx, key, raw)
    return _open(ctx, key, raw, param.low, param.high)


def _parse_mode(
    ctx: _Context,
    prefix: str,
    sec: Mapping[str, Any],
    *,
    in_mixture: bool,
    weighted: bool | None = None,
) -> ModeConfig:
    """One distribution from ``sec``: its model, its registry parameters (and a mixture's weight)."""
    weighted = in_mixture if weighted is None else weighted
    given = _choice(
        ctx,
        f"{prefix}.model",
        _required(ctx, prefix, sec, "model"),
        _size_models(in_mixture=in_mixture),
    )
    model = SIZE_DISTRIBUTION_ALIASES.get(given, given)
    params = SIZE_DISTRIBUTIONS[model].parameters
    allowed = ("model", *(p.name for p in params)) + (
        ("relative_number_density",) if weighted else ()
    )
    _known_keys(ctx, prefix, sec, allowed, f"for {prefix}.model = {given!r}")
    values = {
        p.name: _parameter_value(ctx, f"{prefix}.{p.name}", _required(ctx, prefix, sec, p.name), p)
        for p in params
        if p.required or p.name in sec
    }
    density = None
    if weighted:
        density = _positive(
            ctx,
            f"{prefix}.relative_number_density",
            _required(ctx, prefix, sec, "relative_number_density"),
        )
    mode = ModeConfig(model, _frozen(values), density)
    try:
        mode.build()
    except ValueError as exc:  # any remaining constraint of the class itself
        raise ctx.error(prefix, str(exc)) from None
    return mode


def _parse_size_distribution(ctx: _Context, value: Any) -> SizeDistributionConfig:
    sec = _table(ctx, "size_distribution", value)
    model = _choice(
        ctx,
        "size_distribution.model",
        _required(ctx, "size_distribution", sec, "model"),
        _size_models(in_mixture=False),
    )
    if model != _MULTIMODAL:
        return SizeDistributionConfig(
            model, (_parse_mode(ctx, "size_distribution", sec, in_mixture=False),)
        )
    _known_keys(
        ctx,
        "size_distribution",
        sec,
        ("model", "modes"),
        "for size_distribution.model = 'multimodal'",
    )
    raw = _array(ctx, "size_distribution.modes", _required(ctx, "size_distribution", sec, "modes"))
    if not raw:
        raise ctx.error(
            "size_distribution.modes", "must hold at least one [[size_distribution.modes]] table"
        )
    modes = tuple(
        _parse_mode(
            ctx,
            f"size_distribution.modes[{i}]",
            _table(ctx, f"size_distribution.modes[{i}]", m),
            in_mixture=True,
        )
        for i, m in enumerate(raw)
    )
    return SizeDistributionConfig("multimodal", modes)


def _parse_wavelengths(ctx: _Context, value: Any) -> tuple[float, ...]:
    key = "optics.wavelengths_nm"
    if isinstance(value, dict):
        _known_keys(ctx, key, value, ("start", "stop", "step"))
        start = _positive(ctx, f"{key}.start", _required(ctx, key, value, "start"), "nm")
        stop = _positive(ctx, f"{key}.stop", _required(ctx, key, value, "stop"), "nm")
        step = _positive(ctx, f"{key}.step", _required(ctx, key, value, "step"), "nm")
        if stop < start:
            raise ctx.error(f"{key}.stop", f"must be >= start ({start:g} nm); got {stop:g}")
        intervals = (stop - start) / step
        if intervals + 1 > MAX_GRID_POINTS:
            raise ctx.error(
                f"{key}.step",
                f"gives {intervals + 1:.3g} wavelengths, more than {MAX_GRID_POINTS} (a larger step, "
                "or a shorter range)",
            )
        count = round(intervals)
        if abs(intervals - count) > 1e-9 * max(1.0, intervals):
            raise ctx.error(
                f"{key}.step",
                f"must divide stop - start = {stop - start:g} nm into whole steps; got {step:g}",
            )
        grid = start + step * np.arange(count + 1, dtype=np.float64)
        grid[-1] = stop
        return tuple(float(x) for x in grid)
    items = _array(ctx, key, value)
    if not items:
        raise ctx.error(key, "must not be empty")
    if len(items) > MAX_GRID_POINTS:
        raise ctx.error(key, f"must hold at most {MAX_GRID_POINTS} wavelengths; got {len(items)}")
    values = [_positive(ctx, f"{key}[{i}]", x, "nm") for i, x in enumerate(items)]
    if any(b <= a for a, b in itertools.pairwise(values)):
        raise ctx.error(key, f"must be strictly increasing; got {items!r}")
    return tuple(values)


def _parse_optics(ctx: _Context, value: Any, *, mie: bool, model: str) -> OpticsConfig:
    sec = _table(ctx, "optics", value)
    allowed = ("wavelengths_nm", "n_theta", "theta_step_deg")
    mie_keys = ("weighting", "rtol", "cross_section_rtol", "expansion", "polarization")
    if not mie:
        for key in mie_keys:
            if key in sec:
                raise _not_used(ctx, f"optics.{key}", model)
    expansion = _expansion(ctx, sec.get("expansion", False), model)
    polarization = _polarization(ctx, sec.get("polarization", False), model)
    _known_keys(ctx, "optics", sec, allowed + mie_keys)
    wavelengths = _parse_wavelengths(ctx, sec.get("wavelengths_nm", dict(_DEFAULT_WAVELENGTHS)))
    if "n_theta" in sec and "theta_step_deg" in sec:
        raise ctx.error(
            "optics.theta_step_deg", "give either optics.n_theta or optics.theta_step_deg, not both"
        )
    if "theta_step_deg" in sec:
        step = _open(ctx, "optics.theta_step_deg", sec["theta_step_deg"], 0.0, 180.0 + 1e-9)
        intervals = 180.0 / step
        if intervals + 1 > MAX_GRID_POINTS:
            raise ctx.error(
                "optics.theta_step_deg",
                f"gives {intervals + 1:.3g} angles, more than {MAX_GRID_POINTS}; got {step:g}",
            )
        if abs(intervals - round(intervals)) > 1e-9 * intervals:
            raise ctx.error(
                "optics.theta_step_deg", f"must divide 180 deg into whole steps; got {step:g}"
            )
        n_theta = round(intervals) + 1
    else:
        n_theta = _integer(ctx, "optics.n_theta", sec.get("n_theta", _DEFAULT_N_THETA), 2)
        if n_theta > MAX_GRID_POINTS:
            raise ctx.error("optics.n_theta", f"must be <= {MAX_GRID_POINTS}; got {n_theta}")
    try:
        check_wavelength_unit("optics.wavelengths_nm", np.asarray(wavelengths))
    except ValueError as exc:
        raise ctx.error("optics.wavelengths_nm", str(exc).split(" ", 1)[1]) from None
    if not mie:
        return OpticsConfig(wavelengths, n_theta)
    weighting = _choice(ctx, "optics.weighting", sec.get("weighting", "scattering"), WEIGHTINGS)
    rtol = _open(ctx, "optics.rtol", sec.get("rtol", _DEFAULT_RTOL), 0.0, 0.1)
    cross = _open(
        ctx, "optics.cross_section_rtol", sec.get("cross_section_rtol", rtol / 100.0), 0.0, 0.1
    )
    return OpticsConfig(wavelengths, n_theta, weighting, rtol, cross, expansion, polarization)


#: Highest order ``optics.expansion`` accepts (``true`` gives every order the spheres need).
MAX_EXPANSION_ORDER: Final = 10_000


def _expansion(ctx: _Context, value: Any, model: str) -> bool | int | None:
    """``optics.expansion``: None (false), True, or an order N in [0, MAX_EXPANSION_ORDER]."""
    key = "optics.expansion"
    if value is False:
        return None
    if model != "mie":
        raise ctx.error(
            key,
            f"is available for phase.model = 'mie' only; got phase.model = {model!r} (the "
            "coefficients expand the Mie phase function, not a blend with an analytic one)",
        )
    if value is True:
        return True
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.error(
            key,
            f"must be true, false or an order N >= 0 (an integer); got {value!r} "
            f"({_type_name(value)})",
        )
    if not 0 <= value <= MAX_EXPANSION_ORDER:
        raise ctx.error(
            key,
            f"must be an order in [0, {MAX_EXPANSION_ORDER}] (true: every order the spheres "
            f"need); got {value!r}",
        )
    return value


def _polarization(ctx: _Context, value: Any, model: str) -> bool:
    """``optics.polarization``: whether the scattering matrix is computed (Mie only)."""
    key = "optics.polarization"
    if not isinstance(value, bool):
        raise ctx.error(key, f"must be true or false; got {value!r} ({_type_name(value)})")
    if value and model != "mie":
        raise ctx.error(
            key,
            f"is available for phase.model = 'mie' only; got phase.model = {model!r} (the "
            "matrix is the Mie one, not that of a blend with an analytic phase function)",
        )
    return value


def _analytic_names() -> tuple[str, ...]:
    return (_COSTA_SPECTRUM, *_phase.ANALYTIC_MODELS)


def _parse_analytic(
    ctx: _Context, sec: Mapping[str, Any], name: str, fixed: tuple[str, ...]
) -> Mapping[str, Any]:
    """Parameters of analytic model ``name`` from ``[phase]`` (``fixed`` keys already handled)."""
    if name == _COSTA_SPECTRUM:
        _known_keys(ctx, "phase", sec, (*fixed, "outside"), f"for the analytic model {name!r}")
        outside = _choice(ctx, "phase.outside", sec.get("outside", "quadratic"), _COSTA_OUTSIDE)
        return _frozen({"outside": outside})
    model = _phase.get_analytic_model(name)
    _known_keys(ctx, "phase", sec, (*fixed, *model.parameters), f"for the analytic model {name!r}")
    params = {
        p: _number(ctx, f"phase.{p}", _required(ctx, "phase", sec, p)) for p in model.parameters
    }
    try:
        model.phase(np.array([1.0, -1.0]), **params)
    except ValueError as exc:  # the function's own range checks name the parameter first
        message = str(exc)
        bad = next((p for p in model.parameters if message.startswith(p + " ")), None)
        if bad is None:
            raise ctx.error("phase", message) from None
        raise ctx.error(f"phase.{bad}", message[len(bad) + 1 :]) from None
    return _frozen(params)


def _parse_phase(ctx: _Context, value: Any) -> PhaseConfig:
    sec = _table(ctx, "phase", value)
    models = ("mie", "hybrid", *_analytic_names())
    model = _choice(ctx, "phase.model", sec.get("model", "mie"), models)
    if model == "mie":
        _known_keys(ctx, "phase", sec, ("model",), "for phase.model = 'mie'")
        return PhaseConfig("mie")
    if model == "hybrid":
        weight = _closed(ctx, "phase.weight", sec.get("weight", _DEFAULT_HYBRID_WEIGHT), 0.0, 1.0)
        analytic = _choice(
            ctx, "phase.analytic", sec.get("analytic", _DEFAULT_ANALYTIC), _analytic_names()
        )
        params = _parse_analytic(ctx, sec, analytic, ("model", "weight", "analytic"))
        return PhaseConfig("hybrid", analytic, params, weight)
    return PhaseConfig(model, model, _parse_analytic(ctx, sec, model, ("model",)))


class SweepAxesIgnored(UserWarning):
    """A configuration with a ``[sweep]`` table was read as one point: its own values."""


def _sweep_axes_left_out(ctx: _Context, data: dict[str, Any]) -> None:
    """A ``[sweep]`` table (:mod:`dustoptics.sweep`'s axes) is taken out of ``data``: the
    configuration is its own values, one point, and a warning says so."""
    if "sweep" not in data:
        return
    axes = _table(ctx, "sweep", data.pop("sweep"))
    warnings.warn(
        f"{ctx.source}: the [sweep] table ({len(axes)} "
        f"{'axis' if len(axes) == 1 else 'axes'}: {', '.join(map(repr, axes))}) is left out: "
        "this is the configuration's own values, one point ('dustoptics sweep' computes the axes)",
        SweepAxesIgnored,
        stacklevel=3,
    )


def parse_config(text: str, *, source: str = "<string>") -> BuildConfig:
    """Validate a TOML build configuration.

    Parameters
    ----------
    text : str
        TOML text following the schema of this module.
    source : str, optional
        Name for error messages (a path; default ``"<string>"``).

    Returns
    -------
    BuildConfig

    Raises
    ------
    ConfigError
        Malformed TOML, unknown or missing keys, wrong types, values out of
        range; the message names the key and its line.
    """
    ctx = _Context(text, source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        match = re.search(r"at line (\d+)", str(exc))
        raise ConfigError(
            f"invalid TOML: {exc}",
            key=None,
            line=int(match.group(1)) if match else None,
            source=source,
        ) from None
    except RecursionError:
        raise ConfigError(
            "invalid TOML: nested too deeply to read", key=None, line=None, source=source
        ) from None
    except ValueError as exc:  # tomllib's own: an integer of more than 4300 digits
        raise ConfigError(f"invalid TOML: {exc}", key=None, line=None, source=source) from None
    _sweep_axes_left_out(ctx, data)
    _known_keys(ctx, "", data, _TOP_KEYS)
    name = _string(ctx, "name", _required(ctx, "", data, "name"))
    try:
        check_file_name("name", name)
    except ValueError as exc:
        raise ctx.error("name", str(exc).split(" ", 1)[1]) from None
    description = _string(ctx, "description", _required(ctx, "", data, "description"))
    choices = tuple(
        _string(ctx, f"choices[{i}]", c)
        for i, c in enumerate(_array(ctx, "choices", data.get("choices", [])))
    )
    sources = _parse_sources(ctx, data.get("sources", []))
    phase_config = _parse_phase(ctx, data.get("phase", {"model": "mie"}))
    mie = phase_config.uses_mie
    material: MaterialConfig | None = None
    distribution: SizeDistributionConfig | None = None
    if mie:
        material = _parse_material(ctx, _required(ctx, "", data, "material"))
        distribution = _parse_size_distribution(ctx, _required(ctx, "", data, "size_distribution"))
    else:
        for key in ("material", "size_distribution", "number_density_per_m3"):
            if key in data:
                raise _not_used(ctx, key, phase_config.model)
    optics = _parse_optics(ctx, data.get("optics", {}), mie=mie, model=phase_config.model)
    density = None
    if "number_density_per_m3" in data:
        density = _positive(ctx, "number_density_per_m3", data["number_density_per_m3"], "m^-3")
    return BuildConfig(
        name=name,
        description=description,
        sources=sources,
        choices=choices,
        material=material,
        size_distribution=distribution,
        optics=optics,
        phase=phase_config,
        number_density_per_m3=density,
        source=source,
    )
