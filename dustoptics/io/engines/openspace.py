"""An atmosphere as OpenSpace's ``RenderableAtmosphere`` asset table.

Read from OpenSpace's source at :data:`OPENSPACE_SOURCE`:
``modules/atmosphere/rendering/renderableatmosphere.cpp`` (the dictionary the
asset gives: ``AtmosphereHeight``, ``PlanetRadius``,
``PlanetAverageGroundReflectance``, ``GroundRadianceEmission``, ``SunIntensity``,
``Rayleigh = { Coefficients = { Wavelengths, Scattering }, H_R }``, ``Ozone = {
Coefficients = { Extinction }, H_O }``, ``Mie = { Coefficients = { Scattering,
Extinction }, H_M, G }``), ``data/assets/scene/solarsystem/planets/mars/atmosphere.asset``
(units as its comments give them: lengths in km, coefficients in km^-1,
wavelengths in nm) and ``modules/atmosphere/shaders/`` (Bruneton and Neyret's
2008 model: exponential densities ``exp(-h / H)``, ``rayleighPhaseFunction(mu) =
3 (1 + mu^2) / (16 pi)``, ``miePhaseFunction(mu, G)`` the Cornette-Shanks
function ``3 (1 - G^2) (1 + mu^2) / (8 pi (2 + G^2) (1 + G^2 - 2 G mu)^1.5)``
with one ``G`` for the three channels; the ozone term's column is multiplied
by ``0.0000006`` in ``transmittance_calc_fs.glsl`` and ``atmosphere_deferred_fs.glsl``).

Mapping: channels R, G, B at 680, 550, 440 nm (OpenSpace's ``Wavelengths``);
Rayleigh ``Scattering`` = the molecules' ``beta_sca``; Mie ``Scattering`` and
``Extinction`` = the aerosols'; ``H_R``, ``H_M`` = the profiles' scale heights (a
profile that is not exponential gets the scale height of equal column); ``G``
= a Cornette-Shanks fit to the aerosols' phase function at 550 nm
(:func:`dustoptics.scattering.fit.fit_table`) unless given (the sky fit gives
its own, :func:`openspace_parameters`'s ``g``); ozone as an exponential of
scale height ``H_O`` = 8 km (OpenSpace's own) with the same vertical column,
``Extinction`` = ``beta_abs,max L / H_O / 0.0000006`` (``L`` our layer's column
length).  ``SunIntensity``, ``GroundRadianceEmission`` and the ground
reflectance are OpenSpace's own Mars and Earth values (rendering choices, not
physics).

Files: ``NAME_openspace.asset`` for a set (:func:`write_openspace`; ``dustoptics
build mars|earth --format openspace`` through :mod:`dustoptics.sky.engines.openspace`).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.atmosphere.column import ExponentialProfile, FixedFractionProfile
from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io.engines._channels import channel_coefficients, lua_number
from dustoptics.scattering.fit import fit_table

__all__ = [
    "OPENSPACE_CHANNELS_NM",
    "OPENSPACE_OZONE_FACTOR",
    "OPENSPACE_SOURCE",
    "OpenSpaceAtmosphere",
    "cornette_shanks_g",
    "openspace_asset",
    "openspace_mie_phase",
    "openspace_parameters",
    "write_openspace",
]

#: The OpenSpace source read for this module.
OPENSPACE_SOURCE = (
    "OpenSpace/OpenSpace commit 37e7e4f9458fe7fe676a33a80966bee58bb8d60b (2026-08-07, "
    "releases/v0.20.0-1040): modules/atmosphere/rendering/renderableatmosphere.cpp, "
    "modules/atmosphere/shaders/atmosphere_common.glsl, "
    "data/assets/scene/solarsystem/planets/mars/atmosphere.asset"
)

#: OpenSpace's channel wavelengths (``Rayleigh.Coefficients.Wavelengths``). [nm]
OPENSPACE_CHANNELS_NM = (680.0, 550.0, 440.0)

#: The factor OpenSpace's shaders multiply the ozone column by. [-]
OPENSPACE_OZONE_FACTOR = 0.0000006

#: OpenSpace's ozone scale height in its Earth asset (commented out there). [km]
_OZONE_SCALE_HEIGHT_KM = 8.0

#: OpenSpace's own rendering choices per planet: (SunIntensity, GroundRadianceEmission,
#: PlanetAverageGroundReflectance), from its mars and earth atmosphere.asset.
_RENDERING = {"mars": (13.1, 0.37, 0.1), "earth": (6.9, 0.6, 0.1)}


def openspace_mie_phase(mu: Any, g: float) -> np.ndarray:
    """OpenSpace's ``miePhaseFunction(mu, mieG)`` (Cornette-Shanks). [sr^-1]"""
    m = np.asarray(mu, dtype=np.float64)
    g2 = g * g
    return np.asarray(
        0.1193662072 * (1.0 - g2) * (1.0 + g2 - 2.0 * g * m) ** -1.5 * (1.0 + m * m) / (2.0 + g2),
        dtype=np.float64,
    )


@dataclass(frozen=True)
class OpenSpaceAtmosphere:
    """The ``Renderable`` table of an OpenSpace ``RenderableAtmosphere``, in its units.

    Attributes
    ----------
    name : str
    planet_radius_km, atmosphere_height_km : float
        ``PlanetRadius``, ``AtmosphereHeight``. [km]
    ground_reflectance, ground_radiance_emission, sun_intensity : float
        ``PlanetAverageGroundReflectance``, ``GroundRadianceEmission``, ``SunIntensity``. [-]
    rayleigh_scattering_per_km : tuple of 3 floats
        ``Rayleigh.Coefficients.Scattering`` (R, G, B). [km^-1]
    h_r_km : float
        ``Rayleigh.H_R``. [km]
    mie_scattering_per_km, mie_extinction_per_km : tuple of 3 floats
        ``Mie.Coefficients.Scattering``, ``Extinction``. [km^-1]
    h_m_km : float
        ``Mie.H_M``. [km]
    g : float
        ``Mie.G`` (Cornette-Shanks), in (-1, 1). [-]
    ozone_extinction : tuple of 3 floats or None
        ``Ozone.Coefficients.Extinction`` (before OpenSpace's factor 6e-7); None: no ozone.
    h_o_km : float
        ``Ozone.H_O``. [km]
    notes : tuple of str
        Provenance and choices (the file's comment block).
    """

    name: str
    planet_radius_km: float
    atmosphere_height_km: float
    ground_reflectance: float
    ground_radiance_emission: float
    sun_intensity: float
    rayleigh_scattering_per_km: tuple[float, float, float]
    h_r_km: float
    mie_scattering_per_km: tuple[float, float, float]
    mie_extinction_per_km: tuple[float, float, float]
    h_m_km: float
    g: float
    ozone_extinction: tuple[float, float, float] | None = None
    h_o_km: float = _OZONE_SCALE_HEIGHT_KM
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not -1.0 < self.g < 1.0:
            raise ValueError(f"g must be in (-1, 1) (OpenSpace's G range); got {self.g!r}")


def _triple(values: Any) -> tuple[float, float, float]:
    a = [float(v) for v in values]
    return (a[0], a[1], a[2])


def _scale_height_km(profile: Any, top_m: float) -> tuple[float, str]:
    """A profile's scale height [km], and how it was obtained."""
    if isinstance(profile, FixedFractionProfile):
        return _scale_height_km(profile.base, top_m)
    if isinstance(profile, ExponentialProfile):
        return profile.scale_height_m / 1000.0, "its scale height"
    length = float(profile.column_length_m(top_altitude_m=top_m))
    return length / 1000.0, f"the scale height of equal column ({profile!r} is not exponential)"


def cornette_shanks_g(table: Any, wavelength_nm: float = 550.0) -> tuple[float, float]:
    """Cornette-Shanks g fitted to a table's phase function at one wavelength, and its rms
    relative error (:func:`dustoptics.scattering.fit.fit_table`). [-]"""
    fit = fit_table(
        table, model="cornette-shanks1992", colour="wavelengths", channels_nm=(wavelength_nm,) * 3
    )
    return float(fit.parameters[0, 0]), float(fit.rms_relative_error[0])


def openspace_parameters(
    atmosphere: Any, *, g: float | None = None, channels_nm: Any = OPENSPACE_CHANNELS_NM
) -> OpenSpaceAtmosphere:
    """OpenSpace's parameters for an atmosphere set (see the module docstring).

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
        Molecules, aerosols and optionally ozone.
    g : float, optional
        ``Mie.G``; default: the Cornette-Shanks fit at 550 nm.
    channels_nm : sequence of 3 floats
        The R, G, B wavelengths (OpenSpace's 680, 550, 440). [nm]

    Returns
    -------
    OpenSpaceAtmosphere
    """
    top = float(atmosphere.atmosphere_radius_m - atmosphere.planet_radius_m)
    mol = atmosphere.constituent("molecules")
    aer = atmosphere.constituent("aerosols")
    ozone = next((c for c in atmosphere.constituents if c.role == "ozone"), None)
    m = channel_coefficients(mol.table, channels_nm=channels_nm)
    a = channel_coefficients(aer.table, channels_nm=channels_nm)
    h_r, how_r = _scale_height_km(mol.profile, top)
    h_m, how_m = _scale_height_km(aer.profile, top)
    notes = [
        f"molecules: {mol.table.name!r} ({mol.table.provenance.input_hash}); H_R: {how_r}",
        f"aerosols: {aer.table.name!r} ({aer.table.provenance.input_hash}); H_M: {how_m}",
    ]
    if g is None:
        g, rms = cornette_shanks_g(aer.table)
        notes.append(f"G: Cornette-Shanks fit at 550 nm, rms relative error {rms:.3g}")
    else:
        notes.append(f"G: given ({g:g})")
    ozone_ext = None
    if ozone is not None:
        o = channel_coefficients(ozone.table, channels_nm=channels_nm)
        column = float(ozone.profile.column_length_m(top_altitude_m=top)) / 1000.0
        ozone_ext = _triple(
            o.absorption_per_m * 1000.0 * column / _OZONE_SCALE_HEIGHT_KM / OPENSPACE_OZONE_FACTOR
        )
        notes.append(
            f"ozone: {ozone.table.name!r}; an exponential of H_O = {_OZONE_SCALE_HEIGHT_KM:g} km "
            f"with our layer's column ({column:.4g} km at the peak density), divided by "
            "OpenSpace's factor 0.0000006"
        )
    key = "earth" if "earth" in atmosphere.name else "mars"
    sun, emission, reflectance = _RENDERING[key]
    notes.append(
        f"SunIntensity, GroundRadianceEmission, PlanetAverageGroundReflectance: OpenSpace's own "
        f"{key} asset values (rendering choices)"
    )
    return OpenSpaceAtmosphere(
        name=atmosphere.name,
        planet_radius_km=float(atmosphere.planet_radius_m) / 1000.0,
        atmosphere_height_km=top / 1000.0,
        ground_reflectance=reflectance,
        ground_radiance_emission=emission,
        sun_intensity=sun,
        rayleigh_scattering_per_km=_triple(m.scattering_per_m * 1000.0),
        h_r_km=h_r,
        mie_scattering_per_km=_triple(a.scattering_per_m * 1000.0),
        mie_extinction_per_km=_triple(a.extinction_per_m * 1000.0),
        h_m_km=h_m,
        g=float(g),
        ozone_extinction=ozone_ext,
        notes=tuple(notes),
    )


def _lua3(values: tuple[float, float, float]) -> str:
    return "{ " + ", ".join(lua_number(v) for v in values) + " }"


def _mie_block(
    sca: tuple[float, float, float],
    ext: tuple[float, float, float],
    h_m_km: float,
    g: float,
    indent: str,
) -> list[str]:
    return [
        f"{indent}Mie = {{",
        f"{indent}  Coefficients = {{",
        f"{indent}    -- km^-1, channels 680, 550, 440 nm",
        f"{indent}    Scattering = {_lua3(sca)},",
        f"{indent}    Extinction = {_lua3(ext)}",
        f"{indent}  }},",
        f"{indent}  -- scale height in km",
        f"{indent}  H_M = {lua_number(h_m_km)},",
        f"{indent}  -- Cornette-Shanks phase function parameter",
        f"{indent}  G = {lua_number(g)}",
        f"{indent}}}",
    ]


def _comment(name: str, notes: tuple[str, ...], what: str) -> list[str]:
    return [
        f"-- dustoptics: {what} {name!r} for OpenSpace's RenderableAtmosphere.",
        f"-- OpenSpace source read: {OPENSPACE_SOURCE}.",
        "-- Units: km, km^-1; channels R, G, B = 680, 550, 440 nm; Mie phase Cornette-Shanks(G).",
        *[f"-- {n}" for n in notes],
    ]


def openspace_asset(p: OpenSpaceAtmosphere, *, parent: str | None = None) -> str:
    """The ``.asset`` file of a whole atmosphere: a scene-graph node ``<Name>Atmosphere``
    under ``parent`` (default: the globe asset's ``Mars`` or ``Earth`` node, required
    from ``scene/solarsystem/planets/<planet>/globe``)."""
    planet = "Earth" if "earth" in p.name else "Mars"
    ident = re.sub(r"[^A-Za-z0-9]", "", p.name.title()) + "Atmosphere"
    lines = [
        *_comment(p.name, p.notes, "atmosphere"),
        f'local globe = asset.require("scene/solarsystem/planets/{planet.lower()}/globe")',
        "",
        "local Atmosphere = {",
        f'  Identifier = "{ident}",',
        f"  Parent = {parent or f'globe.{planet}.Identifier'},",
        "  Renderable = {",
        '    Type = "RenderableAtmosphere",',
        f"    AtmosphereHeight = {lua_number(p.atmosphere_height_km)},",
        f"    PlanetRadius = {lua_number(p.planet_radius_km)},",
        f"    PlanetAverageGroundReflectance = {lua_number(p.ground_reflectance)},",
        f"    GroundRadianceEmission = {lua_number(p.ground_radiance_emission)},",
        f"    SunIntensity = {lua_number(p.sun_intensity)},",
        "    Rayleigh = {",
        "      Coefficients = {",
        "        Wavelengths = { 680, 550, 440 },",
        f"        Scattering = {_lua3(p.rayleigh_scattering_per_km)}",
        "      },",
        f"      H_R = {lua_number(p.h_r_km)}",
        "    },",
    ]
    if p.ozone_extinction is not None:
        lines += [
            "    Ozone = {",
            f"      Coefficients = {{ Extinction = {_lua3(p.ozone_extinction)} }},",
            f"      H_O = {lua_number(p.h_o_km)}",
            "    },",
        ]
    lines += _mie_block(p.mie_scattering_per_km, p.mie_extinction_per_km, p.h_m_km, p.g, "    ")
    lines[-1] += ","
    lines += [
        "    Debug = { PreCalculatedTextureScale = 1.0, SaveCalculatedTextures = false }",
        "  },",
        "  GUI = {",
        f'    Name = "{planet} Atmosphere (dustoptics {p.name})",',
        f'    Path = "/Solar System/Planets/{planet}",',
        "    Focusable = false",
        "  }",
        "}",
        "",
        "asset.onInitialize(function()",
        "  openspace.addSceneGraphNode(Atmosphere)",
        "end)",
        "",
        "asset.onDeinitialize(function()",
        "  openspace.removeSceneGraphNode(Atmosphere)",
        "end)",
        "",
        "asset.export(Atmosphere)",
    ]
    return "\n".join(lines) + "\n"


def write_openspace(
    atmosphere: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    parameters: OpenSpaceAtmosphere | None = None,
    **options: Any,
) -> list[Path]:
    """Write ``NAME_openspace.asset`` (a ``RenderableAtmosphere`` scene-graph node).

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
    out_dir : path
    overwrite : bool
    parameters : OpenSpaceAtmosphere, optional
        The parameters to write (e.g. fitted to the sky); default
        :func:`openspace_parameters` of the set with ``**options``.
    """
    p = parameters if parameters is not None else openspace_parameters(atmosphere, **options)
    path = Path(out_dir) / f"{safe_stem(atmosphere.name)}_openspace.asset"
    return write_files({path: openspace_asset(p).encode("utf-8")}, overwrite=overwrite)
