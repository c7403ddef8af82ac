"""Sky quantities as observations of a retrieval: radiance at given directions, chromaticity.

The sky is the Mars sky of :func:`dustoptics.atmosphere.sets.mars_atmosphere`
(CO2 molecules, the dust scaled to a given vertical optical depth at a
reference wavelength, exponential profiles) rendered by :mod:`dustoptics.sky`:
the orders of scattering (:func:`~dustoptics.sky.orders.solve_orders`) once
per Sun elevation, optical depth and ground albedo (a *scene*), then the
radiance along the observed lines of sight
(:func:`~dustoptics.sky.render.line_of_sight_radiance`), and the CIE 1931
chromaticity under sunlight (:func:`~dustoptics.sky.scene.sunlit_xyz`), as
:func:`~dustoptics.sky.compare.mer_chromaticity` computes it.

Observation variables
---------------------
``sky_radiance``
    radiance per unit solar irradiance, dimensions ``sun_elevation_deg``
    [degree], ``wavelength_nm`` [nm] and ``direction``, with the coordinates
    ``view_zenith_deg`` and ``view_azimuth_deg`` (from the Sun's azimuth)
    along ``direction``. [sr^-1]
``sky_chromaticity``
    CIE 1931 (x, y), dimensions ``sun_elevation_deg`` and ``chromaticity``
    (coordinate ``["x", "y"]``), seen in the direction of the attributes
    ``view_zenith_deg`` and ``view_azimuth_deg`` (default 60 and 180: the
    rovers' view away from the Sun, 30 degree above the horizon,
    :data:`~dustoptics.sky.compare.AWAY_FROM_SUN`). [-]

Each carries its scene in attributes: ``optical_depth`` (vertical dust optical
depth, required), ``reference_wavelength_nm`` (its wavelength, default 550),
``ground_albedo`` (Lambertian, default 0.2) and ``observer_altitude_m``
(default 2, a rover's camera).

The Jacobian
------------
By the chain rule through the optics' exact derivatives, with finite
differences only in the radiative transfer: the table at the current
parameters carries d(phase, C_ext, C_sca, g)/dp
(:func:`~dustoptics.scattering.optics.compute_optics` with ``derivatives``);
for each parameter p the sky is solved again with the table moved along its
derivative, ``T + h dT/dp``, and
``d(sky)/dp = (sky(T + h dT/dp) - sky(T)) / h`` (forward differences; central
with ``SkySettings(central_differences=True)``).  No second Mie table is
computed, and the step ``h`` is fixed by the parameter's bounds
(``relative_step`` of their width), so the same observations give the same
numbers bit for bit.  Each Jacobian costs one sky solve per scene and
parameter (two with central differences), beside the solve of the residuals.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final, TextIO

import numpy as np

from dustoptics._validation import BudgetError
from dustoptics.atmosphere.sets import mars_atmosphere
from dustoptics.sky._progress import Reporter
from dustoptics.sky.compare import AWAY_FROM_SUN, COMPARISON_WAVELENGTHS_NM
from dustoptics.sky.medium import N_STREAMS, Medium
from dustoptics.sky.orders import N_LAYERS, WORK_BUDGET, estimate_orders_cost, solve_orders
from dustoptics.sky.render import line_of_sight_radiance
from dustoptics.sky.scene import sunlit_xyz
from dustoptics.table import Table

__all__ = [
    "CHROMATICITY_WAVELENGTHS_NM",
    "MAX_SKY_SECONDS",
    "SKY_OBSERVABLES",
    "SkyScene",
    "SkySettings",
]

#: Sky observation variables and their dimensions.
SKY_OBSERVABLES: Final[Mapping[str, tuple[str, ...]]] = {
    "sky_radiance": ("sun_elevation_deg", "wavelength_nm", "direction"),
    "sky_chromaticity": ("sun_elevation_deg", "chromaticity"),
}
#: The spectral grid of a chromaticity: 360-830 nm in 10 nm steps and the two radiance
#: wavelengths of :mod:`dustoptics.sky.compare`, the grid its rover comparison uses. [nm]
CHROMATICITY_WAVELENGTHS_NM: Final = tuple(
    float(w) for w in np.unique(np.r_[np.arange(360.0, 831.0, 10.0), COMPARISON_WAVELENGTHS_NM])
)
#: Most estimated seconds of sky solves in a retrieval without ``allow_large``
#: (the house's five minutes, :data:`dustoptics.sky.orders.WORK_BUDGET`). [s]
MAX_SKY_SECONDS: Final = 300.0
#: Multiply-adds of the orders of scattering per second on one busy core, the rate
#: :data:`~dustoptics.sky.orders.WORK_BUDGET` is stated at ("about five minutes").
_WORK_PER_SECOND: Final = WORK_BUDGET / 300.0
#: Seconds of a sky solve besides the orders: the medium's slant columns and the
#: lines of sight (measured: 1.4-2.1 s on a loaded 2-core machine). [s]
_FIXED_SECONDS: Final = 2.0


@dataclass(frozen=True)
class SkySettings:
    """Numerical settings of the skies a retrieval solves.

    Attributes
    ----------
    n_streams : int
        Discrete ordinates per hemisphere (default the renderer's,
        :data:`~dustoptics.sky.medium.N_STREAMS`).
    tol : float
        Tolerance of the series of orders of scattering; tighter than the
        renderer's 1e-4 by default so that the finite differences see the
        optics, not where the series stopped. [-]
    relative_step : float
        Finite-difference step of each parameter, as a fraction of the width
        of its bounds. [-]
    central_differences : bool
        Central instead of forward differences (twice the sky solves).
    """

    n_streams: int = N_STREAMS
    tol: float = 1e-6
    relative_step: float = 1e-3
    central_differences: bool = False

    def __post_init__(self) -> None:
        if not (type(self.n_streams) is int and 2 <= self.n_streams <= 32):
            raise ValueError(f"n_streams must be an integer in [2, 32]; got {self.n_streams!r}")
        if not (isinstance(self.tol, float | int) and 1e-10 <= self.tol <= 0.1):
            raise ValueError(f"tol must be within [1e-10, 0.1]; got {self.tol!r}")
        if not (isinstance(self.relative_step, float | int) and 1e-7 <= self.relative_step <= 0.1):
            raise ValueError(
                f"relative_step must be within [1e-7, 0.1]; got {self.relative_step!r}"
            )


@dataclass(frozen=True, order=True)
class SkyScene:
    """What one solve of the orders of scattering depends on besides the dust.

    Attributes
    ----------
    sun_elevation_deg : float
        Sun above the horizon. [deg]
    optical_depth : float
        Vertical dust optical depth at ``reference_wavelength_nm``. [-]
    reference_wavelength_nm : float
        Wavelength of the optical depth. [nm]
    ground_albedo : float
        Lambertian ground albedo. [-]
    observer_altitude_m : float
        Observer above the ground. [m]
    """

    sun_elevation_deg: float
    optical_depth: float
    reference_wavelength_nm: float = 550.0
    ground_albedo: float = 0.2
    observer_altitude_m: float = 2.0


@dataclass(frozen=True)
class _SkySamples:
    name: str
    scene: SkyScene
    view_zenith_deg: np.ndarray  # per sample
    view_azimuth_deg: np.ndarray
    wavelength_nm: np.ndarray  # per sample (NaN: a chromaticity)
    coordinate: np.ndarray  # 0 x, 1 y (-1: a radiance)
    value: np.ndarray
    sigma: np.ndarray


def _attr(var: Any, key: str, default: float | None, low: float, high: float) -> float:
    if key not in var.attrs:
        if default is None:
            raise ValueError(f"observations: {var.name!r} needs the attribute {key!r} (its scene)")
        return default
    raw = var.attrs[key]
    try:
        value = float(raw)
    except (TypeError, ValueError):
        value = math.nan
    if not low <= value <= high:
        # A number as the number (a numpy scalar's repr names its type), anything else as given.
        shown = f"{value:g}" if isinstance(raw, (int, float, np.number)) else repr(raw)
        raise ValueError(
            f"observations: {var.name!r} attribute {key} must be within [{low:g}, {high:g}]; "
            f"got {shown}"
        )
    return value


def _coordinate(var: Any, key: str) -> np.ndarray:
    """The coordinate ``key`` of a sky variable as numbers, or a ValueError naming it."""
    if key not in var.coords:
        raise ValueError(f"observations: {var.name!r} needs the coordinate {key!r}")
    values = np.asarray(var[key].values)
    if values.dtype.kind not in "biuf":
        raise ValueError(
            f"observations: {var.name!r} coordinate {key} must be numbers; got dtype {values.dtype}"
        )
    return np.asarray(values, dtype=np.float64)


def sky_samples(var: Any, sigma: np.ndarray) -> list[_SkySamples]:
    """The finite samples of one sky variable, per scene (one per Sun elevation)."""
    name = str(var.name)
    dims = SKY_OBSERVABLES[name]
    values = np.asarray(var.values, dtype=np.float64)
    elevations = _coordinate(var, "sun_elevation_deg")
    if not np.all((elevations >= -10.0) & (elevations <= 90.0)):
        raise ValueError(
            f"observations: {name!r} sun_elevation_deg must be within [-10, 90]; "
            f"got {elevations.tolist()}"
        )
    tau = _attr(var, "optical_depth", None, 1e-6, 1e3)
    ref = _attr(var, "reference_wavelength_nm", 550.0, 200.0, 5e4)
    albedo = _attr(var, "ground_albedo", 0.2, 0.0, 1.0)
    altitude = _attr(var, "observer_altitude_m", 2.0, 0.0, 1e5)
    out = []
    for i, elev in enumerate(elevations.tolist()):
        scene = SkyScene(float(elev), tau, ref, albedo, altitude)
        v, s = values[i], sigma[i]
        if name == "sky_radiance":
            wl = _coordinate(var, "wavelength_nm")
            zen = _coordinate(var, "view_zenith_deg")
            azi = _coordinate(var, "view_azimuth_deg")
            if zen.shape != (v.shape[1],) or azi.shape != zen.shape:
                raise ValueError(
                    "observations: 'sky_radiance' needs the coordinates view_zenith_deg and "
                    f"view_azimuth_deg along {dims[2]!r}"
                )
            if not np.all((zen >= 0.0) & (zen <= 90.0)):
                raise ValueError(
                    f"observations: view_zenith_deg must be within [0, 90]; got {zen.tolist()}"
                )
            if not np.all((azi >= -360.0) & (azi <= 360.0)):
                raise ValueError(
                    "observations: view_azimuth_deg must be finite and within [-360, 360]; "
                    f"got {azi.tolist()}"
                )
            if not np.all((wl > 0.0) & (wl <= 1e7)):
                raise ValueError(
                    "observations: 'sky_radiance' coordinate wavelength_nm must be finite and "
                    f"within (0, 1e+07]; got {wl[~((wl > 0.0) & (wl <= 1e7))][:5].tolist()}"
                )
            wl_s, zen_s = np.meshgrid(wl, zen, indexing="ij")
            azi_s = np.broadcast_to(azi, v.shape)
            coord = np.full(v.shape, -1)
        else:
            labels = [str(c) for c in var["chromaticity"].values]
            if sorted(labels) != ["x", "y"]:
                raise ValueError(
                    "observations: 'sky_chromaticity' needs the coordinate chromaticity = "
                    f"['x', 'y']; got {labels}"
                )
            zenith = _attr(var, "view_zenith_deg", AWAY_FROM_SUN["view_zenith_deg"], 0.0, 90.0)
            azimuth = _attr(
                var, "view_azimuth_deg", AWAY_FROM_SUN["view_azimuth_deg"], -360.0, 360.0
            )
            wl_s = np.full(v.shape, np.nan)
            zen_s = np.full(v.shape, zenith)
            azi_s = np.full(v.shape, azimuth)
            coord = np.array([0 if c == "x" else 1 for c in labels])
        keep = np.isfinite(v)
        if not np.all(np.isfinite(s[keep]) & (s[keep] > 0)):
            raise ValueError(f"observations: {name!r} uncertainties must be finite and > 0")
        if np.any(keep):
            out.append(
                _SkySamples(
                    name,
                    scene,
                    np.asarray(zen_s, dtype=np.float64)[keep].ravel(),
                    np.asarray(azi_s, dtype=np.float64)[keep].ravel(),
                    np.asarray(wl_s, dtype=np.float64)[keep].ravel(),
                    np.asarray(coord)[keep].ravel(),
                    v[keep].ravel(),
                    s[keep].ravel(),
                )
            )
    return out


def sky_labels(samples: _SkySamples) -> list[str]:
    """What each residual of ``samples`` is, e.g. ``"sky_chromaticity_x@sun60deg"``."""
    sun = f"sun{samples.scene.sun_elevation_deg:g}deg"
    if samples.name == "sky_chromaticity":
        return [
            f"sky_chromaticity_{'xy'[c]}@{sun},{z:g}/{a:g}deg"
            for c, z, a in zip(
                samples.coordinate, samples.view_zenith_deg, samples.view_azimuth_deg
            )
        ]
    return [
        f"sky_radiance@{sun},{w:g}nm,{z:g}/{a:g}deg"
        for w, z, a in zip(samples.wavelength_nm, samples.view_zenith_deg, samples.view_azimuth_deg)
    ]


class SkyModel:
    """The sky observations of a retrieval: their scenes, spectral grid, values and Jacobian.

    Parameters
    ----------
    samples : sequence of _SkySamples
        From :func:`sky_samples`.
    settings : SkySettings
        Streams, tolerance and finite-difference step.
    """

    def __init__(self, samples: Sequence[_SkySamples], settings: SkySettings) -> None:
        self.samples = tuple(samples)
        self.settings = settings
        self.scenes = tuple(sorted({s.scene for s in self.samples}))
        grid: set[float] = {s.scene.reference_wavelength_nm for s in self.samples}
        for s in self.samples:
            grid.update(s.wavelength_nm[np.isfinite(s.wavelength_nm)].tolist())
        if any(s.name == "sky_chromaticity" for s in self.samples):
            grid.update(CHROMATICITY_WAVELENGTHS_NM)
        if len(grid) < 2:  # the orders and the medium need two wavelengths at least
            only = min(grid)
            grid.add(only * 1.01)
        self.wavelength_nm = np.array(sorted(grid))
        self.solves = 0

    @property
    def n_samples(self) -> int:
        return sum(s.value.size for s in self.samples)

    def solves_per_evaluation(self) -> int:
        """Sky solves of one evaluation of the residuals."""
        return len(self.scenes)

    def solves_per_jacobian(self, n_parameters: int) -> int:
        """Sky solves of one Jacobian beyond the residuals'."""
        per = 2 if self.settings.central_differences else 1
        return len(self.scenes) * n_parameters * per

    def seconds_per_solve(self, table: Table) -> float:
        """Estimated seconds of one sky solve with the dust ``table``: the orders of
        scattering of the thickest scene (:func:`~dustoptics.sky.orders.estimate_orders_cost`
        at the rate :data:`~dustoptics.sky.orders.WORK_BUDGET` is stated at) and the medium's
        slant columns and lines of sight."""
        thickest = max(self.scenes, key=lambda sc: sc.optical_depth)
        medium = self._medium(table, thickest)
        cost = estimate_orders_cost(medium, n_layers=N_LAYERS, tol=self.settings.tol)
        return cost.work / _WORK_PER_SECOND + _FIXED_SECONDS

    def check_cost(
        self,
        table: Table,
        *,
        table_seconds: float,
        max_iterations: int,
        n_parameters: int,
        allow_large: bool,
    ) -> tuple[int, float]:
        """The most sky solves of a retrieval and the estimated seconds of the whole fit (the
        solves and one table per evaluation, ``table_seconds`` as the start's took); refuse
        beyond :data:`MAX_SKY_SECONDS` unless ``allow_large``."""
        # Each evaluation and each Jacobian at most once per evaluation, and the result's.
        n = (max_iterations + 1) * (
            self.solves_per_evaluation() + self.solves_per_jacobian(n_parameters)
        )
        each = self.seconds_per_solve(table)
        total = n * each + (max_iterations + 1) * table_seconds
        if total > MAX_SKY_SECONDS and not allow_large:
            raise BudgetError(
                f"the retrieval would solve at most {n} skies ({max_iterations} evaluations x "
                f"{len(self.scenes)} scenes, {n_parameters} parameters' finite differences per "
                f"Jacobian), about {each:.2g} s each with {self.wavelength_nm.size} wavelengths "
                f"and n_streams={self.settings.n_streams}, and a table of about "
                f"{table_seconds:.2g} s per evaluation: about {total:.2g} s, beyond the budget "
                f"of {MAX_SKY_SECONDS:g} s; lower max_iterations, the streams or the scenes, or "
                "pass allow_large=True (--allow-large on the command line) to go ahead"
            )
        return n, total

    # ------------------------------------------------------------ the sky

    def _medium(self, table: Table, scene: SkyScene) -> Medium:
        atm = mars_atmosphere(
            dust_table=table,
            optical_depth=scene.optical_depth,
            reference_wavelength_nm=scene.reference_wavelength_nm,
            name="mars-retrieval",
        )
        return Medium.from_atmosphere(atm, n_streams=self.settings.n_streams)

    def _scene_values(self, table: Table, scene: SkyScene, report: Reporter) -> np.ndarray:
        """The model at every sample of ``scene``, in the order of :attr:`samples`."""
        mine = [s for s in self.samples if s.scene == scene]
        zen = np.concatenate([s.view_zenith_deg for s in mine])
        azi = np.concatenate([s.view_azimuth_deg for s in mine])
        directions = np.unique(np.column_stack([zen, azi]), axis=0)
        medium = self._medium(table, scene)
        field = solve_orders(
            medium,
            sun_zenith_deg=90.0 - scene.sun_elevation_deg,
            ground_albedo=scene.ground_albedo,
            tol=self.settings.tol,
            allow_large=True,  # counted by check_cost
        )
        radiance = line_of_sight_radiance(
            medium,
            field,
            view_zenith_deg=directions[:, 0],
            view_azimuth_deg=directions[:, 1],
            observer_altitude_m=scene.observer_altitude_m,
            allow_large=True,
        )  # (direction, wavelength)
        self.solves += 1
        report(
            f"sky solve {self.solves} (Sun {scene.sun_elevation_deg:g} deg, "
            f"{field.n_orders} orders of scattering)",
            last=True,
        )
        out = []
        for s in mine:
            row = [
                int(np.flatnonzero((directions[:, 0] == z) & (directions[:, 1] == a))[0])
                for z, a in zip(s.view_zenith_deg, s.view_azimuth_deg)
            ]
            if s.name == "sky_radiance":
                col = np.searchsorted(self.wavelength_nm, s.wavelength_nm)
                out.append(radiance[row, col])
            else:
                xyz = sunlit_xyz(self.wavelength_nm, radiance[row])
                xy = xyz[:, :2] / xyz.sum(axis=-1, keepdims=True)
                out.append(xy[np.arange(len(row)), s.coordinate])
        return np.concatenate(out)

    def values(self, table: Table, report: Reporter) -> np.ndarray:
        """The model at every sample (scene by scene, in the order of :meth:`order`)."""
        return np.concatenate([self._scene_values(table, sc, report) for sc in self.scenes])

    def order(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """Observed values, uncertainties and labels in the order of :meth:`values`."""
        values, sigma, labels = [], [], []
        for scene in self.scenes:
            for s in self.samples:
                if s.scene == scene:
                    values.append(s.value)
                    sigma.append(s.sigma)
                    labels += sky_labels(s)
        return np.concatenate(values), np.concatenate(sigma), labels

    def jacobian(
        self,
        table: Table,
        base: np.ndarray,
        parameters: Sequence[str],
        steps: np.ndarray,
        report: Reporter,
    ) -> np.ndarray:
        """d(values)/d(parameters), shape (n_samples, n_parameters): the table moved
        along its exact derivatives, the sky by finite differences (module docstring)."""
        columns = []
        for p, h in zip(parameters, steps.tolist()):
            plus = self.values(_moved(table, p, h), report)
            if self.settings.central_differences:
                minus = self.values(_moved(table, p, -h), report)
                columns.append((plus - minus) / (2.0 * h))
            else:
                columns.append((plus - base) / h)
        return np.column_stack(columns)


def _moved(table: Table, parameter: str, h: float) -> Table:
    """The table's optics moved by ``h`` along its derivatives with respect to ``parameter``."""
    assert table.cross_sections is not None
    return table.replace(
        phase=table.phase + h * table.derivative("phase", parameter),
        cross_sections={
            "cext_um2": table.cross_sections.cext_um2 + h * table.derivative("cext_um2", parameter),
            "csca_um2": table.cross_sections.csca_um2 + h * table.derivative("csca_um2", parameter),
        },
        g=table.g + h * table.derivative("g", parameter),
        derivatives=None,
    )


def sky_progress(stream: TextIO | None) -> Reporter:
    """The reporter of the sky solves of a retrieval."""
    return Reporter(stream, label="retrieve: sky")
