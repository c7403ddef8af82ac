"""uvspec (libRadtran) on the files dustoptics writes, run as their headers say, against CDISORT.

Usage::

    LIBRADTRAN_DIR=/path/to/libRadtran python scripts/uvspec_rt_files.py [--optical-depth TAU]

Mars dust (the seed thesis's Blue Moon's dust, r_eff 1.6 um, v_eff 0.2; 1,801 angles) at 550
and 670 nm is exported with ``--format disort,libradtran,libradtran-nc --optical-depth TAU
--scale-height-m 11100 --top-altitude-m 50000 --n-layers 10`` (default TAU 1 at 550 nm).
uvspec 2.0.2 runs the two libRadtran routes with the input lines their headers give
(``aerosol_file explicit`` + ``disort_intcor moments``; ``aerosol_species_file``, its default
phase-function correction), molecules off (``no_scattering mol``, ``no_absorption mol``),
DISORT with 32 streams, Sun at 45 deg; CDISORT (nanodisort) gets the DISORT file's layers,
moments and phase block with the same streams.  Printed: the direct transmittance at the
surface against Beer-Lambert's, and the sky radiance in the Sun's vertical plane 1-20 deg
from the Sun by the three, relative to CDISORT.  Seconds.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import nanodisort  # type: ignore[import-untyped]
import numpy as np

import dustoptics as do
from dustoptics.cli import main as cli
from dustoptics.io.rt.disort import read_disort

SZA_DEG = 45.0
STREAMS = 32
SUN_DISTANCES_DEG = (1.0, 2.0, 5.0, 10.0, 20.0)


def uvspec(lrt: Path, cwd: Path, recipe: list[str], nm: float, umu: np.ndarray) -> list[str]:
    lines = [
        f"data_files_path {lrt / 'data'}/",
        f"atmosphere_file {lrt / 'data' / 'atmmod' / 'afglus.dat'}",
        "source solar",
        "output_quantity transmittance",
        "mol_abs_param crs",
        f"wavelength {nm:g} {nm:g}",
        f"sza {SZA_DEG:g}",
        "phi0 0",
        "no_absorption mol",
        "no_scattering mol",
        f"number_of_streams {STREAMS}",
        "umu " + " ".join(f"{u:.10f}" for u in umu),
        "phi 0 180",
        "zout 0",
        *recipe,
    ]
    run = subprocess.run(
        [str(lrt / "bin" / "uvspec")],
        input="\n".join(lines) + "\n",
        cwd=cwd,
        capture_output=True,
        text=True,
        check=True,
    )
    return run.stdout.split("\n")


def parse(out: list[str], n_umu: int) -> tuple[float, np.ndarray]:
    """edir and the radiance at phi 0 and 180 for each umu (uvspec's default output)."""
    rows = [ln.split() for ln in out if ln.strip()]
    edir = float(rows[0][1])
    rad = np.array([[float(r[2]), float(r[3])] for r in rows[2 : 2 + n_umu]])
    return edir, rad


def recipe(path: Path) -> list[str]:
    lines = path.read_text().splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("# uvspec input"))
    out = []
    for ln in lines[start + 1 :]:
        if not ln.startswith("#   "):
            break
        out.append(ln[4:].strip())
    return out


def cdisort(f: do.io.rt.disort.DisortFile, w: int, umu: np.ndarray) -> np.ndarray:
    dtau = f.dtauc()[w]
    s = nanodisort.DisortState()
    s.nstr, s.nlyr, s.nmom = STREAMS, dtau.size, f.pmom.shape[1] - 1
    s.ntau, s.numu, s.nphi, s.nphase = 1, umu.size, 1, f.mu_phase.size
    s.usrtau = s.usrang = s.lamber = s.quiet = True
    s.onlyfl = False
    s.intensity_correction, s.old_intensity_correction = True, False
    s.allocate()
    s.dtauc, s.ssalb = dtau.copy(), np.full(dtau.size, f.ssa[w])
    s.pmom = np.asfortranarray(np.repeat(f.pmom[w][:, None], dtau.size, 1))
    s.mu_phase = f.mu_phase
    s.phase = np.ascontiguousarray(np.repeat(f.phase[w][None, :], dtau.size, 0))
    s.utau, s.umu, s.phi = np.array([dtau.sum()]), umu, np.array([0.0])
    s.fbeam, s.umu0, s.phi0, s.albedo = 1.0, math.cos(math.radians(SZA_DEG)), 0.0, 0.0
    s.solve()
    return np.asarray(s.uu)[:, 0, 0].copy()


def run(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--optical-depth", type=float, default=1.0)
    args = p.parse_args(argv)
    lrt = Path(os.environ.get("LIBRADTRAN_DIR", ""))
    if not (lrt / "bin" / "uvspec").is_file():
        print("LIBRADTRAN_DIR must name a libRadtran build (bin/uvspec)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        do.compute_optics(
            do.mars_dust(),
            do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
            [550.0, 670.0],
            expansion=True,
            name="dust",
        ).save(root / "dust.nc")
        argv = ["export", str(root / "dust.nc"), "--out", str(root), "--quiet"]
        argv += ["--format", "disort,libradtran,libradtran-nc"]
        argv += ["--optical-depth", str(args.optical_depth), "--scale-height-m", "11100"]
        argv += ["--top-altitude-m", "50000", "--n-layers", "10"]
        assert cli(argv) == 0
        d = root / "dust"
        f = read_disort(d / "dust_disort.txt")
        vz = np.array([SZA_DEG - x for x in SUN_DISTANCES_DEG])
        umu_dn = np.sort(-np.cos(np.radians(vz)))  # CDISORT: downward, increasing
        print(
            f"Mars dust, tau {args.optical_depth:g} at 550 nm, exponential 11.1 km to 50 km in "
            f"10 layers, Sun zenith {SZA_DEG:g} deg, {STREAMS} streams"
        )
        for w, nm in enumerate(f.wavelength_nm):
            ours = cdisort(f, w, umu_dn)[::-1]  # back to SUN_DISTANCES_DEG order
            tau = float(f.dtauc()[w].sum())
            mu0 = math.cos(math.radians(SZA_DEG))
            beer = mu0 * math.exp(-tau / mu0)
            print(f"{nm:g} nm: vertical optical depth {tau:.6f}")
            for route, path in (
                ("explicit", d / "dust_aerosol_explicit.dat"),
                ("species", d / "dust_aerosol_species.dat"),
            ):
                # uvspec: umu > 0 looks down... its radiance toward the sky is at umu < 0 too.
                out = uvspec(lrt, d, recipe(path), nm, umu_dn)
                edir, rad = parse(out, umu_dn.size)
                toward = rad[::-1, np.argmax(rad[-1])]
                rel = " ".join(f"{100 * (u / o - 1):+.3f}" for u, o in zip(toward, ours))
                print(
                    f"  uvspec {route:8s} edir {edir:.6e} (Beer-Lambert {beer:.6e}); radiance "
                    f"vs CDISORT with the phase block at {SUN_DISTANCES_DEG} deg [%]: {rel}"
                )
            print(f"  CDISORT radiance [sr-1]: {' '.join(f'{x:.5g}' for x in ours)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(run())
