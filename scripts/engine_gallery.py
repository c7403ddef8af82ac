"""Draw the engines' gallery: exact sky | engine fitted | engine community, side by side.

Usage: python scripts/engine_gallery.py [--out DIR] [--size PX] [--report-cache DIR]
       [--planets KEY ...] [--engines NAME ...] [--sun-elevations DEG ...]
       [--zenith-step DEG] [--azimuth-step DEG]

For each engine and planet set (default: every engine, Mars with the default dust preset
and Earth), one PNG ``ENGINE-PLANET.png`` (``mars:blue-moons`` -> ``mars-blue-moons``) with
a row per Sun elevation (default 45 and 0 deg) of three fisheyes at one exposure
(dustoptics.sky.engines.gallery).  The parameters are the error table's rows: the table the
package ships (dustoptics.sky.engines.report.shipped_report), or with ``--report-cache`` the
per-planet files ``engines report --cache-dir`` keeps (read only; nothing is fitted here).
Each label's Delta E 2000 is recomputed from the row's parameters and must equal the row's.
Deterministic: the same bytes on every run of one installation.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from dustoptics.io._atomic import write_files
from dustoptics.models.presets import DEFAULT_PRESET
from dustoptics.sky.engines import ENGINES
from dustoptics.sky.engines.core import reference_skies
from dustoptics.sky.engines.gallery import (
    GALLERY_SUN_ELEVATIONS_DEG,
    engine_panels,
    exact_dome,
    gallery_png,
    row_params,
)
from dustoptics.sky.engines.report import EngineReport, ReportRow, build_planet, shipped_report
from dustoptics.sky.medium import Medium
from dustoptics.sky.scene import default_view_zenith_deg

DEFAULT_OUT = Path(__file__).resolve().parents[1] / "docs" / "gallery" / "engines"
DEFAULT_PLANETS = (f"mars:{DEFAULT_PRESET}", "earth")


def _rows(planet: str, cache: Path | None) -> dict[tuple[str, str], ReportRow]:
    if cache is None:
        report = shipped_report()
    else:
        path = cache / f"engines-{planet.replace(':', '-')}.json"
        if not path.is_file():
            raise SystemExit(f"--report-cache: no {path} (dustoptics engines report --cache-dir)")
        report = EngineReport.from_json(path.read_text(encoding="utf-8"))
    return {(r.engine, r.kind): r for r in report.rows if r.planet == planet}


def _zenith_grid(step: float | None) -> np.ndarray:
    if step is None:
        return default_view_zenith_deg()
    return np.linspace(0.0, 90.0, round(90.0 / step) + 1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--size", type=int, default=160, help="fisheye side [pixels]")
    parser.add_argument("--report-cache", type=Path, default=None)
    parser.add_argument("--planets", nargs="+", default=list(DEFAULT_PLANETS))
    parser.add_argument("--engines", nargs="+", default=list(ENGINES), choices=list(ENGINES))
    parser.add_argument(
        "--sun-elevations", nargs="+", type=float, default=list(GALLERY_SUN_ELEVATIONS_DEG)
    )
    parser.add_argument(
        "--zenith-step", type=float, default=None, help="[deg] (default 1, 0.25 near the horizon)"
    )
    parser.add_argument("--azimuth-step", type=float, default=2.0, help="[deg]")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    zen = _zenith_grid(args.zenith_step)
    files: dict[Path, bytes] = {}
    for planet in args.planets:
        rows = _rows(planet, args.report_cache)
        missing = [
            f"{e} {k}" for e in args.engines for k in ("fitted", "community") if (e, k) not in rows
        ]
        if missing:
            raise SystemExit(f"{planet}: the report has no rows for {', '.join(missing)}")
        atmosphere = build_planet(planet)
        medium = Medium.from_atmosphere(atmosphere)
        panels: dict[str, list] = {e: [] for e in args.engines}
        pairs = {e: {k: rows[(e, k)] for k in ("fitted", "community")} for e in args.engines}
        params = {
            e: {k: row_params(ENGINES[e], row, atmosphere) for k, row in pair.items()}
            for e, pair in pairs.items()
        }
        for elevation in args.sun_elevations:
            sky = exact_dome(
                medium,
                sun_elevation_deg=elevation,
                view_zenith_deg=zen,
                azimuth_step_deg=args.azimuth_step,
            )
            (dome,) = reference_skies(medium, sun_elevations_deg=[elevation])
            for engine in args.engines:
                p = engine_panels(
                    pairs[engine], atmosphere, sky, dome, size=args.size, params=params[engine]
                )
                panels[engine].append(p)
                print(
                    f"{planet} {engine} Sun {elevation:g} deg: dE00 mean fitted "
                    f"{p.delta_e_mean[0]:.2f} (row {p.row_delta_e_mean[0]:.2f}), community "
                    f"{p.delta_e_mean[1]:.2f} (row {p.row_delta_e_mean[1]:.2f})",
                    flush=True,
                )
        for engine, rows_of in panels.items():
            name = f"{engine}-{planet.replace(':', '-')}.png"
            files[args.out / name] = gallery_png(rows_of)
    write_files(files, overwrite=True)
    for path, data in files.items():
        print(f"{path.name}: {len(data)} bytes")
    total = sum(len(d) for d in files.values())
    print(
        f"{len(files)} files, {total} bytes, {time.perf_counter() - start:.0f} s", file=sys.stderr
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
