"""The ``dustoptics`` command line: thin, the library does the work.

Usage::

    dustoptics build [NAME_OR_CONFIG] [--out DIR] [--format FMT[,FMT...]] [--force] [--quiet]
    dustoptics build mars|earth [--out DIR] [--dust PRESET] [--optical-depth TAU] [--force]
    dustoptics export FILE --out DIR --format FMT[,FMT...] [--force]
    dustoptics info FILE_OR_FOLDER [--full]
    dustoptics plot FILE --kind {phase,polar,map,spectra} [--wavelengths-nm LIST] --out FIG.png|.svg
    dustoptics presets [--show NAME]
    dustoptics materials
    dustoptics fit NAME_OR_FILE [--model MODEL] [--colour C] [--out DIR] [--force]
    dustoptics sweep CONFIG --out STORE|FILE.nc [--scheduler ADDRESS] [--workers N] [--force]
    dustoptics sky mars|earth|compare --out DIR [--force]
    dustoptics engines report [--shipped] [--planet P,...] [--engine E,...] [--cache-dir DIR]
    dustoptics --version

``python -m dustoptics`` (or ``python -m dustoptics.cli``) runs the same command line.

``build`` computes a preset (``dustoptics presets``) or a TOML configuration
file (:mod:`dustoptics.models.config`; copy a preset with ``presets --show NAME``)
and writes it into ``DIR/NAME/`` in each format of :data:`dustoptics.io.FORMATS`
(``--help`` lists them; by default ``NAME.nc`` and the seed CSVs); ``build mars`` and
``build earth`` write CosmoScout VR's whole atmosphere set (molecules,
aerosols, ozone, densities and the settings JSON).  ``export`` turns
a table file into other formats in ``DIR/NAME/``, as do ``fit`` (its JSON and
shader constants) and ``sky`` (``DIR/mars-PRESET/``, ``DIR/earth/``,
``DIR/mars-comparison/``); ``info`` says what a file holds and how it was made (a
summary; ``--full`` for everything); ``plot`` draws it (needs the ``plot`` extra).
What would fail when the files are written (a name no file can carry, an option
out of range, a format's needs, files that exist and differ without ``--force``)
is refused before any work.
``sweep`` computes a configuration over the axes of its ``[sweep]`` table
into a resumable Zarr store (or a ``.nc`` file) on Dask (needs the ``sweep``
extra; :func:`dustoptics.sweep.sweep`).

Exit status: 0 on success, 1 on failure (an output exists without ``--force``,
a damaged input file, an input the physics rejects), 2 on a usage error
(unknown preset, format or option value), 130 on an interrupt (Ctrl-C: one
line, ``dustoptics: interrupted``).  Errors are printed as
``dustoptics: error: <message>`` on stderr, without a traceback.  A closed
output pipe (``dustoptics info f.nc | head``) is not an error.

Each command is a module of this package that parses its options, calls the
library and reports (:mod:`~dustoptics.cli.parser` holds the options they
share, :mod:`~dustoptics.cli.errors` the exit status).  The work is the
library's, for Python users too: :class:`dustoptics.models.build.TableBuilder`
and :func:`dustoptics.io.outputs.prepare_export` (build),
:func:`dustoptics.io.outputs.place_table` (build, export),
:func:`dustoptics.atmosphere.build.build_atmosphere` (build mars|earth),
:func:`dustoptics.io.describe.describe_path` (info),
:class:`dustoptics.sky.job.SkyJob` (sky), :func:`dustoptics.scattering.fit.fit_table`
(fit), :func:`dustoptics.sweep.sweep` (sweep).
"""

from __future__ import annotations

import argparse
import gc
import sys
import warnings
from typing import TextIO

from dustoptics.cli import _interrupt, errors

__all__ = ["main"]

#: Commands whose process (``dustoptics build``, not a program calling :func:`main`) runs
#: without Python's cyclic garbage collector: its collections while numpy, scipy, numba,
#: h5py and xarray are imported cost 0.23-0.37 s of the 2.7 s CPU of a warm build
#: (blue-moons, and ``build mars``), and without them the peak memory grew by 0.5-2 MB of
#: 283-310 MB (``/usr/bin/time -v``).  The process ends with the command.
_WITHOUT_CYCLIC_GC = ("build",)


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 1 failure, 2 usage).

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit status (:mod:`dustoptics.cli.errors`).
    """
    # Here, not at the top: this package is imported first by ``import dustoptics`` (Ctrl-C
    # handling starts before numpy, the package and numba's cache directory are set up).
    from dustoptics import _numba_cache
    from dustoptics.cli.parser import build_parser

    given = sys.argv[1:] if argv is None else argv
    if _interrupt.is_the_command() and given[:1] and given[0] in _WITHOUT_CYCLIC_GC:
        gc.disable()

    def command() -> int:
        try:
            args = build_parser(given).parse_args(given)
        except SystemExit as exc:  # argparse: --help/--version (0) or usage (2)
            return int(exc.code or 0)
        # A first run says so when numba starts compiling (build announces its own kernels).
        stream = None if getattr(args, "quiet", False) else sys.stderr
        with warnings.catch_warnings(), _numba_cache.compile_notice(args.command, stream):
            # A warning the library gives a user reaches them as one line, not as Python's
            # "file:line: Category: message" with the source line under it.
            warnings.showwarning = _show_warning
            status: int = args.run(args)
        return status

    with _interrupt.handling():  # Ctrl-C: one line and 130, wherever it lands
        status = errors.exit_status(command)
    if _interrupt.is_the_command():
        # The process ends with this command: Python's last garbage collection at exit
        # would finalize every object (numba's and LLVM's, xarray's: 0.6 s after a
        # build); frozen, they are left to the operating system.  atexit handlers still
        # run, and every file is closed by now.  Not in a program that calls main().
        gc.freeze()
    return status


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    """``dustoptics: warning: <message>`` on stderr (:func:`warnings.showwarning`'s signature)."""
    print(f"{errors.PROG}: warning: {message}", file=sys.stderr)


def _parser() -> argparse.ArgumentParser:
    """The argument parser (for the documentation's command reference)."""
    from dustoptics.cli.parser import build_parser  # not at the top: as in main

    return build_parser()
