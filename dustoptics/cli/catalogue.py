"""``dustoptics presets`` and ``dustoptics materials``: what the package ships."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import add_command
from dustoptics.models import presets
from dustoptics.particles.catalogue import get_material, list_materials

__all__ = ["add_parser", "run_materials", "run_presets"]


def add_parser(sub: Any) -> None:
    """Add the ``presets`` and ``materials`` subcommands to the subparsers ``sub``."""
    p = add_command(
        sub,
        "presets",
        examples=(f"{PROG} presets", f"{PROG} presets --show hybrid > my-dust.toml"),
    )
    p.set_defaults(run=run_presets)
    p.add_argument("--show", metavar="NAME", help="print the TOML of preset NAME (copy it to edit)")

    p = add_command(
        sub,
        "materials",
        examples=(f"{PROG} materials",),
    )
    p.set_defaults(run=run_materials)


def run_presets(args: argparse.Namespace) -> int:
    """Run ``presets``: one line per preset, or ``--show NAME``'s TOML."""

    if args.show is not None:
        try:
            text = presets.preset_text(args.show)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        sys.stdout.write(text)
        return 0
    for preset in presets.preset_registry().values():
        marker = " (default)" if preset.default else ""
        print(f"{preset.name:18s} {preset.summary}{marker}")
    return 0


def run_materials(args: argparse.Namespace) -> int:
    """Run ``materials``: one line per material, its wavelength range and source."""

    for name in list_materials():
        material = get_material(name)
        lo, hi = material.wavelength_range_nm
        print(f"{name:36s} {lo:8.1f} - {hi:8.1f} nm  {material.citation}")
    return 0
