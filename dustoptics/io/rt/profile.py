"""The vertical profile of the radiative-transfer files: the layers a user asks for.

The formats ``disort``, ``libradtran`` and ``libradtran-nc`` share one options
dataclass, :class:`RTProfileOptions` (``--scale-height-m``,
``--top-altitude-m``, ``--n-layers``, ``--profile-file``), which becomes the
homogeneous layers the files carry (:class:`RTLayers`):

- nothing given: one uniform layer from 0 to 1 km (the files' layout before
  the options existed; the table's number density fills it);
- ``--top-altitude-m`` alone: a uniform density from the surface to the top,
  in ``--n-layers`` layers of equal thickness (default 1);
- ``--scale-height-m`` H: the exponential profile ``exp(-z / H)`` up to
  ``--top-altitude-m`` (default 120,000 m, as the cosmoscout format's), in
  ``--n-layers`` layers (default 10) that each hold an equal share of the
  column, their boundaries rounded to 1 m;
- ``--profile-file FILE``: a piecewise-linear relative density from a text
  file of two columns, altitude [km] (from exactly 0, increasing) and relative
  density (>= 0; scaled so that its largest value is 1: the table's number
  density is the density there), ``#`` comments; one layer between each two
  lines, the file's last altitude the top.

Each layer holds the exact integral of the relative density over it
(:meth:`~dustoptics.atmosphere.column.DensityProfile.column_length_m`), so the
layers' mean number densities ``N0 L_i / dz_i`` give the profile's column to
rounding: the vertical optical depth at a wavelength is
``N0 <C_ext> sum_i L_i`` (:func:`~dustoptics.atmosphere.column.optical_depth`),
and ``--optical-depth`` computes ``N0`` from it (:func:`rt_profile_of`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.column import (
    DensityProfile,
    ExponentialProfile,
    PiecewiseLinearProfile,
)
from dustoptics.io._text import number
from dustoptics.io.registry import option

__all__ = [
    "DEFAULT_EXPONENTIAL_LAYERS",
    "DEFAULT_TOP_ALTITUDE_M",
    "RTLayers",
    "RTProfileOptions",
    "coverage_lines",
    "read_profile_file",
    "rt_layers",
    "rt_profile",
]

#: Top of an exponential profile when no top is given (the cosmoscout format's default). [m]
DEFAULT_TOP_ALTITUDE_M: Final = 120_000.0
#: Layers of an exponential profile when none are given (each an equal share of the column).
DEFAULT_EXPONENTIAL_LAYERS: Final = 10
#: The layer of the files when no profile is asked for: 0 to 1 km, uniform. [km]
DEFAULT_LAYER_KM: Final = (0.0, 1.0)
#: More layers than this would write as many libRadtran layer files: refused.
MAX_LAYERS: Final = 200


@dataclass(frozen=True)
class RTLayers:
    """Homogeneous layers of a vertical profile, from the surface up.

    Attributes
    ----------
    bottom_km, top_km : tuple of float
        Each layer's bottom and top altitude, increasing, contiguous. [km]
    column_m : tuple of float
        Each layer's integral of the relative density, ``int rho dz``; its mean
        number density is ``N0 column_m / (1000 (top_km - bottom_km))``. [m]
    description : str
        What profile the layers are (for the files' headers).
    """

    bottom_km: tuple[float, ...]
    top_km: tuple[float, ...]
    column_m: tuple[float, ...]
    description: str

    @property
    def n_layers(self) -> int:
        """How many layers."""
        return len(self.bottom_km)

    @property
    def relative_density(self) -> np.ndarray:
        """Each layer's mean relative density, ``column_m / thickness``. [-]"""
        dz_m = 1000.0 * (np.asarray(self.top_km) - np.asarray(self.bottom_km))
        return np.asarray(self.column_m) / dz_m

    @property
    def total_column_m(self) -> float:
        """The column length ``L = sum_i column_m`` (tau = N0 <C_ext> L). [m]"""
        return math.fsum(self.column_m)


def read_profile_file(path: str | os.PathLike[str]) -> PiecewiseLinearProfile:
    """A relative density profile from a text file: altitude [km], relative density per line.

    Lines starting with ``#`` and blank lines are skipped; columns are separated by
    blanks or commas.  The densities are scaled so that the largest is 1.

    Raises
    ------
    ValueError
        The file cannot be read, a line has not two numbers, the altitudes do not start
        at 0 and increase, or a density is negative or all are 0.
    """
    where = f"profile file {os.fspath(path)!r}"
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{where}: cannot be read ({exc})") from None
    rows = []
    for i, line in enumerate(text.splitlines(), start=1):
        cells = line.replace(",", " ").split()
        if not cells or cells[0].startswith("#"):
            continue
        try:
            if len(cells) != 2:
                raise ValueError
            rows.append((float(cells[0]), float(cells[1])))
        except ValueError:
            raise ValueError(
                f"{where}, line {i}: expected two numbers, altitude [km] and relative "
                f"density; got {line.strip()!r}"
            ) from None
    if len(rows) < 2:
        raise ValueError(f"{where}: needs at least two lines of altitude [km] and density")
    z_km, rho = np.array(rows).T
    if not (np.all(np.isfinite(rho)) and np.all(rho >= 0.0) and rho.max() > 0.0):
        raise ValueError(f"{where}: relative densities must be finite, >= 0 and not all 0")
    try:
        return PiecewiseLinearProfile(altitude_m=(z_km * 1000.0).tolist(), density=rho / rho.max())
    except ValueError as exc:
        raise ValueError(f"{where}: {exc} (altitudes in km in the file)") from None


def _layers(profile: DensityProfile, edges_m: np.ndarray, description: str) -> RTLayers:
    cumulative = np.array(
        [0.0] + [profile.column_length_m(top_altitude_m=float(z)) for z in edges_m[1:]]
    )
    return RTLayers(
        bottom_km=tuple((edges_m[:-1] / 1000.0).tolist()),
        top_km=tuple((edges_m[1:] / 1000.0).tolist()),
        column_m=tuple(np.diff(cumulative).tolist()),
        description=description,
    )


def _check_layers(n_layers: int) -> int:
    if not 1 <= n_layers <= MAX_LAYERS:
        raise ValueError(f"n_layers must be within 1 .. {MAX_LAYERS}; got {n_layers!r}")
    return n_layers


def _check_length(name: str, value: float | None) -> None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be finite and > 0 m; got {value!r}")


def rt_profile(
    *,
    scale_height_m: float | None = None,
    top_altitude_m: float | None = None,
    n_layers: int | None = None,
    profile_file: str | os.PathLike[str] | None = None,
) -> tuple[DensityProfile, np.ndarray, str]:
    """The profile asked for, its layer boundaries [m] and its description (:func:`rt_layers`)."""
    if profile_file is not None:
        others = {
            "scale_height_m": scale_height_m,
            "top_altitude_m": top_altitude_m,
            "n_layers": n_layers,
        }
        given = [k for k, v in others.items() if v is not None]
        if given:
            raise ValueError(
                f"profile_file sets the layers and the top (one layer between two of its lines); "
                f"{', '.join(given)} cannot be honoured with it: remove it"
            )
        profile = read_profile_file(profile_file)
        edges = np.asarray(profile.altitude_m)
        return profile, edges, f"piecewise linear from {Path(profile_file).name}"
    _check_length("scale_height_m", scale_height_m)
    _check_length("top_altitude_m", top_altitude_m)
    if scale_height_m is None:
        n = _check_layers(1 if n_layers is None else n_layers)
        top = DEFAULT_LAYER_KM[1] * 1000.0 if top_altitude_m is None else top_altitude_m
        edges = np.round(np.linspace(0.0, top, n + 1), 3)
        uniform = PiecewiseLinearProfile(altitude_m=(0.0, float(edges[-1])), density=(1.0, 1.0))
        return uniform, edges, f"uniform from 0 to {number(float(edges[-1]))} m"
    n = _check_layers(DEFAULT_EXPONENTIAL_LAYERS if n_layers is None else n_layers)
    top = DEFAULT_TOP_ALTITUDE_M if top_altitude_m is None else top_altitude_m
    # Boundaries of equal column: 1 - exp(-z/H) = (i/n) (1 - exp(-top/H)), rounded to 1 m.
    share = np.arange(n) / n * -math.expm1(-top / scale_height_m)
    edges = np.append(np.round(-scale_height_m * np.log1p(-share), 0), top)
    if np.any(np.diff(edges) <= 0.0):
        raise ValueError(
            f"n_layers = {n} layers of equal column are thinner than 1 m below "
            f"top_altitude_m = {top!r} m: choose fewer"
        )
    description = (
        f"exponential, scale height {number(scale_height_m)} m, top {number(top)} m, "
        "layers of equal column"
    )
    return ExponentialProfile(scale_height_m=scale_height_m), edges, description


def rt_layers(
    *,
    scale_height_m: float | None = None,
    top_altitude_m: float | None = None,
    n_layers: int | None = None,
    profile_file: str | os.PathLike[str] | None = None,
) -> RTLayers:
    """The layers of the profile asked for (module docstring); all None: 0-1 km, uniform.

    Parameters
    ----------
    scale_height_m : float, optional
        Exponential profile's scale height, > 0. [m]
    top_altitude_m : float, optional
        Top of the profile above the surface, > 0. [m]
    n_layers : int, optional
        Homogeneous layers, 1 .. 200.
    profile_file : path-like, optional
        A relative density profile (:func:`read_profile_file`); excludes the others.

    Returns
    -------
    RTLayers

    Raises
    ------
    ValueError
        A value out of range, a profile file with another option, or a profile file that
        cannot be read.

    Examples
    --------
    >>> rt_layers(scale_height_m=11100.0, top_altitude_m=50000.0, n_layers=2).top_km
    (7.572, 50.0)
    """
    profile, edges, description = rt_profile(
        scale_height_m=scale_height_m,
        top_altitude_m=top_altitude_m,
        n_layers=n_layers,
        profile_file=profile_file,
    )
    return _layers(profile, edges, description)


@dataclass(frozen=True)
class RTProfileOptions:
    """The radiative-transfer formats' vertical profile (module docstring).

    None everywhere: one uniform layer from 0 to 1 km.
    """

    scale_height_m: float | None = option(
        help="exponential density profile's scale height [m] (cosmoscout: default 10000; "
        "disort, libradtran, libradtran-nc: default none, one uniform layer)",
        type="positive_float",
        metavar="H",
    )
    top_altitude_m: float | None = option(
        help="top of the density profile above the surface [m] (cosmoscout: default 120000; "
        "disort, libradtran, libradtran-nc: default 1000 uniform, 120000 with --scale-height-m)",
        type="positive_float",
        metavar="Z",
    )
    n_layers: int | None = option(
        help="homogeneous layers of the DISORT and libRadtran files (default 1 for a uniform "
        "density, 10 of equal column for --scale-height-m; at most 200)",
        type="positive_int",
        metavar="N",
    )
    profile_file: str | None = option(
        help="relative density profile for the DISORT and libRadtran files: lines of altitude "
        "[km] (from 0, increasing) and relative density, '#' comments; one layer between two "
        "lines, the last altitude the top",
        metavar="FILE",
    )

    def given(self) -> bool:
        """Whether any profile option is given."""
        return any(
            v is not None
            for v in (self.scale_height_m, self.top_altitude_m, self.n_layers, self.profile_file)
        )

    def layers(self) -> RTLayers:
        """The layers (:func:`rt_layers`)."""
        return rt_layers(
            scale_height_m=self.scale_height_m,
            top_altitude_m=self.top_altitude_m,
            n_layers=self.n_layers,
            profile_file=self.profile_file,
        )

    def column(self) -> tuple[DensityProfile, float]:
        """The profile and its top [m], for the number density of an optical depth."""
        profile, edges, _ = rt_profile(
            scale_height_m=self.scale_height_m,
            top_altitude_m=self.top_altitude_m,
            n_layers=self.n_layers,
            profile_file=self.profile_file,
        )
        return profile, float(edges[-1])

    def keywords(self) -> dict[str, Any]:
        """The writers' keyword: ``layers`` when a profile is asked for (else the default)."""
        return {"layers": self.layers()} if self.given() else {}

    def recorded(self) -> dict[str, Any]:
        """The profile, recorded in the files' provenance (its layers, so a changed profile
        file changes the input hash)."""
        if not self.given():
            return {}
        layers = self.layers()
        return {
            "density_profile": layers.description,
            "layer_bottom_km": list(layers.bottom_km),
            "layer_top_km": list(layers.top_km),
            "layer_column_m": list(layers.column_m),
        }

    def check(self, wavelength_nm: Any) -> None:
        """Refuse a profile that cannot be made, before the table is computed."""
        self.layers()


def coverage_lines(wavelength_nm: Any) -> list[str]:
    """Header lines: the wavelengths the file covers, and that uvspec must stay inside them."""
    wl = np.asarray(wavelength_nm, dtype=np.float64)
    return [
        f"# wavelength coverage: {number(float(wl.min()))} .. {number(float(wl.max()))} nm "
        f"({wl.size} wavelengths); uvspec stops at the grid's edges: keep its 'wavelength' "
        "range (and its solar or filter grid) inside it",
    ]
