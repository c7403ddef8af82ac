"""The Earth's aerosol options of ``sky earth`` and ``build earth``.

``--aerosol NAME``, ``--aerosol-optical-depth TAU[@NM]``, ``--turbidity T``
and ``--relative-humidity PCT`` become the aerosol keywords of
:func:`~dustoptics.atmosphere.sets.earth_atmosphere` (:func:`aerosol_keywords`),
checked before any work: an unknown name, a value out of range, or both an
optical depth and a turbidity is a usage error.
"""

from __future__ import annotations

import argparse
from typing import Any

from dustoptics.atmosphere.aerosols import RELATIVE_HUMIDITIES_PERCENT, TURBIDITY_RANGE
from dustoptics.atmosphere.sets import (
    EARTH_AEROSOL_OPTICAL_DEPTH_RANGE,
    EARTH_AEROSOLS,
    check_earth_aerosol,
)
from dustoptics.cli.errors import UsageError
from dustoptics.cli.parser import detail_group

__all__ = ["AEROSOL_OPTIONS", "add_aerosol_options", "aerosol_keywords"]

#: Attribute names of the options, for commands that refuse them where they change nothing.
AEROSOL_OPTIONS = ("aerosol", "aerosol_optical_depth", "turbidity", "relative_humidity")


def _names() -> tuple[str, ...]:

    return tuple(EARTH_AEROSOLS)


def _aerosol(text: str) -> str:
    """``--aerosol``: one of the Earth's aerosols."""
    if text not in _names():
        raise argparse.ArgumentTypeError(
            f"unknown aerosol {text!r}; choose from {', '.join(_names())}"
        )
    return text


def _optical_depth(text: str) -> tuple[float, float]:
    """``--aerosol-optical-depth TAU[@NM]``: (tau, wavelength [nm]), 550 nm unless given."""

    tau_text, _, nm_text = text.partition("@")
    try:
        tau = float(tau_text)
        nm = float(nm_text) if nm_text else 550.0
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected TAU or TAU@NM, e.g. 0.1@550; got {text!r}"
        ) from None
    low, high = EARTH_AEROSOL_OPTICAL_DEPTH_RANGE
    if not low < tau <= high:
        raise argparse.ArgumentTypeError(f"TAU must be > {low:g} and <= {high:g}; got {text!r}")
    if not 250.0 <= nm <= 2500.0:
        raise argparse.ArgumentTypeError(f"NM must lie within 250-2500 nm; got {text!r}")
    return tau, nm


def _turbidity(text: str) -> float:
    """``--turbidity T``: Preetham's turbidity within its range."""

    low, high = TURBIDITY_RANGE
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number; got {text!r}") from None
    if not low < value <= high:
        raise argparse.ArgumentTypeError(f"must be > {low:g} and <= {high:g}; got {text!r}")
    return value


def _humidity(text: str) -> int:
    """``--relative-humidity PCT``: one of OPAC's humidities."""

    allowed = RELATIVE_HUMIDITIES_PERCENT
    if text not in {str(h) for h in allowed}:
        raise argparse.ArgumentTypeError(
            f"must be one of OPAC's {', '.join(map(str, allowed))} [%]; got {text!r}"
        )
    return int(text)


def add_aerosol_options(parser: argparse.ArgumentParser) -> None:
    """Add the Earth's aerosol options to ``parser`` (their own group)."""
    g = detail_group(parser, "Earth aerosols (OPAC's types, Hess et al. 1998, by dustoptics' Mie)")
    g.add_argument(
        "--aerosol",
        type=_aerosol,
        metavar="NAME",
        help="the aerosols: one of OPAC's types (continental-clean, continental-average, "
        "continental-polluted, urban, desert, maritime-clean, maritime-polluted, "
        "maritime-tropical, arctic, antarctic) or kobe2026 (Kobe's constant coefficients, "
        "optical depth 0.0027); default continental-average",
    )
    g.add_argument(
        "--aerosol-optical-depth",
        type=_optical_depth,
        metavar="TAU[@NM]",
        help="vertical aerosol optical depth at NM nanometres (default 550), > 0 and <= 5; "
        "default 0.1 at 550 nm (a typical clear day) for OPAC's types",
    )
    g.add_argument(
        "--turbidity",
        type=_turbidity,
        metavar="T",
        help="instead of --aerosol-optical-depth: turbidity 1 < T <= 10, as the optical depth "
        "(0.04608 T - 0.04586) (lambda / 1 um)^-1.3 of Preetham et al. 1999 (appendix A.3) "
        "at 550 nm (T 2: 0.101)",
    )
    g.add_argument(
        "--relative-humidity",
        type=_humidity,
        metavar="PCT",
        help="relative humidity of OPAC's components: 0 (dry), 50, 70, 80, 90, 95, 98 or 99 "
        "(default 80, Hess et al.'s Table 5)",
    )


def aerosol_keywords(args: argparse.Namespace) -> dict[str, Any]:
    """The aerosol keywords the options give (only those given), checked before any work.

    Raises
    ------
    UsageError
        Both ``--aerosol-optical-depth`` and ``--turbidity``, or an option that
        changes nothing (a humidity for Kobe's aerosols).
    """

    out: dict[str, Any] = {}
    if getattr(args, "aerosol", None) is not None:
        out["aerosol"] = args.aerosol
    tau = getattr(args, "aerosol_optical_depth", None)
    turbidity = getattr(args, "turbidity", None)
    if tau is not None and turbidity is not None:
        raise UsageError(
            "give --aerosol-optical-depth or --turbidity, not both (the turbidity is an optical depth)"
        )
    if tau is not None:
        out["aerosol_optical_depth"], out["aerosol_reference_nm"] = tau
    if turbidity is not None:
        out["turbidity"] = turbidity
    if getattr(args, "relative_humidity", None) is not None:
        if out.get("aerosol") == "kobe2026":
            raise UsageError(
                "--relative-humidity changes nothing for --aerosol kobe2026; remove it"
            )
        out["aerosol_relative_humidity_percent"] = args.relative_humidity
    try:
        check_earth_aerosol(**out)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return out
