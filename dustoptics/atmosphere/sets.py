"""Complete atmospheres for renderers: molecules, aerosols, ozone, densities.

An :class:`Atmosphere` is a planet (radius, atmosphere top, Sun distance,
refractivity) and its constituents, each a :class:`Constituent`: a
:class:`~dustoptics.table.Table` whose ``number_density_per_m3`` is the number
density where the constituent's relative density is 1, and a
:class:`~dustoptics.atmosphere.column.DensityProfile`.
:func:`dustoptics.io.csv.cosmoscout.write_atmosphere` writes it as CosmoScout
VR's CSV set plus the settings JSON that points CosmoScout's Bruneton
preprocessor at the files.

Builders (the presets of the seeds)
-----------------------------------
:func:`mars_atmosphere`
    CO2 molecules (``"costa2021-mars"``: Bideau-Mehu 1973 CO2 at 610 Pa and
    215 K, King factor with delta = 0.09, Penndorf phase function; or
    ``"collienne2013"``: Collienne et al.'s three coefficients) and a dust
    table computed by the caller (any dust preset), whose number density is
    set from a measured optical depth at a reference wavelength.
:func:`earth_atmosphere`
    Air molecules (``"bodhaine1999"``: Bodhaine et al. 1999's dry air at 360
    ppm CO2, whose optical depth is their eq. 30, by default; ``"penndorf1957"``,
    standard air with one King factor, 0.7-1.2 % more optical depth;
    ``"costa2021"`` or ``"kobe2026"``), aerosols (one of OPAC's types
    by :mod:`~dustoptics.atmosphere.aerosols`, by default the continental
    average at optical depth 0.1 at 550 nm, a typical clear day; Kobe's
    constant coefficients; or any table) and ozone (the shipped Serdyuchenko et al. 2014
    spectrum in Bruneton's layer by default, or any
    :class:`~dustoptics.atmosphere.gases.OzoneCrossSection` with any profile),
    on CosmoScout VR's 15 wavelengths 360-830 nm by default.
:func:`earth_atmosphere_kobe2026`
    Kobe's Earth on his three wavelengths 475, 510, 650 nm (his air without
    the King factor, his three ozone cross-sections at 6e-7 of the air).

Planet settings (the seeds' renderer configurations and CosmoScout VR's)
------------------------------------------------------------------------
Mars: radius 3390 km, atmosphere top 3510 km (the seeds' renderer), molecule
scale height 8 km and dust scale height 11.1 km (Costa et al. 2021, Table 1),
Sun distance 227.9e9 m (CosmoScout VR's ``mars.json``; its irradiance is
(1 AU / 1.524 AU)^2 = 0.43 of Earth's, the seeds' "sun strength").
Earth: radius 6371 km, top 6451 km, Sun distance 149.6e9 m (CosmoScout VR's
``earth.json``).

References
----------
.. [1] German Aerospace Center (DLR), CosmoScout VR, plugin csp-atmospheres
   (bruneton-preprocessor settings, scattering-table-generator),
   https://github.com/cosmoscout/cosmoscout-vr.
.. [2] J. Costa et al., IEEE TVCG 27(2), 785-795 (2021),
   doi:10.1109/TVCG.2020.3030333, Table 1.
.. [3] D. Kobe, "Ozone absorption in single atmospheric scattering,"
   graduation work, Howest DAE, 2025-2026, sections 10.4, 11.3, 11.5.
.. [4] T. Meyran, "Physically based real-time rendering of the Martian
   atmosphere," M.Sc. thesis, Hochschule Hannover, 2022.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from dustoptics._validation import as_increasing_grid, check_choice, check_positive
from dustoptics.atmosphere import aerosols as _aerosols
from dustoptics.atmosphere import gases
from dustoptics.atmosphere.column import (
    BRUNETON2017_OZONE,
    BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3,
    DensityProfile,
    ExponentialProfile,
    FixedFractionProfile,
    number_density_from_optical_depth,
    sample_profile,
)
from dustoptics.scattering import phase as _phase
from dustoptics.scattering import tabulated_phase as _tabulated
from dustoptics.table import CrossSections, Provenance, Source, Table

__all__ = [
    "CONSTITUENT_ROLES",
    "COSMOSCOUT_WAVELENGTHS_NM",
    "DEFAULT_EARTH_AEROSOL",
    "DEFAULT_EARTH_AEROSOL_OPTICAL_DEPTH",
    "EARTH_AEROSOLS",
    "EARTH_AEROSOL_OPTICAL_DEPTH_RANGE",
    "EARTH_MOLECULE_MODELS",
    "EARTH_WAVELENGTHS_NM",
    "KOBE2026_AEROSOL_BETA_SCA_PER_M",
    "KOBE2026_WAVELENGTHS_NM",
    "MARS_MOLECULE_MODELS",
    "RGB_WAVELENGTHS_NM",
    "Atmosphere",
    "Constituent",
    "check_earth_aerosol",
    "earth_atmosphere",
    "earth_atmosphere_kobe2026",
    "mars_atmosphere",
    "with_optical_depth",
]

#: Roles CosmoScout VR's Bruneton model has: two scattering media and one absorbing.
CONSTITUENT_ROLES: Final = ("molecules", "aerosols", "ozone")

#: Molecule models of :func:`mars_atmosphere`.
MARS_MOLECULE_MODELS: Final = ("costa2021-mars", "collienne2013")
#: Molecule models of :func:`earth_atmosphere`.
EARTH_MOLECULE_MODELS: Final = ("kobe2026", "costa2021", "penndorf1957", "bodhaine1999")

#: Molecule scale heights by model. [m]  Kobe: 7994 m (his section 10.4.1);
#: Costa Earth: 7995.75 m (ICAO, their Table 1); Penndorf: 8000 m (Bruneton's
#: models); Mars: 8000 m (Costa et al. Table 1).
_MOLECULE_SCALE_HEIGHT_M: Final = {
    "kobe2026": 7994.0,
    "costa2021": 7995.75,
    "penndorf1957": 8000.0,
    "bodhaine1999": 8000.0,
    "costa2021-mars": 8000.0,
    "collienne2013": 8000.0,
}

#: Aerosols of :func:`earth_atmosphere` by name: OPAC's types (Hess et al. 1998) and Kobe's.
EARTH_AEROSOLS: Final = (*_aerosols.AEROSOL_TYPES, "kobe2026")
#: The default Earth's aerosols: OPAC's continental average (land with human influence,
#: the commonest setting of an observer on Earth; Angstrom exponent 1.42 at 500-800 nm,
#: near the 1.3 of Angstrom's and Preetham's standard atmosphere).
DEFAULT_EARTH_AEROSOL: Final = "continental-average"
#: Its vertical optical depth at 550 nm: a typical clear day (Preetham's turbidity 2 gives
#: 0.1007; the CIE clear sky, type 12, is met at this depth: see the sky documentation). [-]
DEFAULT_EARTH_AEROSOL_OPTICAL_DEPTH: Final = 0.1
#: Aerosol optical depths :func:`earth_atmosphere` accepts: (0, 5], 5 being a dense dust storm
#: or smoke plume (no clear-sky reference reaches beyond). [-]
EARTH_AEROSOL_OPTICAL_DEPTH_RANGE: Final = (0.0, 5.0)

#: Kobe's aerosol scattering coefficient (after Bruneton & Neyret and Bodare &
#: Sandberg), wavelength independent; extinction is ``beta_sca / 0.9``. [m^-1]
KOBE2026_AEROSOL_BETA_SCA_PER_M: Final = 2e-6

_MARS_RADIUS_M: Final = 3390e3
_MARS_TOP_M: Final = 3510e3
_MARS_SUN_DISTANCE_M: Final = 227.9e9
_EARTH_RADIUS_M: Final = 6371e3
_EARTH_TOP_M: Final = 6451e3
_EARTH_SUN_DISTANCE_M: Final = 149.6e9
_N_ALTITUDES: Final = 1024

#: CosmoScout VR's default wavelengths: 15 evenly spaced from 360 to 830 nm. [nm]
COSMOSCOUT_WAVELENGTHS_NM: Final = tuple(np.linspace(360.0, 830.0, 15).tolist())

#: The Earth set's wavelengths: 48 evenly spaced from 360 to 830 nm (Bruneton's), a
#: multiple of three (CosmoScout's preprocessor runs passes of three) that holds the
#: RGB wavelengths :data:`RGB_WAVELENGTHS_NM` exactly, so that an engine rendering
#: them reads the set's own optics there (15 wavelengths put 440 nm between samples:
#: interpolated, the molecules' extinction is 1.4 % and the ozone's 21 % off). [nm]
EARTH_WAVELENGTHS_NM: Final = tuple(float(w) for w in range(360, 831, 10))

#: The wavelengths engines render as red, green and blue (CosmoScout VR's three-wavelength
#: mode, Bruneton's demo, the seed shader). [nm]
RGB_WAVELENGTHS_NM: Final = (440.0, 550.0, 680.0)

#: Kobe's three wavelengths (his ozone cross-sections exist only there). [nm]
KOBE2026_WAVELENGTHS_NM: Final = (475.0, 510.0, 650.0)


@dataclass(frozen=True)
class Constituent:
    """One medium of an atmosphere.

    Attributes
    ----------
    role : {"molecules", "aerosols", "ozone"}
        Its slot in CosmoScout VR's model (ozone must not scatter).
    table : Table
        Optics with cross-sections and ``number_density_per_m3``, the number
        density where ``profile`` is 1. [m^-3]
    profile : DensityProfile
        Relative density over altitude.
    """

    role: str
    table: Table
    profile: DensityProfile

    def __post_init__(self) -> None:
        check_choice("role", self.role, CONSTITUENT_ROLES)
        if not isinstance(self.table, Table):
            raise TypeError(f"table must be a dustoptics Table; got {type(self.table).__name__}")
        if self.table.cross_sections is None or (
            self.table.cross_sections is None
            or self.table.cross_sections.number_density_per_m3 is None
        ):
            raise ValueError(
                f"constituent {self.role!r}: table {self.table.name!r} needs cross-sections and "
                "number_density_per_m3 (the density where the profile is 1)"
            )
        if not isinstance(self.profile, DensityProfile):
            raise TypeError(f"profile must be a DensityProfile; got {type(self.profile).__name__}")
        assert self.table.cross_sections is not None  # has_cross_sections
        if self.role == "ozone" and np.any(self.table.cross_sections.csca_um2 > 0):
            raise ValueError(
                f"constituent 'ozone' must not scatter (csca_um2 = 0); table {self.table.name!r} does"
            )


@dataclass(frozen=True)
class Atmosphere:
    """A planet's atmosphere as a renderer loads it.

    Attributes
    ----------
    name : str
        Prefix of the written files (letters, digits, ``.``, ``_``, ``-``).
    planet_radius_m : float
        Radius of the ground. [m]
    atmosphere_radius_m : float
        Radius of the top of the atmosphere, > planet radius. [m]
    constituents : tuple of Constituent
        One ``molecules``, one ``aerosols``, at most one ``ozone``; identical
        wavelengths.
    sun_distance_m : float
        Mean Sun distance (CosmoScout scales the solar irradiance by it). [m]
    refractivity : float
        ``n - 1`` of the air at the ground (CosmoScout's ``ior``, for
        refraction), at 550 nm. [-]
    n_altitudes : int
        Samples of each density profile in CosmoScout VR's density file
        (its default 1024), at the texel centres :attr:`density_altitudes_m`.
    rgb_optics : Atmosphere, optional
        The same atmosphere computed exactly at :data:`RGB_WAVELENGTHS_NM`
        (:func:`dustoptics.atmosphere.build.build_atmosphere` attaches it), so
        that an engine's error from the set's wavelength sampling can be
        stated (:func:`~dustoptics.io.engines.cosmoscout_preprocessor.cosmoscout_sampling`).
    """

    name: str
    planet_radius_m: float
    atmosphere_radius_m: float
    constituents: tuple[Constituent, ...]
    sun_distance_m: float
    refractivity: float
    n_altitudes: int = _N_ALTITUDES
    rgb_optics: Atmosphere | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name must be a non-empty string; got {self.name!r}")
        _depth_m(self.planet_radius_m, self.atmosphere_radius_m)
        check_positive("sun_distance_m", self.sun_distance_m, unit="m")
        if not (math.isfinite(self.refractivity) and self.refractivity >= 0.0):
            raise ValueError(
                f"refractivity (n - 1) must be finite and >= 0; got {self.refractivity!r}"
            )
        if (
            isinstance(self.n_altitudes, bool)
            or not isinstance(self.n_altitudes, int)
            or self.n_altitudes < 2
        ):
            raise ValueError(f"n_altitudes must be an integer >= 2; got {self.n_altitudes!r}")
        cons = tuple(self.constituents)
        roles = [c.role for c in cons if isinstance(c, Constituent)]
        if len(roles) != len(cons):
            raise TypeError("constituents must all be Constituent objects")
        for role, allowed in (("molecules", (1,)), ("aerosols", (1,)), ("ozone", (0, 1))):
            if roles.count(role) not in allowed:
                raise ValueError(
                    f"an atmosphere needs exactly one 'molecules', one 'aerosols' and at most one "
                    f"'ozone' constituent; got roles {roles}"
                )
        wl = cons[0].table.wavelength_nm
        for c in cons[1:]:
            if not np.array_equal(c.table.wavelength_nm, wl):
                raise ValueError(
                    f"constituent {c.role!r} has wavelengths {c.table.wavelength_nm.tolist()} nm; "
                    f"{cons[0].role!r} has {wl.tolist()} nm: all must be identical"
                )
        object.__setattr__(self, "constituents", cons)

    @property
    def thickness_m(self) -> float:
        """Atmosphere top above the ground. [m]"""
        return self.atmosphere_radius_m - self.planet_radius_m

    @property
    def density_altitudes_m(self) -> np.ndarray:
        """Altitudes of the density samples: the texel centres ``(i + 1/2) T / N``. [m]

        CosmoScout VR's preprocessor puts the N values of a density file into
        a linearly filtered texture that spans the thickness ``T`` and reads
        it at ``u = altitude / T``, so value ``i`` stands at the centre of
        texel ``i``; samples taken there are read back where they belong
        (samples at ``i T / (N - 1)`` would be read half a texel too high).
        """
        n = self.n_altitudes
        return (np.arange(n) + 0.5) * (self.thickness_m / n)

    @property
    def wavelength_nm(self) -> np.ndarray:
        """The shared wavelengths. [nm]"""
        return self.constituents[0].table.wavelength_nm

    def constituent(self, role: str) -> Constituent:
        """The constituent with that role (``KeyError`` if absent)."""
        for c in self.constituents:
            if c.role == role:
                return c
        raise KeyError(f"atmosphere {self.name!r} has no {role!r} constituent")

    def file_prefix(self, role: str) -> str:
        """File-name prefix of a constituent: ``<name>_<role>``."""
        return f"{self.name}_{role}"

    def cosmoscout_constituents(self) -> dict[str, tuple[Table, np.ndarray]]:
        """Mapping for :func:`~dustoptics.io.csv.cosmoscout.write_cosmoscout_set`.

        Each profile is sampled at the :attr:`n_altitudes` texel centres
        :attr:`density_altitudes_m` (where CosmoScout VR's preprocessor reads
        the values) and rescaled to a largest sample of 1; the table's number
        density is multiplied by the same factor, so ``beta`` times the written
        density is the constituent's coefficient at every sampled altitude.
        """
        out: dict[str, tuple[Table, np.ndarray]] = {}
        half_texel = 0.5 * self.thickness_m / self.n_altitudes
        for c in self.constituents:
            s = sample_profile(
                c.profile,
                bottom_altitude_m=half_texel,
                top_altitude_m=self.thickness_m - half_texel,
                n_altitudes=self.n_altitudes,
            )
            table = c.table
            if s.peak != 1.0:
                assert (
                    table.cross_sections is not None
                    and table.cross_sections.number_density_per_m3 is not None
                )  # checked by the constituent
                table = table.replace(
                    cross_sections={
                        "number_density_per_m3": table.cross_sections.number_density_per_m3 * s.peak
                    }
                )
            out[self.file_prefix(c.role)] = (table, np.array(s.relative_density))
        return out


# ---------------------------------------------------------------- builders


def with_optical_depth(
    table: Table,
    *,
    optical_depth: float,
    reference_wavelength_nm: float,
    profile: DensityProfile,
    top_altitude_m: float,
    reference_cext_um2: float | None = None,
) -> Table:
    """The table with the number density that gives a vertical optical depth.

    ``N0 = tau / (<C_ext>(lambda_ref) L)`` with ``L`` the profile's column
    length up to ``top_altitude_m``
    (:func:`~dustoptics.atmosphere.column.number_density_from_optical_depth`).
    The optical depth, its wavelength, ``<C_ext>`` there, the profile and the
    column top are recorded in the provenance (``inputs["column"]`` and a
    note), so the file says where its number density came from.

    Parameters
    ----------
    table : Table
        A table with cross-sections.
    optical_depth : float
        Vertical optical depth at ``reference_wavelength_nm``, > 0. [-]
    reference_wavelength_nm : float
        Within the table's wavelengths; ``<C_ext>`` is read linearly between
        rows unless ``reference_cext_um2`` gives it. [nm]
    profile : DensityProfile
        The constituent's relative density profile.
    top_altitude_m : float
        Top of the column above the surface. [m]
    reference_cext_um2 : float, optional
        ``<C_ext>`` at the reference wavelength, computed exactly there. [um^2]

    Returns
    -------
    Table
    """
    tau = check_positive("optical_depth", optical_depth)
    cext = (
        _cext_at(table, reference_wavelength_nm)
        if reference_cext_um2 is None
        else check_positive("reference_cext_um2", reference_cext_um2, unit="um^2")
    )
    n0 = number_density_from_optical_depth(
        optical_depth=tau, cext_um2=cext, profile=profile, top_altitude_m=top_altitude_m
    )
    column = {
        "optical_depth": tau,
        "reference_wavelength_nm": float(reference_wavelength_nm),
        "reference_cext_um2": cext,
        "cext_source": "given (computed at the reference wavelength)"
        if reference_cext_um2 is not None
        else "the table's rows, linear in wavelength",
        "profile": repr(profile),
        "top_altitude_m": float(top_altitude_m),
        "number_density_per_m3": n0,
    }
    prov = table.provenance
    note = (
        f"number density {n0:.6g} m^-3 from vertical optical depth {tau:g} at "
        f"{float(reference_wavelength_nm):g} nm (<C_ext> = {cext:.6g} um^2, {profile!r}, "
        f"column top {float(top_altitude_m):g} m)"
    )
    provenance = Provenance(
        inputs={**prov.inputs, "column": column},
        sources=prov.sources,
        software=prov.software,
        quadrature=prov.quadrature,
        notes=(*prov.notes, note),
    )
    return table.replace(cross_sections={"number_density_per_m3": n0}, provenance=provenance)


def _cext_at(table: Table, wavelength_nm: float) -> float:
    wl = table.wavelength_nm
    w = check_positive("reference_wavelength_nm", wavelength_nm, unit="nm")
    if not wl[0] <= w <= wl[-1]:
        raise ValueError(
            f"reference_wavelength_nm must lie within the table's wavelengths [{wl[0]:g}, {wl[-1]:g}] nm "
            f"(no extrapolation); got {wavelength_nm!r}"
        )
    if table.cross_sections is None:
        raise ValueError(f"table {table.name!r} holds a phase function only; it needs cext_um2")
    return float(np.interp(w, wl, table.cross_sections.cext_um2))


def _depth_m(planet_radius_m: float, atmosphere_radius_m: float) -> float:
    """The atmosphere's depth, checked: both radii > 0, the atmosphere's the larger. [m]"""
    r = check_positive("planet_radius_m", planet_radius_m, unit="m")
    top = check_positive("atmosphere_radius_m", atmosphere_radius_m, unit="m")
    if top <= r:
        raise ValueError(
            f"atmosphere_radius_m must exceed planet_radius_m ({r!r} m); got {atmosphere_radius_m!r}"
        )
    return top - r


def _molecules(
    model: str | gases.RayleighModel,
    allowed: tuple[str, ...],
    wl: np.ndarray,
    scale_height_m: float | None,
) -> tuple[Constituent, float]:
    """The molecules (exponential profile; default scale height the model's, else 8 km) and
    their ground refractivity at 550 nm."""
    if not isinstance(model, gases.RayleighModel):
        check_choice("molecules", model, allowed)
    if model == "collienne2013":
        table = gases.collienne2013_table(wl, name="collienne2013-molecules")
        name, refractivity = model, gases.get_rayleigh_model("costa2021-mars").refractivity(550.0)
    else:
        gas = gases.get_rayleigh_model(model) if isinstance(model, str) else model
        table, name, refractivity = gas.table(wl), gas.name, gas.refractivity(550.0)
    if scale_height_m is None:
        scale_height_m = _MOLECULE_SCALE_HEIGHT_M.get(name, 8000.0)
    profile = ExponentialProfile(scale_height_m=scale_height_m)
    return Constituent(role="molecules", table=table, profile=profile), float(refractivity)


def mars_atmosphere(
    *,
    dust_table: Table,
    optical_depth: float = 0.5,
    reference_wavelength_nm: float = 550.0,
    reference_cext_um2: float | None = None,
    dust_scale_height_m: float = 11100.0,
    dust_profile: DensityProfile | None = None,
    molecules: str | gases.RayleighModel = "costa2021-mars",
    molecules_scale_height_m: float | None = None,
    planet_radius_m: float = _MARS_RADIUS_M,
    atmosphere_radius_m: float = _MARS_TOP_M,
    name: str = "mars",
) -> Atmosphere:
    """Mars: CO2 molecules and a dust table scaled to a measured optical depth.

    Parameters
    ----------
    dust_table : Table
        Dust optics with cross-sections (e.g. from
        :func:`dustoptics.scattering.optics.compute_optics`);
        its wavelengths are the atmosphere's.
    optical_depth : float, default 0.5
        Vertical dust optical depth at ``reference_wavelength_nm`` (clear
        seasons 0.3-1, MER), > 0. [-]
    reference_wavelength_nm : float, default 550
        Wavelength of the measured optical depth, within the table's range
        (linear interpolation of ``cext_um2`` unless ``reference_cext_um2``
        is given). [nm]
    reference_cext_um2 : float, optional
        The dust's <C_ext> computed at ``reference_wavelength_nm`` (exact,
        where the table's grid does not hold that wavelength). [um^2]
    dust_scale_height_m : float, default 11100
        Exponential dust profile (Costa et al. Table 1: 11.1 km). [m]
    dust_profile : DensityProfile, optional
        Any other dust profile (then ``dust_scale_height_m`` is ignored).
    molecules : {"costa2021-mars", "collienne2013"} or RayleighModel
        Molecule model (see :mod:`dustoptics.atmosphere.gases`).
    molecules_scale_height_m : float, optional
        Default 8000 m (Costa et al. Table 1). [m]
    planet_radius_m, atmosphere_radius_m : float
        Default 3390 km and 3510 km (the seeds' renderer). [m]
    name : str, default "mars"
        File prefix.

    Returns
    -------
    Atmosphere
        The dust number density is ``N0 = tau / (<C_ext> L)`` with ``L`` the
        dust column length up to the atmosphere top, so the rendered column
        has exactly the given optical depth.
    """
    if not isinstance(dust_table, Table):
        raise TypeError(f"dust_table must be a Table; got {type(dust_table).__name__}")
    wl = dust_table.wavelength_nm
    top = _depth_m(planet_radius_m, atmosphere_radius_m)
    profile = (
        dust_profile
        if dust_profile is not None
        else ExponentialProfile(scale_height_m=dust_scale_height_m)
    )
    dust = with_optical_depth(
        dust_table,
        optical_depth=optical_depth,
        reference_wavelength_nm=reference_wavelength_nm,
        reference_cext_um2=reference_cext_um2,
        profile=profile,
        top_altitude_m=top,
    )
    mols, refractivity = _molecules(molecules, MARS_MOLECULE_MODELS, wl, molecules_scale_height_m)
    return Atmosphere(
        name=name,
        planet_radius_m=planet_radius_m,
        atmosphere_radius_m=atmosphere_radius_m,
        constituents=(
            mols,
            Constituent(role="aerosols", table=dust, profile=profile),
        ),
        sun_distance_m=_MARS_SUN_DISTANCE_M,
        refractivity=refractivity,
    )


def _kobe_aerosols(wl: np.ndarray, *, g: float) -> Table:
    theta = np.linspace(0.0, 180.0, 1801)
    p = _tabulated.renormalize(
        np.broadcast_to(
            _tabulated.tabulate(_phase.cornette_shanks1992, theta_deg=theta, g=g),
            (wl.size, theta.size),
        ),
        theta_deg=theta,
    )
    beta_sca = np.full(wl.size, KOBE2026_AEROSOL_BETA_SCA_PER_M)
    return Table(
        name="kobe2026-aerosols",
        wavelength_nm=wl,
        theta_deg=theta,
        phase=p,
        g=np.full(wl.size, float(_phase.cornette_shanks1992_asymmetry(g=g))),
        cross_sections=CrossSections(
            cext_um2=beta_sca / 0.9 * 1e12, csca_um2=beta_sca * 1e12, number_density_per_m3=1.0
        ),
        provenance=Provenance(
            inputs={"kind": "kobe2026-aerosols", "wavelength_nm": wl, "cornette_shanks_g": g},
            sources=(
                Source(name="kobe2026", role="aerosol coefficients", citation=_phase.KOBE_2026),
                Source(
                    name="cornette_shanks1992",
                    role="phase function",
                    citation=_phase.CORNETTE_SHANKS_1992,
                ),
            ),
            notes=(
                (
                    "Kobe's beta_M = 2e-6 m^-1 and beta_M^e = beta_M / 0.9, published without a number "
                    "density: carried per unit density (number_density_per_m3 = 1, cross-section = beta)."
                ),
                (
                    "Phase function: Cornette-Shanks, g = 0.76 by default (Bruneton 2008's Earth aerosols "
                    "as CosmoScout VR reproduces them), not Kobe's Henyey-Greenstein g = -0.99 (his "
                    "sign convention for the angle)."
                ),
            ),
        ),
    )


_SHIPPED_OZONE: Final = "serdyuchenko2014"


def _check_aerosol_optical_depth(value: float) -> float:
    low, high = EARTH_AEROSOL_OPTICAL_DEPTH_RANGE
    if isinstance(value, bool) or not (isinstance(value, (int, float)) and low < value <= high):
        raise ValueError(f"aerosol_optical_depth must be > {low:g} and <= {high:g}; got {value!r}")
    return float(value)


def check_earth_aerosol(
    *,
    aerosol: str | None = None,
    aerosol_optical_depth: float | None = None,
    aerosol_reference_nm: float = 550.0,
    turbidity: float | None = None,
    aerosol_relative_humidity_percent: int = _aerosols.DEFAULT_RELATIVE_HUMIDITY_PERCENT,
    has_table: bool = False,
) -> tuple[str | None, float | None]:
    """Check :func:`earth_atmosphere`'s aerosol keywords without any work.

    Parameters
    ----------
    aerosol, aerosol_optical_depth, aerosol_reference_nm, turbidity, aerosol_relative_humidity_percent
        As for :func:`earth_atmosphere`.
    has_table : bool, default False
        Whether an ``aerosol_table`` is given too.

    Returns
    -------
    (str or None, float or None)
        The aerosols' name (None for a given table) and the vertical optical
        depth at ``aerosol_reference_nm`` they are set to (None: their own).

    Raises
    ------
    ValueError
        An unknown name, an optical depth, turbidity, humidity or reference
        wavelength out of range, or both an optical depth and a turbidity.
    """
    if aerosol is not None and has_table:
        raise ValueError(
            f"give aerosol (a name) or aerosol_table (a Table), not both; got aerosol={aerosol!r} and a table"
        )
    if aerosol_optical_depth is not None and turbidity is not None:
        raise ValueError(
            "give aerosol_optical_depth or turbidity, not both; got "
            f"aerosol_optical_depth={aerosol_optical_depth!r} and turbidity={turbidity!r}"
        )
    name = aerosol if aerosol is not None or has_table else DEFAULT_EARTH_AEROSOL
    opac = name is not None and name != "kobe2026"
    if name is not None:
        check_choice("aerosol", name, EARTH_AEROSOLS)
    ref = check_positive("aerosol_reference_nm", aerosol_reference_nm, unit="nm")
    if opac and not 250.0 <= ref <= 2500.0:
        raise ValueError(
            f"aerosol_reference_nm must lie within OPAC's 250-2500 nm; got {aerosol_reference_nm!r}"
        )
    if opac:
        _aerosols._check_humidity(aerosol_relative_humidity_percent)
    if turbidity is not None:
        return name, _check_aerosol_optical_depth(
            _aerosols.preetham_optical_depth(turbidity, wavelength_nm=ref)
        )
    if aerosol_optical_depth is not None:
        return name, _check_aerosol_optical_depth(aerosol_optical_depth)
    return name, DEFAULT_EARTH_AEROSOL_OPTICAL_DEPTH if opac else None


def _earth_aerosols(
    wl: np.ndarray,
    *,
    aerosol: str | None,
    aerosol_table: Table | None,
    optical_depth: float | None,
    reference_nm: float,
    turbidity: float | None,
    relative_humidity_percent: int,
    profile: DensityProfile | None,
    g: float,
    top_altitude_m: float,
) -> tuple[Table, DensityProfile]:
    """The aerosols' table, at their optical depth, and profile (checked before any work)."""
    if aerosol_table is not None and not isinstance(aerosol_table, Table):
        raise TypeError(f"aerosol_table must be a Table; got {type(aerosol_table).__name__}")
    name, tau = check_earth_aerosol(
        aerosol=aerosol,
        aerosol_optical_depth=optical_depth,
        aerosol_reference_nm=reference_nm,
        turbidity=turbidity,
        aerosol_relative_humidity_percent=relative_humidity_percent,
        has_table=aerosol_table is not None,
    )
    opac = name is not None and name != "kobe2026"
    ref = float(reference_nm)
    if not opac and tau is not None and not wl[0] <= ref <= wl[-1]:
        raise ValueError(
            f"aerosol_reference_nm must lie within the wavelengths [{wl[0]:g}, {wl[-1]:g}] nm "
            f"(Kobe's aerosols and a given table are read there); got {reference_nm!r}"
        )
    reference_cext: float | None = None
    if aerosol_table is not None:
        table = aerosol_table
    elif opac:
        assert name is not None
        table = _aerosols.aerosol_table(
            name, wavelength_nm=wl, relative_humidity_percent=relative_humidity_percent
        )
        if ref not in wl:
            at_ref = _aerosols.aerosol_table(
                name,
                wavelength_nm=[ref],
                relative_humidity_percent=relative_humidity_percent,
                theta_deg=[0.0, 180.0],
            )
            assert at_ref.cross_sections is not None  # Mie computes it
            reference_cext = float(at_ref.cross_sections.cext_um2[0])
    else:
        table = _kobe_aerosols(wl, g=g)
    if profile is None:
        profile = (
            _aerosols.AEROSOL_TYPES[name].profile
            if opac and name is not None
            else ExponentialProfile(scale_height_m=1200.0)
        )
    if tau is not None:
        table = with_optical_depth(
            table,
            optical_depth=tau,
            reference_wavelength_nm=ref,
            profile=profile,
            top_altitude_m=top_altitude_m,
            reference_cext_um2=reference_cext,
        )
    return table, profile


def earth_atmosphere(
    *,
    wavelength_nm: ArrayLike = COSMOSCOUT_WAVELENGTHS_NM,
    molecules: str | gases.RayleighModel = "bodhaine1999",
    molecules_scale_height_m: float | None = None,
    aerosol: str | None = None,
    aerosol_optical_depth: float | None = None,
    aerosol_reference_nm: float = 550.0,
    turbidity: float | None = None,
    aerosol_relative_humidity_percent: int = _aerosols.DEFAULT_RELATIVE_HUMIDITY_PERCENT,
    aerosol_table: Table | None = None,
    aerosol_profile: DensityProfile | None = None,
    aerosol_g: float = 0.76,
    ozone: gases.OzoneCrossSection | str | None = _SHIPPED_OZONE,
    ozone_profile: DensityProfile | None = None,
    ozone_number_density_per_m3: float | None = None,
    planet_radius_m: float = _EARTH_RADIUS_M,
    atmosphere_radius_m: float = _EARTH_TOP_M,
    name: str = "earth",
) -> Atmosphere:
    """Earth: air molecules, aerosols and (optionally) ozone.

    Parameters
    ----------
    wavelength_nm : array_like, default COSMOSCOUT_WAVELENGTHS_NM
        Strictly increasing wavelengths; CosmoScout VR's 15 from 360 to 830 nm
        by default. [nm]
    molecules : {"bodhaine1999", "penndorf1957", "costa2021", "kobe2026"} or RayleighModel
        Molecule model; default Bodhaine et al. 1999 (Peck & Reeder index,
        wavelength-dependent King factor of N2, O2, Ar and CO2 at 360 ppm),
        whose vertical optical depth is their eq. 30 to 1e-4 (tested);
        ``"penndorf1957"`` is standard air with one King factor (Edlén 1953
        index, delta = 0.035, 0 degC and 101325 Pa), within 3.1e-4 of
        Penndorf's 1957 table and 0.69 % (360 nm) to 1.17 % (830 nm) above
        Bodhaine's optical depth (:func:`~dustoptics.atmosphere.gases.rayleigh_optical_depth_difference`).
    molecules_scale_height_m : float, optional
        Default by model: 7994 m (Kobe), 7995.75 m (Costa), 8000 m. [m]
    aerosol : str, optional
        The aerosols by name (:data:`EARTH_AEROSOLS`): one of OPAC's types
        (:data:`~dustoptics.atmosphere.aerosols.AEROSOL_TYPES`, Hess et al.
        1998, by :func:`~dustoptics.atmosphere.aerosols.aerosol_table`) or
        ``"kobe2026"`` (Kobe's constant coefficients, ``beta_sca = 2e-6
        m^-1``, ``beta_ext = beta_sca / 0.9``, a Cornette-Shanks phase function
        of ``aerosol_g``: vertical optical depth 0.0027).  Default
        :data:`DEFAULT_EARTH_AEROSOL` (``"continental-average"``) unless
        ``aerosol_table`` is given.
    aerosol_optical_depth : float, optional
        Vertical aerosol optical depth at ``aerosol_reference_nm``, within
        :data:`EARTH_AEROSOL_OPTICAL_DEPTH_RANGE`.  Default
        :data:`DEFAULT_EARTH_AEROSOL_OPTICAL_DEPTH` (0.1, a typical clear
        day) for OPAC's types; Kobe's aerosols and an ``aerosol_table`` keep
        their own number density unless it is given. [-]
    aerosol_reference_nm : float, default 550
        Wavelength of ``aerosol_optical_depth`` (and of ``turbidity``'s),
        250-2500 nm for OPAC's types, within ``wavelength_nm`` otherwise; the
        extinction is computed there exactly. [nm]
    turbidity : float, optional
        Instead of ``aerosol_optical_depth``: a turbidity ``T``, 1 < T <= 10,
        as the optical depth ``beta(T) (lambda / 1 um)^-1.3`` of Preetham et
        al. (1999, appendix A.3;
        :func:`~dustoptics.atmosphere.aerosols.preetham_optical_depth`) at
        ``aerosol_reference_nm``. [-]
    aerosol_relative_humidity_percent : int, default 80
        OPAC's types: the humidity of the components (0 dry; 50, 70, 80, 90,
        95, 98, 99). [%]
    aerosol_table : Table, optional
        Any aerosol optics with cross-sections and ``number_density_per_m3``,
        at ``wavelength_nm``, instead of ``aerosol``.
    aerosol_profile : DensityProfile, optional
        Default: the OPAC type's, an exponential with its mixing layer's
        column (:attr:`~dustoptics.atmosphere.aerosols.AerosolType.profile`;
        1.77 km for the continental types);
        exponential, 1200 m (Kobe, Bruneton) for the others.
    aerosol_g : float, default 0.76
        Cornette-Shanks ``g`` of Kobe's aerosols. [-]
    ozone : OzoneCrossSection, "serdyuchenko2014" or None
        Ozone cross-sections: by default the shipped spectrum
        (:func:`~dustoptics.atmosphere.gases.ozone_serdyuchenko2014`); None
        for no ozone.
    ozone_profile : DensityProfile, optional
        Default Bruneton's layer
        (:data:`~dustoptics.atmosphere.column.BRUNETON2017_OZONE`), at its
        peak density of 300 Dobson units unless ``ozone_number_density_per_m3``
        is given.  A :class:`~dustoptics.atmosphere.column.FixedFractionProfile`
        (Kobe's: 6e-7 of the molecules) takes its density from the molecules.
    ozone_number_density_per_m3 : float, optional
        Ozone density where ``ozone_profile`` is 1. [m^-3]
    planet_radius_m, atmosphere_radius_m : float
        Default 6371 km and 6451 km (CosmoScout VR). [m]
    name : str, default "earth"
        File prefix.

    Returns
    -------
    Atmosphere
    """
    wl = as_increasing_grid("wavelength_nm", wavelength_nm, unit="nm")
    mols, refractivity = _molecules(molecules, EARTH_MOLECULE_MODELS, wl, molecules_scale_height_m)
    mol_table = mols.table
    _depth_m(planet_radius_m, atmosphere_radius_m)
    aerosols, profile_a = _earth_aerosols(
        wl,
        aerosol=aerosol,
        aerosol_table=aerosol_table,
        optical_depth=aerosol_optical_depth,
        reference_nm=aerosol_reference_nm,
        turbidity=turbidity,
        relative_humidity_percent=aerosol_relative_humidity_percent,
        profile=aerosol_profile,
        g=aerosol_g,
        top_altitude_m=atmosphere_radius_m - planet_radius_m,
    )
    cons = [
        mols,
        Constituent(role="aerosols", table=aerosols, profile=profile_a),
    ]
    if isinstance(ozone, str):
        check_choice("ozone", ozone, (_SHIPPED_OZONE,))
        ozone = gases.ozone_serdyuchenko2014()
    if ozone is not None:
        profile = ozone_profile if ozone_profile is not None else BRUNETON2017_OZONE
        if profile is BRUNETON2017_OZONE and ozone_number_density_per_m3 is None:
            ozone_number_density_per_m3 = BRUNETON2017_OZONE_PEAK_NUMBER_DENSITY_PER_M3
        if isinstance(profile, FixedFractionProfile):
            if ozone_number_density_per_m3 is not None:
                raise ValueError(
                    "ozone_number_density_per_m3 is set by a FixedFractionProfile (fraction x the "
                    f"molecules' density); got ozone_number_density_per_m3={ozone_number_density_per_m3!r} too"
                )
            assert (
                mol_table.cross_sections is not None
                and mol_table.cross_sections.number_density_per_m3 is not None
            )  # the molecules' table sets it
            n_o3 = profile.number_density_per_m3(
                base_number_density_per_m3=mol_table.cross_sections.number_density_per_m3
            )
        elif ozone_number_density_per_m3 is None:
            raise ValueError(
                f"ozone_number_density_per_m3 is required with ozone_profile {profile!r} "
                "(the ozone number density where the profile is 1) [m^-3]"
            )
        else:
            n_o3 = ozone_number_density_per_m3
        cons.append(
            Constituent(
                role="ozone",
                table=gases.ozone_table(
                    wl, cross_section=ozone, number_density_per_m3=n_o3, name=ozone.name
                ),
                profile=profile,
            )
        )
    return Atmosphere(
        name=name,
        planet_radius_m=planet_radius_m,
        atmosphere_radius_m=atmosphere_radius_m,
        constituents=tuple(cons),
        sun_distance_m=_EARTH_SUN_DISTANCE_M,
        refractivity=refractivity,
    )


def earth_atmosphere_kobe2026(*, name: str = "earth-kobe2026") -> Atmosphere:
    """Kobe's Earth: his air, aerosols and ozone on his three wavelengths.

    Wavelengths 475, 510, 650 nm; molecules ``"kobe2026"`` (n = 1.0003 at
    N_s = 2.545e25 m^-3, no King factor: 3.6 % above Penndorf's standard air
    at 510 nm), scale height 7994 m; Kobe's constant aerosols; his three ozone
    cross-sections at 6e-7 of the air density (Kobe 2026, sections 10.4, 11.3,
    11.5).
    """
    return earth_atmosphere(
        wavelength_nm=KOBE2026_WAVELENGTHS_NM,
        molecules="kobe2026",
        aerosol="kobe2026",
        ozone=gases.KOBE2026_OZONE,
        ozone_profile=FixedFractionProfile(
            base=ExponentialProfile(scale_height_m=_MOLECULE_SCALE_HEIGHT_M["kobe2026"]),
            fraction=gases.KOBE2026_OZONE_FRACTION,
        ),
        name=name,
    )
