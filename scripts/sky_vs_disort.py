"""The sky against CDISORT: the largest radiance error of every validation case.

Usage::

    python scripts/sky_vs_disort.py [--streams N] [--reference-streams M] [--cases LIST]
                                    [--json OUT.json] [--no-horizon]

For each validation case of ``tests/reference/disort.py`` (Rayleigh scattering,
an Earth aerosol at optical depth 0.1 and 0.4, Mars dust at 0.5, 1 and 2, Mars
dust at 0.5 in a uniform layer from the ground to 1 km; 440,
550 and 670 nm; the Sun at 20, 45 and 70 deg elevation) the renderer's
radiance at its defaults (``--streams`` overrides the number of streams) is
compared with converged CDISORT (``NSTR = 2 x --reference-streams``) on a
plane-parallel planet, in the directions a plane-parallel model can judge
(``validation_directions``: view zenith 0-10 deg in
1 deg steps, a grid to 75 deg, a ring 3-15 deg around the Sun).  The table
gives the largest relative error, where it is (view zenith, azimuth from the
Sun, scattering angle, wavelength), the largest with the view within 10 deg
of the zenith, and the error model's estimate
(:func:`~dustoptics.sky.accuracy.radiance_error_estimate`).

Then the horizon: the same atmospheres on their real planets (spherical
shell, pseudo-spherical beam) against the plane-parallel column, view zenith
60-90 deg, to show by how much and why the two differ there.

Needs the ``test`` extra (nanodisort).  About 30 minutes on two cores (the
converged reference is most of it).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from dustoptics.atmosphere import sets
from dustoptics.sky.medium import Medium
from dustoptics.sky.orders import solve_orders
from dustoptics.sky.render import line_of_sight_radiance
from tests.reference import disort as ref


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _case_label(kind: str, tau: float) -> str:
    return kind if kind == "rayleigh" else f"{kind} {tau:g}"


def run_cases(
    cases: list[tuple[str, float]], *, streams: int | None, reference_streams: int
) -> list[dict]:
    tables = {}
    rows = []
    for kind, tau in cases:
        key = "mars-dust" if kind.startswith("mars-dust") else "earth-aerosol"
        if key not in tables:
            log(f"Mie optics of the {key} (3 wavelengths)")
            tables[key] = ref.validation_table(key)
        atm = ref.validation_atmosphere(kind, tau, table=tables[key])
        for elevation in ref.VALIDATION_SUN_ELEVATIONS_DEG:
            t0 = time.perf_counter()
            res = ref.compare_with_disort(
                atm,
                sun_elevation_deg=elevation,
                reference_streams=reference_streams,
                threads=2,
                n_streams=streams,
            )
            err = np.abs(res["relative_error"])
            i, x = np.unravel_index(int(np.argmax(err)), err.shape)
            near_zenith = res["view_zenith_deg"] <= 10.0 + 1e-9
            row = {
                "case": _case_label(kind, tau),
                "sun_elevation_deg": elevation,
                "max_error": float(err.max()),
                "view_zenith_deg": float(res["view_zenith_deg"][i]),
                "view_azimuth_deg": float(res["view_azimuth_deg"][i]),
                "theta_deg": float(res["theta_deg"][i]),
                "wavelength_nm": float(ref.VALIDATION_WAVELENGTHS_NM[x]),
                "max_error_zenith_10deg": float(err[near_zenith].max()),
                "estimate": float(np.max(res["radiance_error_estimate"])),
                "directions": int(err.shape[0]),
                "seconds": time.perf_counter() - t0,
            }
            rows.append(row)
            log(
                f"{row['case']:<17} Sun {elevation:4.0f} deg: {100 * row['max_error']:.3f} % "
                f"({row['seconds']:.0f} s)"
            )
    return rows


def format_cases(rows: list[dict], *, streams: int, reference_streams: int) -> str:
    lines = [
        f"The sky against CDISORT ({streams} streams; reference NSTR = {2 * reference_streams}, "
        f"{ref.REFERENCE_LAYERS} layers, {ref.REFERENCE_MOMENTS} moments)",
        "largest |radiance / CDISORT - 1| over the judged directions (Sun >= 20 deg, view "
        "zenith <= 75 deg, >= 3 deg from the Sun) and 440, 550, 670 nm",
        "",
        f"{'case':<17} {'Sun':>5} {'max':>8}  {'where: zenith, azimuth, from Sun, nm':<38} "
        f"{'zenith<=10':>10} {'estimate':>9}",
    ]
    for r in rows:
        where = (
            f"{r['view_zenith_deg']:5.1f} {r['view_azimuth_deg']:6.1f} {r['theta_deg']:5.1f} "
            f"{r['wavelength_nm']:4.0f}"
        )
        lines.append(
            f"{r['case']:<17} {r['sun_elevation_deg']:5.0f} {100 * r['max_error']:7.3f}%  "
            f"{where:<38} {100 * r['max_error_zenith_10deg']:9.3f}% {100 * r['estimate']:8.3f}%"
        )
    worst = max(rows, key=lambda r: r["max_error"])
    lines.append("")
    lines.append(
        f"largest: {100 * worst['max_error']:.3f} % ({worst['case']}, Sun {worst['sun_elevation_deg']:g} deg)"
    )
    return "\n".join(lines)


def run_horizon() -> list[dict]:
    """The spherical shell against the plane-parallel column near the horizon."""
    zen = np.array([0.0, 60.0, 75.0, 80.0, 85.0, 88.0, 90.0])
    azi = np.array([90.0])
    out = []
    dust = ref.validation_table("mars-dust", [550.0])
    aerosol = ref.validation_table("earth-aerosol", [550.0])
    for label, kind, tau, table in (
        ("earth (air, aerosol 0.1)", "earth-aerosol", 0.1, aerosol),
        ("mars (dust 0.5)", "mars-dust", 0.5, dust),
    ):
        flat = ref.validation_atmosphere(kind, tau, wavelength_nm=[550.0], table=table)
        if kind == "mars-dust":
            real = sets.mars_atmosphere(dust_table=table, optical_depth=tau, name="mars")
        else:
            real = sets.earth_atmosphere(
                wavelength_nm=[550.0],
                ozone=None,
                aerosol_table=flat.constituent("aerosols").table,
                aerosol_profile=flat.constituent("aerosols").profile,
            )
        res = {}
        for name, atm, geometry in (
            ("plane", flat, "plane-parallel"),
            ("sphere", real, "pseudo-spherical"),
        ):
            medium = Medium.from_atmosphere(atm)
            field = solve_orders(medium, sun_zenith_deg=45.0, geometry=geometry)
            res[name] = line_of_sight_radiance(
                medium,
                field,
                view_zenith_deg=zen,
                view_azimuth_deg=np.full(zen.size, azi[0]),
                observer_altitude_m=0.0,
            )[:, 0]
        out.append(
            {
                "case": label,
                "view_zenith_deg": zen.tolist(),
                "plane": res["plane"].tolist(),
                "sphere": res["sphere"].tolist(),
            }
        )
    return out


def format_horizon(rows: list[dict]) -> str:
    lines = [
        "",
        "The horizon: spherical shell / plane-parallel column (Sun at 45 deg elevation, 90 deg "
        "in azimuth, 550 nm)",
    ]
    for r in rows:
        ratio = np.array(r["sphere"]) / np.array(r["plane"])
        cells = "  ".join(f"{z:g}: {q:.3f}" for z, q in zip(r["view_zenith_deg"], ratio))
        lines.append(f"  {r['case']:<26} {cells}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--streams", type=int, default=None, help="the renderer's streams")
    parser.add_argument(
        "--reference-streams",
        type=int,
        default=ref.REFERENCE_STREAMS,
        help=f"CDISORT's streams per hemisphere (default {ref.REFERENCE_STREAMS})",
    )
    parser.add_argument(
        "--cases",
        default=None,
        help="comma-separated KIND:TAU (default all: "
        + ",".join(f"{k}:{t:g}" for k, t in ref.VALIDATION_CASES)
        + ")",
    )
    parser.add_argument("--json", type=Path, default=None, metavar="OUT.json")
    parser.add_argument("--no-horizon", action="store_true", help="skip the horizon table")
    args = parser.parse_args(argv)
    cases = (
        list(ref.VALIDATION_CASES)
        if args.cases is None
        else [(c.split(":")[0], float(c.split(":")[1])) for c in args.cases.split(",")]
    )
    from dustoptics.sky.medium import N_STREAMS

    streams = args.streams or N_STREAMS
    t0 = time.perf_counter()
    rows = run_cases(cases, streams=args.streams, reference_streams=args.reference_streams)
    print(format_cases(rows, streams=streams, reference_streams=args.reference_streams))
    horizon = [] if args.no_horizon else run_horizon()
    if horizon:
        print(format_horizon(horizon))
    print(f"(ran {time.perf_counter() - t0:.0f} s)")
    if args.json is not None:
        args.json.write_text(json.dumps({"cases": rows, "horizon": horizon}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
