"""``dustoptics retrieve``: the dust parameters that fit observations in a file.

Reads the observations (a netCDF file of ``ssa``, ``g``, ``extinction_ratio``,
``phase``, ``sky_radiance`` and/or ``sky_chromaticity`` with their
uncertainties, the sky's scene in its variables' attributes,
:mod:`dustoptics.retrieve`), takes
the dust model from a preset or a TOML configuration (its values are the
start), calls :func:`dustoptics.retrieve.retrieve` and prints the fitted
values with their standard errors and correlations; ``--out FILE.json``
writes the whole result.  Progress (the sky solves' estimate, then one line per
evaluation: its number, chi-square, elapsed seconds) goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.cli._retrieve_files import (
    MAX_OBSERVATIONS_BYTES,
    check_not_an_input,
    read_model,
    read_observations,
)
from dustoptics.cli.errors import PROG, UsageError
from dustoptics.cli.parser import add_command
from dustoptics.io._atomic import check_targets, write_files
from dustoptics.models.build import is_config_path

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    """Add the ``retrieve`` subcommand to the subparsers ``sub``."""
    p = add_command(
        sub,
        "retrieve",
        examples=(
            f"{PROG} retrieve obs.nc --model blue-moons --fit r_eff_um=0.2:5 "
            "--fit hematite_fraction=0:0.2",
            f"{PROG} retrieve obs.nc --model my-dust.toml --fit v_eff=0.02:0.45 "
            "--prior v_eff=0.2,0.05 --out fit.json",
            f"{PROG} retrieve mer_sky.nc --model mer-start.toml --fit r_eff_um=0.5:4 "
            "--fit v_eff=0.05:0.6 --allow-large",
        ),
    )
    p.set_defaults(run=run)
    p.add_argument(
        "observations",
        type=Path,
        metavar="OBS.nc",
        help="netCDF file of ssa, g, extinction_ratio, phase, sky_radiance and/or "
        "sky_chromaticity with uncertainties (the sky's optical_depth, ground_albedo as "
        "attributes)",
    )
    p.add_argument(
        "--model",
        required=True,
        metavar="NAME_OR_TOML",
        help="the dust to start from: a preset name or a configuration file (Mie dust)",
    )
    p.add_argument(
        "--fit",
        action="append",
        required=True,
        metavar="PARAM=LO:HI",
        help="a parameter to fit and its bounds (repeat for more): the size distribution's "
        "(r_eff_um, v_eff, ...), hematite_fraction, host_n, host_k",
    )
    p.add_argument(
        "--prior",
        action="append",
        default=[],
        metavar="PARAM=MEAN,SD",
        help="a Gaussian prior on a fitted parameter (repeat for more)",
    )
    p.add_argument(
        "--max-iterations",
        type=int,
        default=50,
        metavar="N",
        help="most evaluations of the residuals, each one table with derivatives (default 50)",
    )
    p.add_argument(
        "--sky-streams",
        type=int,
        default=None,
        metavar="N",
        help="discrete ordinates per hemisphere of the skies of sky observations (default 20)",
    )
    p.add_argument(
        "--sky-tol",
        type=float,
        default=None,
        metavar="TOL",
        help="tolerance of the skies' orders of scattering (default 1e-6)",
    )
    p.add_argument(
        "--allow-large",
        action="store_true",
        help="go ahead when the sky solves are estimated beyond five minutes, or a table the "
        "fit may compute (at the size bounds) beyond the budget of one",
    )
    p.add_argument(
        "--max-observation-bytes",
        type=int,
        default=MAX_OBSERVATIONS_BYTES,
        metavar="BYTES",
        help="largest observations file, on disk and as its variables declare they are in "
        f"memory, that is read (default {MAX_OBSERVATIONS_BYTES}, 256 MiB)",
    )
    p.add_argument("--out", type=Path, metavar="FILE.json", help="write the result as JSON")
    p.add_argument(
        "--force",
        action="store_true",
        help="replace an existing --out file (never one of the inputs)",
    )


def _pairs(options: list[str], flag: str, sep: str) -> dict[str, tuple[float, float]]:
    """``NAME=A<sep>B`` options as {name: (a, b)}; a malformed one is a usage error."""
    out: dict[str, tuple[float, float]] = {}
    for text in options:
        name, eq, rest = text.partition("=")
        parts = rest.split(sep)
        try:
            if not (eq and name and len(parts) == 2):
                raise ValueError
            pair = (float(parts[0]), float(parts[1]))
        except ValueError:
            form = "PARAM=LO:HI" if sep == ":" else "PARAM=MEAN,SD"
            raise UsageError(f"{flag} must be {form}; got {text!r}") from None
        if name.strip() in out:
            raise UsageError(f"{flag} {name.strip()} is given twice; give each parameter once")
        out[name.strip()] = pair
    return out


def _finite_or_none(values: Any) -> Any:
    """A list (of lists) of floats with NaN and inf as None (JSON has neither)."""
    if isinstance(values, list):
        return [_finite_or_none(v) for v in values]
    return values if math.isfinite(values) else None


def _write(result: Any, path: Path, force: bool) -> None:

    check_targets([path], overwrite=force)
    record = {
        "parameters": list(result.parameters),
        "values": result.values.tolist(),
        "standard_errors": _finite_or_none(result.standard_errors.tolist()),
        "covariance": _finite_or_none(result.covariance.tolist()),
        "initial_values": result.initial_values.tolist(),
        "labels": list(result.labels),
        "residuals": result.residuals.tolist(),
        "chi_square": result.chi_square,
        "iterations": result.iterations,
        "function_evaluations": result.function_evaluations,
        "converged": result.converged,
        "message": result.message,
        "sky_solves": result.sky_solves,
        "path_values": result.history_values.tolist(),
    }
    text = json.dumps(record, indent=1)
    write_files({path: (text + "\n").encode()}, overwrite=force)


def _checked_options(args: argparse.Namespace) -> Any:
    """The numerical options checked (usage errors), and the sky's settings."""
    from dustoptics.retrieve import SkySettings
    from dustoptics.retrieve.fit import MAX_ITERATIONS

    if not 1 <= args.max_iterations <= MAX_ITERATIONS:
        raise UsageError(
            f"--max-iterations must be within [1, {MAX_ITERATIONS}]; got {args.max_iterations}"
        )
    if args.max_observation_bytes < 1:
        raise UsageError(f"--max-observation-bytes must be >= 1; got {args.max_observation_bytes}")
    settings = {}
    if args.sky_streams is not None:
        settings["n_streams"] = args.sky_streams
    if args.sky_tol is not None:
        settings["tol"] = args.sky_tol
    try:
        return SkySettings(**settings)
    except ValueError as exc:
        raise UsageError(f"--sky-streams/--sky-tol: {exc}") from None


def run(args: argparse.Namespace) -> int:
    """Run ``retrieve``; returns the exit status.  The options, the model and the
    output file are checked before the observations are read or any table computed."""

    # lazy: dustoptics.retrieve (scipy.optimize, xarray) adds 0.8-1 s to every command's start-up
    from dustoptics.retrieve import retrieve

    bounds = _pairs(args.fit, "--fit", ":")
    priors = _pairs(args.prior, "--prior", ",")
    sky = _checked_options(args)
    if args.out is not None:
        inputs = {"observations file": args.observations}
        if is_config_path(args.model):
            inputs["--model file"] = Path(args.model)
        check_not_an_input(args.out, inputs)
    model = read_model(args.model)
    if args.out is not None:
        check_targets([args.out], overwrite=args.force)
    observations = read_observations(args.observations, args.max_observation_bytes)

    result = retrieve(
        observations,
        model=model,
        parameters=list(bounds),
        bounds=bounds,
        priors=priors or None,
        max_iterations=args.max_iterations,
        sky=sky,
        progress=sys.stderr,
        allow_large=args.allow_large,
    )
    state = "converged" if result.converged else "NOT converged"
    print(
        f"{args.model}: {state} after {result.iterations} iterations "
        f"({result.function_evaluations} evaluations): {result.message}"
    )
    n = result.residuals.size
    print(f"  chi-square {result.chi_square:.6g} from {n} residuals")
    if result.sky_solves:
        print(f"  {result.sky_solves} sky solves")
    print(f"  {'parameter':>20s}  {'start':>12s}  {'fitted':>12s}  {'std. error':>12s}")
    for p, v0, v, se in zip(
        result.parameters,
        result.initial_values,
        result.values,
        result.standard_errors,
        strict=True,
    ):
        print(f"  {p:>20s}  {v0:12.6g}  {v:12.6g}  {se:12.3g}")
    if len(result.parameters) > 1:
        se = result.standard_errors
        with np.errstate(divide="ignore", invalid="ignore"):
            corr = result.covariance / np.outer(se, se)
        print("  correlations:")
        for i, p in enumerate(result.parameters):
            row = "  ".join(f"{c:+6.3f}" for c in corr[i])
            print(f"  {p:>20s}  {row}")
    if args.out is not None:
        _write(result, args.out, args.force)
        print(f"wrote {args.out}")
    return 0
