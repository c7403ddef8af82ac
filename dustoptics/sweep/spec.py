"""What a sweep is: a build configuration with axes, validated before any work.

A sweep takes a configuration (:mod:`dustoptics.models.config`: a preset name,
a TOML file, its text or a :class:`~dustoptics.models.config.BuildConfig`)
and axes: dotted keys of the TOML configuration, each with the values it
takes.  Any numeric input can be an axis::

    size_distribution.r_eff_um              [um]
    size_distribution.v_eff                 [-]
    size_distribution.modes[1].r_eff_um     [um] (a mode of a multimodal distribution)
    material.hematite_fraction              [-]
    material.host_index.n                   [-] (and material.host_index.k)
    optics.rtol                             [-]

In a TOML file the axes go into a ``[sweep]`` table, as lists or as evenly
spaced ranges (both ends included)::

    [sweep]
    "size_distribution.r_eff_um" = [0.5, 1.0, 2.0, 4.0]
    "size_distribution.v_eff" = { start = 0.1, stop = 0.4, num = 4 }

An axis name has one canonical form, which names the dimension of the
result: whitespace around its parts is dropped (``" size_distribution.r_eff_um\n"``)
and indices are plain integers (``modes[01]`` is ``modes[1]``); two axes that
name one input (two spellings, or a quoted and a bare key of a ``[sweep]``
table) are refused, naming both.

The points are the Cartesian product of the axes, the first axis slowest.
Before any point is made, the number of points (from the axes' lengths) is
held against the memory they take in this process
(:data:`CLIENT_BYTES_PER_POINT` each); then every point's configuration is the
base configuration with the axis values set, validated by
:func:`dustoptics.models.config.parse_config`, its cost estimated as a single
build's (:func:`dustoptics.scattering.optics.check_cost`, which refuses a
point a single build would refuse), and its material evaluated at the
wavelengths, all before any work: an axis value outside its model's range
raises a ValueError naming the axis, the value and the range.
"""

from __future__ import annotations

import copy
import itertools
import json
import math
import os
import re
import tomllib
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics import _validation
from dustoptics._files import read_config_text
from dustoptics._validation import BudgetError, check_budget
from dustoptics.models.compute import mie_request
from dustoptics.models.config import (
    BuildConfig,
    ConfigError,
    _Context,
    _parse_size_distribution,
    _scan,
    parse_config,
)
from dustoptics.models.presets import list_presets, preset_text
from dustoptics.scattering.optics import RequestCost, check_cost
from dustoptics.table import canonical_json, plain

__all__ = ["Axis", "SweepSpec", "canonical_key", "config_data", "load_sweep", "toml_text"]

#: Prefix of the keys that change only the size distribution: points that
#: differ only in these share their Mie work (:mod:`dustoptics.sweep.shared`).
SIZE_PREFIX = "size_distribution."

#: Memory a point takes in the process that starts a sweep: its TOML data and
#: configuration (about 3 KiB), its labels and provenance in the result's
#: template (about 26 KiB, measured for blue-moons). [bytes]
CLIENT_BYTES_PER_POINT = 32 * 1024


@dataclass(frozen=True)
class Axis:
    """One swept input.

    Attributes
    ----------
    key : str
        Dotted key of the TOML configuration (``size_distribution.r_eff_um``);
        also the name of the dimension in the result.
    values : tuple of float
        The values it takes, in order.
    """

    key: str
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "key", canonical_key(self.key))

    @property
    def size_only(self) -> bool:
        """Whether the axis changes only the size distribution."""
        return self.key.startswith(SIZE_PREFIX)


# ------------------------------------------------------------------ TOML data

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _toml_key(key: str) -> str:
    return key if _BARE.match(key) else json.dumps(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"configuration values must be finite; got {value!r}")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, Mapping):
        return (
            "{"
            + ", ".join(f"{_toml_key(str(k))} = {_toml_value(v)}" for k, v in value.items())
            + "}"
        )
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} ({type(value).__name__}) as TOML")


def toml_text(data: Mapping[str, Any]) -> str:
    """TOML text of configuration data (one ``key = value`` line per top-level key).

    >>> toml_text({"name": "x", "material": {"model": "constant", "n": 1.5}})
    'name = "x"\\nmaterial = {model = "constant", n = 1.5}\\n'
    """
    return "".join(f"{_toml_key(k)} = {_toml_value(v)}\n" for k, v in data.items())


def config_data(config: BuildConfig) -> dict[str, Any]:
    """The TOML data of a configuration object: ``parse_config(toml_text(
    config_data(c)))`` gives back an equal configuration (same inputs)."""
    if not isinstance(config, BuildConfig):
        raise TypeError(f"config must be a BuildConfig; got {type(config).__name__}")
    data: dict[str, Any] = {"name": config.name, "description": config.description}
    if config.choices:
        data["choices"] = list(config.choices)
    if config.number_density_per_m3 is not None:
        data["number_density_per_m3"] = config.number_density_per_m3
    if config.sources:
        data["sources"] = [plain(s) for s in config.sources]
    if config.material is not None:
        data["material"] = plain(config.material.to_inputs())
    if config.size_distribution is not None:
        data["size_distribution"] = plain(config.size_distribution.to_inputs())
    data["optics"] = plain(config.optics.to_inputs())
    data["phase"] = plain(config.phase.to_inputs())
    return data


def _strip_sweep_table(text: str) -> str:
    """``text`` with the ``[sweep]`` table's lines blanked (so that line
    numbers in the base configuration's errors stay right)."""
    lines = text.splitlines()
    out = []
    inside = False
    depth = 0
    state: dict[str, Any] = {"string": None}
    for raw in lines:
        stripped = raw.strip()
        at_top = depth == 0 and state["string"] is None
        if at_top and stripped.startswith("["):
            inside = (
                re.match(r"^\[\s*sweep\s*\]", stripped) is not None
                or re.match(r"^\[\[?\s*sweep\s*\.", stripped) is not None
            )
        depth += _scan(raw, state)
        out.append("" if inside else raw)
    return "\n".join(out) + ("\n" if text.endswith("\n") else "")


_PART = re.compile(r"([A-Za-z0-9_-]+)\s*(?:\[\s*([0-9]+)\s*\])?")


def canonical_key(key: str) -> str:
    """The canonical form of a sweep axis's dotted key.

    Whitespace around each part goes, and an index is a plain integer; this is the
    name of the axis's dimension in the result.

    >>> canonical_key(" size_distribution.modes[01] . r_eff_um\\n")
    'size_distribution.modes[1].r_eff_um'

    Raises
    ------
    ValueError
        Not a dotted key of the configuration.
    """
    if not isinstance(key, str):
        raise TypeError(f"sweep axis names must be strings; got {key!r} ({type(key).__name__})")
    return ".".join(name if index is None else f"{name}[{index}]" for name, index in _path(key))


def _path(key: str) -> list[tuple[str, int | None]]:
    parts = []
    for part in key.split("."):
        match = _PART.fullmatch(part.strip())
        if not match:
            raise ValueError(
                f"sweep axis {key!r} is not a dotted key of the configuration "
                "(e.g. 'size_distribution.r_eff_um' or 'size_distribution.modes[1].r_eff_um')"
            )
        parts.append((match.group(1), None if match.group(2) is None else int(match.group(2))))
    return parts


def _get(data: Mapping[str, Any], key: str) -> Any:
    """The value at dotted ``key`` of ``data`` (None if absent)."""
    node: Any = data
    for name, index in _path(key):
        if not isinstance(node, Mapping) or name not in node:
            return None
        node = node[name]
        if index is not None:
            if not isinstance(node, list) or index >= len(node):
                return None
            node = node[index]
    return node


def _set(data: dict[str, Any], key: str, value: float) -> None:
    """Set dotted ``key`` of ``data`` (in place) to ``value``."""
    parts = _path(key)
    node: Any = data
    for depth, (name, index) in enumerate(parts):
        last = depth == len(parts) - 1
        where = ".".join(f"{n}" + ("" if i is None else f"[{i}]") for n, i in parts[: depth + 1])
        if not isinstance(node, dict):
            raise ValueError(
                f"sweep axis {key!r}: {where.rsplit('.', 1)[0]!r} is not a table of the configuration"
            )
        if last and index is None:
            node[name] = value
            return
        if name not in node:
            if index is not None:
                raise ValueError(f"sweep axis {key!r}: the configuration has no {where!r}")
            node[name] = {}
        node = node[name]
        if index is not None:
            if not isinstance(node, list) or index >= len(node):
                raise ValueError(f"sweep axis {key!r}: the configuration has no {where!r}")
            if last:
                raise ValueError(f"sweep axis {key!r} names a table, not a number")
            node = node[index]


# ------------------------------------------------------------------ axes


def _axis_size(key: str, raw: Any) -> int:
    """How many values an axis takes, from a list or a {start, stop, num} range,
    without making them (``num`` may be anything a TOML file holds)."""
    if isinstance(raw, Mapping):
        extra = set(raw) - {"start", "stop", "num"}
        if extra or not {"start", "stop", "num"} <= set(raw):
            raise ValueError(
                f"sweep axis {key!r}: a range is {{start = ..., stop = ..., num = ...}}; "
                f"got keys {sorted(map(str, raw))!r}"
            )
        num = raw["num"]
        if isinstance(num, (bool, np.bool_)) or not isinstance(num, (int, np.integer)) or num < 1:
            raise ValueError(f"sweep axis {key!r}: num must be an integer >= 1; got {num!r}")
        for k in ("start", "stop"):
            _number(key, raw[k])
        return int(num)
    if isinstance(raw, (str, bytes)) or not isinstance(raw, Sequence | np.ndarray):
        raise TypeError(
            f"sweep axis {key!r}: values must be a list of numbers or a range "
            f"{{start, stop, num}}; got {type(raw).__name__}"
        )
    if len(raw) == 0:
        raise ValueError(f"sweep axis {key!r}: needs at least one value")
    return len(raw)


def _axis_values(key: str, raw: Any) -> tuple[float, ...]:
    """Axis values from a list or a {start, stop, num} range (both ends included)."""
    _axis_size(key, raw)
    if isinstance(raw, Mapping):
        num = int(raw["num"])
        start, stop = (_number(key, raw[k]) for k in ("start", "stop"))
        grid = np.linspace(start, stop, num) if num > 1 else np.array([start])
        values = tuple(float(v) for v in grid)
        if len(set(values)) != len(values):
            raise ValueError(
                f"sweep axis {key!r}: values must be distinct; the range {start!r} .. {stop!r} "
                f"in {num} steps repeats values"
            )
        return values
    values = tuple(_number(key, v) for v in raw)
    if len(set(values)) != len(values):
        shown = list(values) if len(values) <= 20 else f"{list(values[:20])!r}..."
        raise ValueError(f"sweep axis {key!r}: values must be distinct; got {shown}")
    return values


def _number(key: str, value: Any) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(
        value, (int, float, np.integer, np.floating)
    ):
        raise TypeError(
            f"sweep axis {key!r}: values must be numbers; got {value!r} ({type(value).__name__})"
        )
    try:
        out = float(value)
    except OverflowError:
        out = math.inf
    if not math.isfinite(out):
        raise ValueError(f"sweep axis {key!r}: values must be finite; got {value!r}")
    return out


def _toml_spelling(parts: Sequence[str]) -> str:
    """How a ``[sweep]`` key was written: bare parts joined by dots, others quoted."""
    return ".".join(_toml_key(p) for p in parts)


#: Deepest dotted ``[sweep]`` key: the configuration's deepest input
#: (``size_distribution.modes[1].r_eff_um``, ``material.host_index.n``) is 3 deep.
_MAX_KEY_DEPTH = 8


def _flatten_sweep_table(
    table: Mapping[str, Any], prefix: tuple[str, ...] = ()
) -> dict[str, tuple[str, Any]]:
    """``[sweep]`` entries by canonical key -> (their spelling, their values):
    quoted (``"a.b" = [...]``) or nested (``a.b = [...]``, which TOML reads as
    tables).  Two entries for one input are refused, naming both."""
    out: dict[str, tuple[str, Any]] = {}
    if len(prefix) > _MAX_KEY_DEPTH:
        raise ValueError(
            f"[sweep] key {_toml_spelling(prefix[:4])}... is nested {len(prefix)} tables deep; "
            f"a configuration's inputs are at most {_MAX_KEY_DEPTH} deep"
        )
    for k, v in table.items():
        parts = prefix + (str(k),)
        if isinstance(v, Mapping) and not {"start", "stop", "num"} & set(v):
            entries = _flatten_sweep_table(v, parts)
        else:
            spelling = _toml_spelling(parts)
            entries = {canonical_key(".".join(parts)): (spelling, v)}
        for key, (spelling, values) in entries.items():
            if key in out:
                raise ValueError(
                    f"[sweep] names the input {key!r} twice, as {out[key][0]} and as "
                    f"{spelling}; keep one of them"
                )
            out[key] = (spelling, values)
    return out


# ------------------------------------------------------------------ outputs

#: Why a sweep refuses ``optics.expansion = true``.
_EVERY_ORDER = (
    "a sweep cannot take true (every order the spheres need, which differs by point and "
    "wavelength): it stores the coefficients of every point on one order axis, so give the "
    "highest order N (optics.expansion = N; about 2 x the largest size parameter keeps every "
    "order that matters)"
)


def expansion_orders(config: BuildConfig) -> int:
    """The length of a sweep's ``order`` dimension: N + 1 for ``optics.expansion = N``,
    0 without expansion coefficients.

    Raises
    ------
    ValueError
        ``optics.expansion = true`` (see :func:`load_sweep`).
    """
    expansion = config.optics.expansion
    if expansion is None:
        return 0
    if expansion is True:
        raise ValueError(f"optics.expansion: {_EVERY_ORDER}")
    return int(expansion) + 1


def _check_outputs(base: Mapping[str, Any], source: str) -> None:
    """Refuse what a sweep cannot store, naming the key, before any point is made."""
    optics = base.get("optics")
    if isinstance(optics, Mapping) and optics.get("expansion") is True:
        raise ConfigError(_EVERY_ORDER, key="optics.expansion", line=None, source=source)


# ------------------------------------------------------------------ the spec


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: the base configuration's TOML data and the axes.

    Attributes
    ----------
    base : Mapping
        TOML data of the base configuration (see :func:`config_data`).
    axes : tuple of Axis
        The axes, first slowest.
    source : str
        Where the configuration came from (preset name, path, ``"<object>"``).
    """

    base: Mapping[str, Any]
    axes: tuple[Axis, ...]
    source: str = "<object>"

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of values per axis."""
        return tuple(len(a.values) for a in self.axes)

    @property
    def n_points(self) -> int:
        return int(np.prod(self.shape, dtype=np.int64))

    def point_data(self, index: Sequence[int]) -> dict[str, Any]:
        """TOML data of the point at ``index`` (one index per axis)."""
        data = copy.deepcopy(dict(self.base))
        for axis, i in zip(self.axes, index):
            _set(data, axis.key, axis.values[i])
        return data

    def indices(self) -> Iterator[tuple[int, ...]]:
        """Indices of all points, first axis slowest."""
        return itertools.product(*(range(n) for n in self.shape))

    def identity(self) -> str:
        """Canonical JSON of the base and the axes: what a stored sweep must match to resume."""
        return canonical_json(
            {"base": plain(self.base), "axes": [[a.key, list(a.values)] for a in self.axes]}
        )


def parse_point(data: Mapping[str, Any], *, source: str = "<sweep point>") -> BuildConfig:
    """The validated configuration of one point's TOML data."""
    return parse_config(toml_text(data), source=source)


def _point_parser() -> Callable[[Mapping[str, Any]], BuildConfig]:
    """A :func:`parse_point` for the points of one sweep: a point that differs
    from the first only in its size distribution reuses the first's other
    sections and validates its distribution alone (the sections of a
    configuration are validated independently; 20x faster than the whole
    text, which matters for sweeps of thousands of points)."""
    first: list[tuple[BuildConfig, dict[str, Any]]] = []

    def parse(data: Mapping[str, Any]) -> BuildConfig:
        rest = {k: v for k, v in data.items() if k != "size_distribution"}
        if first and "size_distribution" in data and rest == first[0][1]:
            distribution = _parse_size_distribution(
                _Context("", "<sweep point>"), data["size_distribution"]
            )
            return replace(first[0][0], size_distribution=distribution)
        config = parse_point(data)
        if not first:
            first.append((config, rest))
        return config

    return parse


def parse_points(points: Sequence[Mapping[str, Any]]) -> list[BuildConfig]:
    """The validated configurations of a sweep's points (see :func:`parse_point`)."""
    parse = _point_parser()
    return [parse(p) for p in points]


def _base_from(config: Any) -> tuple[dict[str, Any], dict[str, Any], str]:
    """(base TOML data, [sweep] table, source) of a preset name, TOML path or text, or object."""
    if isinstance(config, BuildConfig):
        return config_data(config), {}, "<object>"
    if isinstance(config, (str, os.PathLike)):
        text_config = str(config)
        if isinstance(config, str) and text_config in list_presets():
            text, source = preset_text(text_config), f"preset {text_config}"
        elif isinstance(config, str) and "\n" in text_config:
            text, source = text_config, "<string>"
        else:
            path = Path(config)
            if not path.is_file():
                raise ValueError(
                    f"config must be a preset name ({', '.join(list_presets())}), a TOML file, "
                    f"TOML text or a BuildConfig; got {text_config!r}"
                )
            text, source = read_config_text(path), str(path)
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"invalid TOML: {exc}", key=None, line=None, source=source) from None
        except RecursionError:
            raise ConfigError(
                "invalid TOML: nested too deeply to read", key=None, line=None, source=source
            ) from None
        table = data.pop("sweep", {})
        if not isinstance(table, Mapping):
            raise ConfigError("must be a table [sweep]", key="sweep", line=None, source=source)
        base = parse_config(
            _strip_sweep_table(text), source=source
        )  # the base's own errors, with lines
        return config_data(base), dict(table), source
    raise TypeError(
        f"config must be a preset name, a TOML file path, TOML text or a BuildConfig; got {type(config).__name__}"
    )


def load_sweep(
    config: Any, over: Mapping[str, Any] | None = None, *, allow_large: bool = False
) -> SweepSpec:
    """A validated sweep from a configuration and axes.

    Parameters
    ----------
    config : str, os.PathLike or BuildConfig
        A preset name, a TOML file (its ``[sweep]`` table gives axes), TOML
        text, or a configuration object.
    over : Mapping, optional
        Axes: dotted key -> list of values or ``{"start", "stop", "num"}``;
        they replace axes of the same input in the file's ``[sweep]`` table
        and follow its axes.
    allow_large : bool
        Accept more points than :data:`CLIENT_BYTES_PER_POINT` lets into the
        memory budget, and points beyond a single build's budget.

    Returns
    -------
    SweepSpec

    Raises
    ------
    ValueError
        A key that is not a numeric input, two keys (or two spellings of one)
        for the same input, or a value outside its model's range (the message
        names the axis, the value and the range), a point whose material has
        no data at a wavelength, or a request beyond the budget
        (:class:`~dustoptics._validation.BudgetError`).
    TypeError
        Values that are not numbers.
    """
    return _load_points(config, over, allow_large=allow_large)[0]


def _load_points(
    config: Any, over: Mapping[str, Any] | None, *, allow_large: bool = False
) -> tuple[SweepSpec, list[dict[str, Any]], list[BuildConfig], list[RequestCost | None]]:
    """:func:`load_sweep`, with the points' TOML data (in C order of the axes),
    their configurations, validated once, and their costs (None for a point
    without Mie work)."""
    if not isinstance(allow_large, bool):
        raise TypeError(f"allow_large must be True or False; got {allow_large!r}")
    base, table, source = _base_from(config)
    _check_outputs(base, source)
    raw = {key: values for key, (_, values) in _flatten_sweep_table(table).items()}
    if over is not None:
        if not isinstance(over, Mapping):
            raise TypeError(
                f"over must be a mapping of dotted keys to values; got {type(over).__name__}"
            )
        given: dict[str, Any] = {}
        for k, values in over.items():
            key = canonical_key(k)
            if key in given:
                raise ValueError(
                    f"over names the input {key!r} twice, as {given[key]!r} and as {k!r}; "
                    "keep one of them"
                )
            given[key] = k
            raw[key] = values
    if not raw:
        raise ValueError("a sweep needs at least one axis: give over={...} or a [sweep] table")
    sizes = []
    for key, values in raw.items():
        current = _get(base, key)
        if isinstance(current, Mapping):
            numbers = [
                k
                for k, v in current.items()
                if isinstance(v, (int, float)) and not isinstance(v, bool)
            ]
            raise ValueError(
                f"sweep axis {key!r} names a table of the configuration, not a number; "
                f"sweep one of its numbers: {', '.join(f'{key}.{k}' for k in numbers)}"
            )
        if current is not None and (
            isinstance(current, bool) or not isinstance(current, (int, float))
        ):
            raise ValueError(
                f"sweep axis {key!r} is not a numeric input of the configuration (its value is {current!r})"
            )
        sizes.append(_axis_size(key, values))
    _check_points(list(raw), sizes, allow_large=allow_large)
    axes = tuple(Axis(key, _axis_values(key, values)) for key, values in raw.items())
    spec = SweepSpec(base=base, axes=axes, source=source)
    data, configs, costs = _validate(spec, allow_large=allow_large)
    return spec, data, configs, costs


def _physical_memory_bytes() -> float:
    """This machine's memory, or infinity where it cannot be read. [bytes]"""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):
        return math.inf


def _check_points(keys: Sequence[str], sizes: Sequence[int], *, allow_large: bool) -> None:
    """Refuse a number of points (from the axes' lengths, before any is made)
    whose descriptions alone exceed the memory budget (unless ``allow_large``)
    or this machine's memory (always)."""
    n = math.prod(sizes)
    needed = float(n) * CLIENT_BYTES_PER_POINT
    shape = " x ".join(f"{size} ({key})" for key, size in zip(keys, sizes))
    physical = _physical_memory_bytes()
    if needed > physical:
        raise BudgetError(
            f"a sweep of {n:.4g} points ({shape}) would need about {needed / 1024**3:.3g} GiB "
            f"in this process for the points alone, more than this machine's "
            f"{physical / 1024**3:.3g} GiB: use fewer values per axis, or split the sweep"
        )
    check_budget(
        f"a sweep of {n:.4g} points",
        needed,
        allow_large=allow_large,
        change=(
            f"its points ({shape}) are each described, validated and labelled in this process, "
            f"about {CLIENT_BYTES_PER_POINT / 1024:g} KiB each, "
            f"{_validation.MEMORY_BUDGET_BYTES // CLIENT_BYTES_PER_POINT} points at most: use "
            "fewer values per axis, or split the sweep"
        ),
    )


def _validate(
    spec: SweepSpec, *, allow_large: bool = False
) -> tuple[list[dict[str, Any]], list[BuildConfig], list[RequestCost | None]]:
    """Every axis value alone, then every point (its configuration and its
    cost, refused where a single build would refuse it), then every distinct
    material at the wavelengths: all before any work.  Returns the points'
    TOML data, configurations and costs."""
    for axis in spec.axes:
        for value in axis.values:
            data = copy.deepcopy(dict(spec.base))
            _set(data, axis.key, value)
            try:
                parse_point(data)
            except ConfigError as exc:
                raise ValueError(
                    f"sweep axis {axis.key!r}: value {value!r} is outside its model's range: "
                    f"{exc.key}: {exc.reason}"
                ) from None
    materials: dict[str, Any] = {}
    parse = _point_parser()
    points, configs, costs = [], [], []
    for index in spec.indices():
        data = spec.point_data(index)
        try:
            config = parse(data)
        except ConfigError as exc:
            raise ValueError(
                f"sweep point ({_where(spec, index)}) is not a valid configuration: "
                f"{exc.key}: {exc.reason}"
            ) from None
        points.append(data)
        configs.append(config)
        costs.append(_point_cost(spec, index, config, allow_large))
        if config.material is not None:
            materials.setdefault(canonical_json(config.material.to_inputs()), (config, index))
    for config, index in materials.values():
        try:
            m = config.material.build()
            if callable(m):
                m(config.wavelengths_nm)
        except ValueError as exc:
            raise ValueError(f"sweep point ({_where(spec, index)}): {exc}") from None
    return points, configs, costs


def _where(spec: SweepSpec, index: Sequence[int]) -> str:
    return ", ".join(f"{a.key} = {a.values[i]!r}" for a, i in zip(spec.axes, index))


def _point_cost(
    spec: SweepSpec,
    index: Sequence[int],
    config: BuildConfig,
    allow_large: bool,
) -> RequestCost | None:
    """A point's Mie cost as a single build estimates it (one thread: a chunk
    is one task), refused where a single build would refuse it."""
    if not config.phase.uses_mie or config.size_distribution is None:
        return None
    try:
        return check_cost(mie_request(config), workers=1, allow_large=allow_large)
    except BudgetError as exc:
        raise BudgetError(f"sweep point ({_where(spec, index)}): {exc}") from None
    except ValueError as exc:
        raise ValueError(f"sweep point ({_where(spec, index)}): {exc}") from None
