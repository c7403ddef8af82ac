"""``dustoptics sky mars|earth`` options that preview an engine's approximations.

``--phase fit:MODEL``, ``--rgb [ENGINE|R,G,B]``, ``--angles SAMPLING:N`` and
``--float16``, alone or together, also render the sky an engine draws and
compare it with the exact one
(:func:`dustoptics.sky.approximations.preview_sky`): the differences go into
``NAME_sky.nc`` and ``NAME_preview.png`` and a short table is printed.
The options' syntax is checked by the parser (an unknown ``--phase`` is refused
with the allowed list); what the set cannot take (channels outside its
wavelengths, too few angles, float16 overflow) before the sky is rendered.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from dustoptics.cli.errors import UsageError
from dustoptics.cli.report import say
from dustoptics.sky.approximations import (
    ANGLE_SAMPLINGS,
    ENGINE_CHANNELS_NM,
    NEAR_SUN_DEG,
    PHASE_CHOICES,
    Approximations,
    PreviewSummary,
)

__all__ = ["add_preview_options", "approximations_from_args", "report_preview"]


def _phase(text: str) -> str:
    try:
        Approximations(phase=text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def _channels(text: str) -> tuple[float, float, float]:
    if text in ENGINE_CHANNELS_NM:
        return ENGINE_CHANNELS_NM[text]
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(v > 0 for v in values):
        raise argparse.ArgumentTypeError(
            f"must be an engine ({', '.join(ENGINE_CHANNELS_NM)}) or three wavelengths "
            f"R,G,B in nm; got {text!r}"
        )
    return values[0], values[1], values[2]


def _angles(text: str) -> str:
    try:
        Approximations(angles=text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def _fraction(text: str) -> float:
    try:
        Approximations(angle_tolerance=float(text))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return float(text)


def _radius(text: str) -> float:
    try:
        Approximations(near_sun_deg=float(text))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return float(text)


def add_preview_options(parser: Any) -> None:
    """Add the preview options to the parser of ``sky mars`` or ``sky earth``."""
    g = parser.add_argument_group(
        "engine preview",
        "also render the sky an engine draws and compare it with the exact one (CIE xy "
        "distance, luminance ratio; over the dome and near the Sun): NAME_sky.nc gets the "
        "differences, NAME_preview.png shows exact | approximated | differences",
    )
    g.add_argument(
        "--phase",
        type=_phase,
        default="exact",
        metavar="exact|fit:MODEL[@NM]",
        help="the aerosols' phase function as fitted per wavelength (channel) by MODEL, or "
        "with @NM one fit at NM nm for all (Bruneton's one g: fit:cornette-shanks@550); MODEL: "
        + ", ".join(c.removeprefix("fit:") for c in PHASE_CHOICES[1:])
        + " (default exact)",
    )
    g.add_argument(
        "--rgb",
        nargs="?",
        const="bruneton",
        type=_channels,
        default=None,
        metavar="ENGINE|R,G,B",
        help="three channels instead of the spectrum, an engine's (without a value: bruneton) "
        "or three wavelengths R,G,B [nm]: "
        + "; ".join(
            f"{k} {'/'.join(f'{v:g}' for v in nm)} nm" for k, nm in ENGINE_CHANNELS_NM.items()
        ),
    )
    g.add_argument(
        "--angles",
        type=_angles,
        default=None,
        metavar="SAMPLING:N",
        help=f"phase functions at an engine's N angles, SAMPLING one of "
        f"{', '.join(ANGLE_SAMPLINGS)} (e.g. theta:721, cosmoscout:721)",
    )
    g.add_argument(
        "--float16",
        action="store_true",
        help="phase-function samples rounded to float16, as a half-float texture stores them",
    )
    g.add_argument(
        "--angle-tolerance",
        type=_fraction,
        default=Approximations().angle_tolerance,
        metavar="F",
        help="largest error of the phase function's sphere integral --angles may leave; fewer "
        "angles are refused with the smallest count that does (default %(default)g)",
    )
    g.add_argument(
        "--near-sun",
        type=_radius,
        default=NEAR_SUN_DEG,
        metavar="DEG",
        help="radius of the region near the Sun in the comparison [degree] (default %(default)g)",
    )


def approximations_from_args(args: argparse.Namespace) -> Approximations | None:
    """The approximations the options ask for, or None when none is asked.

    Raises
    ------
    UsageError
        ``--angle-tolerance`` without ``--angles``, or ``--near-sun`` without
        an approximation (they would change nothing).
    """
    default = Approximations()
    a = Approximations(
        phase=args.phase,
        channels_nm=args.rgb,
        angles=args.angles,
        float16=args.float16,
        angle_tolerance=args.angle_tolerance,
        near_sun_deg=args.near_sun,
    )
    if args.angles is None and args.angle_tolerance != default.angle_tolerance:
        raise UsageError("--angle-tolerance applies to --angles, which is not given")
    if not a.any and args.near_sun != default.near_sun_deg:
        raise UsageError(
            "--near-sun applies to a preview: give --phase fit:MODEL, --rgb, --angles or --float16"
        )
    return a if a.any else None


def report_preview(args: argparse.Namespace, written: list[Path]) -> None:
    """Print the preview's table, read back from the ``*_sky.nc`` just written (if one was asked)."""
    if not hasattr(args, "phase") or approximations_from_args(args) is None:
        return
    import xarray as xr  # lazy: xarray adds 0.7-1 s to every command's start-up (-X importtime)

    for path in written:
        if path.name.endswith("_sky.nc"):
            with xr.open_dataset(path, engine="scipy") as ds:
                if "preview_approximations" in ds.attrs:
                    say(args, PreviewSummary.from_attributes(ds.attrs).table())
