"""CalcMySky/ShowMySky: the sky of an ``.atmo`` description, and the format.

CalcMySky (:data:`~dustoptics.io.engines.calcmysky.CALCMYSKY_SOURCE`) precomputes
the spectral radiative transfer of its description, scattering order by order
(8 in ``examples/mars.atmo``), with each scatterer's own GLSL phase function,
and ShowMySky turns the spectral radiance into colour.  It is the one engine
here that takes the whole physics of a set: nothing is fitted.  Its sky is
the package's own solver (:func:`~dustoptics.sky.scene.sky_radiance`, the exact
sky's) on the medium the ``.atmo`` describes -- what CalcMySky would read of it:

- aerosols and molecules with the extinction cross-section of the fitted power
  law (``cross section at 1 um``, ``angstrom exponent``) times the
  single-scattering albedo of the file;
- the aerosols' phase function as the GLSL block returns it (256 nodes per
  wavelength, linear in ``sqrt(theta)``; the rows interpolated from the file's
  wavelengths when they are not the set's);
- the same densities and ozone.

So the "fitted" row measures what the ``.atmo`` loses (the power law, the
phase nodes, the wavelength resampling); CalcMySky's own discretisation
(texture sizes) is not modelled.

Community row: ``examples/mars.atmo`` (CO2 ``0.0897172 fm^2`` at 1 um, Angstrom 4,
Viking's two-exponential density; dust ``10.155 um^2`` at 1 um, Angstrom -0.2,
the single-scattering albedo of Ockert-Bell et al. 1997 Table 2 as its
``spectra/mars-dust-single-scattering-albedo.csv`` lists it, HG with ``g =
0.64 + 0.23 exp(-0.00002378121 (lambda - 310)^2)``, ``4.559e6 m^-3 exp(-h / 10.8
km)``; Mars radius 3389.5 km, atmosphere 120 km); for Earth ``examples/sample.atmo``
(air 0.04022 fm^2 at 1 um, Angstrom 4, ``3.08458e25 m^-3 exp(-h / 8 km)``; aerosols
0.042968 um^2, Angstrom 0, albedo 1, ``1.03333e8 m^-3 exp(-h / 1.2 km)``, its
Cornette-Shanks g = 0.76 plus a forward spike, times 0.904; radius 6371 km, 120 km
high) with the set's own ozone (its ozone profile, a fit to the US standard
atmosphere, is not reproduced).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.column import ExponentialProfile, PiecewiseLinearProfile
from dustoptics.atmosphere.sets import Atmosphere, Constituent
from dustoptics.io.engines.calcmysky import (
    CALCMYSKY_SOURCE,
    DEFAULT_NODES,
    angstrom_fit,
    calcmysky_phase_lookup,
    calcmysky_wavelengths,
    write_calcmysky,
)
from dustoptics.sky.engines._sets import exact_sky_rgb, remember_set, set_of
from dustoptics.sky.engines.core import EngineFit, EngineModel, register_engine

__all__ = ["CALCMYSKY", "calcmysky_medium", "mars_atmo_example", "sample_atmo_example"]

#: examples/spectra/mars-dust-single-scattering-albedo.csv (Ockert-Bell et al. 1997, Table 2),
#: the points within 210-1015 nm. [nm], [-]
_OCKERT_BELL_SSA: Final = (
    (210.0, 300.0, 350.0, 400.0, 500.0, 600.0, 670.0, 700.0, 800.0, 1015.0),
    (0.72, 0.61, 0.61, 0.63, 0.78, 0.91, 0.93, 0.94, 0.95, 0.95),
)


def _replace_optics(table: Any, *, cext_um2: Any, ssa: Any, phase: Any, n0: float | None = None):
    cs = table.cross_sections
    cext = np.asarray(cext_um2, dtype=float)
    changes: dict[str, Any] = {"cext_um2": cext, "csca_um2": cext * np.asarray(ssa, dtype=float)}
    if cs.cback_um2 is not None:
        changes["cback_um2"] = None
    if n0 is not None:
        changes["number_density_per_m3"] = float(n0)
    return table.replace(phase=np.asarray(phase, dtype=float), cross_sections=cs.replace(**changes))


def calcmysky_medium(atmosphere: Atmosphere, *, n_nodes: int = DEFAULT_NODES) -> Atmosphere:
    """The set as CalcMySky reads its ``.atmo`` (see the module docstring)."""
    wl_file, _ = calcmysky_wavelengths(atmosphere.wavelength_nm)
    constituents = []
    for c in atmosphere.constituents:
        t = c.table
        if c.role == "ozone":
            constituents.append(c)
            continue
        wl = np.asarray(t.wavelength_nm, dtype=float)
        c1, alpha, _ = angstrom_fit(wl, t.quantity("cext_um2"))
        cext = c1 * (wl / 1000.0) ** -alpha
        ssa = np.interp(wl, wl_file, np.interp(wl_file, wl, np.asarray(t.ssa, dtype=float)))
        phase = np.asarray(t.phase, dtype=float)
        if c.role == "aerosols":
            nodes = 180.0 * (np.arange(n_nodes) / (n_nodes - 1)) ** 2
            at_nodes = np.asarray(t.phase_at(nodes), dtype=float)
            in_file = np.stack([np.interp(wl_file, wl, at_nodes[:, j]) for j in range(n_nodes)], -1)
            back = np.stack([np.interp(wl, wl_file, in_file[:, j]) for j in range(n_nodes)], -1)
            phase = calcmysky_phase_lookup(back, t.theta_deg)
        constituents.append(
            Constituent(c.role, _replace_optics(t, cext_um2=cext, ssa=ssa, phase=phase), c.profile)
        )
    return Atmosphere(
        name=f"{atmosphere.name} as CalcMySky reads it",
        planet_radius_m=atmosphere.planet_radius_m,
        atmosphere_radius_m=atmosphere.atmosphere_radius_m,
        constituents=tuple(constituents),
        sun_distance_m=atmosphere.sun_distance_m,
        refractivity=atmosphere.refractivity,
    )


def mars_atmo_example(atmosphere: Atmosphere) -> Atmosphere:
    """CalcMySky's ``examples/mars.atmo`` on the set's tables' wavelength and angle grids."""
    mol = atmosphere.constituent("molecules")
    dust = atmosphere.constituent("aerosols")
    wl = np.asarray(dust.table.wavelength_nm, dtype=float)
    # CO2: 0.0897172 fm^2 at 1 um, Angstrom 4; Viking 1's density fit (m^-3, altitude in m).
    z = np.linspace(0.0, 120e3, 1201)
    n_co2 = np.where(
        z < 39652.4, 1.0744578e24 * np.exp(-0.129e-3 * z), 2.2886392e23 * np.exp(-0.09e-3 * z)
    )
    co2 = _replace_optics(
        mol.table,
        cext_um2=0.0897172e-18 * (np.asarray(mol.table.wavelength_nm) / 1000.0) ** -4.0,
        ssa=np.ones(np.asarray(mol.table.wavelength_nm).size),
        phase=np.array(
            np.broadcast_to(
                3.0 / (16.0 * math.pi) * (1.0 + np.cos(np.radians(mol.table.theta_deg)) ** 2),
                np.asarray(mol.table.phase).shape,
            )
        ),
        n0=float(n_co2[0]),
    )
    g = 0.64 + 0.23 * np.exp(-0.00002378121 * (wl - 310.0) ** 2)
    mu = np.cos(np.radians(np.asarray(dust.table.theta_deg, dtype=float)))
    hg = (
        (1.0 - g[:, None] ** 2)
        / (1.0 + g[:, None] ** 2 - 2.0 * g[:, None] * mu) ** 1.5
        / (4 * math.pi)
    )
    dust_table = _replace_optics(
        dust.table,
        cext_um2=10.155 * (wl / 1000.0) ** 0.2,
        ssa=np.interp(wl, *_OCKERT_BELL_SSA),
        phase=hg,
        n0=4.559e6,
    )
    return Atmosphere(
        name="CalcMySky examples/mars.atmo",
        planet_radius_m=3389.5e3,
        atmosphere_radius_m=3389.5e3 + 120e3,
        constituents=(
            Constituent(
                "molecules", co2, PiecewiseLinearProfile(z.tolist(), (n_co2 / n_co2[0]).tolist())
            ),
            Constituent("aerosols", dust_table, ExponentialProfile(scale_height_m=10.8e3)),
        ),
        sun_distance_m=atmosphere.sun_distance_m,
        refractivity=atmosphere.refractivity,
    )


def sample_atmo_example(atmosphere: Atmosphere) -> Atmosphere:
    """CalcMySky's ``examples/sample.atmo`` (Earth) on the set's grids; the set's own ozone."""
    mol = atmosphere.constituent("molecules")
    aer = atmosphere.constituent("aerosols")
    wl_m = np.asarray(mol.table.wavelength_nm, dtype=float)
    mu_m = np.cos(np.radians(np.asarray(mol.table.theta_deg, dtype=float)))
    molecules = _replace_optics(
        mol.table,
        cext_um2=0.04022e-18 * (wl_m / 1000.0) ** -4.0,
        ssa=np.ones(wl_m.size),
        phase=np.array(
            np.broadcast_to(3.0 / (16.0 * math.pi) * (1.0 + mu_m**2), np.shape(mol.table.phase))
        ),
        n0=3.08458e25,
    )
    # Its aerosols: Cornette-Shanks g = 0.76 plus a forward spike, times 0.904 (its GLSL).
    g = 0.76
    mu = np.cos(np.radians(np.asarray(aer.table.theta_deg, dtype=float)))
    k = 3.0 / (8.0 * math.pi) * (1.0 - g * g) / (2.0 + g * g)
    row = (
        k * (1.0 + mu**2) / (1.0 + g * g - 2.0 * g * mu) ** 1.5 + 1.0 / ((1.0 - mu) * 600.0 + 0.05)
    ) * 0.904
    n_wl = np.asarray(aer.table.wavelength_nm).size
    aerosols = _replace_optics(
        aer.table,
        cext_um2=np.full(n_wl, 0.042968),
        ssa=np.ones(n_wl),
        phase=np.array(np.broadcast_to(row, np.shape(aer.table.phase))),
        n0=1.03333e8,
    )
    others = tuple(c for c in atmosphere.constituents if c.role == "ozone")
    return Atmosphere(
        name="CalcMySky examples/sample.atmo",
        planet_radius_m=6371e3,
        atmosphere_radius_m=6371e3 + 120e3,
        constituents=(
            Constituent("molecules", molecules, ExponentialProfile(scale_height_m=8e3)),
            Constituent("aerosols", aerosols, ExponentialProfile(scale_height_m=1.2e3)),
            *others,
        ),
        sun_distance_m=atmosphere.sun_distance_m,
        refractivity=atmosphere.refractivity,
    )


def calcmysky_sky_rgb(
    params: Mapping[str, float],
    *,
    sun_elevation_deg: float,
    view_zenith_deg: Any,
    view_azimuth_deg: Any,
) -> np.ndarray:
    """The sky of the medium ``params`` name (``set_key``): linear sRGB per unit solar
    illuminance [sr^-1] (:func:`~dustoptics.sky.engines._sets.exact_sky_rgb`)."""
    return exact_sky_rgb(
        set_of(params),
        sun_elevation_deg=sun_elevation_deg,
        view_zenith_deg=view_zenith_deg,
        view_azimuth_deg=view_azimuth_deg,
    )


_ORIGINAL: dict[int, Atmosphere] = {}


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    key = remember_set(calcmysky_medium(atmosphere))
    _ORIGINAL[int(key)] = atmosphere
    return {"set_key": key}


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    if atmosphere.name.startswith("mars"):
        return {"set_key": remember_set(mars_atmo_example(atmosphere))}
    return {"set_key": remember_set(sample_atmo_example(atmosphere))}


def write_calcmysky_fit(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """Write ``NAME_calcmysky.atmo`` of the set behind a fit, its sky error in the header."""
    key = int(fit.params["set_key"])
    if key not in _ORIGINAL:
        raise ValueError("a CalcMySky file is written from the set its fit was made for")
    notes = [
        "Sky error of this description against the exact spectral sky (CIE Delta E 2000 over "
        "the dome, mean / 95th pct): "
        + "; ".join(
            f"Sun {e.sun_elevation_deg:g} deg {e.delta_e_mean:.2f} / {e.delta_e_p95:.2f}"
            for e in fit.errors
        )
    ]
    return write_calcmysky(_ORIGINAL[key], out_dir, overwrite=overwrite, notes=notes)


CALCMYSKY = register_engine(
    EngineModel(
        name="calcmysky",
        title="CalcMySky/ShowMySky (.atmo)",
        source=CALCMYSKY_SOURCE,
        parameters=(),
        community_parameters=(),
        render=calcmysky_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_calcmysky_fit,
    ),
    suffixes=(".atmo",),
)
