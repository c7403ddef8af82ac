"""Unity HDRP's Physically Based Sky (Unity 6, HDRP 17): its model and format.

Read from Unity-Technologies/Graphics (``Packages/com.unity.render-pipelines.
high-definition/Runtime/Sky/PhysicallyBasedSky/``): ``PhysicallyBasedSky.cs``
(the Volume override's parameters and how they become coefficients),
``PhysicallyBasedSkyCommon.hlsl`` (the medium, the Chapman approximation of the
transmittance, the phase functions), ``PhysicallyBasedSkyEvaluation.hlsl``
(``GetSample``: 16 samples, quadratic) and ``SkyLUTGenerator.compute`` (Hillaire
2020's multiple-scattering table over 64 Hammersley directions and the sky-view
table).  The numpy version is :mod:`~dustoptics.sky.engines._hillaire`.

The override's ``Custom`` model:

- air: extinction per channel from the zenith opacity ``airDensityR/G/B``
  (``ExtinctionFromZenithOpacityAndScaleHeight``: ``-ln(1 - alpha) / H``),
  single-scattering albedo ``airTint``, scale height ``H = 0.144765
  airMaximumAltitude`` (the altitude where the density falls to 0.1 %),
  Rayleigh phase function;
- aerosols: one grey extinction from ``aerosolDensity`` and
  ``aerosolMaximumAltitude`` the same way, scattering = extinction x
  ``aerosolTint``, Cornette-Shanks phase function of ``aerosolAnisotropy``;
- ozone: (0.00065, 0.00188, 0.00008) km^-1 x ``ozoneDensityDimmer`` in a tent
  from ``ozoneMinimumAltitude`` over ``ozoneLayerWidth`` (defaults 20 and 20 km);
- the top of the atmosphere at the larger of the two maximum altitudes; the
  planet's radius is the Visual Environment's (Unity 6 moved it there).

Defaults (Earth): air scattering (5.8, 13.5, 33.1) x 1e-6 m^-1 over 8 km
(``airMaximumAltitude`` 55.26 km), aerosol extinction 10e-6 m^-1 over 1.2 km
with tint 0.9 and anisotropy 0.8, ozone dimmer 1, ground tint (0.12, 0.10,
0.09), radius 6378.1 km.

The fit adjusts the air's three extinctions and maximum altitude, the
aerosols' extinction, tint, maximum altitude and anisotropy, and one exposure
(the camera's, the same for every Sun elevation); the ozone dimmer is 1 for a
set with ozone, 0 without; the ground tint is 0.2 (the exact sky's albedo).
The Sun is a directional light of the sunlight's colour.

Community row: the defaults with the planet's radius and, for a dust, the
aerosol tint set to the dust's tint
(:func:`~dustoptics.sky.engines.core.dust_tint_linear_srgb`); only the exposure
adjusted.

Files: ``NAME_unity_pbs.json`` and ``NAME_unity_pbs.asset``, a Volume Profile
in Unity's YAML with the Physically Based Sky override (its script GUIDs are
those of the HDRP and SRP-core packages' ``PhysicallyBasedSky.cs.meta`` and
``VolumeProfile.cs.meta``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.io._atomic import safe_stem
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

__all__ = ["UNITY", "UNITY_SOURCE", "unity_files", "unity_setup", "unity_sky_rgb"]

UNITY_SOURCE: Final = (
    "Unity 6 HDRP 17 Physically Based Sky, Unity-Technologies/Graphics "
    "Runtime/Sky/PhysicallyBasedSky/PhysicallyBasedSky.cs, PhysicallyBasedSkyCommon.hlsl, "
    "PhysicallyBasedSkyEvaluation.hlsl, SkyLUTGenerator.compute"
)

#: ``ScaleHeightFromLayerDepth``: H = d x 0.144765 (density 0.1 % at the layer depth d).
LAYER_DEPTH_TO_SCALE_HEIGHT: Final = 0.144765

#: Script GUIDs of ``PhysicallyBasedSky.cs`` (HDRP) and ``VolumeProfile.cs`` (SRP core).
PBS_SCRIPT_GUID: Final = "d877ec3e844f2ca46830012e8e79319b"
VOLUME_PROFILE_GUID: Final = "d7fd9488000d3734a9e00ee676215985"

_OZONE_PER_M: Final = np.array([0.00065, 0.00188, 0.00008]) / 1000.0

#: The override's Earth defaults, SI units (extinctions in m^-1, altitudes in m).
EARTH_DEFAULTS: Final = {
    "planet_radius_m": 6378100.0,
    "air_extinction_r": 5.8e-6,
    "air_extinction_g": 13.5e-6,
    "air_extinction_b": 33.1e-6,
    "air_tint": 1.0,
    "air_maximum_altitude_m": 8000.0 / LAYER_DEPTH_TO_SCALE_HEIGHT,
    "aerosol_extinction": 10e-6,
    "aerosol_tint_r": 0.9,
    "aerosol_tint_g": 0.9,
    "aerosol_tint_b": 0.9,
    "aerosol_maximum_altitude_m": 1200.0 / LAYER_DEPTH_TO_SCALE_HEIGHT,
    "aerosol_anisotropy": 0.8,
    "ozone_density_dimmer": 1.0,
    "ozone_minimum_altitude_m": 20000.0,
    "ozone_layer_width_m": 20000.0,
    "ground_tint": 0.12,
    "exposure": 1.0,
}


def unity_setup(params: Mapping[str, float]) -> _hillaire.HillaireSetup:
    """The Hillaire medium of the override's values (every key of :data:`EARTH_DEFAULTS`)."""
    radius_km = params["planet_radius_m"] / 1000.0
    air_ext = rgb_of(params, "air_extinction") * 1000.0
    air_scat = air_ext * params["air_tint"]
    aer_ext = params["aerosol_extinction"] * 1000.0
    tint = rgb_of(params, "aerosol_tint")
    top = max(params["air_maximum_altitude_m"], params["aerosol_maximum_altitude_m"]) / 1000.0
    bottom = params["ozone_minimum_altitude_m"] / 1000.0
    width = params["ozone_layer_width_m"] / 1000.0
    return _hillaire.HillaireSetup(
        planet_radius_km=radius_km,
        top_radius_km=radius_km + top,
        rayleigh_scattering_per_km=air_scat,
        rayleigh_absorption_per_km=air_ext - air_scat,
        rayleigh_scale_height_km=params["air_maximum_altitude_m"]
        * LAYER_DEPTH_TO_SCALE_HEIGHT
        / 1000.0,
        mie_scattering_per_km=aer_ext * tint,
        mie_absorption_per_km=aer_ext * (1.0 - tint),
        mie_scale_height_km=params["aerosol_maximum_altitude_m"]
        * LAYER_DEPTH_TO_SCALE_HEIGHT
        / 1000.0,
        mie_phase=_hillaire.cornette_shanks(params["aerosol_anisotropy"]),
        ozone_absorption_per_km=_OZONE_PER_M * 1000.0 * params["ozone_density_dimmer"],
        ozone_bottom_km=bottom,
        ozone_peak_km=bottom + width / 2.0,
        ozone_top_km=bottom + width,
        ground_albedo=np.full(3, params["ground_tint"]),
        distribution="quadratic",
        ms_distribution="quadratic",
        directions="hammersley",
        ms_samples=16,
    )


unity_sky_rgb = hillaire_renderer(
    unity_setup,
    "unity_sky_rgb",
    """The Physically Based Sky per unit solar illuminance times ``exposure``, linear sRGB. [sr^-1]""",
)


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    """The set's own coefficients at 680, 550 and 440 nm: the fit's start."""
    ray = channel_values(atmosphere, "molecules", "beta_sca_per_m")
    sca = channel_values(atmosphere, "aerosols", "beta_sca_per_m")
    ext = sca + channel_values(atmosphere, "aerosols", "beta_abs_per_m")
    grey = float(np.max(ext))
    has_ozone = any(c.role == "ozone" for c in atmosphere.constituents)
    out = dict(EARTH_DEFAULTS)
    out.update(
        planet_radius_m=float(atmosphere.planet_radius_m),
        air_maximum_altitude_m=scale_height_m(atmosphere, "molecules", 8000.0)
        / LAYER_DEPTH_TO_SCALE_HEIGHT,
        aerosol_extinction=max(grey, 1e-9),
        aerosol_maximum_altitude_m=scale_height_m(atmosphere, "aerosols", 1200.0)
        / LAYER_DEPTH_TO_SCALE_HEIGHT,
        aerosol_anisotropy=float(
            np.clip(channel_values(atmosphere, "aerosols", "g")[1], -0.99, 0.99)
        ),
        ozone_density_dimmer=1.0 if has_ozone else 0.0,
        ground_tint=0.2,
        exposure=1.0,
    )
    for i, c in enumerate(RGB):
        out[f"air_extinction_{c}"] = float(max(ray[i], 1e-9))
        out[f"aerosol_tint_{c}"] = float(np.clip(sca[i] / grey, 0.0, 1.0)) if grey > 0 else 0.9
    return out


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    out = dict(EARTH_DEFAULTS)
    out["planet_radius_m"] = float(atmosphere.planet_radius_m)
    if atmosphere.name.startswith("mars"):
        tint = dust_tint_linear_srgb(atmosphere)
        for i, c in enumerate(RGB):
            out[f"aerosol_tint_{c}"] = float(tint[i])
    return out


def _opacity(extinction_per_m: float, max_altitude_m: float) -> float:
    """``ZenithOpacityFromExtinctionAndScaleHeight``: 1 - exp(-extinction H)."""
    return 1.0 - math.exp(-extinction_per_m * max_altitude_m * LAYER_DEPTH_TO_SCALE_HEIGHT)


def override_values(params: Mapping[str, float]) -> dict[str, Any]:
    """The override's serialized fields (``m_Value`` of each) for the fitted values."""
    air_alt = params["air_maximum_altitude_m"]
    return {
        "type": 2,  # PhysicallyBasedSkyModel.Custom
        "airDensityR": _opacity(params["air_extinction_r"], air_alt),
        "airDensityG": _opacity(params["air_extinction_g"], air_alt),
        "airDensityB": _opacity(params["air_extinction_b"], air_alt),
        "airTint": [params["air_tint"]] * 3,
        "airMaximumAltitude": air_alt,
        "aerosolDensity": _opacity(
            params["aerosol_extinction"], params["aerosol_maximum_altitude_m"]
        ),
        "aerosolTint": [params[f"aerosol_tint_{c}"] for c in RGB],
        "aerosolMaximumAltitude": params["aerosol_maximum_altitude_m"],
        "aerosolAnisotropy": params["aerosol_anisotropy"],
        "ozoneDensityDimmer": params["ozone_density_dimmer"],
        "ozoneMinimumAltitude": params["ozone_minimum_altitude_m"],
        "ozoneLayerWidth": params["ozone_layer_width_m"],
        "groundTint": [params["ground_tint"]] * 3,
    }


def _header(fit: EngineFit) -> list[str]:
    ev = math.log2(fit.params["exposure"])
    return [
        f"Unity HDRP Physically Based Sky (Custom) for {fit.atmosphere} ({fit.kind} by dustoptics).",
        f"Model read from: {UNITY_SOURCE}.",
        f"Visual Environment > Planet radius: {fit.params['planet_radius_m'] / 1000.0:.4f} km.",
        "Altitudes in m; densities are zenith opacities; tints are albedos.",
        "Light with a directional light of the Sun's colour; exposure compensation",
        f"{ev:+.3f} EV gives radiance per unit solar illuminance [sr^-1].",
        *error_header(fit),
    ]


def _yaml_value(value: Any) -> str:
    if isinstance(value, list):
        return f"{{r: {value[0]!r}, g: {value[1]!r}, b: {value[2]!r}, a: 1}}"
    if isinstance(value, int):
        return str(value)
    return repr(float(value))


def unity_asset(fit: EngineFit, name: str) -> str:
    """A Volume Profile asset (Unity YAML) holding the Physically Based Sky override."""
    lines = [
        "%YAML 1.1",
        "%TAG !u! tag:unity3d.com,2011:",
        *(f"# {line}" for line in _header(fit)),
        "--- !u!114 &11400000",
        "MonoBehaviour:",
        "  m_ObjectHideFlags: 0",
        "  m_CorrespondingSourceObject: {fileID: 0}",
        "  m_PrefabInstance: {fileID: 0}",
        "  m_PrefabAsset: {fileID: 0}",
        "  m_GameObject: {fileID: 0}",
        "  m_Enabled: 1",
        "  m_EditorHideFlags: 0",
        f"  m_Script: {{fileID: 11500000, guid: {VOLUME_PROFILE_GUID}, type: 3}}",
        f"  m_Name: {name}",
        "  m_EditorClassIdentifier: ",
        "  components:",
        "  - {fileID: 11400002}",
        "--- !u!114 &11400002",
        "MonoBehaviour:",
        "  m_ObjectHideFlags: 3",
        "  m_CorrespondingSourceObject: {fileID: 0}",
        "  m_PrefabInstance: {fileID: 0}",
        "  m_PrefabAsset: {fileID: 0}",
        "  m_GameObject: {fileID: 0}",
        "  m_Enabled: 1",
        "  m_EditorHideFlags: 0",
        f"  m_Script: {{fileID: 11500000, guid: {PBS_SCRIPT_GUID}, type: 3}}",
        "  m_Name: PhysicallyBasedSky",
        "  m_EditorClassIdentifier: ",
        "  active: 1",
    ]
    for key, value in override_values(fit.params).items():
        lines += [f"  {key}:", "    m_OverrideState: 1", f"    m_Value: {_yaml_value(value)}"]
    return "\n".join(lines) + "\n"


def unity_files(fit: EngineFit) -> dict[str, str]:
    """The two files' contents: ``json`` and ``asset``."""
    return {
        "json": fit_json(
            fit,
            _header(fit),
            "Unity HDRP Physically Based Sky",
            UNITY_SOURCE,
            planet_radius_km=fit.params["planet_radius_m"] / 1000.0,
            override=override_values(fit.params),
            exposure_compensation_ev=math.log2(fit.params["exposure"]),
        ),
        "asset": unity_asset(fit, f"{safe_stem(fit.atmosphere)}_unity_pbs"),
    }


def write_unity(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """Write ``NAME_unity_pbs.json`` and ``NAME_unity_pbs.asset`` atomically."""
    return write_texts(fit, out_dir, "unity_pbs", unity_files(fit), overwrite=overwrite)


UNITY = register_engine(
    EngineModel(
        name="unity",
        title="Unity HDRP Physically Based Sky",
        source=UNITY_SOURCE,
        parameters=(
            *per_channel("air_extinction", 1e-10, 1e-2, "m^-1"),
            Parameter("air_maximum_altitude_m", 1e3, 5e5, log=True, unit="m"),
            Parameter("aerosol_extinction", 1e-10, 1e-2, log=True, unit="m^-1"),
            *(Parameter(f"aerosol_tint_{c}", 0.0, 1.0) for c in RGB),
            Parameter("aerosol_maximum_altitude_m", 1e3, 5e5, log=True, unit="m"),
            Parameter("aerosol_anisotropy", -0.99, 0.99),
            Parameter("exposure", 1e-3, 1e3, log=True),
        ),
        community_parameters=("exposure",),
        render=unity_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_unity,
    ),
    suffixes=(".json", ".asset"),
)
