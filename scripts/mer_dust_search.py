"""Which published Mars dust puts the sky inside the rovers' colour range (issue 28).

Runs :func:`dustoptics.sky.mer_search.search_mer_dust` over its default grid
of published values (4 dusts x 4 optical depths x 2 ground albedos x 2 Sun
elevations: 64 skies, 5-10 minutes on one core) and prints the table; with
``--write`` it also writes ``docs/concepts/generated/mer_dust_search.txt``,
which the docs include.  The numbers are the library's; nothing is typed.

    python scripts/mer_dust_search.py --write
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dustoptics.sky.mer_search import search_mer_dust

OUT = Path(__file__).resolve().parents[1] / "docs" / "concepts" / "generated"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--write", action="store_true", help=f"also write {OUT}/mer_dust_search.txt")
    args = p.parse_args(argv)
    text = search_mer_dust(progress=sys.stderr).to_text()
    print(text)
    if args.write:
        OUT.mkdir(parents=True, exist_ok=True)
        (OUT / "mer_dust_search.txt").write_text(
            "# written by: python scripts/mer_dust_search.py --write\n" + text + "\n",
            encoding="utf-8",
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
