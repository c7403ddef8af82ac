"""The thesis's four Mars models against the rovers' sky colour (issue 28).

Runs :func:`dustoptics.sky.compare.mer_chromaticity` for the four models
(Collienne, Costa, Blue Moon's, hybrid) at Sun elevations 0, 10, ..., 90
degree (40 skies, 3-7 minutes on one core), prints the table and each model's
mean over the Sun elevations beside the means Meyran (2022, section 5.1.2)
prints where he prints them (Collienne: x 0.313, y 0.318); with ``--write``
it also writes ``docs/concepts/generated/mars_models_vs_rovers.txt``, which
the docs include.  The numbers are the library's; nothing is typed.

    python scripts/mars_models_vs_rovers.py --write
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from dustoptics.sky.compare import mer_chromaticity

OUT = Path(__file__).resolve().parents[1] / "docs" / "concepts" / "generated"
#: Means over Sun elevations 0-90 degree that the thesis prints (Meyran 2022, section 5.1.2).
THESIS_MEANS = {"collienne": (0.313, 0.318)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--write", action="store_true", help=f"also write {OUT}/mars_models_vs_rovers.txt"
    )
    args = p.parse_args(argv)
    elevations = tuple(float(e) for e in range(0, 91, 10))
    table = mer_chromaticity(sun_elevations_deg=elevations, progress=sys.stderr)
    lines = [table.to_text(), "mean over the Sun elevations 0-90 degree (thesis: Meyran 2022):"]
    for model in dict.fromkeys(r.model for r in table.rows):
        xy = np.array([[r.x, r.y] for r in table.rows if r.model == model])
        x, y = xy.mean(axis=0)
        line = f"  {model}: x {x:.4f}, y {y:.4f}"
        if model in THESIS_MEANS:
            tx, ty = THESIS_MEANS[model]
            line += f" (thesis x {tx:.3f}, y {ty:.3f}: off by {x - tx:+.4f}, {y - ty:+.4f})"
        lines.append(line)
    text = "\n".join(lines)
    print(text)
    if args.write:
        OUT.mkdir(parents=True, exist_ok=True)
        (OUT / "mars_models_vs_rovers.txt").write_text(
            "# written by: python scripts/mars_models_vs_rovers.py --write\n" + text + "\n",
            encoding="utf-8",
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
