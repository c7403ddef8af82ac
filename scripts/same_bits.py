"""Show that a change moved no bit: the outputs of this checkout against another commit's.

Usage::

    python scripts/same_bits.py --against REF     # e.g. --against main~3; exit 1 if any file differs
    python scripts/same_bits.py --write DIR       # write the outputs of this checkout into DIR

The outputs are the default table (``compute_optics(mars_dust(), ModifiedGamma(r_eff_um=1.6,
v_eff=0.2))`` saved as netCDF-4), the same with the expansion coefficients
(``expansion=True``), every preset's table file and GLSL snippet (as
``scripts/build_tables.py`` writes them into ``tables/``), a small sweep store (two
effective radii, a local cluster of threads, written as one netCDF file), and every
registered format of four tables (the default table, the one with the expansion, the
``blue-moons`` and ``hybrid`` presets) written through the command line
(``dustoptics export FILE --format NAME``, in-process with ``dustoptics.cli.main``), once
with each format's defaults and once with its options given (``OPTIONS`` in the child's script).  A format
that cannot write a table (a phase-function-only table for cross-section formats, a table
without the expansion for DISORT) is skipped on both sides alike: the exit status is
recorded in ``exports.txt``, compared like the files.  Last, the sampling options CosmoScout
VR's preprocessor is given for a Mars and an Earth set of three wavelengths, as JSON.  ``--against``
checks REF out into a temporary git worktree, writes both sets of outputs in child processes
(the other commit's package first on ``sys.path``; both report the version installed here, so
the provenance's software versions agree) and compares them file by file, byte for byte.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]

#: What the child writes; it imports the package from sys.path[0].
_WRITER = r"""
import sys
from pathlib import Path

out = Path(sys.argv[1])
import dustoptics as do
from dustoptics.io import write_glsl
from dustoptics.models import presets

print("dustoptics from", do.__file__, file=sys.stderr)
t = do.compute_optics(do.mars_dust(), do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2))
t.save(out / "default.nc")
for name in presets.list_presets():
    table = presets.build_preset(name)
    (out / name).mkdir()
    table.save(out / name / f"{name}.nc")
    write_glsl(table, out / name)

from dustoptics.sweep import local_cluster, sweep
from distributed import Client

from dustoptics.cli import main
from dustoptics.io import FORMATS

d = do.compute_optics(
    do.mars_dust(), do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2), expansion=True
).replace(name="default-expansion")
d.save(out / "default-expansion.nc")

#: Each format's options on the command line (the second write of every table).
TEXTURE = ["--layout", "wavelength", "--sampling", "cos", "--n-angles", "181", "--precision", "float16"]
SHADER = ["--prefix", "DUST", "--resolution-deg", "0.5", "--channels-nm", "650,550,450"]
OPTIONS = {
    "glsl": SHADER + ["--glsl-version", "100"],
    "hlsl": SHADER,
    "wgsl": SHADER,
    "texture": ["--sampling", "cos", "--n-angles", "181"],
    "ktx2": TEXTURE,
    "exr": TEXTURE,
    "npy": TEXTURE,
    "cosmoscout": ["--scale-height-m", "8000", "--top-altitude-m", "90000", "--n-altitudes", "64"],
}
tables = {
    "default": out / "default.nc",
    "default-expansion": out / "default-expansion.nc",
    "blue-moons": out / "blue-moons" / "blue-moons.nc",
    "hybrid": out / "hybrid" / "hybrid.nc",
}
log = []
for label, path in tables.items():
    for fmt in sorted(FORMATS):
        for variant, extra in (("defaults", []), ("options", OPTIONS.get(fmt))):
            if extra is None:
                continue
            target = out / "exports" / label / fmt / variant
            argv = ["export", str(path), "--out", str(target), "--format", fmt, "--quiet"]
            argv += ["--number-density-per-m3", "1e8"] + extra
            try:
                status = main(argv)
            except SystemExit as exc:
                status = exc.code
            log.append(f"{label} {fmt} {variant}: exit {status}")
(out / "exports.txt").write_text("\n".join(log) + "\n")

# The sampling CosmoScout VR's preprocessor is given for a Mars set (its settings' numbers).
import json

from dustoptics.atmosphere.build import build_atmosphere
from dustoptics.io.engines.cosmoscout_preprocessor import cosmoscout_sampling

for name in ("mars", "earth"):
    atm = build_atmosphere(name, wavelength_nm=[450.0, 550.0, 650.0])
    record = cosmoscout_sampling(atm).to_dict()
    (out / f"{name}-sampling.json").write_text(json.dumps(record, sort_keys=True, default=repr))

with local_cluster(1, processes=False) as cluster, Client(cluster) as client:
    sweep(
        "blue-moons",
        {"size_distribution.r_eff_um": [1.0, 2.0]},
        out=out / "sweep.nc",
        client=client,
        chunk_wavelengths=24,
        progress=None,
    )
"""


def write_outputs(package_root: Path, out: Path) -> None:
    """Write the outputs with the package found in ``package_root`` into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join([str(package_root), os.environ.get("PYTHONPATH", "")]),
    )
    subprocess.run([sys.executable, "-c", _WRITER, str(out)], env=env, cwd=out, check=True)


def digests(root: Path) -> dict[str, str]:
    """sha256 of every file below ``root``, by relative path."""
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--against", metavar="REF", help="a commit to compare this checkout with")
    group.add_argument("--write", metavar="DIR", type=Path, help="write this checkout's outputs")
    args = parser.parse_args(argv)
    if args.write is not None:
        write_outputs(REPO_ROOT, args.write)
        return 0
    with tempfile.TemporaryDirectory(prefix="same-bits-") as tmp:
        base = Path(tmp) / "worktree"
        subprocess.run(
            ["git", "-C", str(REPO_ROOT), "worktree", "add", "--detach", str(base), args.against],
            check=True,
            capture_output=True,
        )
        try:
            write_outputs(base, Path(tmp) / "before")
            write_outputs(REPO_ROOT, Path(tmp) / "after")
        finally:
            subprocess.run(
                ["git", "-C", str(REPO_ROOT), "worktree", "remove", "--force", str(base)],
                check=False,
            )
        before, after = digests(Path(tmp) / "before"), digests(Path(tmp) / "after")
    differ = sorted(k for k in before.keys() | after.keys() if before.get(k) != after.get(k))
    for name in sorted(before.keys() | after.keys()):
        print(f"{'same' if name not in differ else 'DIFFERS'}  {name}")
    print(f"{len(before) - len(differ)} of {len(before)} files byte-identical with {args.against}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
