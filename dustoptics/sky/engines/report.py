"""The error table: every engine's fitted and community parameters against the exact sky.

For each planet set (:func:`planet_sets`: Earth, and Mars with every dust
preset that has cross-sections, at vertical optical depth 0.5 at 550 nm), the
exact sky is rendered on the coarse dome at the Sun elevations
:data:`~dustoptics.sky.engines.core.FIT_SUN_ELEVATIONS_DEG`
(:func:`~dustoptics.sky.engines.core.reference_skies`), and each engine of
:data:`~dustoptics.sky.engines.core.ENGINES` is fitted to it
(``kind="fitted"``) and evaluated with what people use today
(``kind="community"``, exposure adjusted): :func:`engines_report`.

The computation takes minutes per planet (the exact skies, and the fits of the
engines that march rays); :func:`engines_report` keeps each planet's rows in
a cache directory, and the package ships the table it computed
(:data:`SHIPPED_REPORT`, read by :func:`shipped_report`), which the
documentation prints at build time (:meth:`EngineReport.table_rst`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Final, TextIO

import numpy as np

from dustoptics.atmosphere.build import build_atmosphere
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.io._atomic import write_files
from dustoptics.models.presets import list_presets, load_preset
from dustoptics.sky.engines.core import (
    DOME_AZIMUTH_DEG,
    DOME_ZENITH_DEG,
    ENGINES,
    FIT_SUN_ELEVATIONS_DEG,
    SkyError,
    fit_engine,
    reference_skies,
)

__all__ = [
    "MARS_OPTICAL_DEPTH",
    "REPORT_VERSION",
    "SHIPPED_REPORT",
    "EngineReport",
    "ReportRow",
    "build_planet",
    "engines_report",
    "planet_sets",
    "shipped_report",
]

#: Vertical optical depth of the Mars dust at 550 nm in every Mars set of the table. [-]
MARS_OPTICAL_DEPTH: Final = 0.5

#: Changes when the computation changes (cached rows of another version are recomputed).
REPORT_VERSION: Final = 1

#: The table the package ships (``dustoptics engines report --out`` writes it).
SHIPPED_REPORT: Final = "report.json"


def planet_sets() -> tuple[str, ...]:
    """``"earth"`` and ``"mars:PRESET"`` for every preset with cross-sections (a Mie dust)."""
    dusts = [name for name in list_presets() if load_preset(name).phase.uses_mie]
    return ("earth", *(f"mars:{name}" for name in dusts))


def build_planet(key: str, *, progress: TextIO | None = None) -> Atmosphere:
    """The atmosphere set of a :func:`planet_sets` key, named by it (``mars-PRESET``)."""
    if key == "earth":
        return build_atmosphere("earth", progress=progress)
    planet, _, dust = key.partition(":")
    if planet != "mars" or not dust:
        raise ValueError(f"planet must be 'earth' or 'mars:PRESET'; got {key!r}")
    atmosphere = build_atmosphere(
        "mars", dust=dust, optical_depth=MARS_OPTICAL_DEPTH, progress=progress
    )
    return dataclasses.replace(atmosphere, name=f"mars-{dust}")


@dataclass(frozen=True)
class ReportRow:
    """One engine, planet and kind of parameters, with the errors per Sun elevation."""

    engine: str
    planet: str
    kind: str
    errors: tuple[SkyError, ...]
    params: dict[str, float]

    @property
    def delta_e_mean(self) -> float:
        """Mean over the Sun elevations of the dome's mean Delta E 2000. [-]"""
        return float(np.mean([e.delta_e_mean for e in self.errors]))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN as None)."""
        return {
            "engine": self.engine,
            "planet": self.planet,
            "kind": self.kind,
            "params": self.params,
            "errors": [_nan_to_none(dataclasses.asdict(e)) for e in self.errors],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ReportRow:
        """The inverse of :meth:`to_dict`."""
        errors = tuple(
            SkyError(**{k: _none_to_nan(v) for k, v in e.items()}) for e in data["errors"]
        )
        return cls(data["engine"], data["planet"], data["kind"], errors, dict(data["params"]))


def _nan_to_none(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _nan_to_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_nan_to_none(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _none_to_nan(value: Any) -> Any:
    if value is None:
        return math.nan
    if isinstance(value, list):
        return tuple(math.nan if v is None else v for v in value)
    return value


@dataclass(frozen=True)
class EngineReport:
    """Every row, and how the table was made."""

    rows: tuple[ReportRow, ...]
    sun_elevations_deg: tuple[float, ...] = FIT_SUN_ELEVATIONS_DEG
    version: int = REPORT_VERSION

    def to_json(self) -> str:
        """The report as JSON text."""
        document = {
            "version": self.version,
            "sun_elevations_deg": list(self.sun_elevations_deg),
            "dome": {
                "zenith_deg": list(DOME_ZENITH_DEG),
                "azimuth_deg": list(DOME_AZIMUTH_DEG),
                "plus": "the zenith angle 10 deg above the Sun",
            },
            "rows": [row.to_dict() for row in self.rows],
        }
        return json.dumps(document, indent=1, allow_nan=False) + "\n"

    @classmethod
    def from_json(cls, text: str) -> EngineReport:
        """The inverse of :meth:`to_json`."""
        data = json.loads(text)
        return cls(
            rows=tuple(ReportRow.from_dict(r) for r in data["rows"]),
            sun_elevations_deg=tuple(data["sun_elevations_deg"]),
            version=int(data["version"]),
        )

    def lines(self) -> list[list[str]]:
        """Header and one row per engine, planet and kind: Delta E 2000 mean over the dome
        averaged over the Sun elevations, mean and 95th percentile per Sun elevation, xy at the zenith and 10 deg above the Sun (exact ->
        engine) and the luminance ratio, both at the highest Sun."""
        header = ["engine", "planet", "parameters", "dE00 mean, all elevations"]
        header += [f"dE00 {e:g} deg (mean/p95)" for e in self.sun_elevations_deg]
        header += ["xy zenith (exact -> engine)", "xy 10 deg from Sun", "luminance ratio"]
        out = [header]
        for row in self.rows:
            first = row.errors[0]
            cells = [ENGINES[row.engine].title if row.engine in ENGINES else row.engine]
            cells += [row.planet, row.kind, f"{row.delta_e_mean:.1f}"]
            cells += [f"{e.delta_e_mean:.1f} / {e.delta_e_p95:.1f}" for e in row.errors]
            cells.append(f"{_fmt_xy(first.xy_zenith_exact)} -> {_fmt_xy(first.xy_zenith_engine)}")
            cells.append(
                f"{_fmt_xy(first.xy_near_sun_exact)} -> {_fmt_xy(first.xy_near_sun_engine)}"
            )
            cells.append(" / ".join(f"{e.luminance_ratio:.2f}" for e in row.errors))
            out.append(cells)
        return out

    def row_losses(self) -> list[str]:
        """Engines and planets whose fitted Delta E 2000, averaged over the dome and the Sun
        elevations, is not smaller than the community row's: one line each."""
        by_key = {(r.engine, r.planet, r.kind): r for r in self.rows}
        return [
            f"{engine} {planet}: fitted {row.delta_e_mean:.2f} >= community "
            f"{by_key[(engine, planet, 'community')].delta_e_mean:.2f}"
            for (engine, planet, kind), row in by_key.items()
            if kind == "fitted"
            and (engine, planet, "community") in by_key
            and not row.delta_e_mean < by_key[(engine, planet, "community")].delta_e_mean
        ]

    def losses(self) -> list[str]:
        """Where the fitted row's Delta E 2000 (mean or 95th percentile, at any Sun
        elevation) is not smaller than the community row's: one line each."""
        by_key = {(r.engine, r.planet, r.kind): r for r in self.rows}
        out = []
        for (engine, planet, kind), fitted in by_key.items():
            community = by_key.get((engine, planet, "community"))
            if kind != "fitted" or community is None:
                continue
            for f, c in zip(fitted.errors, community.errors, strict=True):
                for what, a, b in (
                    ("mean", f.delta_e_mean, c.delta_e_mean),
                    ("p95", f.delta_e_p95, c.delta_e_p95),
                ):
                    if not a < b:
                        out.append(
                            f"{engine} {planet} Sun {f.sun_elevation_deg:g} deg: fitted {what} "
                            f"{a:.2f} >= community {b:.2f}"
                        )
        return out

    def table_text(self) -> str:
        """A plain-text table (``dustoptics engines report``)."""
        rows = self.lines()
        widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
        text = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
        text.insert(1, "  ".join("-" * w for w in widths))
        return "\n".join(text) + "\n"

    def table_rst(self) -> str:
        """The table as a reStructuredText list table (the documentation's)."""
        rows = self.lines()
        out = [".. list-table::", "   :header-rows: 1", ""]
        for r in rows:
            out.append(f"   * - {r[0]}")
            out += [f"     - {c}" for c in r[1:]]
        return "\n".join(out) + "\n"


def _fmt_xy(xy: tuple[float, float]) -> str:
    if not all(math.isfinite(v) for v in xy):
        return "(black)"
    return f"({xy[0]:.3f}, {xy[1]:.3f})"


def _planet_rows(key: str, engines: Sequence[str], progress: TextIO | None) -> list[ReportRow]:
    atmosphere = build_planet(key)
    skies = reference_skies(atmosphere)
    rows = []
    for name in engines:
        for kind in ("community", "fitted"):
            if progress is not None:
                print(f"{key}: {name} {kind}", file=progress, flush=True)
            fit = fit_engine(ENGINES[name], atmosphere, skies, kind=kind)
            rows.append(ReportRow(name, key, kind, fit.errors, dict(fit.params)))
    return rows


def engines_report(
    *,
    planets: Sequence[str] | None = None,
    engines: Sequence[str] | None = None,
    cache_dir: str | Path | None = None,
    progress: TextIO | None = None,
) -> EngineReport:
    """Fit every engine to every planet set and measure both rows (minutes per planet).

    Parameters
    ----------
    planets : sequence of str, optional
        Keys of :func:`planet_sets` (default all).
    engines : sequence of str, optional
        Keys of :data:`~dustoptics.sky.engines.core.ENGINES` (default all).
    cache_dir : path, optional
        Where each planet's rows are kept (``engines-PLANET.json``) and read back
        when they were made by this :data:`REPORT_VERSION`; only the engines
        missing there are fitted (an engine added later costs its own rows).
    progress : text stream, optional
        Where to report each fit.

    Returns
    -------
    EngineReport
    """
    keys = list(planet_sets() if planets is None else planets)
    names = list(ENGINES if engines is None else engines)
    unknown = [n for n in names if n not in ENGINES]
    if unknown:
        raise ValueError(f"engines must be among {sorted(ENGINES)}; got {unknown}")
    rows: list[ReportRow] = []
    for key in keys:
        found: list[ReportRow] = []
        path = None
        if cache_dir is not None:
            path = Path(cache_dir) / f"engines-{key.replace(':', '-')}.json"
            if path.is_file():
                cached = EngineReport.from_json(path.read_text(encoding="utf-8"))
                if cached.version == REPORT_VERSION:
                    found = list(cached.rows)
        missing = [n for n in names if n not in {r.engine for r in found}]
        if missing:
            found += _planet_rows(key, missing, progress)
            if path is not None:
                text = EngineReport(tuple(found)).to_json()
                write_files({path: text.encode("utf-8")}, overwrite=True)
        rows += [r for n in names for r in found if r.engine == n]
    return EngineReport(tuple(rows))


def shipped_report() -> EngineReport:
    """The table shipped with the package (:data:`SHIPPED_REPORT`)."""
    text = resources.files("dustoptics.sky.engines").joinpath(SHIPPED_REPORT).read_text("utf-8")
    return EngineReport.from_json(text)
