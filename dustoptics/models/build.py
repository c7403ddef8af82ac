"""A configuration's table, computed with progress, and the options of the formats it goes to.

What ``dustoptics build`` and ``dustoptics export`` do before any file is written:

- :class:`TableBuilder`: computes the table of a preset or a TOML
  configuration (:func:`dustoptics.models.compute.build_table`), reporting
  progress per wavelength and, on the first build of an install, that the Mie
  kernels are compiling;
- :class:`FormatOptions`: the options of the individual output formats,
  each writer getting its own (:meth:`FormatOptions.for_format`) and each
  file recording those that change its numbers (:meth:`FormatOptions.recorded`);
- :func:`prepare_export`: the table and options for a set of formats: the
  CosmoScout VR density profile and a number density from an optical depth.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

if TYPE_CHECKING:
    from dustoptics.models.config import BuildConfig
    from dustoptics.table import Table

__all__ = [
    "COMPILE_ESTIMATE_S",
    "FormatOptions",
    "TableBuilder",
    "is_config_path",
    "prepare_export",
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
    """

    def __init__(
        self, config: BuildConfig, *, progress: TextIO | None = None, allow_large: bool = False
    ) -> None:
        self.config = config
        self.progress = progress
        self.allow_large = allow_large

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
        from dustoptics.models import files, presets

        if is_config_path(name_or_config):
            cfg = files.load_config(name_or_config)
        else:
            cfg = presets.load_preset(name_or_config)
        return cls(cfg, progress=progress, allow_large=allow_large)

    @property
    def name(self) -> str:
        """The configuration's name (the table's)."""
        return self.config.name

    def build(self) -> Table:
        """Compute the table (:func:`dustoptics.models.compute.build_table`).

        Returns
        -------
        Table
        """
        from dustoptics import _numba_cache
        from dustoptics.models.compute import build_table

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

        table = build_table(self.config, progress=report, allow_large=self.allow_large)
        if compiled is not None and progress is not None:
            print(
                f"{_PROG}: this first build took {time.perf_counter() - start:.1f} s; later "
                "builds load the compiled kernels from the cache",
                file=progress,
            )
        return table


@dataclass(frozen=True)
class FormatOptions:
    """Options of the individual formats (the command line's format options).

    None leaves a writer's default.  Each writer gets the options it takes
    (:meth:`for_format`).

    Attributes
    ----------
    channels_nm : tuple of float, optional
        glsl, hlsl, wgsl, ktx2, exr, npy: the three channels' wavelengths. [nm]
    colour : str, optional
        Same formats: colour channels instead of wavelengths
        (``"cie1931-xyz"``, ``"linear-srgb-astmg173"``).
    resolution_deg : float, optional
        glsl, hlsl, wgsl: angular step of the constant array. [deg]
    sampling : str, optional
        texture, ktx2, exr, npy: ``"theta"`` or ``"cos"``.
    n_angles : int, optional
        texture, ktx2, exr, npy: samples along the angle axis.
    density : numpy.ndarray, optional
        cosmoscout: density relative to the ground at the texel centres (i + 1/2) T / N.
    prefix : str, optional
        glsl, hlsl, wgsl: prefix of every identifier.
    glsl_version : str, optional
        glsl: ``"130"`` or ``"100"``.
    layout : str, optional
        ktx2, exr, npy: ``"rgb"`` or ``"wavelength"``.
    precision : str, optional
        ktx2, exr, npy: ``"float32"`` or ``"float16"``.
    profile : dict, optional
        cosmoscout: the density profile's parameters, recorded in provenance.
    """

    channels_nm: tuple[float, ...] | None = None
    colour: str | None = None
    resolution_deg: float | None = None
    sampling: str | None = None
    n_angles: int | None = None
    density: np.ndarray | None = None
    prefix: str | None = None
    glsl_version: str | None = None
    layout: str | None = None
    precision: str | None = None
    #: The density profile's parameters (cosmoscout), as recorded in provenance.
    profile: dict[str, Any] | None = None

    def recorded(self, name: str) -> dict[str, Any]:
        """The options given for format ``name`` that change the numbers it writes.

        :func:`dustoptics.io.outputs.write_formats` adds them to the table's
        provenance inputs (key ``"export"``), so that the input hash a file
        records changes with them.  Writers' defaults are stated in the files
        themselves and not repeated.

        Parameters
        ----------
        name : str
            A format name (:data:`dustoptics.io.FORMATS`).

        Returns
        -------
        dict
            JSON-serializable (tuples as lists).

        Examples
        --------
        >>> FormatOptions(n_angles=181).recorded("texture")
        {'n_angles': 181}
        """
        if name == "cosmoscout":
            return dict(self.profile or {})
        return {
            key: list(value) if isinstance(value, tuple) else value
            for key, value in self.for_format(name).items()
            if value is not None
        }

    def for_format(self, name: str) -> dict[str, Any]:
        """Keyword options for the writer of format ``name``.

        Parameters
        ----------
        name : str
            A format name (:data:`dustoptics.io.FORMATS`).

        Returns
        -------
        dict
            The keywords that writer takes; empty for formats without options.
        """
        if name in ("glsl", "hlsl", "wgsl"):
            out: dict[str, Any] = {"channels_nm": self.channels_nm, "colour": self.colour}
            if self.resolution_deg is not None:
                out["resolution_deg"] = self.resolution_deg
            if self.prefix is not None:
                # Every identifier prefixed, the lookup too (MIE keeps the seed's names).
                out["prefix"] = self.prefix
                if self.prefix != "MIE":
                    out["function_name"] = f"{self.prefix}_MiePhaseFunction"
            if name == "glsl" and self.glsl_version is not None:
                out["version"] = self.glsl_version
            return out
        if name in ("ktx2", "exr", "npy"):
            out = {"channels_nm": self.channels_nm, "colour": self.colour}
            for key in ("layout", "sampling", "n_angles", "precision"):
                if getattr(self, key) is not None:
                    out[key] = getattr(self, key)
            return out
        if name == "texture":
            out = {}
            if self.sampling is not None:
                out["sampling"] = self.sampling
            if self.n_angles is not None:
                out["n_angles"] = self.n_angles
            return out
        if name == "cosmoscout":
            return {"density": self.density}
        return {}


def prepare_export(
    table: Table,
    formats: Sequence[str],
    *,
    options: FormatOptions | None = None,
    optical_depth: float | None = None,
    reference_wavelength_nm: float = 550.0,
    scale_height_m: float = 10_000.0,
    top_altitude_m: float = 120_000.0,
    n_altitudes: int = 1024,
) -> tuple[Table, FormatOptions]:
    """The table and format options for writing ``table`` in ``formats``.

    With ``"cosmoscout"`` among the formats, the constituent's density is an
    exponential profile (:class:`~dustoptics.atmosphere.column.ExponentialProfile`)
    sampled up to ``top_altitude_m``; its parameters are recorded in the
    CosmoScout files' provenance; an ``optical_depth`` sets the table's number
    density (:func:`~dustoptics.atmosphere.sets.with_optical_depth`, recorded in
    its provenance).  Without it, the profile parameters and optical depth are
    not used.

    Parameters
    ----------
    table : Table
    formats : sequence of str
        Names of :data:`dustoptics.io.FORMATS`.
    options : FormatOptions, optional
        The other formats' options (default none).
    optical_depth : float, optional
        cosmoscout: vertical optical depth at ``reference_wavelength_nm`` that
        sets the number density, > 0. [-]
    reference_wavelength_nm : float, optional
        Wavelength of ``optical_depth``, within the table's.  Default 550. [nm]
    scale_height_m : float, optional
        cosmoscout: the profile's scale height.  Default 10000 (the seeds'
        Mars dust). [m]
    top_altitude_m : float, optional
        cosmoscout: atmosphere top above the surface.  Default 120000 (Mars,
        3510 - 3390 km). [m]
    n_altitudes : int, optional
        cosmoscout: density samples.  Default 1024.

    Returns
    -------
    table : Table
        The table, with its number density set when ``optical_depth`` is given.
    options : FormatOptions
        ``options`` with the density profile for cosmoscout.

    Raises
    ------
    ValueError
        cosmoscout without a number density (neither the table's nor an
        ``optical_depth``), or profile parameters out of range.
    """
    options = FormatOptions() if options is None else options
    if "cosmoscout" not in formats:
        return table, options
    from dustoptics.atmosphere.column import ExponentialProfile, sample_profile

    profile = ExponentialProfile(scale_height_m=scale_height_m)
    if optical_depth is not None:
        from dustoptics.atmosphere.sets import with_optical_depth

        table = with_optical_depth(
            table,
            optical_depth=optical_depth,
            reference_wavelength_nm=reference_wavelength_nm,
            profile=profile,
            top_altitude_m=top_altitude_m,
        )
    if table.cross_sections is None or table.cross_sections.number_density_per_m3 is None:
        raise ValueError(
            "the cosmoscout format needs a number density for beta [m^-1]: give optical_depth "
            "or a table with number_density_per_m3"
        )
    # At the texel centres (i + 1/2) T / N, where CosmoScout VR's preprocessor reads the values
    # (dustoptics.io.csv.cosmoscout), as the atmosphere sets do.  The profile's own values (the
    # first below 1): the table keeps its ground number density for every format, and beta
    # times the written density is the coefficient at every sampled altitude.
    half_texel = 0.5 * top_altitude_m / n_altitudes
    samples = sample_profile(
        profile,
        bottom_altitude_m=half_texel,
        top_altitude_m=top_altitude_m - half_texel,
        n_altitudes=n_altitudes,
    )
    density = np.asarray(samples.relative_density) * samples.peak
    recorded = {
        "density_profile": "exponential",
        "scale_height_m": scale_height_m,
        "top_altitude_m": top_altitude_m,
        "n_altitudes": n_altitudes,
        "density_sampling": "texel centres (i + 1/2) top_altitude_m / n_altitudes",
    }
    return table, replace(options, density=density, profile=recorded)
