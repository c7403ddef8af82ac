"""Compute the NASA Ames Mars GCM's visible dust file again and compare it with the shipped one.

The shipped file is ``data/Dust_vis_wolff2010_JD_15bands.dat`` of nasa/AmesGCM (read at
commit eaba9b5400031651f6d5545acbca08eaf471defb; give its path).  What the repository says
about how it was made, all in ``atmos_param_mars/Rad/rtmod_mgcm.F90`` at that commit:

- its name: Wolff's Mars dust ("wolff2010");
- the model reads one row per radius ``rad_rt`` (0.1-50 um, 20, log-spaced) and weights
  the rows by its own log-normal distribution per radius bin (``opt_dst``,
  ``calc_opts``): a row is the efficiency of particles of that radius (single radii);
- the band edges ``bwnv`` (``setspv``), and of the model's Wolff dust values "M. Wolff
  Planck-weighted values (T=6000K)" (``setrad``).

The refractive index: the package's catalogue entry ``marsdust-wolff2009`` is the Mars dust
table the NASA Ames Mars Climate Modeling Group distributes ("Wolff Dust Refractive
Indicies", Wolff et al. 2009, CRISM, 0.44-2.92 um, with further rows of unstated origin at
263 and 321 nm and beyond 2.92 um); Wolff et al. 2010 (MARCI, the "2010" of the file's
name) is not in the catalogue, so this is the nearest cited index.  The index starts at
263 nm: band 7 (0.24-0.40 um) is averaged over 0.263-0.40 um.

The file is computed by the package's own ``ames-dustvis`` format (single radii, Planck
6000 K, Gauss-Legendre nodes in wavenumber) from a configuration holding that index, and
compared per band and radius with the shipped file.  Nothing is fitted to the shipped file.

Usage::

    python scripts/ames_reproduction.py PATH/TO/Dust_vis_wolff2010_JD_15bands.dat \
        [--csv docs/concepts/ames_reproduction.csv] [--nodes-per-band 16]

Prints a summary per band; ``--csv NAME.csv`` writes every band and radius, with comment
lines naming the Ames commit and the command, and ``NAME_table.csv``, the same rows without
them (the documentation's table, docs/concepts/ames_reproduction.rst).
"""

from __future__ import annotations

import argparse
import csv
import io
import sys
from pathlib import Path

import numpy as np

from dustoptics.io._atomic import write_files
from dustoptics.io.gcm import ames
from dustoptics.models.compute import build_table
from dustoptics.models.config import parse_config

#: The configuration: Wolff et al.'s index alone; the size distribution is not used for
#: the file's rows (single radii), only for the configuration's own one-wavelength table.
CONFIG = """\
name = "ames-wolff"
description = "Mars dust of Wolff et al. (the Ames-distributed index), for the Ames file"

[material]
model = "catalogue"
name = "marsdust-wolff2009"

[size_distribution]
model = "monodisperse"
radius_um = 1.0

[optics]
weighting = "scattering"
rtol = 1e-3
wavelengths_nm = [670.0]
n_theta = 19

[phase]
model = "mie"
"""

QUANTITIES = ("qext", "qsca", "g")


def compare(shipped: Path, *, nodes_per_band: int) -> tuple[dict, ames.AmesFile]:
    """Our grid (``ames.ames_grid``) and the shipped file, read in the model's layout."""
    table = build_table(parse_config(CONFIG, source="ames_reproduction.py"))
    grid = ames.ames_grid(table, bands="vis", gcm_nodes_per_band=nodes_per_band)
    theirs = ames.read_ames(shipped, n_bands=7)
    if theirs.qext.shape != grid["qext"].shape:
        raise SystemExit(f"{shipped}: {theirs.qext.shape} rows x bands; expected (20, 7)")
    return grid, theirs


def g_planck_only(grid: dict) -> np.ndarray:
    """g averaged with the Planck weight alone (not by Q_sca B): the other convention, for
    the explanation of the differences only. [-], shape (n_radius, n_band)"""
    result: np.ndarray = grid["optics"].g @ grid["bands"].weights.T
    return result


def rows(grid: dict, theirs: ames.AmesFile) -> list[list[str]]:
    """One row per radius and band: shipped, ours and the difference of each quantity, and
    g averaged with the Planck weight alone with its difference."""
    edges = np.array(ames.BANDS["vis"].edges_cm)
    g_b = g_planck_only(grid)
    out = []
    for i, r in enumerate(grid["radius_um"]):
        for b in range(edges.size - 1):
            row = [f"{r:.4g}", str(b + 1), f"{1e4 / edges[b + 1]:.3f}-{1e4 / edges[b]:.3f}"]
            for q in QUANTITIES:
                s, o = float(getattr(theirs, q)[i, b]), float(grid[q][i, b])
                diff = o - s if q == "g" else (o - s) / s
                row += [f"{s:.4g}", f"{o:.4g}", f"{diff:+.3f}"]
            row += [f"{g_b[i, b]:.4g}", f"{g_b[i, b] - theirs.g[i, b]:+.3f}"]
            out.append(row)
    return out


HEADER = [
    "radius_um",
    "band",
    "band_um",
    "qext_shipped",
    "qext_ours",
    "qext_rel_diff",
    "qsca_shipped",
    "qsca_ours",
    "qsca_rel_diff",
    "g_shipped",
    "g_ours",
    "g_diff",
    "g_planck_only",
    "g_planck_only_diff",
]


def summary(grid: dict, theirs: ames.AmesFile) -> str:
    """Median and largest |difference| per band (relative for Q, absolute for g; last, g
    averaged with the Planck weight alone)."""
    lines = [
        "band  um           |dQext/Qext| med max   |dQsca/Qsca| med max   |dg| med max"
        "      |dg| Planck only"
    ]
    edges = np.array(ames.BANDS["vis"].edges_cm)
    g_b = g_planck_only(grid)
    for b in range(edges.size - 1):
        cells = []
        for q in QUANTITIES:
            s, o = getattr(theirs, q)[:, b], grid[q][:, b]
            d = np.abs(o - s) if q == "g" else np.abs(o - s) / s
            cells.append(f"{np.median(d):7.3f} {d.max():7.3f}")
        d = np.abs(g_b[:, b] - theirs.g[:, b])
        cells.append(f"{np.median(d):7.3f} {d.max():7.3f}")
        band = f"{1e4 / edges[b + 1]:.2f}-{1e4 / edges[b]:.2f}"
        lines.append(f"{b + 1:>4}  {band:<11}  " + "      ".join(cells))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("shipped", type=Path, help="path of Dust_vis_wolff2010_JD_15bands.dat")
    p.add_argument("--csv", type=Path, help="write every band and radius to this CSV file")
    p.add_argument("--nodes-per-band", type=int, default=ames.DEFAULT_NODES_PER_BAND)
    args = p.parse_args(argv)
    grid, theirs = compare(args.shipped, nodes_per_band=args.nodes_per_band)
    print(summary(grid, theirs), flush=True)
    print(
        "Planck energy (6000 K) of each band inside the index's range: "
        + ", ".join(f"{c:.4f}" for c in grid["bands"].covered)
    )
    if args.csv is not None:
        body = io.StringIO()
        writer = csv.writer(body, lineterminator="\n")
        writer.writerow(HEADER)
        writer.writerows(rows(grid, theirs))
        text = io.StringIO()
        text.write(
            f"# NASA Ames Mars GCM {ames.BANDS['vis'].file_name} (nasa/AmesGCM "
            f"{ames.AMES_COMMIT}) against dustoptics' ames-dustvis format: single radii, "
            f"index marsdust-wolff2009, Planck {grid['temperature_k']:g} K, "
            f"{grid['nodes_per_band']} nodes per band\n"
        )
        text.write(
            "# written by: python scripts/ames_reproduction.py Dust_vis_wolff2010_JD_15bands.dat"
            f" --csv {args.csv.name}\n"
        )
        text.write(body.getvalue())
        # The same rows without the comment lines, for the documentation's csv-table.
        plain = args.csv.with_name(args.csv.stem + "_table.csv")
        write_files(
            {
                args.csv: text.getvalue().encode("ascii"),
                plain: body.getvalue().encode("ascii"),
            },
            overwrite=True,
        )
        print(f"wrote {args.csv} and {plain}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
