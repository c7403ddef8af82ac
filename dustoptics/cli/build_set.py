"""``dustoptics build mars|earth|earth-kobe2026``: an atmosphere set's files, and the builder of
a preset's or configuration's table that ``build`` and ``fit`` share.

The set is computed by :func:`~dustoptics.atmosphere.build.build_atmosphere` and written by
:func:`~dustoptics.atmosphere.build.write_atmosphere_set` (CosmoScout VR's files, with
``--format bruneton`` Bruneton's parameters, with an engine's format that engine's parameters
fitted to the set's sky, :mod:`dustoptics.sky.engines`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TextIO

from dustoptics.atmosphere.build import DEFAULT_DUST, build_atmosphere, set_inputs
from dustoptics.cli.aerosol_options import aerosol_keywords
from dustoptics.cli.checks import check_set_outputs
from dustoptics.cli.errors import UsageError
from dustoptics.cli.export import same_table
from dustoptics.cli.report import report_placement
from dustoptics.io.outputs import place_outputs, write_atmosphere_set
from dustoptics.models.build import TableBuilder, is_config_path
from dustoptics.sky.engines import ENGINES, reference_skies
from dustoptics.sky.engines.core import write_engine_files

__all__ = ["run_set", "table_builder"]


def table_builder(
    name: str, *, progress: TextIO | None = None, allow_large: bool = False
) -> TableBuilder:
    """:meth:`TableBuilder.from_name`, an unknown preset name a usage error."""
    if is_config_path(name):
        return TableBuilder.from_name(name, progress=progress, allow_large=allow_large)
    try:
        return TableBuilder.from_name(name, progress=progress, allow_large=allow_large)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def run_set(args: argparse.Namespace) -> int:
    """``build mars|earth|earth-kobe2026``: the set's files in ``DIR/NAME/``."""
    if args.format is not None and not set(args.format) <= {"cosmoscout", "bruneton", *ENGINES}:
        raise UsageError(
            f"'build {args.name}' writes CosmoScout VR's atmosphere set (format cosmoscout), and "
            f"with --format bruneton also Bruneton's model parameters, with --format "
            f"{','.join(ENGINES)} an engine's parameters fitted to its sky; --format "
            f"{','.join(args.format)} is not available for a set. Build a table "
            "('dustoptics build PRESET --format ...') to get the other formats"
        )
    if args.name == "earth-kobe2026" and args.wavelengths_nm is not None:
        raise UsageError("earth-kobe2026 has Kobe's three wavelengths only; drop --wavelengths-nm")
    progress = None if args.quiet else sys.stderr
    dust = DEFAULT_DUST if args.dust is None else args.dust
    optical_depth = 0.5 if args.optical_depth is None else args.optical_depth
    dust_config = None
    if args.name == "mars":
        dust_config = table_builder(dust, progress=progress).config
        if not dust_config.phase.uses_mie:
            raise UsageError(
                f"dust {dust!r} has no cross-sections (a phase-function-only model); "
                "choose a Mie preset"
            )
    earth_aerosol = aerosol_keywords(args) if args.name == "earth" else {}
    check_set_outputs(args, dust=dust, optical_depth=optical_depth)
    atm = build_atmosphere(
        args.name,
        dust=dust if dust_config is None else dust_config,
        optical_depth=optical_depth,
        reference_wavelength_nm=args.reference_wavelength_nm,
        ozone_csv=args.ozone_csv,
        wavelength_nm=args.wavelengths_nm,
        progress=progress,
        **earth_aerosol,
    )
    inputs = set_inputs(
        args.name,
        dust=dust,
        optical_depth=optical_depth,
        reference_wavelength_nm=args.reference_wavelength_nm,
        ozone_csv=args.ozone_csv,
        wavelength_nm=args.wavelengths_nm,
        **earth_aerosol,
    )
    bruneton = args.format is not None and "bruneton" in args.format
    engines = [f for f in args.format or () if f in ENGINES]
    skies = reference_skies(atm) if engines else ()
    out_dir = args.out / args.name

    def write(directory: Path) -> list[Path]:
        written = write_atmosphere_set(
            atm, directory, inputs=inputs, bruneton=bruneton, final_directory=out_dir
        )
        for name in engines:
            written += write_engine_files(name, atm, directory, skies=skies)
        return written

    placed = place_outputs(
        write,
        out_dir,
        force=args.force,
        same=same_table,
    )
    report_placement(args, f"{args.name} (CosmoScout VR set)", out_dir, placed)
    return 0
