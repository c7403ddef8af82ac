"""What the commands print on stdout: files written, files left up to date."""

from __future__ import annotations

import argparse
from pathlib import Path

from dustoptics.io.outputs import Placement

__all__ = ["report_placement", "say"]


def say(args: argparse.Namespace, text: str) -> None:
    """Print ``text`` unless the command was given ``--quiet``."""
    if not getattr(args, "quiet", False):
        print(text)


def report_placement(args: argparse.Namespace, name: str, out_dir: Path, placed: Placement) -> None:
    """The files a placement wrote, then those it left untouched (up to date)."""
    if placed.written:
        say(args, f"{name}: wrote {len(placed.written)} files to {out_dir}")
        for path in placed.written:
            say(args, f"  {path}")
    if placed.unchanged:
        say(args, f"{name}: {len(placed.unchanged)} files up to date in {out_dir} (left untouched)")
        for path in placed.unchanged:
            say(args, f"  {path}")
