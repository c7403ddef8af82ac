"""``dustoptics sky``: the sky an atmosphere makes, as images and data (:class:`~dustoptics.sky.job.SkyJob`).

The files go into ``DIR/NAME/``, NAME the job's (``mars-hybrid``, ``earth``,
``mars-comparison``), as ``build`` and ``export`` place theirs: run again with
the same inputs, the files are up to date and left untouched; files of other
inputs are replaced only with ``--force``.  The presets, the image size and the
files that would be replaced are checked before any work.  The PNG images need
matplotlib (the ``plot`` extra): without it, or with ``--no-png``, the netCDF
file is written alone.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from dustoptics._validation import check_inside
from dustoptics.cli.aerosol_options import add_aerosol_options, aerosol_keywords
from dustoptics.cli.checks import check_presets
from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import _positive_float, add_command
from dustoptics.cli.report import report_placement, say
from dustoptics.cli.sky_preview import add_preview_options, approximations_from_args, report_preview
from dustoptics.sky import scene
from dustoptics.sky.job import SkyJob, sky_colour_summary

__all__ = ["add_parser", "run"]

#: Fisheye sizes ``--size`` accepts, those of :meth:`dustoptics.sky.scene.Sky.fisheye`
#: (beyond the largest with ``--allow-large``, refused by the job before any work). [pixels]
SIZE_RANGE_PX = (16, 8192)


def _size(text: str) -> int:
    """``--size``: an integer of at least ``SIZE_RANGE_PX[0]``."""
    low, high = SIZE_RANGE_PX
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer; got {text!r}") from None
    if value < low:
        raise argparse.ArgumentTypeError(
            f"must be an integer in [{low}, {high}] ({high} and beyond with --allow-large); "
            f"got {text!r}"
        )
    return value


def add_parser(sub: Any) -> None:
    """Add the ``sky`` subcommand (``mars``, ``earth``, ``compare``) to the subparsers ``sub``."""
    p = add_command(
        sub,
        "sky",
        examples=(
            f"{PROG} sky mars --dust hybrid --sunset --out skies",
            f"{PROG} sky compare --out skies",
        ),
    )
    p.set_defaults(run=run)
    skies = p.add_subparsers(dest="sky_command", metavar="{mars,earth,compare}", required=True)
    for planet in ("mars", "earth"):
        q = add_command(
            skies,
            planet,
            help=f"spectral sky of {planet} over an observer near the ground",
            examples=(
                f"{PROG} sky mars --dust blue-moons --sun-elevation 2 --out skies"
                if planet == "mars"
                else f"{PROG} sky earth --sun-elevation 30 --size 1024 --out skies",
            ),
        )
        if planet == "mars":
            q.add_argument(
                "--dust",
                default="hybrid",
                metavar="PRESET",
                help="dust model (a preset: collienne, costa, blue-moons, hybrid, ...; default hybrid)",
            )
            q.add_argument(
                "--optical-depth",
                type=_positive_float,
                default=0.5,
                metavar="TAU",
                help="vertical dust optical depth at 550 nm (default 0.5)",
            )
        q.add_argument(
            "--sun-elevation",
            type=float,
            default=10.0 if planet == "mars" else 45.0,
            metavar="DEG",
            help="Sun elevation [degree], -10 .. 90",
        )
        q.add_argument(
            "--albedo",
            type=float,
            default=0.2,
            metavar="A",
            help="Lambertian ground albedo (default 0.2)",
        )
        q.add_argument(
            "--size",
            type=_size,
            default=512,
            metavar="PX",
            help=f"fisheye size [pixels], {SIZE_RANGE_PX[0]} .. {SIZE_RANGE_PX[1]}, more with "
            "--allow-large (default 512)",
        )
        q.add_argument(
            "--exposure",
            type=_positive_float,
            metavar="E",
            help="display white at Y * E = 1 (default: the 99th percentile of the sky is white)",
        )
        q.add_argument(
            "--sunset",
            action="store_true",
            help="also a sunset sequence, Sun elevation 20 to -2 degree, at one exposure",
        )
        q.add_argument(
            "--space",
            action="store_true",
            help="also the limb seen from space, Sun in quadrature (NAME_limb.png, its own "
            "exposure unless --exposure)",
        )
        _add_common_options(q)
        q.add_argument(
            "--exr",
            choices=("half", "float"),
            help="also the sky as a linear HDR environment map, NAME_environment.exr "
            "(equirectangular OpenEXR, Rec. 709 primaries, kcd m-2, the Sun left out and "
            "described in the header), in 16-bit half or 32-bit float",
        )
        q.add_argument(
            "--exr-height",
            type=_size,
            default=512,
            metavar="PX",
            help="the environment map's height [pixels] (its width is twice it; default 512)",
        )
        q.add_argument(
            "--cubemap",
            action="store_true",
            help="with --exr: also the map on a cube, NAME_environment_cube.exr "
            "(a 6 x 1 strip +X -X +Y -Y +Z -Z, Y up)",
        )
        add_preview_options(q)
        if planet == "earth":
            add_aerosol_options(q)
    q = add_command(
        skies,
        "compare",
        help="the seed thesis's comparisons of the Mars dust models; prints the sky's "
        "chromaticity against the Mars Exploration Rovers' range",
        examples=(f"{PROG} sky compare --models costa,hybrid --optical-depth 1 --out skies",),
    )
    q.add_argument(
        "--models",
        type=lambda t: tuple(x.strip() for x in t.split(",") if x.strip()),
        default=None,
        metavar="LIST",
        help="presets (default collienne,costa,blue-moons,hybrid)",
    )
    q.add_argument(
        "--optical-depth",
        type=_positive_float,
        default=0.5,
        metavar="TAU",
        help="vertical dust optical depth at 550 nm (default 0.5; Collienne's model keeps its "
        "own thin aerosol)",
    )
    q.add_argument(
        "--sun-elevation",
        type=float,
        default=10.0,
        metavar="DEG",
        help="Sun elevation of the radiance and luminance comparisons [degree]",
    )
    _add_common_options(q)


def _add_common_options(q: argparse.ArgumentParser) -> None:
    """--out, --force, --quiet, --allow-large, --no-png: every sky command's."""
    q.add_argument("--out", type=Path, required=True, metavar="DIR", help=_OUT_HELP)
    q.add_argument("--force", action="store_true", help="replace existing files")
    q.add_argument("--quiet", action="store_true", help="no summary output or progress")
    q.add_argument("--allow-large", action="store_true", help=_LARGE_HELP)
    q.add_argument("--no-png", action="store_true", help=_NO_PNG_HELP)


_NO_PNG_HELP = "no PNG images: the netCDF file only (without matplotlib, the default)"

_LARGE_HELP = (
    "go ahead beyond the memory and work budget of the skies and images (refused before any "
    "work otherwise)"
)

_OUT_HELP = (
    "output directory; files go to DIR/NAME/, NAME mars-PRESET, earth or mars-comparison "
    "(as for build)"
)


def _png(args: argparse.Namespace) -> bool:
    """Whether to write the PNG images: not with ``--no-png``, nor without matplotlib (a
    one-line note then says so; the rest is written)."""
    if args.no_png:
        if args.sky_command != "compare" and (args.sunset or args.space):
            given = " and ".join(o for o in ("--sunset", "--space") if getattr(args, o[2:]))
            raise UsageError(
                f"with --no-png, {given} would write nothing (PNG images only); drop one of them"
            )
        return False
    try:
        scene.check_png_support()
    except ImportError:
        print(
            f"{PROG}: note: no PNG images, they need matplotlib: pip install "
            "'dustoptics[plot]' (or give --no-png); writing the rest",
            file=sys.stderr,
        )
        return False
    return True


def run(args: argparse.Namespace) -> int:
    """Run ``sky``: the job's files, known and checked before any work; returns the exit status."""
    png = _png(args)

    if args.sky_command == "compare":
        if args.models is not None:
            check_presets("--models", args.models)
        job = SkyJob(
            "compare",
            out_dir=args.out,
            models=args.models,
            optical_depth=args.optical_depth,
            sun_elevation_deg=args.sun_elevation,
            progress=None if args.quiet else sys.stderr,
            allow_large=args.allow_large,
            png=png,
        )
    else:
        if not (-10.0 <= args.sun_elevation <= 90.0):
            raise UsageError(
                f"--sun-elevation must be within [-10, 90] degree; got {args.sun_elevation!r}"
            )
        if not (0.0 <= args.albedo <= 1.0):
            raise UsageError(f"--albedo must be within [0, 1]; got {args.albedo!r}")
        if args.sky_command == "mars":
            check_presets("--dust", (args.dust,))
        if args.cubemap and args.exr is None:
            raise UsageError("--cubemap is the environment map on a cube: give --exr too")
        job = SkyJob(
            args.sky_command,
            out_dir=args.out,
            sun_elevation_deg=args.sun_elevation,
            albedo=args.albedo,
            size_px=args.size,
            exposure=args.exposure,
            sunset=args.sunset and png,
            space=args.space and png,
            # Options of 'sky mars' only.
            dust=getattr(args, "dust", "hybrid"),
            optical_depth=getattr(args, "optical_depth", 0.5),
            preview=approximations_from_args(args),
            earth_aerosol=aerosol_keywords(args) if args.sky_command == "earth" else {},
            progress=None if args.quiet else sys.stderr,
            allow_large=args.allow_large,
            png=png,
            exr=args.exr,
            exr_height_px=args.exr_height,
            cubemap=args.cubemap,
        )
    # The job's own folder, DIR/NAME/, checked to stay inside DIR (NAME is a preset's).
    job = replace(job, out_dir=args.out / job.name)
    check_inside(args.out, job.out_dir)
    placed = job.place(force=args.force)
    report_placement(args, job.name, job.out_dir, placed)
    report_preview(args, [*placed.written, *placed.unchanged])
    sky_file = job.out_dir / f"{job.name}_sky.nc"
    # Read back only to be said (--quiet says nothing).
    summary = sky_colour_summary(sky_file) if sky_file.is_file() and not args.quiet else None
    if summary is not None:
        say(args, summary)
    if args.sky_command == "compare" and not args.quiet:  # the rover table, read back
        # lazy: sky.compare adds 20-30 ms to every command's start-up (-X importtime)
        from dustoptics.sky.compare import read_rover_comparison

        say(args, read_rover_comparison(job.out_dir / f"{job.name}.nc").to_text())
    return 0
