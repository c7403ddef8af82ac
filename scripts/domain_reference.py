"""Write the arbitrary-precision Mie references of the validated domain's large spheres.

Usage::

    python scripts/domain_reference.py [--out tests/data/mie-benchmarks/domain_reference_mpmath.json]
    python scripts/domain_reference.py --docs     # only rewrite the README's and docs' statement

For every point of :func:`points` (the corners of
:data:`dustoptics.scattering.domain.VALIDATED_DOMAIN`, the largest size
parameters the Mars presets and the Earth aerosols reach with their index at
that wavelength, hematite's largest k in the ultraviolet at the largest x, and
seeded random interior points), the mpmath reference of
``tests/reference/mpmath_mie.py`` (30 digits) at the angles :data:`THETA_DEG`:
Q_ext, Q_sca, Q_back, g and S1, S2, as 20-digit strings, under a provenance
header (this command, the commit, mpmath's version, the working precision).
``tests/scattering/test_domain.py`` reads the file (and recomputes its cheap
points in the test, which must give the same digits).  About a minute on one
core.  ``--docs`` rewrites the generated statement of the domain
(:func:`dustoptics.scattering.domain.domain_summary`) between the
``validated-domain:begin`` and ``validated-domain:end`` markers of README.md
and docs/concepts/accuracy.rst.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

import mpmath as mp

from dustoptics import get_material
from dustoptics.atmosphere.aerosols import (
    AEROSOL_COMPONENTS,
    RELATIVE_HUMIDITIES_PERCENT,
    aerosol_component,
)
from dustoptics.models.compute import mie_request
from dustoptics.models.presets import list_presets, load_preset
from dustoptics.scattering.domain import VALIDATED_DOMAIN, domain_summary
from dustoptics.scattering.optics import estimate_cost
from tests.reference.mpmath_mie import mie_reference

DEFAULT_OUT = REPO / "tests" / "data" / "mie-benchmarks" / "domain_reference_mpmath.json"

#: Scattering angles of the reference amplitudes. [degree]
THETA_DEG = (0.0, 2.0, 10.0, 30.0, 60.0, 90.0, 120.0, 150.0, 170.0, 178.0, 180.0)

#: Working precision of the reference. [decimal digits]
DPS = 30


def mars_largest() -> tuple[str, float, complex]:
    """The preset whose size parameters reach highest, that x and its index there."""
    best = ("", 0.0, 0j)
    for name in list_presets():
        config = load_preset(name)
        if not config.phase.uses_mie:
            continue
        request = mie_request(config)
        x_hi = estimate_cost(request, workers=1).max_size_parameter
        if x_hi > best[1]:
            best = (name, x_hi, complex(request.m[0]))
    return best


def earth_largest() -> tuple[str, float, complex]:
    """The OPAC component (any humidity) whose size parameters reach highest over its data."""
    best = ("", 0.0, 0j)
    for name in AEROSOL_COMPONENTS:
        for rh in RELATIVE_HUMIDITIES_PERCENT:
            comp = aerosol_component(name, relative_humidity_percent=rh)
            wl_nm = float(comp.refractive_index.wavelength_nm.min())
            x_hi = 2.0 * math.pi * comp.r_max_um / (wl_nm * 1e-3)
            if x_hi > best[1]:
                label = f"OPAC {name} at {rh} % humidity, r_max {comp.r_max_um:g} um, {wl_nm:g} nm"
                best = (label, x_hi, complex(comp.refractive_index(wl_nm)))
    return best


def hematite_uv() -> tuple[str, complex]:
    """The largest k of Querry's hematite (either ray) below 400 nm and its index."""
    best = ("", 0j)
    for name in ("hematite-querry1985-ordinary", "hematite-querry1985-extraordinary"):
        index = get_material(name)
        wl = index.wavelength_nm[index.wavelength_nm < 400.0]
        m = np.asarray(index(wl))
        i = int(np.argmax(m.imag))
        if m.imag[i] > best[1].imag:
            best = (f"{name} at {wl[i]:g} nm", complex(m[i]))
    return best


def points() -> list[dict]:
    """The reference points: label, m and x."""
    d = VALIDATED_DOMAIN
    out = []
    for x in (d.min_size_parameter, d.max_size_parameter):
        for n in (d.min_n, d.max_n):
            for k in (0.0, d.max_k):
                out.append({"label": "corner", "m": complex(n, k), "x": x})
        out.append({"label": "lowest contrast", "m": complex(1.0 + d.min_index_contrast), "x": x})
    # The smallest sphere a table can hold (radius 1e-6 um at 1e7 nm: x = 6.3e-10).
    for n in (d.min_n, d.max_n):
        for k in (0.0, d.max_k):
            out.append({"label": "smallest x of a table", "m": complex(n, k), "x": 1e-9})
    name, x, m = mars_largest()
    out.append({"label": f"largest Mars preset ({name}), its index", "m": m, "x": x})
    name, x, m = earth_largest()
    out.append({"label": f"largest Earth aerosol ({name}), its index", "m": m, "x": x})
    name, m = hematite_uv()
    for x in (30.0, d.max_size_parameter):
        out.append({"label": f"largest k of hematite in the UV ({name})", "m": m, "x": x})
    rng = np.random.default_rng(20261206)
    for _ in range(8):
        x = float(np.exp(rng.uniform(np.log(1e-3), np.log(d.max_size_parameter))))
        n = float(np.exp(rng.uniform(np.log(d.min_n), np.log(d.max_n))))
        k = (
            0.0
            if rng.uniform() < 0.3
            else float(np.exp(rng.uniform(np.log(1e-4), np.log(d.max_k))))
        )
        if abs(complex(n, k) - 1.0) >= d.min_index_contrast:
            out.append({"label": "random interior (seed 20261206)", "m": complex(n, k), "x": x})
    return out


def _digits(value: mp.mpf) -> str:
    return mp.nstr(value, 20, min_fixed=1, max_fixed=0)


#: The files that state the domain, each with its markers' comment syntax.
DOCS = {
    REPO / "README.md": ("<!-- validated-domain:begin", "<!-- validated-domain:end -->"),
    REPO / "docs" / "concepts" / "accuracy.rst": (
        ".. validated-domain:begin",
        ".. validated-domain:end",
    ),
}


def write_docs() -> None:
    """Put :func:`domain_summary` between each file's markers."""
    for path, (begin, end) in DOCS.items():
        text = path.read_text(encoding="utf-8")
        i = text.index(begin)
        i = text.index("\n", i) + 1
        j = text.index(end, i)
        text = text[:i] + "\n" + domain_summary() + "\n\n" + text[j:]
        tmp = path.with_suffix(path.suffix + ".tmp")
        tmp.write_text(text, encoding="utf-8")
        tmp.replace(path)
        print(f"wrote the domain's statement into {path}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    parser.add_argument(
        "--docs", action="store_true", help="only rewrite the README's and docs' statement"
    )
    args = parser.parse_args(argv)
    if args.docs:
        write_docs()
        return 0
    mu = [math.cos(math.radians(t)) for t in THETA_DEG]
    rows = []
    for p in points():
        t0 = time.perf_counter()
        ref = mie_reference(m=p["m"], x=p["x"], mu=mu, dps=DPS)
        print(
            f"{p['label']}: m = {p['m']}, x = {p['x']:.6g}: {time.perf_counter() - t0:.1f} s",
            file=sys.stderr,
        )
        rows.append(
            {
                "label": p["label"],
                "n": p["m"].real,
                "k": p["m"].imag,
                "x": p["x"],
                "terms": ref.n_terms,
                "qext": _digits(ref.qext),
                "qsca": _digits(ref.qsca),
                "qback": _digits(ref.qback),
                "g": _digits(ref.g),
                "s1": [[_digits(s.real), _digits(s.imag)] for s in ref.s1],
                "s2": [[_digits(s.real), _digits(s.imag)] for s in ref.s2],
            }
        )
    commit = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True, check=False
    ).stdout.strip()
    doc = {
        "provenance": {
            "what": "Lorenz-Mie references of single homogeneous spheres (Bohren & Huffman 1983, "
            "m = n + i k), for dustoptics.scattering.domain.VALIDATED_DOMAIN",
            "written_by": "python scripts/domain_reference.py",
            "reference_code": "tests/reference/mpmath_mie.py",
            "commit": commit,
            "mpmath": mp.__version__,
            "dps": DPS,
            "digits_stored": 20,
            "theta_deg": list(THETA_DEG),
            "fields": "qext, qsca, qback [-], g [-], s1, s2 [re, im] at theta_deg (van de Hulst)",
        },
        "points": rows,
    }
    text = json.dumps(doc, indent=1, sort_keys=True) + "\n"
    tmp = args.out.with_suffix(".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(args.out)
    print(f"wrote {args.out} ({len(rows)} points)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
