"""A configuration's table, computed with progress, and the options of the formats it goes to.

What ``dustoptics build`` and ``dustoptics export`` do before any file is written:

- :class:`TableBuilder`: computes the table of a preset or a TOML
  configuration (:func:`dustoptics.models.compute.build_table`), reporting
  progress per wavelength and, on the first build of an install, that the Mie
  kernels are compiling;
- :func:`is_config_path`: whether a name is a configuration file or a preset.

The formats' options live with the formats (:class:`dustoptics.io.FormatOptions`,
:func:`dustoptics.io.outputs.prepare_export`).
"""

from __future__ import annotations

import os
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from dustoptics import _numba_cache
from dustoptics.models import files, presets
from dustoptics.models.compute import build_table

if TYPE_CHECKING:
    from dustoptics.models.config import BuildConfig
    from dustoptics.table import Table

__all__ = [
    "COMPILE_ESTIMATE_S",
    "TableBuilder",
    "is_config_path",
]

#: About how long the first build's kernels take to compile on two idle cores: half of
#: the 13 s of CPU time they took in one process on the benchmark's 2-core machine
#: while it was busy (``scripts/benchmark.py --compile``); longer on a busy machine.
#: Not printed: the build names each kernel as it is compiled. [s]
COMPILE_ESTIMATE_S = "5-10"

#: Prefix of the lines :class:`TableBuilder` reports (the program's name).
_PROG = "dustoptics"


def is_config_path(name_or_config: str) -> bool:
    """Whether :meth:`TableBuilder.from_name` reads ``name_or_config`` as a configuration file.

    A name ending in ``.toml``, holding a path separator, or naming an
    existing file is a configuration file; anything else is a preset name.

    Parameters
    ----------
    name_or_config : str

    Returns
    -------
    bool

    Examples
    --------
    >>> is_config_path("hybrid"), is_config_path("my-dust.toml")
    (False, True)
    """
    return (
        name_or_config.endswith(".toml")
        or os.sep in name_or_config
        or Path(name_or_config).is_file()
    )


class TableBuilder:
    """Computes the table of a configuration, reporting progress per wavelength.

    Parameters
    ----------
    config : BuildConfig
        A validated configuration (:func:`dustoptics.models.files.load_config`,
        :func:`dustoptics.models.presets.load_preset`).
    progress : text stream, optional
        Where to report progress (a line per wavelength on a terminal, the
        first and last otherwise); None is silent.
    allow_large : bool, optional
        Go ahead beyond the memory and work budget
        (:func:`dustoptics.scattering.optics.compute_optics`); default False.
    allow_unvalidated : bool, optional
        Go ahead, with a warning, outside the validated domain
        (:mod:`dustoptics.scattering.domain`); default False (refused).
    """

    def __init__(
        self,
        config: BuildConfig,
        *,
        progress: TextIO | None = None,
        allow_large: bool = False,
        allow_unvalidated: bool = False,
    ) -> None:
        self.config = config
        self.progress = progress
        self.allow_large = allow_large
        self.allow_unvalidated = allow_unvalidated
        #: Why the build asks for more than the configuration does, recorded in the provenance.
        self.notes: list[str] = []

    @classmethod
    def from_name(
        cls, name_or_config: str, *, progress: TextIO | None = None, allow_large: bool = False
    ) -> TableBuilder:
        """A builder for a preset name or the path of a TOML configuration file.

        Parameters
        ----------
        name_or_config : str
            A preset (:func:`dustoptics.models.presets.list_presets`) or a
            configuration file (see :func:`is_config_path`).
        progress : text stream, optional
            See :class:`TableBuilder`.
        allow_large : bool, optional
            See :class:`TableBuilder`.

        Returns
        -------
        TableBuilder

        Raises
        ------
        ValueError
            An unknown preset (the message lists the valid ones).
        dustoptics.models.config.ConfigError
            A configuration file that does not follow the schema.
        OSError
            A configuration file that cannot be read.
        """
        if is_config_path(name_or_config):
            cfg = files.load_config(name_or_config)
        else:
            cfg = presets.load_preset(name_or_config)
        return cls(cfg, progress=progress, allow_large=allow_large)

    @property
    def name(self) -> str:
        """The configuration's name (the table's)."""
        return self.config.name

    def ask_for_expansion(self, reason: str) -> None:
        """Compute the expansion coefficients (``optics.expansion = true``) for ``reason``.

        What a format needs that the computation can supply is asked for, not refused: the
        configuration is changed (its inputs, hence the table's input hash, record
        ``expansion``), the change is reported on ``progress`` and noted in the provenance.

        Parameters
        ----------
        reason : str
            Who needs them (``"--format disort"``), for the report and the note.

        Raises
        ------
        ValueError
            The configuration's phase model is not Mie: only Mie computes them.
        """
        if self.config.optics.expansion is not None:
            return
        if self.config.phase.model != "mie":
            raise ValueError(
                f"{reason} needs the phase function's expansion coefficients, which only a Mie "
                f"model has; {self.name!r} has phase.model = {self.config.phase.model!r}"
            )
        self.config = replace(self.config, optics=replace(self.config.optics, expansion=True))
        note = (
            f"{reason} needs the phase function's expansion coefficients: computed "
            "(optics.expansion = true)"
        )
        self.notes.append(note)
        if self.progress is not None:
            print(f"{_PROG}: {note}", file=self.progress)

    def build(self) -> Table:
        """Compute the table (:func:`dustoptics.models.compute.build_table`).

        Returns
        -------
        Table
        """
        start = time.perf_counter()
        progress = self.progress
        tty = progress is not None and progress.isatty()
        compiled = None
        if self.config.phase.uses_mie:
            # The kernels numba's cache lacks, on every core, each reported as it is done.
            groups = ["optics"] + ([] if self.config.optics.expansion is None else ["matrix"])
            compiled = _numba_cache.compile_kernels(groups, progress=progress)

        def report(done: int, total: int) -> None:
            if progress is None:
                return
            if tty or done in (0, total):
                end = "\n" if done == total else ("\r" if tty else "\n")
                elapsed = time.perf_counter() - start
                print(
                    f"{self.name}: {done}/{total} wavelengths, {elapsed:.1f} s",
                    end=end,
                    file=progress,
                )
                progress.flush()

        table = build_table(
            self.config,
            progress=report,
            allow_large=self.allow_large,
            allow_unvalidated=self.allow_unvalidated,
        )
        if self.notes:
            prov = table.provenance
            table = table.replace(provenance=replace(prov, notes=(*prov.notes, *self.notes)))
        if compiled is not None and progress is not None:
            print(
                f"{_PROG}: this first build took {time.perf_counter() - start:.1f} s; later "
                "builds load the compiled kernels from the cache",
                file=progress,
            )
        return table
