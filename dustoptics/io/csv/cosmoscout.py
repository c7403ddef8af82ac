"""CosmoScout VR's per-constituent CSV set (``csp-atmospheres``, Bruneton model).

CosmoScout VR's Bruneton atmosphere loads each constituent of an atmosphere
(molecules, aerosols, ozone, ...) from CSV files named after it (layout and
reader rules in the project brief, section 7):

``<name>_phase.csv``
    Header ``lambda`` then the ``n_theta`` angles [deg]; one row per
    wavelength: lambda [m], then the phase function [sr^-1], normalized to 1
    over the sphere, at the texel centres ``(j + 1/2) 180 / n_theta`` deg
    (below).
``<name>_scattering.csv``
    Header ``lambda,beta_sca``; lambda [m] and the scattering coefficient
    [m^-1] at the peak number density.
``<name>_absorption.csv``
    Header ``lambda,beta_abs``; the absorption coefficient [m^-1].
``<name>_density.csv``
    A header line, then one relative density [-] per line, value ``i`` of
    ``N`` at the altitude ``(i + 1/2) T / N`` above the ground (``T`` the
    thickness of the atmosphere; below); the largest is exactly 1, so beta
    times this profile is the coefficient at each altitude.

CosmoScout's reader skips the first line of each file, splits lines on commas,
reads lambda as a 32-bit float times 1e9 (nm), and demands exactly the same
wavelengths in every file of a set.  :func:`write_cosmoscout_set` therefore
writes every wavelength with the same text in every file (the table's
wavelength [nm] shifted exactly to metres in decimal), and
:func:`check_cosmoscout_set` applies these rules to a written directory.

A constituent that does not scatter (``csca`` zero at every wavelength, e.g.
ozone, which only absorbs) gets no phase and no scattering file: CosmoScout
configures such a constituent (its ozone) with only absorption and density
files, and a phase function of a non-scattering medium is undefined.

Where the preprocessor reads the values (CosmoScout VR at commit
e59005a3bbea2426c841f30da6cb35a4d313455e, whose ``bruneton-preprocessor``
files are those of release v1.10.0; ``Preprocessor.cpp`` and
``csp-atmosphere-preprocessing-functions.glsl``): the N values of a density
file fill a linearly filtered texture spanning the atmosphere, read at
``u = altitude / T``, and the n columns of a phase file fill one read at
``u = acos(nu) / pi``; with no half-texel correction, value ``i`` stands at
the centre of texel ``i``.  Sampling the profile at ``i T / (N - 1)`` and the
phase function at ``j 180 / (n - 1)`` (the layout of CosmoScout's own
scattering-table generator) shifts both by up to half a texel: the column of
an exponential layer of scale height ``H`` comes out ``(T/2 - H) / (N H)`` too
large (0.4 % for the Martian dust at N = 1024), and the dust's forward peak is
stretched so that its integral over the sphere is 1.088 at 561 nm with 181
columns (1.008 with 1801).  This module therefore writes both at the texel
centres: density value ``i`` at ``(i + 1/2) T / N`` (the profile sampled there by
:meth:`~dustoptics.atmosphere.sets.Atmosphere.cosmoscout_constituents`),
phase column ``j`` at ``(j + 1/2) 180 / n`` deg, the angles stated in the
header (the preprocessor does not parse it).  Molecules and aerosols get the
same angles, as the preprocessor requires.  :func:`read_cosmoscout_constituent`
returns the header's angles, and :func:`check_cosmoscout_set` accepts both
layouts (texel centres, or 0 to 180 deg with both ends).

The whole set (:func:`write_atmosphere`) comes with the preprocessor's
settings (:func:`settings_json`): every sampling option it reads, chosen for
the set by :mod:`dustoptics.io.engines.cosmoscout_preprocessor`, and file
names that resolve wherever it runs (absolute paths; it opens them relative
to its working directory, which must be CosmoScout's root).
"""

from __future__ import annotations

import decimal
import json
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics._validation import as_float_array
from dustoptics.atmosphere.column import ExponentialProfile, sample_profile
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.io._atomic import FormatError, check_targets, file_set, write_files
from dustoptics.io._text import floats, number, parse, read_checked, read_rows
from dustoptics.io.engines.cosmoscout_preprocessor import CosmoScoutSampling, cosmoscout_sampling
from dustoptics.io.registry import Format, option, register
from dustoptics.scattering.tabulated_phase import sphere_integral
from dustoptics.table import Table

__all__ = [
    "COSMOSCOUT_KINDS",
    "PHASE_COLUMN_COUNTS",
    "SPICE_RADII_M",
    "CosmoScoutConstituent",
    "check_cosmoscout_set",
    "cosmoscout_phase_angles",
    "cosmoscout_phase_error",
    "cosmoscout_plugin_entry",
    "cosmoscout_wavelength_text",
    "read_cosmoscout_constituent",
    "settings_json",
    "write_atmosphere",
    "write_cosmoscout_constituent",
    "write_cosmoscout_files",
    "write_cosmoscout_set",
]

#: File kinds of a constituent, in the order they are written.
COSMOSCOUT_KINDS = ("phase", "scattering", "absorption", "density")

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
_FILE = re.compile(r"(?P<name>.+)_(?P<kind>phase|scattering|absorption|density)\.csv")
_DENSITY_HEADER = "density"


@dataclass(frozen=True)
class CosmoScoutConstituent:
    """One constituent read back from a CosmoScout VR CSV set.

    Attributes
    ----------
    name : str
        Constituent name (the file-name prefix).
    wavelength_m : numpy.ndarray, shape (n_wavelength,)
        Wavelengths as written (parsed as float64). [m]
    theta_deg : numpy.ndarray or None, shape (n_theta,)
        Angles of the phase-function columns, or None for a constituent
        without a phase file (non-scattering). [deg]
    phase : numpy.ndarray or None, shape (n_wavelength, n_theta)
        Phase function, normalized to 1 over the sphere. [sr^-1]
    beta_sca_per_m : numpy.ndarray or None, shape (n_wavelength,)
        Scattering coefficient at the peak density, or None (no scattering
        file). [m^-1]
    beta_abs_per_m : numpy.ndarray, shape (n_wavelength,)
        Absorption coefficient at the peak density. [m^-1]
    density : numpy.ndarray, shape (n_altitude,)
        Relative density, value ``i`` of ``N`` at ``(i + 1/2) T / N`` above the
        ground of an atmosphere of thickness ``T`` (where the preprocessor
        reads it), maximum 1. [-]
    """

    name: str
    wavelength_m: np.ndarray
    theta_deg: np.ndarray | None
    phase: np.ndarray | None
    beta_sca_per_m: np.ndarray | None
    beta_abs_per_m: np.ndarray
    density: np.ndarray


# ------------------------------------------------------------------ writing


def cosmoscout_wavelength_text(wavelength_nm: float) -> str:
    """The text of a wavelength [nm] in metres, as written in every file.

    The shortest round-trip decimal of the wavelength in nm, shifted by 9
    decimal places (exact), so the same wavelength is always the same text.

    >>> cosmoscout_wavelength_text(440.0), cosmoscout_wavelength_text(552.5)
    ('4.4e-7', '5.525e-7')
    """
    value = decimal.Decimal(repr(float(wavelength_nm))).scaleb(-9).normalize()
    return format(value, "e")


def cosmoscout_phase_angles(n_theta: int) -> np.ndarray:
    """Angles of the phase columns: the texel centres ``(j + 1/2) 180 / n_theta``. [deg]

    Where the preprocessor's linearly filtered phase texture, read at
    ``u = acos(nu) / pi``, puts column ``j`` (module docstring).

    >>> cosmoscout_phase_angles(4).tolist()
    [22.5, 67.5, 112.5, 157.5]
    """
    n = _check_n_theta(n_theta)
    return (np.arange(n) + 0.5) * (180.0 / n)


def _check_name(name: Any) -> str:
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ValueError(
            f"name must be a non-empty file-name prefix of letters, digits, '.', '_' and '-' "
            f"(starting with a letter or digit); got {name!r}"
        )
    return name


def _check_n_theta(n_theta: Any) -> int:
    if isinstance(n_theta, bool) or not isinstance(n_theta, (int, np.integer)) or n_theta < 2:
        raise ValueError(
            f"n_theta must be an integer >= 2 (phase columns over 0 to 180 deg); got {n_theta!r}"
        )
    return int(n_theta)


def _check_density(name: str, density: Any) -> np.ndarray:
    what = f"density of constituent {name!r}"
    try:
        arr = as_float_array(what, density, ndim=1)
    except ValueError as exc:
        raise ValueError(f"{exc} (a 1-D profile of finite relative densities)") from None
    if arr.size < 2:
        raise ValueError(f"{what} needs at least 2 altitudes (ground and top); got {arr.size}")
    if np.any(arr < 0):
        raise ValueError(f"{what} must be >= 0; got minimum {float(arr.min())!r}")
    if float(arr.max()) != 1.0:
        raise ValueError(
            f"{what} must have maximum exactly 1 (relative to the peak density at which beta is "
            f"given); got maximum {float(arr.max())!r} (divide the profile by its maximum)"
        )
    return arr


def _lines(rows: list[str]) -> bytes:
    return ("\n".join(rows) + "\n").encode("ascii")


def _constituent_files(
    table: Table, directory: Path, *, name: str, density: Any, n_theta: int
) -> dict[Path, bytes]:
    if not isinstance(table, Table):
        raise TypeError(
            f"constituent {name!r}: table must be a dustoptics.table.Table; got {type(table).__name__}"
        )
    if table.cross_sections is None:
        raise ValueError(
            f"constituent {name!r}: table {table.name!r} holds a phase function only; CosmoScout "
            "needs scattering and absorption coefficients (a table with cross-sections)"
        )
    if table.cross_sections.number_density_per_m3 is None:
        raise ValueError(
            f"constituent {name!r}: table {table.name!r} has no number_density_per_m3; give the "
            "peak number density [m^-3] (Table.replace(cross_sections={'number_density_per_m3': ...})) so that "
            "beta = N C can be written in m^-1"
        )
    profile = _check_density(name, density)
    lam = [cosmoscout_wavelength_text(w) for w in floats("wavelength_nm", table.wavelength_nm)]
    files: dict[Path, bytes] = {}
    scatters = bool(np.any(table.cross_sections.csca_um2 > 0))
    if scatters:
        theta = cosmoscout_phase_angles(n_theta)
        phase = table.phase_at(theta)
        header = "lambda," + ",".join(number(t) for t in floats("theta_deg", theta))
        rows = [header]
        rows += [
            lw + "," + ",".join(number(v) for v in row) for lw, row in zip(lam, phase.tolist())
        ]
        files[directory / f"{name}_phase.csv"] = _lines(rows)
        beta_sca = floats("beta_sca_per_m", table.beta_sca_per_m)
        files[directory / f"{name}_scattering.csv"] = _lines(
            ["lambda,beta_sca"] + [f"{lw},{number(b)}" for lw, b in zip(lam, beta_sca)]
        )
    beta_abs = floats("beta_abs_per_m", table.beta_abs_per_m)
    files[directory / f"{name}_absorption.csv"] = _lines(
        ["lambda,beta_abs"] + [f"{lw},{number(b)}" for lw, b in zip(lam, beta_abs)]
    )
    files[directory / f"{name}_density.csv"] = _lines(
        [_DENSITY_HEADER] + [number(d) for d in profile.tolist()]
    )
    return files


def write_cosmoscout_constituent(
    table: Table,
    directory: str | os.PathLike[str],
    *,
    name: str,
    density: Any,
    n_theta: int = 181,
    overwrite: bool = False,
) -> list[Path]:
    """Write one constituent's CosmoScout VR CSV files.

    Parameters
    ----------
    table : Table
        The constituent's table, with cross-sections and
        ``number_density_per_m3`` (the peak number density [m^-3] at which
        the coefficients beta = N C are written).
    directory : path-like
        Output directory; created if missing.
    name : str
        Constituent name, the prefix of the file names (letters, digits,
        ``.``, ``_``, ``-``).
    density : array_like, shape (n_altitude,)
        Relative density, value ``i`` of ``N`` at the altitude
        ``(i + 1/2) T / N`` above the ground of an atmosphere of thickness
        ``T``, where CosmoScout's preprocessor reads it (module docstring;
        :attr:`~dustoptics.atmosphere.sets.Atmosphere.density_altitudes_m`):
        finite, >= 0, maximum exactly 1. [-]
    n_theta : int, optional
        Number of phase-function columns, at the texel centres
        ``(j + 1/2) 180 / n_theta`` deg (:func:`cosmoscout_phase_angles`).
        Default 181.
    overwrite : bool, optional
        Replace existing files.  Default False.

    Returns
    -------
    list of pathlib.Path
        ``<name>_phase.csv``, ``<name>_scattering.csv`` (both only if the
        constituent scatters), ``<name>_absorption.csv``,
        ``<name>_density.csv``.

    Raises
    ------
    ValueError
        Bad ``name``, ``n_theta`` or ``density``; a table without
        cross-sections or without a number density.
    FileExistsError
        A file exists and ``overwrite`` is False (nothing is written).

    Notes
    -----
    The phase function is resampled from the table's angle grid with
    :meth:`~dustoptics.table.Table.phase_at` (linear in angle, as a renderer
    interpolates it) at the texel centres; the values are not renormalized.
    As the preprocessor interpolates them (linear between the centres,
    constant within half a column of 0 and 180 deg), the Martian dust's phase
    function integrates over the sphere to within 1.1 % of 1 with 181
    columns, 0.27 % with 361 and 0.07 % with 721 (at 360 nm, the narrowest
    forward peak of CosmoScout's wavelengths; :func:`cosmoscout_phase_error`).
    """
    files = _constituent_files(
        table,
        Path(directory),
        name=_check_name(name),
        density=density,
        n_theta=_check_n_theta(n_theta),
    )
    return write_files(files, overwrite=overwrite)


def write_cosmoscout_set(
    directory: str | os.PathLike[str],
    constituents: Mapping[str, tuple[Table, Any]],
    *,
    n_theta: int = 181,
    overwrite: bool = False,
) -> list[Path]:
    """Write the CSV files of several constituents of one atmosphere, atomically.

    Parameters
    ----------
    directory : path-like
        Output directory; created if missing.
    constituents : mapping of str to (Table, array_like)
        Constituent name -> (its table, its relative density profile), as for
        :func:`write_cosmoscout_constituent`.  All tables must have identical
        wavelengths (CosmoScout demands the same wavelengths in every file).
    n_theta : int, optional
        Number of phase-function columns (:func:`cosmoscout_phase_angles`).
        Default 181.
    overwrite : bool, optional
        Replace existing files.  Default False.

    Returns
    -------
    list of pathlib.Path
        Every file written, constituent by constituent.

    Raises
    ------
    ValueError
        No constituents, wavelengths that differ between tables, or a bad
        constituent (see :func:`write_cosmoscout_constituent`).
    FileExistsError
        A file exists and ``overwrite`` is False (nothing is written).

    Notes
    -----
    All files are prepared, then staged, then renamed into place: a failure
    leaves none of them behind.
    """
    if not isinstance(constituents, Mapping) or not constituents:
        raise ValueError("constituents must be a non-empty mapping name -> (Table, density)")
    n = _check_n_theta(n_theta)
    root = Path(directory)
    files: dict[Path, bytes] = {}
    reference: tuple[str, np.ndarray] | None = None
    for name, entry in constituents.items():
        _check_name(name)
        try:
            table, density = entry
        except (TypeError, ValueError):
            raise ValueError(
                f"constituent {name!r} must be a (Table, density) pair; got {entry!r}"
            ) from None
        if isinstance(table, Table):
            if reference is None:
                reference = (name, table.wavelength_nm)
            elif not np.array_equal(table.wavelength_nm, reference[1]):
                raise ValueError(
                    f"constituent {name!r} has wavelengths {table.wavelength_nm.tolist()} nm; "
                    f"constituent {reference[0]!r} has {reference[1].tolist()} nm: all tables of a "
                    "CosmoScout set must have identical wavelengths"
                )
        files.update(_constituent_files(table, root, name=name, density=density, n_theta=n))
    return write_files(files, overwrite=overwrite)


def write_cosmoscout_files(
    table: Table,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    density: Any = None,
    name: str | None = None,
    n_theta: int = 181,
) -> list[Path]:
    """The ``"cosmoscout"`` entry of :data:`dustoptics.io.FORMATS`: one constituent.

    As :func:`write_cosmoscout_constituent`, with ``name`` defaulting to the
    table's name; ``density`` (the profile relative to the table's number
    density [-], at the texel centres) is required.  Its largest value ``m``
    need not be 1 (an exponential sampled at the texel centres starts below
    it): the files then hold ``density / m`` and the coefficients at ``m``
    times the number density, the same ``beta`` times density everywhere.
    """
    if density is None:
        raise ValueError(
            "the cosmoscout format needs density=, the constituent's relative density at evenly "
            "spaced altitudes"
        )
    density = np.asarray(density, dtype=float)
    peak = float(np.max(density)) if density.size else 0.0
    if (
        density.ndim == 1
        and 0.0 < peak < 1.0
        and (
            table.cross_sections is not None
            and table.cross_sections.number_density_per_m3 is not None
        )
    ):
        table = table.replace(
            cross_sections={
                "number_density_per_m3": table.cross_sections.number_density_per_m3 * peak
            }
        )
        density = density / peak
    return write_cosmoscout_constituent(
        table, out_dir, name=table.name if name is None else name, density=density,
        n_theta=n_theta, overwrite=overwrite,
    )  # fmt: skip


@dataclass(frozen=True)
class ProfileOptions:
    """The cosmoscout format's density profile: exponential, sampled at the texel centres.

    Attributes
    ----------
    scale_height_m : float
        The profile's scale height.  Default 10000 (the seeds' Mars dust). [m]
    top_altitude_m : float
        Atmosphere top above the surface.  Default 120000 (Mars, 3510 - 3390 km). [m]
    n_altitudes : int
        Density samples.  Default 1024.
    """

    scale_height_m: float = option(
        help="exponential density profile's scale height [m] (cosmoscout: default 10000, the "
        "seeds' Mars dust; disort, libradtran, libradtran-nc: default none, one uniform layer)",
        default=10_000.0,
        type="positive_float",
        metavar="H",
    )
    top_altitude_m: float = option(
        help="atmosphere top above the surface [m] (cosmoscout: default 120000, Mars 3510 - 3390 "
        "km; disort, libradtran, libradtran-nc: default 1000 uniform, 120000 with "
        "--scale-height-m)",
        default=120_000.0,
        type="positive_float",
        metavar="Z",
    )
    n_altitudes: int = option(
        help="density samples (default 1024)", default=1024, type="positive_int", metavar="N"
    )

    @property
    def profile(self) -> ExponentialProfile:
        """The exponential profile."""
        return ExponentialProfile(scale_height_m=self.scale_height_m)

    def keywords(self) -> dict[str, Any]:
        """``density``: the profile at the texel centres (i + 1/2) T / N, relative to the ground.

        Where CosmoScout VR's preprocessor reads the values, as the atmosphere sets do.  The
        profile's own values (the first below 1): the table keeps its ground number density,
        and beta times the written density is the coefficient at every sampled altitude.
        """
        half_texel = 0.5 * self.top_altitude_m / self.n_altitudes
        samples = sample_profile(
            self.profile,
            bottom_altitude_m=half_texel,
            top_altitude_m=self.top_altitude_m - half_texel,
            n_altitudes=self.n_altitudes,
        )
        return {"density": np.asarray(samples.relative_density) * samples.peak}

    def recorded(self) -> dict[str, Any]:
        """The profile's parameters, recorded in the files' provenance."""
        return {
            "density_profile": "exponential",
            "scale_height_m": self.scale_height_m,
            "top_altitude_m": self.top_altitude_m,
            "n_altitudes": self.n_altitudes,
            "density_sampling": "texel centres (i + 1/2) top_altitude_m / n_altitudes",
        }

    def check(self, wavelength_nm: Any) -> None:
        """Refuse profile parameters out of range before the table is computed."""
        sample_profile(
            self.profile, top_altitude_m=self.top_altitude_m, n_altitudes=self.n_altitudes
        )


RECORD = register(
    Format(
        name="cosmoscout",
        summary="CosmoScout VR's NAME_phase.csv, _scattering, ... (needs N0)",
        write=write_cosmoscout_files,
        suffixes=(".csv",),
        options=ProfileOptions,
        needs=frozenset({"cross_sections", "number_density"}),
        plain_name=True,
    )
)


# ------------------------------------------------------------------ reading


def _read_numbers(
    path: Path, header: list[str] | None, width: int | None
) -> tuple[list[str], np.ndarray]:
    """Header cells and the numeric rows of one file (skipping the header line)."""
    rows = read_rows(path)
    head = [cell.strip() for cell in rows[0]]
    if header is not None and head != header:
        raise FormatError(f"{path}: header must be {','.join(header)!r}; got {','.join(head)!r}")
    if len(rows) < 2:
        raise FormatError(f"{path}: no data rows after the header")
    ncol = width if width is not None else len(head)
    out = np.empty((len(rows) - 1, ncol))
    for i, row in enumerate(rows[1:]):
        if len(row) != ncol:
            raise FormatError(f"{path}: line {i + 2} has {len(row)} cells; expected {ncol}")
        for j, cell in enumerate(row):
            label = head[j] if j < len(head) else str(j + 1)
            out[i, j] = parse(path, i + 2, f"{j + 1} ({label})", cell)
    return head, out


def _wavelengths(path: Path, values: np.ndarray) -> np.ndarray:
    if np.any(values <= 0):
        raise FormatError(f"{path}: lambda [m] must be > 0; got {values.tolist()}")
    if values.size > 1 and not np.all(np.diff(values) > 0):
        raise FormatError(f"{path}: lambda [m] must be strictly increasing; got {values.tolist()}")
    return values


def _nonnegative(path: Path, what: str, values: np.ndarray) -> np.ndarray:
    if np.any(values < 0):
        raise FormatError(f"{path}: {what} must be >= 0; got minimum {float(values.min())!r}")
    return values


def read_cosmoscout_constituent(
    directory: str | os.PathLike[str], name: str
) -> CosmoScoutConstituent:
    """Read one constituent's files written by :func:`write_cosmoscout_constituent`.

    Parameters
    ----------
    directory : path-like
        Directory of the set.
    name : str
        Constituent name (file-name prefix).

    Returns
    -------
    CosmoScoutConstituent
        ``phase``, ``theta_deg`` and ``beta_sca_per_m`` are None when the
        constituent has no phase and scattering files (it does not scatter).

    Raises
    ------
    FileNotFoundError
        The absorption or density file is missing, or only one of the phase
        and scattering files exists.
    FormatError
        A malformed file (header, ragged or non-numeric rows, negative
        values, a density whose maximum is not 1) or wavelengths that differ
        between the files; the message names the file.
    """
    root = Path(directory)
    _check_name(name)
    paths = {kind: root / f"{name}_{kind}.csv" for kind in COSMOSCOUT_KINDS}
    for kind in ("absorption", "density"):
        if not paths[kind].is_file():
            raise FileNotFoundError(f"{paths[kind]}: no such file")
    if paths["phase"].is_file() != paths["scattering"].is_file():
        present, absent = (
            ("phase", "scattering") if paths["phase"].is_file() else ("scattering", "phase")
        )
        raise FileNotFoundError(f"{paths[absent]}: no such file (but {paths[present].name} exists)")

    _, absorption = _read_numbers(paths["absorption"], ["lambda", "beta_abs"], None)
    wavelength = _wavelengths(paths["absorption"], absorption[:, 0])
    beta_abs = _nonnegative(paths["absorption"], "beta_abs [m^-1]", absorption[:, 1])
    _, density_rows = _read_numbers(paths["density"], None, 1)
    density = _nonnegative(paths["density"], "the relative density", density_rows[:, 0])
    if density.max() != 1.0:
        raise FormatError(
            f"{paths['density']}: the relative density must have maximum 1; got {density.max()!r}"
        )

    def same_wavelengths(path: Path, values: np.ndarray) -> None:
        if not np.array_equal(values, wavelength):
            raise FormatError(
                f"{path}: lambda column {values.tolist()} differs from {paths['absorption'].name}'s "
                f"{wavelength.tolist()}"
            )

    theta = phase = beta_sca = None
    if paths["phase"].is_file():
        head, data = _read_numbers(paths["phase"], None, None)
        if len(head) < 3 or head[0] != "lambda":
            raise FormatError(
                f"{paths['phase']}: header must be 'lambda' then at least 2 angles [deg]; got {','.join(head)!r}"
            )
        theta = np.array(
            [parse(paths["phase"], 1, f"{j} (header)", c) for j, c in enumerate(head[1:], 2)]
        )
        centres = (np.arange(theta.size) + 0.5) * (180.0 / theta.size)
        ends = np.linspace(0.0, 180.0, theta.size)
        if not (
            np.allclose(theta, centres, rtol=0, atol=1e-9)
            or np.allclose(theta, ends, rtol=0, atol=1e-9)
        ):
            raise FormatError(
                f"{paths['phase']}: header angles must be the {theta.size} texel centres "
                f"(j + 1/2) 180 / {theta.size} deg or {theta.size} evenly spaced values from 0 to "
                f"180 deg; got {theta.tolist()}"
            )
        same_wavelengths(paths["phase"], data[:, 0])
        phase = _nonnegative(paths["phase"], "the phase function [sr^-1]", data[:, 1:])
        _, scattering = _read_numbers(paths["scattering"], ["lambda", "beta_sca"], None)
        same_wavelengths(paths["scattering"], scattering[:, 0])
        beta_sca = _nonnegative(paths["scattering"], "beta_sca [m^-1]", scattering[:, 1])
    return CosmoScoutConstituent(
        name=name,
        wavelength_m=wavelength,
        theta_deg=theta,
        phase=phase,
        beta_sca_per_m=beta_sca,
        beta_abs_per_m=beta_abs,
        density=density,
    )


def _reader_wavelengths_nm(path: Path) -> list[float]:
    """CosmoScout's reading of a file's first column: skip a line, float32(lambda) * 1e9."""
    out = []
    try:
        text = read_checked(path).decode("ascii")
    except UnicodeDecodeError as exc:
        raise FormatError(
            f"{path}: not an ASCII CSV file ({exc.reason} at byte {exc.start})"
        ) from None
    for i, line in enumerate(text.splitlines()[1:], start=2):
        cell = line.split(",")[0]
        try:
            lam32 = np.float32(cell)
        except ValueError:
            raise FormatError(f"{path}: line {i}: lambda {cell!r} is not a number") from None
        out.append(float(lam32) * 1e9)
    return out


def check_cosmoscout_set(directory: str | os.PathLike[str]) -> list[str]:
    """Apply CosmoScout VR's reader rules to every constituent in a directory.

    The rules (project brief, section 7): the first line of every file is a
    header and is skipped; lines are split on commas; every data line of a
    phase file has 1 + n_theta cells (lambda, then one value per header
    angle; the angles are the texel centres ``(j + 1/2) 180 / n_theta`` deg,
    or, as other writers lay them out, evenly spaced from 0 to 180 deg), of a
    scattering or
    absorption file 2 cells, of a density file 1 cell; lambda, read as a
    32-bit float times 1e9, gives exactly the same wavelengths in every file
    of the set (all constituents); each constituent has an absorption and a
    density file, and a phase and a scattering file together or neither.
    Each constituent is also read with :func:`read_cosmoscout_constituent`
    (finite, nonnegative values, density maximum 1).

    Parameters
    ----------
    directory : path-like
        Directory holding the set.

    Returns
    -------
    list of str
        The constituent names, sorted.

    Raises
    ------
    FormatError
        On the first violation; the message names the file and the rule.
    FileNotFoundError
        The directory does not exist.
    """
    root = Path(directory)
    if not root.is_dir():
        raise FileNotFoundError(f"{root}: no such directory")
    kinds: dict[str, set[str]] = {}
    for path in sorted(root.iterdir()):
        match = _FILE.fullmatch(path.name)
        if match and path.is_file():
            kinds.setdefault(match["name"], set()).add(match["kind"])
    if not kinds:
        raise FormatError(
            f"{root}: no CosmoScout files (<name>_phase.csv, _scattering.csv, ...) found"
        )
    reference: tuple[Path, list[float]] | None = None
    for name, present in sorted(kinds.items()):
        for kind in ("absorption", "density"):
            if kind not in present:
                raise FormatError(
                    f"{root / f'{name}_{kind}.csv'}: missing (every constituent needs one)"
                )
        if ("phase" in present) != ("scattering" in present):
            raise FormatError(
                f"{root}: constituent {name!r} has only one of {name}_phase.csv and "
                f"{name}_scattering.csv; a scattering constituent needs both"
            )
        try:
            constituent = read_cosmoscout_constituent(root, name)
        except FileNotFoundError as exc:  # pragma: no cover - checked above
            raise FormatError(str(exc)) from None
        n = constituent.wavelength_m.size
        for kind in sorted(present - {"density"}):
            path = root / f"{name}_{kind}.csv"
            lam_nm = _reader_wavelengths_nm(path)
            if len(lam_nm) != n:
                raise FormatError(
                    f"{path}: {len(lam_nm)} wavelength rows; {name}_absorption.csv has {n}"
                )
            if reference is None:
                reference = (path, lam_nm)
            elif lam_nm != reference[1]:
                raise FormatError(
                    f"{path}: wavelengths read as float32(lambda) * 1e9 = {lam_nm} nm differ from "
                    f"{reference[0].name}'s {reference[1]} nm (CosmoScout demands the same in every file)"
                )
    return sorted(kinds)


# ---------------------------------------------------------------- whole atmospheres


def settings_json(
    atmosphere: Atmosphere,
    *,
    directory: str | os.PathLike[str] = ".",
    path_prefix: str | None = None,
    sampling: CosmoScoutSampling | None = None,
) -> str:
    """CosmoScout VR's Bruneton-preprocessor input for the atmosphere.

    Parameters
    ----------
    atmosphere : Atmosphere
        The atmosphere.
    directory : path-like, default "."
        Where the set's CSV files are: the file names are their absolute paths
        (this directory resolved against the current working directory), which
        the preprocessor opens from wherever it runs.
    path_prefix : str, optional
        Instead, prepend this text to the bare file names, verbatim.  The
        preprocessor opens the names relative to its working directory, which
        must be CosmoScout VR's repository root (it loads its shaders from
        there), so a relative prefix is a path from that root (e.g.
        ``"plugins/csp-atmospheres/data/mars/"``).
    sampling : CosmoScoutSampling, optional
        The sampling options
        (:func:`~dustoptics.io.engines.cosmoscout_preprocessor.cosmoscout_sampling`,
        which also takes options of your own and refuses those the set cannot
        live with); default chosen for the set at a tolerance of 0.5 %.

    Returns
    -------
    str
        JSON text (2-space indent, fixed key order, trailing newline):
        ``sunDistance`` [m], ``minAltitude`` and ``maxAltitude`` (the planet
        and atmosphere radii [m], as CosmoScout names them), ``ior``
        (``n - 1``), ``molecules``, ``aerosols`` (``phase``, ``betaSca``,
        ``betaAbs``, ``density`` files), ``ozone`` (``betaAbs``, ``density``)
        when present, then every sampling option the preprocessor reads
        (``refraction``, ``groundAlbedo``, ``multiScatteringOrder``, the step
        sizes [m] and sample counts, the texture sizes, ``maxSunZenithAngle``
        [rad]), and ``dustoptics``: why each was chosen and the errors they
        leave (the preprocessor ignores keys it does not read).
    """
    if not isinstance(atmosphere, Atmosphere):
        raise TypeError(f"atmosphere must be an Atmosphere; got {type(atmosphere).__name__}")
    if sampling is None:
        sampling = cosmoscout_sampling(atmosphere)
    elif not isinstance(sampling, CosmoScoutSampling):
        raise TypeError(f"sampling must be a CosmoScoutSampling; got {type(sampling).__name__}")
    if path_prefix is not None and not isinstance(path_prefix, str):
        raise TypeError(f"path_prefix must be a string or None; got {path_prefix!r}")
    root = Path(os.fspath(directory)).resolve()

    def name(role: str, kind: str) -> str:
        file = f"{atmosphere.file_prefix(role)}_{kind}.csv"
        return path_prefix + file if path_prefix is not None else str(root / file)

    data: dict[str, Any] = {
        "sunDistance": atmosphere.sun_distance_m,
        "minAltitude": atmosphere.planet_radius_m,
        "maxAltitude": atmosphere.atmosphere_radius_m,
        "ior": atmosphere.refractivity,
    }
    files = {
        "phase": "phase",
        "betaSca": "scattering",
        "betaAbs": "absorption",
        "density": "density",
    }
    for c in atmosphere.constituents:
        keys = ("betaAbs", "density") if c.role == "ozone" else tuple(files)  # ozone: absorbs only
        data[c.role] = {key: name(c.role, files[key]) for key in keys}
    data.update(sampling.settings)
    data["dustoptics"] = sampling.to_dict()
    return json.dumps(data, indent=2, allow_nan=False) + "\n"


#: Phase-column counts tried for a whole set, smallest first (1 deg, 1/2, 1/4, ... steps).
PHASE_COLUMN_COUNTS: Final = (181, 361, 721, 1441, 2881, 5761)


def cosmoscout_phase_error(table: Table, n_theta: int) -> float:
    """How far the phase columns, as the preprocessor reads them, are from integrating to 1.

    The ``n_theta`` columns at the texel centres (:func:`cosmoscout_phase_angles`),
    read linearly between centres and held constant within half a column of 0
    and 180 deg, integrated over the sphere exactly
    (:func:`~dustoptics.scattering.tabulated_phase.sphere_integral`) and
    compared with the table's own integral.

    Returns
    -------
    float
        The largest ``|integral / table's integral - 1|`` over the wavelengths. [-]
    """
    centres = cosmoscout_phase_angles(n_theta)
    p = np.asarray(table.phase_at(centres), dtype=np.float64)
    grid = np.concatenate([[0.0], centres, [180.0]])
    read = sphere_integral(np.concatenate([p[:, :1], p, p[:, -1:]], axis=1), theta_deg=grid)
    theta = np.asarray(table.theta_deg, dtype=np.float64)
    own = (
        sphere_integral(table.phase, theta_deg=theta)
        if theta[0] == 0.0 and theta[-1] == 180.0
        else 1.0
    )
    return float(np.max(np.abs(np.asarray(read) / own - 1.0)))


def _phase_columns(atmosphere: Atmosphere, n_theta: int | None, tolerance: float) -> int:
    """The set's phase-column count: chosen, or checked (refused naming the smallest that does)."""
    tables = [
        c.table
        for c in atmosphere.constituents
        if c.table.cross_sections is not None and np.any(c.table.cross_sections.csca_um2 > 0)
    ]

    def ok(n: int) -> bool:
        return all(cosmoscout_phase_error(t, n) <= tolerance for t in tables)

    if n_theta is None:
        return next((n for n in PHASE_COLUMN_COUNTS if ok(n)), PHASE_COLUMN_COUNTS[-1])
    n = _check_n_theta(n_theta)
    if ok(n):
        return n
    low, high = n, 2 * n  # smallest passing count, by bisection (the error falls as n grows)
    while not ok(high):
        low, high = high, 2 * high
        if high > 1_000_000:
            break
    while high - low > 1:
        mid = (low + high) // 2
        low, high = (low, mid) if ok(mid) else (mid, high)
    worst = max(cosmoscout_phase_error(t, n) for t in tables)
    raise ValueError(
        f"n_theta {n} is too few phase columns for atmosphere {atmosphere.name!r} at tolerance "
        f"{tolerance:g}: as CosmoScout's preprocessor reads them the phase function's integral "
        f"over the sphere is off by {worst:.3g}; the smallest that does is {high}"
    )


#: Radii CosmoScout VR takes from SPICE for its bodies (``pck00010.tpc``, the first of the
#: three): Mars and Earth. [m]
SPICE_RADII_M: Final = {"Mars": 3_396_190.0, "Earth": 6_378_136.6}


def cosmoscout_plugin_entry(
    atmosphere: Atmosphere,
    *,
    data_directory: str | os.PathLike[str],
    body_radius_m: float,
) -> dict[str, Any]:
    """The ``csp-atmospheres`` plugin's entry for the body, loading the preprocessor's output.

    At run time the plugin sets the ground and the top of the atmosphere at
    the body's radius (from SPICE unless the object sets ``"radii"``) plus
    ``bottomAltitude`` and ``topAltitude``; the radii the textures were
    computed for (the settings' ``minAltitude``, ``maxAltitude``) are not
    passed on, and the textures' parametrization depends on both.  This entry
    puts them back: ``bottomAltitude = planet radius - body radius``,
    ``topAltitude = atmosphere radius - body radius``.

    Parameters
    ----------
    atmosphere : Atmosphere
        The set the textures were computed from.
    data_directory : path-like
        The preprocessor's output directory, as CosmoScout VR sees it (a
        relative path is relative to its working directory,
        ``install/<os>-<build type>/bin``).
    body_radius_m : float
        The radius CosmoScout VR has for the body (:data:`SPICE_RADII_M`). [m]

    Returns
    -------
    dict
        ``{"topAltitude", "bottomAltitude", "model": "Bruneton",
        "modelSettings": {"dataDirectory"}}``, to go under
        ``plugins / csp-atmospheres / atmospheres / <body>`` of a scene file.

    Examples
    --------
    >>> from dustoptics.atmosphere.sets import earth_atmosphere
    >>> entry = cosmoscout_plugin_entry(
    ...     earth_atmosphere(), data_directory="/data/earth", body_radius_m=SPICE_RADII_M["Earth"]
    ... )
    >>> entry["bottomAltitude"], entry["topAltitude"]
    (-7136.6, 72863.4)
    """
    if not isinstance(atmosphere, Atmosphere):
        raise TypeError(f"atmosphere must be an Atmosphere; got {type(atmosphere).__name__}")
    radius = float(body_radius_m)
    if not (math.isfinite(radius) and radius > 0.0):
        raise ValueError(f"body_radius_m must be a positive radius [m]; got {body_radius_m!r}")
    return {
        "topAltitude": round(atmosphere.atmosphere_radius_m - radius, 6),
        "bottomAltitude": round(atmosphere.planet_radius_m - radius, 6),
        "model": "Bruneton",
        "modelSettings": {"dataDirectory": os.fspath(data_directory)},
    }


def write_atmosphere(
    atmosphere: Atmosphere,
    directory: str | os.PathLike[str],
    *,
    n_theta: int | None = None,
    overwrite: bool = False,
    path_prefix: str | None = None,
    sampling: CosmoScoutSampling | None = None,
) -> list[Path]:
    """Write CosmoScout VR's CSV set and ``<name>_settings.json``, the preprocessor's input.

    Run the preprocessor from CosmoScout VR's repository root,
    ``bruneton-preprocessor <directory>/<name>_settings.json <output>``, and
    point the plugin's ``dataDirectory`` at ``<output>``
    (``docs/howto/renderer.rst`` has the recipe).

    Parameters
    ----------
    atmosphere : Atmosphere
        The atmosphere.
    directory : path-like
        Output directory (created if missing).
    n_theta : int, optional
        Phase-function columns (:func:`cosmoscout_phase_angles`).  Default:
        the smallest of :data:`PHASE_COLUMN_COUNTS` whose columns, as the
        preprocessor reads them, integrate every phase function of the set
        to within the sampling's tolerance of 1 (:func:`cosmoscout_phase_error`;
        the Martian dust needs 361, where 181 leave 1.1 %).  A count that
        does not is refused, naming the smallest that does.
    overwrite : bool, default False
        Replace existing files.
    path_prefix : str, optional
        See :func:`settings_json` (default: absolute paths of the files written).
    sampling : CosmoScoutSampling, optional
        See :func:`settings_json`.

    Returns
    -------
    list of pathlib.Path
        The CSV files, then the settings file.

    Raises
    ------
    ValueError
        Too few phase columns for the set (the message names the smallest
        count that does), before anything is written.
    FileExistsError
        A target exists and ``overwrite`` is False (checked before anything
        is written).
    """
    root = Path(directory)
    settings_path = root / f"{atmosphere.name}_settings.json"
    check_targets([settings_path], overwrite=overwrite)
    if sampling is None:
        sampling = cosmoscout_sampling(atmosphere)
    n_theta = _phase_columns(atmosphere, n_theta, sampling.tolerance)
    text = settings_json(atmosphere, directory=root, path_prefix=path_prefix, sampling=sampling)
    # One set: the CSV files and the settings appear together or not at all.
    with file_set(root, overwrite=overwrite):
        written = write_cosmoscout_set(
            root, atmosphere.cosmoscout_constituents(), n_theta=n_theta, overwrite=overwrite
        )
        written += write_files({settings_path: text.encode("utf-8")}, overwrite=overwrite)
    return written
