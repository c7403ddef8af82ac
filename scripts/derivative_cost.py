"""CPU time of the default table with and without its derivatives, in one process.

    python scripts/derivative_cost.py [--repeats N]

The default Mars-dust table (``compute_optics(mars_dust(), ModifiedGamma(r_eff_um=1.6,
v_eff=0.2))``, 48 x 1,801) on one thread, alone and with ``derivatives=("r_eff_um",
"v_eff", "n", "k")``, after one untimed call of each; process CPU time, so that a loaded
machine moves the ratio less than wall time (``scripts/benchmark.py --derivatives`` gives
the wall-time rows).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import dustoptics as do

NAMES = ("r_eff_um", "v_eff", "n", "k")


def _cpu(derivatives: tuple[str, ...]) -> float:
    start = time.process_time()
    do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        workers=1,
        derivatives=derivatives,
    )
    return time.process_time() - start


def main(args: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    opts = parser.parse_args(args)
    _cpu(())
    _cpu(NAMES)
    alone = min(_cpu(()) for _ in range(opts.repeats))
    both = min(_cpu(NAMES) for _ in range(opts.repeats))
    print(f"table alone {alone:.2f} s CPU, with derivatives {both:.2f} s CPU: {both / alone:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
