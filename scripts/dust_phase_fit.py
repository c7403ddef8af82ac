"""Regenerate dustoptics/models/data/fits/dust_phase_fit.json: the Mars dust phase function's
HG + Draine parameters as closed forms of r_eff (dustoptics.models.dust_phase_fit).

Usage: python scripts/dust_phase_fit.py [--out PATH]

For each preset of DUST_FIT_PRESETS: Mie tables at the 8 grid radii (0.5 .. 4 um) and their 7
midpoints, the fit along r_eff, the polynomials, and the closed form's error at all 15 radii.
Prints the error table.  About 2 minutes a preset on one core.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from dustoptics.io._atomic import write_files
from dustoptics.models.dust_phase_fit import (
    DUST_FIT_PRESETS,
    compute_dust_phase_fit,
    fits_to_json,
)

DEFAULT_OUT = (
    Path(__file__).resolve().parents[1] / "dustoptics/models/data/fits/dust_phase_fit.json"
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    fits = []
    for preset in DUST_FIT_PRESETS:
        fit = compute_dust_phase_fit(preset)
        fits.append(fit)
        for r, fitted, channel, rms, worst, alone in fit.error_table():
            print(
                f"{preset:12s} r_eff {r:6.3f} um {'fit ' if fitted else 'held'} {channel}: "
                f"rms {100 * rms:6.2f} %  max {100 * worst:7.2f} %  "
                f"(fitted alone: rms {100 * alone:6.2f} %)",
                flush=True,
            )
    write_files({args.out: fits_to_json(fits).encode()}, overwrite=True)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
