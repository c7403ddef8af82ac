"""What the commands print on stdout: files written, files left up to date."""

from __future__ import annotations

import argparse
from pathlib import Path

from dustoptics.io.outputs import Placement

__all__ = ["count", "report_placement", "say"]


def say(args: argparse.Namespace, text: str) -> None:
    """Print ``text`` unless the command was given ``--quiet``."""
    if not getattr(args, "quiet", False):
        print(text)


def count(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` and the noun, singular for one: ``count(1, "file")`` is ``"1 file"``.

    >>> count(1, "file"), count(2, "file"), count(0, "entry", "entries")
    ('1 file', '2 files', '0 entries')
    """
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def report_placement(args: argparse.Namespace, name: str, out_dir: Path, placed: Placement) -> None:
    """The files a placement wrote, then those it left untouched (up to date)."""
    if placed.written:
        say(args, f"{name}: wrote {count(len(placed.written), 'file')} to {out_dir}")
        for path in placed.written:
            say(args, f"  {path}")
    if placed.unchanged:
        n = count(len(placed.unchanged), "file")
        say(args, f"{name}: {n} up to date in {out_dir} (left untouched)")
        for path in placed.unchanged:
            say(args, f"  {path}")
