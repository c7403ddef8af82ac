"""Which published Mars dust puts the sky inside the rovers' colour range.

The Mars Exploration Rovers measured the sky's chromaticity (Bell, Savransky
& Wolff 2006: means x = 0.396-0.408, y = 0.377-0.383,
:data:`~dustoptics.sky.compare.MER_SKY_CHROMATICITY`).
:func:`search_mer_dust` renders the sky for every combination of published
dust properties on a small grid (:data:`PUBLISHED_DUSTS`: refractive index or
hematite fraction with a size distribution; :data:`PUBLISHED_OPTICAL_DEPTHS`;
:data:`PUBLISHED_GROUND_ALBEDOS`) and the comparison's geometry (looking away
from the Sun at 30 deg elevation, :data:`SEARCH_SUN_ELEVATIONS_DEG`), and
tells which fall inside the range and how far the others are.  It is a search
over published values, not a fit: a fit is issue 30's retrieval.

Cost: one Mie table per dust (a few seconds) and one solve of the orders of
scattering per optical depth, ground albedo and Sun elevation (seconds each
on one core); the number of skies is counted before any work and bounded by
:data:`MAX_SKIES` unless ``allow_large``.  ``scripts/mer_dust_search.py``
runs the default grid and writes the table the docs include.

References
----------
.. [1] J. F. Bell III, D. Savransky and M. J. Wolff, J. Geophys. Res. 111(E12)
   (2006), doi:10.1029/2006JE002687 (the rovers' sky chromaticity).
.. [2] M. J. Wolff et al., J. Geophys. Res. 114, E00D04 (2009),
   doi:10.1029/2009JE003350 (dust refractive index; r_eff 1.5 um, v_eff 0.3).
.. [3] M. G. Tomasko, L. R. Doose, M. Lemmon, P. H. Smith and E. Wegryn,
   J. Geophys. Res. 104(E4), 8987-9007 (1999), doi:10.1029/1998JE900016
   (r_eff 1.6 um, v_eff 0.2).
.. [4] K. Ehlers, R. Chakrabarty and H. Moosmüller, Appl. Opt. 53(9),
   1808-1819 (2014), doi:10.1364/AO.53.001808 (3 % hematite in n = 1.5).
.. [5] M. T. Lemmon et al., Science 306, 1753-1756 (2004),
   doi:10.1126/science.1104474, and Icarus 251, 96-111 (2015),
   doi:10.1016/j.icarus.2014.03.029 (the rovers' optical depths).
.. [6] P. R. Christensen et al., J. Geophys. Res. 106(E10), 23823-23871
   (2001), doi:10.1029/2000JE001370 (surface albedo, about 0.1-0.3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, TextIO

from dustoptics._validation import BudgetError, check_closed_interval, check_positive
from dustoptics.atmosphere.sets import mars_atmosphere
from dustoptics.particles.mixing import mars_dust
from dustoptics.particles.sizedist import ModifiedGamma
from dustoptics.scattering.optics import compute_optics
from dustoptics.sky._progress import Reporter, reporter
from dustoptics.sky.compare import (
    COMPARISON_WAVELENGTHS_NM,
    MER_SKY_CHROMATICITY,
    _away_chromaticity,
    _grid,
    _signed,
    _verdict,
    mer_distance,
)
from dustoptics.sky.medium import Medium
from dustoptics.table import Table

__all__ = [
    "MAX_SKIES",
    "PUBLISHED_DUSTS",
    "PUBLISHED_GROUND_ALBEDOS",
    "PUBLISHED_OPTICAL_DEPTHS",
    "SEARCH_SUN_ELEVATIONS_DEG",
    "MerDust",
    "MerDustRow",
    "MerDustSearch",
    "search_mer_dust",
]

_WOLFF_2009 = "Wolff et al. 2009, JGR 114, E00D04"
_TOMASKO_1999 = "Tomasko et al. 1999, JGR 104, 8987"
_EHLERS_2014 = "Ehlers et al. 2014, Appl. Opt. 53, 1808 (Querry 1985 hematite)"


@dataclass(frozen=True)
class MerDust:
    """A published Mars dust: refractive index (or hematite mixture) and sizes.

    Attributes
    ----------
    name : str
        Short label.
    host_index : str or float
        The host's index: a catalogue name (``"marsdust-wolff2009"``) or a real
        index (1.5). [-]
    hematite_fraction : float
        Volume fraction of hematite (Querry 1985, extraordinary ray) mixed in
        by Maxwell Garnett. [-]
    r_eff_um : float
        Effective radius of the modified gamma distribution. [um]
    v_eff : float
        Effective variance. [-]
    sources : str
        Where the index and the sizes come from.
    """

    name: str
    host_index: str | float
    hematite_fraction: float
    r_eff_um: float
    v_eff: float
    sources: str

    def table(self, wavelength_nm: tuple[float, ...]) -> Table:
        """Its Mie optics (cross-section weighted) on ``wavelength_nm``."""
        index = mars_dust(hematite_fraction=self.hematite_fraction, host_index=self.host_index)
        return compute_optics(
            index,
            ModifiedGamma(r_eff_um=self.r_eff_um, v_eff=self.v_eff),
            wavelength_nm=list(wavelength_nm),
            name=self.name,
        )


#: The dusts searched: two indices (Wolff et al. 2009's retrieved dust; the
#: Blue Moon's 3 % hematite in n = 1.5) with two size distributions (Wolff et
#: al. 2009's r_eff 1.5 um, v_eff 0.3; Tomasko et al. 1999's 1.6 um, 0.2).
PUBLISHED_DUSTS: Final = (
    MerDust("wolff2009", "marsdust-wolff2009", 0.0, 1.5, 0.3, f"index, sizes: {_WOLFF_2009}"),
    MerDust(
        "wolff2009-tomasko-sizes",
        "marsdust-wolff2009",
        0.0,
        1.6,
        0.2,
        f"index: {_WOLFF_2009}; sizes: {_TOMASKO_1999}",
    ),
    MerDust("blue-moons", 1.5, 0.03, 1.6, 0.2, f"index: {_EHLERS_2014}; sizes: {_TOMASKO_1999}"),
    MerDust(
        "blue-moons-wolff-sizes",
        1.5,
        0.03,
        1.5,
        0.3,
        f"index: {_EHLERS_2014}; sizes: {_WOLFF_2009}",
    ),
)
#: Vertical dust optical depths at 550 nm: the rovers' record outside dust
#: storms (Lemmon et al. 2004, 2015). [-]
PUBLISHED_OPTICAL_DEPTHS: Final = (0.3, 0.5, 1.0, 1.5)
#: Lambertian ground albedos: Mars's surface, about 0.1-0.3 (Christensen et al. 2001). [-]
PUBLISHED_GROUND_ALBEDOS: Final = (0.2, 0.3)
#: Sun elevations: mid-morning and near noon, when the rovers' surveys were taken. [deg]
SEARCH_SUN_ELEVATIONS_DEG: Final = (30.0, 60.0)
#: Largest number of skies without ``allow_large`` (about 10 s each on a busy core).
MAX_SKIES: Final = 200


@dataclass(frozen=True)
class MerDustRow:
    """One dust, optical depth, ground albedo and Sun elevation, against the range.

    Attributes
    ----------
    dust : MerDust
        The dust.
    optical_depth : float
        Vertical dust optical depth at 550 nm. [-]
    ground_albedo : float
        Lambertian ground albedo. [-]
    sun_elevation_deg : float
        Sun elevation. [deg]
    x, y : float
        CIE 1931 chromaticity looking away from the Sun, view elevation 30 deg. [-]
    dx, dy : float
        Distance outside the rovers' range per coordinate, 0 inside
        (:func:`~dustoptics.sky.compare.mer_distance`). [-]
    """

    dust: MerDust
    optical_depth: float
    ground_albedo: float
    sun_elevation_deg: float
    x: float
    y: float
    dx: float
    dy: float

    @property
    def distance(self) -> float:
        """Distance to the range in the (x, y) plane, 0 inside. [-]"""
        return math.hypot(self.dx, self.dy)


@dataclass(frozen=True)
class MerDustSearch:
    """The result of :func:`search_mer_dust`.

    Attributes
    ----------
    rows : tuple of MerDustRow
        Every combination searched, in search order.
    """

    rows: tuple[MerDustRow, ...]

    @property
    def inside(self) -> tuple[MerDustRow, ...]:
        """The rows inside the rovers' range."""
        return tuple(r for r in self.rows if r.distance == 0.0)

    @property
    def closest(self) -> MerDustRow:
        """The row nearest to the range (the first of equals)."""
        return min(self.rows, key=lambda r: r.distance)

    def to_text(self) -> str:
        """Every row as a plain-text table, then the dusts' sources and the verdict."""
        x0, x1 = MER_SKY_CHROMATICITY["x"]
        y0, y1 = MER_SKY_CHROMATICITY["y"]
        width = max(len(r.dust.name) for r in self.rows)
        lines = [
            f"MER sky chromaticity range x {x0:.3f}-{x1:.3f}, y {y0:.3f}-{y1:.3f} "
            "(Bell, Savransky & Wolff 2006); looking away from the Sun at 30 degree elevation",
            f"{'dust':<{width}}  tau550  albedo  Sun [deg]       x       y  distance",
        ]
        for r in self.rows:
            lines.append(
                f"{r.dust.name:<{width}}  {r.optical_depth:6.2f}  {r.ground_albedo:6.2f}  "
                f"{r.sun_elevation_deg:9.1f}  {r.x:.4f}  {r.y:.4f}  "
                + (
                    "inside"
                    if r.distance == 0.0
                    else f"{_signed(r.distance)[1:]} ({_verdict(r.dx, r.dy)})"
                )
            )
        lines.append("dusts:")
        seen: list[str] = []
        for r in self.rows:
            if r.dust.name not in seen:
                seen.append(r.dust.name)
                d = r.dust
                host = d.host_index if isinstance(d.host_index, str) else f"n = {d.host_index:g}"
                lines.append(
                    f"  {d.name}: {host}, hematite {d.hematite_fraction:g}, r_eff {d.r_eff_um:g} "
                    f"um, v_eff {d.v_eff:g} ({d.sources})"
                )
        n_in = len(self.inside)
        c = self.closest
        lines.append(
            f"{n_in} of {len(self.rows)} inside the range"
            + (
                ""
                if n_in
                else f"; closest: {c.dust.name}, tau {c.optical_depth:g}, albedo "
                f"{c.ground_albedo:g}, Sun {c.sun_elevation_deg:g} degree, "
                f"{_signed(c.distance)[1:]} away"
            )
        )
        return "\n".join(lines)


def search_mer_dust(
    *,
    dusts: tuple[MerDust, ...] = PUBLISHED_DUSTS,
    optical_depths: tuple[float, ...] = PUBLISHED_OPTICAL_DEPTHS,
    ground_albedos: tuple[float, ...] = PUBLISHED_GROUND_ALBEDOS,
    sun_elevations_deg: tuple[float, ...] = SEARCH_SUN_ELEVATIONS_DEG,
    tol: float = 1e-4,
    progress: TextIO | Reporter | None = None,
    allow_large: bool = False,
) -> MerDustSearch:
    """Render the sky for every published dust on the grid; compare with the rovers.

    Parameters
    ----------
    dusts : tuple of MerDust
        Dusts (default :data:`PUBLISHED_DUSTS`).
    optical_depths : tuple of float
        Vertical dust optical depths at 550 nm, > 0. [-]
    ground_albedos : tuple of float
        Lambertian ground albedos, 0 .. 1. [-]
    sun_elevations_deg : tuple of float
        Sun elevations, -10 .. 90. [deg]
    tol : float
        Tolerance of the orders of scattering. [-]
    progress : text stream, optional
        Where to report the dusts and skies done after the first two seconds
        (the number of skies is stated first); None is silent.
    allow_large : bool
        Go ahead with more than :data:`MAX_SKIES` skies.

    Returns
    -------
    MerDustSearch

    Raises
    ------
    dustoptics._validation.BudgetError
        More than :data:`MAX_SKIES` skies and ``allow_large`` is False (before any work).
    """
    if not dusts or not all(isinstance(d, MerDust) for d in dusts):
        raise ValueError(f"dusts must be a non-empty tuple of MerDust; got {dusts!r}")
    for tau in optical_depths:
        check_positive("optical_depths", tau)
    for a in ground_albedos:
        check_closed_interval("ground_albedos", a, 0.0, 1.0)
    for e in sun_elevations_deg:
        check_closed_interval("sun_elevations_deg", e, -10.0, 90.0)
    n_skies = len(dusts) * len(optical_depths) * len(ground_albedos) * len(sun_elevations_deg)
    if n_skies == 0:
        raise ValueError("optical_depths, ground_albedos and sun_elevations_deg must not be empty")
    if n_skies > MAX_SKIES and not allow_large:
        raise BudgetError(
            f"the search would render {n_skies} skies ({len(dusts)} dusts x "
            f"{len(optical_depths)} optical depths x {len(ground_albedos)} albedos x "
            f"{len(sun_elevations_deg)} Sun elevations), beyond the budget of {MAX_SKIES} "
            "(about 10 s each); search fewer values, or pass allow_large=True"
        )
    report = reporter(progress, label="mer search")
    if report.stream is not None:
        report.stream.write(
            f"mer search: {len(dusts)} Mie tables and {n_skies} skies, about {5 * n_skies} to "
            f"{10 * n_skies} s on one core\n"
        )
    grid = _grid(COMPARISON_WAVELENGTHS_NM)
    rows: list[MerDustRow] = []
    for dust in dusts:
        table = dust.table(grid)
        for tau in optical_depths:
            atm = mars_atmosphere(dust_table=table, optical_depth=float(tau), name="mars-search")
            medium = Medium.from_atmosphere(atm)
            for albedo in ground_albedos:
                for elev in sun_elevations_deg:
                    report(f"sky {len(rows) + 1} of {n_skies} ({dust.name}, tau {tau:g})")
                    xy, _ = _away_chromaticity(
                        medium,
                        float(elev),
                        ground_albedo=float(albedo),
                        tol=tol,
                        report=report,
                        allow_large=False,
                    )
                    x, y = float(xy[0]), float(xy[1])
                    rows.append(
                        MerDustRow(
                            dust, float(tau), float(albedo), float(elev), x, y, *mer_distance(x, y)
                        )
                    )
    report(f"{n_skies} skies done", last=True)
    return MerDustSearch(rows=tuple(rows))
