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

The points are the Cartesian product of the axes, the first axis slowest.
Every point's configuration is the base configuration with the axis values
set, validated by :func:`dustoptics.models.config.parse_config`, and its
material evaluated at the wavelengths, all before any work: an axis value
outside its model's range raises a ValueError naming the axis, the value and
the range.
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

from dustoptics.models.config import (
    BuildConfig,
    ConfigError,
    _Context,
    _parse_size_distribution,
    _scan,
    parse_config,
)
from dustoptics.models.presets import list_presets, preset_text
from dustoptics.table import canonical_json, plain

__all__ = ["Axis", "SweepSpec", "config_data", "load_sweep", "toml_text"]

#: Prefix of the keys that change only the size distribution: points that
#: differ only in these share their Mie work (:mod:`dustoptics.sweep.shared`).
SIZE_PREFIX = "size_distribution."


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


_PART = re.compile(r"^([A-Za-z0-9_-]+)(?:\[(\d+)\])?$")


def _path(key: str) -> list[tuple[str, int | None]]:
    parts = []
    for part in key.split("."):
        match = _PART.match(part)
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


def _axis_values(key: str, raw: Any) -> tuple[float, ...]:
    """Axis values from a list or a {start, stop, num} range (both ends included)."""
    if isinstance(raw, Mapping):
        extra = set(raw) - {"start", "stop", "num"}
        if extra or not {"start", "stop", "num"} <= set(raw):
            raise ValueError(
                f"sweep axis {key!r}: a range is {{start = ..., stop = ..., num = ...}}; got {dict(raw)!r}"
            )
        num = raw["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise ValueError(f"sweep axis {key!r}: num must be an integer >= 1; got {num!r}")
        start, stop = (_number(key, raw[k]) for k in ("start", "stop"))
        grid = np.linspace(start, stop, num) if num > 1 else np.array([start])
        return tuple(float(v) for v in grid)
    if isinstance(raw, (str, bytes)) or not isinstance(raw, Sequence | np.ndarray):
        raise TypeError(
            f"sweep axis {key!r}: values must be a list of numbers or a range "
            f"{{start, stop, num}}; got {raw!r}"
        )
    values = tuple(_number(key, v) for v in raw)
    if not values:
        raise ValueError(f"sweep axis {key!r}: needs at least one value")
    if len(set(values)) != len(values):
        raise ValueError(f"sweep axis {key!r}: values must be distinct; got {list(values)!r}")
    return values


def _number(key: str, value: Any) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(
        value, (int, float, np.integer, np.floating)
    ):
        raise TypeError(
            f"sweep axis {key!r}: values must be numbers; got {value!r} ({type(value).__name__})"
        )
    out = float(value)
    if not math.isfinite(out):
        raise ValueError(f"sweep axis {key!r}: values must be finite; got {value!r}")
    return out


def _flatten_sweep_table(table: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """``[sweep]`` entries as dotted keys: quoted (``"a.b" = [...]``) or nested
    (``a.b = [...]``, which TOML reads as tables)."""
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, Mapping) and not {"start", "stop", "num"} & set(v):
            out.update(_flatten_sweep_table(v, key))
        else:
            out[key] = v
    return out


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
            text, source = path.read_text(encoding="utf-8"), str(path)
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"invalid TOML: {exc}", key=None, line=None, source=source) from None
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


def load_sweep(config: Any, over: Mapping[str, Any] | None = None) -> SweepSpec:
    """A validated sweep from a configuration and axes.

    Parameters
    ----------
    config : str, os.PathLike or BuildConfig
        A preset name, a TOML file (its ``[sweep]`` table gives axes), TOML
        text, or a configuration object.
    over : Mapping, optional
        Axes: dotted key -> list of values or ``{"start", "stop", "num"}``;
        they replace axes of the same key in the file's ``[sweep]`` table and
        follow its axes.

    Returns
    -------
    SweepSpec

    Raises
    ------
    ValueError
        A key that is not a numeric input, or a value outside its model's
        range (the message names the axis, the value and the range), or a
        point whose material has no data at a wavelength.
    TypeError
        Values that are not numbers.
    """
    return _load_points(config, over)[0]


def _load_points(
    config: Any, over: Mapping[str, Any] | None
) -> tuple[SweepSpec, list[dict[str, Any]], list[BuildConfig]]:
    """:func:`load_sweep`, with the points' TOML data (in C order of the axes)
    and their configurations, validated once."""
    base, table, source = _base_from(config)
    raw = _flatten_sweep_table(table)
    if over is not None:
        if not isinstance(over, Mapping):
            raise TypeError(
                f"over must be a mapping of dotted keys to values; got {type(over).__name__}"
            )
        raw.update({str(k): v for k, v in over.items()})
    if not raw:
        raise ValueError("a sweep needs at least one axis: give over={...} or a [sweep] table")
    axes = []
    for key, values in raw.items():
        _path(key)
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
        axes.append(Axis(key, _axis_values(key, values)))
    spec = SweepSpec(base=base, axes=tuple(axes), source=source)
    data, configs = _validate(spec)
    return spec, data, configs


def _validate(spec: SweepSpec) -> tuple[list[dict[str, Any]], list[BuildConfig]]:
    """Every axis value alone, then every point, then every distinct material
    at the wavelengths: all before any work.  Returns the points' TOML data
    and configurations."""
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
    points, configs = [], []
    for index in spec.indices():
        data = spec.point_data(index)
        try:
            config = parse(data)
        except ConfigError as exc:
            where = ", ".join(f"{a.key} = {a.values[i]!r}" for a, i in zip(spec.axes, index))
            raise ValueError(
                f"sweep point ({where}) is not a valid configuration: {exc.key}: {exc.reason}"
            ) from None
        points.append(data)
        configs.append(config)
        if config.material is not None:
            materials.setdefault(canonical_json(config.material.to_inputs()), (config, index))
    for config, index in materials.values():
        try:
            m = config.material.build()
            if callable(m):
                m(config.wavelengths_nm)
        except ValueError as exc:
            where = ", ".join(f"{a.key} = {a.values[i]!r}" for a, i in zip(spec.axes, index))
            raise ValueError(f"sweep point ({where}): {exc}") from None
    return points, configs
