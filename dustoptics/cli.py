"""The ``dustoptics`` command line.

Usage::

    dustoptics build [NAME] [--out DIR] [--rtol RTOL] [--wavelengths-nm LIST]
                     [--n-theta N] [--force] [--quiet]
    dustoptics presets
    dustoptics materials
    dustoptics --version

``build`` computes a preset's table with :func:`dustoptics.compute_optics` and
writes it into ``DIR/NAME/`` with :func:`dustoptics.io.seed_csv.write_seed_csv`.
The presets are defined in :data:`PRESETS`, the only place in the package that
names them.

Exit status: 0 on success, 1 on failure (e.g. an output file exists without
``--force``), 2 on a usage error (unknown preset, bad option value).  Errors
are printed as ``dustoptics: error: <message>`` on stderr, without a traceback.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

__all__ = ["PRESETS", "BuildResult", "Preset", "build", "main"]

PROG = "dustoptics"


@dataclass(frozen=True)
class Preset:
    """A named table definition.

    Attributes
    ----------
    description : str
        One line for ``dustoptics presets``.
    source : str
        Where the model comes from.
    material : callable
        Returns the refractive-index object, m(lambda) = n + i k.
    distribution : callable
        Returns the :class:`~dustoptics.sizedist.SizeDistribution`.
    weighting : str
        ``"scattering"`` (physical) or ``"number"`` (the seed's average).
    theta_deg : callable or None
        Returns the default scattering angles [deg]; None for
        :func:`dustoptics.optics.default_theta_deg` (0 to 180 in 0.1 deg steps).
    wavelengths_nm : callable or None
        Returns the default wavelengths [nm]; None for 360, 370, ..., 830.
    """

    description: str
    source: str
    material: Callable[[], Any] = field(repr=False)
    distribution: Callable[[], Any] = field(repr=False)
    weighting: str = "scattering"
    theta_deg: Callable[[], np.ndarray] | None = field(default=None, repr=False)
    wavelengths_nm: Callable[[], np.ndarray] | None = field(default=None, repr=False)


def _blue_moon_dust() -> Any:
    import dustoptics as do

    return do.mars_dust(hematite_fraction=0.03, host_index=1.5, hematite="querry-extraordinary")


def _mars_sizes() -> Any:
    import dustoptics as do

    return do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)


#: The presets ``dustoptics build`` knows.  (A later version reads them from TOML files.)
PRESETS: dict[str, Preset] = {
    "mars-dust": Preset(
        description=(
            "Blue Moon's Mars dust (3 % hematite in n=1.5, modified gamma r_eff 1.6 um, "
            "v_eff 0.2), physical cross-section weighting"
        ),
        source=(
            "Meyran 2022 after Ehlers et al. 2014; Querry 1985 hematite (extraordinary ray); "
            "sizes Tomasko et al. 1999"
        ),
        material=_blue_moon_dust,
        distribution=_mars_sizes,
        weighting="scattering",
    ),
    "mars-dust-seed": Preset(
        description=(
            "the seed thesis's published table: the same dust, number-weighted phase function, "
            "1,800 angles"
        ),
        source="Meyran 2022 (seed-tables/MiePhaseFunctionSpectrum.csv), computed deterministically",
        material=_blue_moon_dust,
        distribution=_mars_sizes,
        weighting="number",
        theta_deg=lambda: np.linspace(0.0, 180.0, 1800),
    ),
}

DEFAULT_PRESET = "mars-dust"
DEFAULT_OUT = "tables"
DEFAULT_RTOL = 1e-4


@dataclass(frozen=True)
class BuildResult:
    """What :func:`build` wrote.

    Attributes
    ----------
    name : str
        Preset name.
    paths : list of pathlib.Path
        Files written.
    table : OpticsTable
        The computed table.
    seconds : float
        Wall-clock time of the computation. [s]
    warnings : list of str
        Messages of warnings raised while computing (e.g. non-convergence).
    """

    name: str
    paths: list[Path]
    table: Any = field(repr=False)
    seconds: float
    warnings: list[str]


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _note(stream: TextIO | None, message: str) -> None:
    if stream is not None:
        print(message, file=stream, flush=True)


def build(
    name: str = DEFAULT_PRESET,
    out: str | os.PathLike[str] = DEFAULT_OUT,
    *,
    rtol: float = DEFAULT_RTOL,
    wavelengths_nm: Sequence[float] | None = None,
    n_theta: int | None = None,
    overwrite: bool = False,
    progress: TextIO | None = None,
) -> BuildResult:
    """Compute a preset's table and write it into ``out/name/``.

    Parameters
    ----------
    name : str
        A key of :data:`PRESETS`.
    out : path-like
        Parent directory; the files go into ``out/name/``.
    rtol : float
        Quadrature tolerance on the phase function, in (0, 0.1). [-]
    wavelengths_nm : sequence of float, optional
        Override the preset's wavelengths. [nm]
    n_theta : int, optional
        Override the preset's angles with ``n_theta`` evenly spaced angles
        from 0 to 180 deg inclusive (>= 2).
    overwrite : bool
        Replace existing files.
    progress : text stream, optional
        Where to print progress (None: silent).

    Returns
    -------
    BuildResult

    Raises
    ------
    KeyError
        Unknown preset (the message lists the valid names).
    FileExistsError
        An output file exists and ``overwrite`` is False; checked before
        computing.
    ValueError
        Bad parameter (named in the message).
    """
    import dustoptics as do
    from dustoptics.io import seed_csv as export
    from dustoptics.table import Table

    if name not in PRESETS:
        raise KeyError(f"unknown preset {name!r}; valid names: {', '.join(PRESETS)}")
    preset = PRESETS[name]
    target = Path(out) / name
    if not overwrite:
        existing = export.existing_outputs(target)
        if existing:
            raise FileExistsError(
                f"{existing[0]} already exists (use --force / overwrite=True to replace it)"
            )
    if n_theta is not None:
        if not (isinstance(n_theta, (int, np.integer)) and n_theta >= 2):
            raise ValueError(f"n_theta must be an integer >= 2; got {n_theta!r}")
        theta: np.ndarray | None = np.linspace(0.0, 180.0, int(n_theta))
    else:
        theta = None if preset.theta_deg is None else preset.theta_deg()
    wavelengths: Sequence[float] | np.ndarray | None = wavelengths_nm
    if wavelengths is None and preset.wavelengths_nm is not None:
        wavelengths = preset.wavelengths_nm()

    material = preset.material()
    distribution = preset.distribution()
    n_wl = len(wavelengths) if wavelengths is not None else do.optics.default_wavelengths_nm().size
    n_th = theta.size if theta is not None else do.optics.default_theta_deg().size
    _note(
        progress,
        f"{name}: computing {_count(n_wl, 'wavelength')} x {_count(n_th, 'angle')} (rtol {rtol:g})...",
    )
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", do.ConvergenceWarning)
        table = do.compute_optics(
            material,
            distribution,
            wavelengths_nm=wavelengths,
            theta_deg=theta,
            rtol=rtol,
            weighting=preset.weighting,
        )
    seconds = time.perf_counter() - start
    messages = [str(w.message) for w in caught]
    _note(progress, f"{name}: computed in {seconds:.1f} s; writing {target}")
    inputs = {
        "preset": name,
        "description": preset.description,
        "source": preset.source,
        "material": table.material,
        "distribution": table.distribution.to_dict(),
        "weighting": table.weighting,
        "rtol": float(table.rtol),
        "wavelengths_nm": table.wavelength_nm.tolist(),
        "n_theta": int(table.theta_deg.size),
    }
    result = Table.from_optics(table, name=name, inputs=inputs, notes=tuple(messages))
    paths = export.write_seed_csv(result, target, overwrite=overwrite)
    return BuildResult(name=name, paths=paths, table=table, seconds=seconds, warnings=messages)


# ------------------------------------------------------------------ argument types


def _rtol(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number in (0, 0.1); got {text!r}") from None
    if not (0.0 < value < 0.1):
        raise argparse.ArgumentTypeError(f"must be in the open interval (0, 0.1); got {text!r}")
    return value


def _wavelength_list(text: str) -> list[float]:
    cells = [cell.strip() for cell in text.split(",")]
    if not cells or any(cell == "" for cell in cells):
        raise argparse.ArgumentTypeError(
            f"must be a comma-separated list of wavelengths in nm, e.g. 440,550,680; got {text!r}"
        )
    values = []
    for cell in cells:
        try:
            value = float(cell)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{cell!r} is not a number (wavelengths in nm)") from None
        if not (np.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"wavelengths must be finite and > 0 nm; got {cell!r}")
        values.append(value)
    if any(b <= a for a, b in itertools.pairwise(values)):
        raise argparse.ArgumentTypeError(f"wavelengths must be strictly increasing; got {text!r}")
    return values


def _n_theta(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 2; got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(
            f"must be an integer >= 2 (angles 0 and 180 deg included); got {text!r}"
        )
    return value


def _parser() -> argparse.ArgumentParser:
    from dustoptics import __version__

    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Polydisperse Mie optics of atmospheric dust and lookup tables for atmosphere renderers.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    names = ", ".join(PRESETS)
    b = commands.add_parser(
        "build",
        help="compute a preset's table and write it as CSV",
        description=(
            "Compute a preset's table and write MiePhaseFunctionSpectrum.csv, "
            "MieExtinctionSpectrum.csv and table_summary.json into OUT/NAME/."
        ),
    )
    b.add_argument(
        "name",
        nargs="?",
        default=DEFAULT_PRESET,
        choices=list(PRESETS),
        metavar="NAME",
        help=f"preset name (default: {DEFAULT_PRESET}; one of: {names})",
    )
    b.add_argument(
        "--out", default=DEFAULT_OUT, metavar="DIR", help=f"parent directory (default: {DEFAULT_OUT})"
    )
    b.add_argument(
        "--rtol",
        type=_rtol,
        default=DEFAULT_RTOL,
        help=f"quadrature tolerance on the phase function, in (0, 0.1) (default: {DEFAULT_RTOL:g})",
    )
    b.add_argument(
        "--wavelengths-nm",
        type=_wavelength_list,
        default=None,
        metavar="LIST",
        help="comma-separated wavelengths in nm, e.g. 440,550,680 (default: the preset's, 360..830 step 10)",
    )
    b.add_argument(
        "--n-theta",
        type=_n_theta,
        default=None,
        metavar="N",
        help="N evenly spaced angles from 0 to 180 deg (default: the preset's)",
    )
    b.add_argument("--force", action="store_true", help="overwrite existing files")
    b.add_argument("--quiet", action="store_true", help="no progress messages on stderr")

    commands.add_parser("presets", help="list the presets", description="List the presets build knows.")
    commands.add_parser(
        "materials",
        help="list the refractive-index catalogue",
        description="List the material catalogue.",
    )
    return parser


# ------------------------------------------------------------------ commands


def _cmd_build(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    result = build(
        args.name,
        args.out,
        rtol=args.rtol,
        wavelengths_nm=args.wavelengths_nm,
        n_theta=args.n_theta,
        overwrite=args.force,
        progress=None if args.quiet else sys.stderr,
    )
    for message in result.warnings:
        print(f"{PROG}: warning: {message}", file=sys.stderr)
    table = result.table
    for path in result.paths:
        print(f"wrote {path}")
    i = int(np.argmax(table.error_estimate))
    worst = float(table.error_estimate[i])
    status = "within" if worst <= table.rtol else "ABOVE"
    print(
        f"worst error_estimate: {worst:.2e} at {table.wavelength_nm[i]:g} nm "
        f"({status} rtol {table.rtol:g}; {_count(table.wavelength_nm.size, 'wavelength')} x "
        f"{_count(table.theta_deg.size, 'angle')}, {result.seconds:.1f} s)"
    )
    return 0


def _cmd_presets(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    width = max(len(name) for name in PRESETS)
    for name, preset in PRESETS.items():
        print(f"{name:<{width}}  {preset.description}")
        print(f"{'':<{width}}  source: {preset.source}")
    return 0


def _cmd_materials(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    import dustoptics as do

    for name in do.list_materials():
        print(name)
    return 0


_COMMANDS = {"build": _cmd_build, "presets": _cmd_presets, "materials": _cmd_materials}


def _silence_stdout() -> None:
    """After a broken pipe, point stdout at devnull so the exit flush does not fail."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass


def main(argv: list[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit status: 0 success, 1 failure, 2 usage error.
    """
    parser = _parser()
    try:
        args = parser.parse_args(argv)
        return _COMMANDS[args.command](args, parser)
    except SystemExit as exc:  # --help, --version, usage errors
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    except BrokenPipeError:  # e.g. `dustoptics materials | head`: not an error
        _silence_stdout()
        return 0
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except FileExistsError as exc:
        print(f"{PROG}: error: {exc.args[0] if exc.args else exc}", file=sys.stderr)
        return 1
    except (OSError, ValueError, KeyError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
