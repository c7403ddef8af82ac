"""Unreal Engine's SkyAtmosphere component (Hillaire 2020): its model and format.

Unreal Engine 4.24 and later draw the sky of a ``SkyAtmosphere`` component with
S. Hillaire's model, whose reference implementation is public
(github.com/sebh/UnrealEngineSkyAtmosphere at commit 183ead5b, read for this
module: ``Resources/RenderSkyRayMarching.hlsl`` and
``Resources/RenderSkyCommon.hlsl``); the numpy version is
:mod:`~dustoptics.sky.engines._hillaire`.  The component's properties (Unreal
Engine 5 documentation, "Sky Atmosphere Component Properties"; the names are
the C++ ``UPROPERTY`` names, in snake case in the editor's Python API):

- ``BottomRadius`` (km), ``AtmosphereHeight`` (km), ``GroundAlbedo``,
  ``MultiScatteringFactor``;
- ``RayleighScatteringScale`` (km^-1) times the ``RayleighScattering`` colour,
  ``RayleighExponentialDistribution`` (the scale height, km);
- ``MieScatteringScale`` and ``MieAbsorptionScale`` (km^-1) times their colours,
  ``MieAnisotropy`` (Henyey-Greenstein g), ``MieExponentialDistribution`` (km);
- ``OtherAbsorptionScale`` (km^-1) times ``OtherAbsorption`` in the tent
  ``OtherTentDistribution`` (tip altitude, tip value, width; ozone).

The defaults (Earth; the documentation's values, which are Bruneton's Earth of
sebh's ``SetupEarthAtmosphere``): radius 6360 km, height 60 km, Rayleigh 0.0331
x (0.175287, 0.409607, 1) per km over 8 km, Mie scattering 0.003996 and
absorption 0.000444 per km over 1.2 km with g = 0.8, ozone 0.001881 x
(0.345561, 1, 0.045189) per km in a tent at 25 km of width 15 km, ground albedo
0.401978.

The fit adjusts the Rayleigh and Mie coefficients per channel, both scale
heights, the anisotropy and one exposure (``exposure``: the camera's exposure
compensation, ``log2`` of it in EV, the same for every Sun elevation); the
planet's radius and atmosphere height, the ground albedo (0.2, the exact sky's)
and the absorbing layer (the set's ozone at 680, 550, 440 nm, none on Mars)
come from the set.  The Sun is a directional light of the sunlight's colour
(:func:`~dustoptics.sky.engines.core.sunlight_linear_srgb`).

Community row: the defaults above with the planet's radius and, for a dust,
the Mie scattering colour set to the dust's tint
(:func:`~dustoptics.sky.engines.core.dust_tint_linear_srgb`); only the exposure
adjusted.

Files: ``NAME_unreal_sky_atmosphere.json`` (the properties in Unreal's units)
and ``NAME_unreal_sky_atmosphere.py``, a script for the Unreal Editor's Python
console that sets them on the selected actors' SkyAtmosphere components.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky.engines import _hillaire
from dustoptics.sky.engines.core import (
    RGB,
    EngineFit,
    EngineModel,
    Parameter,
    channel_values,
    dust_tint_linear_srgb,
    error_header,
    fit_json,
    hillaire_renderer,
    per_channel,
    register_engine,
    rgb_of,
    scale_height_m,
    write_texts,
)

__all__ = ["UNREAL", "UNREAL_SOURCE", "unreal_files", "unreal_setup", "unreal_sky_rgb"]

UNREAL_SOURCE: Final = (
    "Unreal Engine 5 SkyAtmosphere component (Sky Atmosphere Component Properties "
    "documentation); model: S. Hillaire 2020, github.com/sebh/UnrealEngineSkyAtmosphere "
    "183ead5b, Resources/RenderSkyRayMarching.hlsl and RenderSkyCommon.hlsl"
)

#: The component's Earth defaults, per km and km.
EARTH_DEFAULTS: Final = {
    "bottom_radius_km": 6360.0,
    "atmosphere_height_km": 60.0,
    "ground_albedo": 0.401978,
    "rayleigh_scattering_r": 0.0331 * 0.175287,
    "rayleigh_scattering_g": 0.0331 * 0.409607,
    "rayleigh_scattering_b": 0.0331 * 1.0,
    "rayleigh_exponential_distribution_km": 8.0,
    "mie_scattering_r": 0.003996,
    "mie_scattering_g": 0.003996,
    "mie_scattering_b": 0.003996,
    "mie_absorption_r": 0.000444,
    "mie_absorption_g": 0.000444,
    "mie_absorption_b": 0.000444,
    "mie_anisotropy": 0.8,
    "mie_exponential_distribution_km": 1.2,
    "other_absorption_r": 0.001881 * 0.345561,
    "other_absorption_g": 0.001881 * 1.0,
    "other_absorption_b": 0.001881 * 0.045189,
    "other_tent_tip_altitude_km": 25.0,
    "other_tent_width_km": 15.0,
    "exposure": 1.0,
}


def unreal_setup(params: Mapping[str, float]) -> _hillaire.HillaireSetup:
    """The Hillaire medium of the component's properties (every key of :data:`EARTH_DEFAULTS`)."""
    radius = params["bottom_radius_km"]
    tip, width = params["other_tent_tip_altitude_km"], params["other_tent_width_km"]
    return _hillaire.HillaireSetup(
        planet_radius_km=radius,
        top_radius_km=radius + params["atmosphere_height_km"],
        rayleigh_scattering_per_km=rgb_of(params, "rayleigh_scattering"),
        rayleigh_absorption_per_km=np.zeros(3),
        rayleigh_scale_height_km=params["rayleigh_exponential_distribution_km"],
        mie_scattering_per_km=rgb_of(params, "mie_scattering"),
        mie_absorption_per_km=rgb_of(params, "mie_absorption"),
        mie_scale_height_km=params["mie_exponential_distribution_km"],
        mie_phase=_hillaire.henyey_greenstein(params["mie_anisotropy"]),
        ozone_absorption_per_km=rgb_of(params, "other_absorption"),
        ozone_bottom_km=tip - width,
        ozone_peak_km=tip,
        ozone_top_km=tip + width,
        ground_albedo=np.full(3, params["ground_albedo"]),
        distribution="variable",
        ms_distribution="uniform",
        directions="stratified",
        ms_samples=20,
    )


unreal_sky_rgb = hillaire_renderer(
    unreal_setup,
    "unreal_sky_rgb",
    """The SkyAtmosphere's sky per unit solar illuminance times ``exposure``, linear sRGB. [sr^-1]

    The Sun is a directional light of the sunlight's colour and unit illuminance.
    """,
)


def _planet(atmosphere: Atmosphere) -> dict[str, float]:
    return {
        "bottom_radius_km": atmosphere.planet_radius_m / 1000.0,
        "atmosphere_height_km": (atmosphere.atmosphere_radius_m - atmosphere.planet_radius_m)
        / 1000.0,
    }


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    """The set's own coefficients at 680, 550 and 440 nm: the fit's start."""
    ray = channel_values(atmosphere, "molecules", "beta_sca_per_m") * 1000.0
    mie_s = channel_values(atmosphere, "aerosols", "beta_sca_per_m") * 1000.0
    mie_a = channel_values(atmosphere, "aerosols", "beta_abs_per_m") * 1000.0
    ozone = channel_values(atmosphere, "ozone", "beta_abs_per_m") * 1000.0
    out = dict(EARTH_DEFAULTS)
    out.update(_planet(atmosphere))
    for i, c in enumerate(RGB):
        out[f"rayleigh_scattering_{c}"] = float(max(ray[i], 1e-7))
        out[f"mie_scattering_{c}"] = float(max(mie_s[i], 1e-7))
        out[f"mie_absorption_{c}"] = float(max(mie_a[i], 1e-7))
        out[f"other_absorption_{c}"] = float(ozone[i])
    g = float(channel_values(atmosphere, "aerosols", "g")[1])
    out.update(
        rayleigh_exponential_distribution_km=scale_height_m(atmosphere, "molecules", 8000.0)
        / 1000.0,
        mie_exponential_distribution_km=scale_height_m(atmosphere, "aerosols", 1200.0) / 1000.0,
        mie_anisotropy=min(max(g, 0.0), 0.99),
        ground_albedo=0.2,
        other_tent_tip_altitude_km=25.0,
        other_tent_width_km=15.0,
        exposure=1.0,
    )
    return out


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    out = dict(EARTH_DEFAULTS)
    out["bottom_radius_km"] = atmosphere.planet_radius_m / 1000.0
    if atmosphere.name.startswith("mars"):
        tint = dust_tint_linear_srgb(atmosphere)
        for i, c in enumerate(RGB):
            out[f"mie_scattering_{c}"] = EARTH_DEFAULTS[f"mie_scattering_{c}"] * float(tint[i])
    return out


def _scale_and_colour(params: Mapping[str, float], name: str) -> tuple[float, list[float]]:
    v = rgb_of(params, name)
    scale = float(np.max(v))
    return scale, [float(x / scale) if scale > 0 else 0.0 for x in v]


def _properties(params: Mapping[str, float]) -> dict[str, Any]:
    """The component's properties (editor Python names) and their values."""
    out: dict[str, Any] = {
        "bottom_radius": params["bottom_radius_km"],
        "atmosphere_height": params["atmosphere_height_km"],
        "ground_albedo": [params["ground_albedo"]] * 3,
        "multi_scattering_factor": 1.0,
    }
    for name, prop in (
        ("rayleigh_scattering", "rayleigh_scattering"),
        ("mie_scattering", "mie_scattering"),
        ("mie_absorption", "mie_absorption"),
        ("other_absorption", "other_absorption"),
    ):
        scale, colour = _scale_and_colour(params, name)
        out[f"{prop}_scale"] = scale
        out[prop] = colour
    out["rayleigh_exponential_distribution"] = params["rayleigh_exponential_distribution_km"]
    out["mie_anisotropy"] = params["mie_anisotropy"]
    out["mie_exponential_distribution"] = params["mie_exponential_distribution_km"]
    out["other_tent_distribution"] = {
        "tip_altitude": params["other_tent_tip_altitude_km"],
        "tip_value": 1.0,
        "width": params["other_tent_width_km"],
    }
    return out


def _header(fit: EngineFit) -> list[str]:
    ev = math.log2(fit.params["exposure"])
    return [
        f"Unreal Engine SkyAtmosphere properties for {fit.atmosphere} ({fit.kind} by dustoptics).",
        f"Model read from: {UNREAL_SOURCE}.",
        "Units: km (radius, height, exponential distributions) and km^-1 (scale x colour).",
        "Light the level with a directional light (Atmosphere Sun Light) of the Sun's colour;",
        f"exposure compensation {ev:+.3f} EV gives radiance per unit solar illuminance [sr^-1].",
        *error_header(fit),
    ]


def _python_value(value: Any, key: str) -> str:
    if key == "ground_albedo":
        srgb = [_srgb8(v) for v in value]
        return f"unreal.Color(r={srgb[0]}, g={srgb[1]}, b={srgb[2]}, a=255)"
    if isinstance(value, list):
        return f"unreal.LinearColor({value[0]!r}, {value[1]!r}, {value[2]!r}, 1.0)"
    if isinstance(value, dict):
        args = ", ".join(f"{k}={v!r}" for k, v in value.items())
        return f"unreal.TentDistribution({args})"
    return repr(float(value))


def _srgb8(linear: float) -> int:
    v = 12.92 * linear if linear <= 0.0031308 else 1.055 * linear ** (1 / 2.4) - 0.055
    return round(min(max(v, 0.0), 1.0) * 255)


def unreal_files(fit: EngineFit) -> dict[str, str]:
    """The two files' contents: ``json`` and ``py``."""
    props = _properties(fit.params)
    header = _header(fit)
    script = [
        *(f"# {line}" for line in header),
        "#",
        "# Run in the Unreal Editor's Python console with the SkyAtmosphere actor selected.",
        "import unreal",
        "",
        "PROPERTIES = {",
        *(f"    {k!r}: {_python_value(v, k)}," for k, v in props.items()),
        "}",
        "",
        "for actor in unreal.EditorLevelLibrary.get_selected_level_actors():",
        "    for component in actor.get_components_by_class(unreal.SkyAtmosphereComponent):",
        "        for name, value in PROPERTIES.items():",
        "            component.set_editor_property(name, value)",
        "",
    ]
    return {
        "json": fit_json(
            fit,
            header,
            "Unreal Engine SkyAtmosphere",
            UNREAL_SOURCE,
            properties=props,
            exposure_compensation_ev=math.log2(fit.params["exposure"]),
        ),
        "py": "\n".join(script),
    }


def write_unreal(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """Write ``NAME_unreal_sky_atmosphere.json`` and ``.py`` atomically."""
    return write_texts(
        fit, out_dir, "unreal_sky_atmosphere", unreal_files(fit), overwrite=overwrite
    )


UNREAL = register_engine(
    EngineModel(
        name="unreal",
        title="Unreal Engine SkyAtmosphere",
        source=UNREAL_SOURCE,
        parameters=(
            *per_channel("rayleigh_scattering", 1e-7, 1.0, "km^-1"),
            Parameter("rayleigh_exponential_distribution_km", 0.1, 100.0, log=True, unit="km"),
            *per_channel("mie_scattering", 1e-7, 10.0, "km^-1"),
            *per_channel("mie_absorption", 1e-8, 10.0, "km^-1"),
            Parameter("mie_anisotropy", 0.0, 0.999),
            Parameter("mie_exponential_distribution_km", 0.1, 100.0, log=True, unit="km"),
            Parameter("exposure", 1e-3, 1e3, log=True),
        ),
        community_parameters=("exposure",),
        render=unreal_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_unreal,
    ),
    suffixes=(".json", ".py"),
)
