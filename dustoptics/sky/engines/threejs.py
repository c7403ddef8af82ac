"""three.js ``Sky`` (Preetham's analytic daylight as three.js draws it): its model and format.

Implemented from ``examples/jsm/objects/Sky.js`` of three.js r187 (npm ``three``
0.187.0, the version ``tests/sky/engines/threejs_sky`` pins): the vertex
shader's ``sunIntensity``, ``vSunfade``, ``totalRayleigh`` and ``totalMie``
and the fragment shader's optical length, extinction ``Fex``, in-scattering
``Lin`` (its two ``pow`` terms), night-sky ``L0`` and the ``* 0.04 + (0,
0.0003, 0.00075)`` offset.  ``sunPosition`` is a unit vector (as the three.js
example sets it), ``up`` is +y.  The Sun disc (``showSunDisc``) is left out
(the metrics exclude the Sun) and the clouds are off (``cloudCoverage = 0``,
written in the files; r187's default 0.4 draws procedural clouds).  Older
three.js (r170 and before, e.g. the repository at commit 0255e15d) ended with
``pow(texColor, 1 / (1.2 + 1.2 vSunfade))`` and had no clouds: these files
are for r187.

The shader's output is treated as linear sRGB and scaled by one exposure
(``renderer.toneMappingExposure`` with ``THREE.LinearToneMapping``) to radiance
per unit solar illuminance [sr^-1]; the fit adjusts that exposure,
``rayleigh``, ``mieCoefficient`` and ``mieDirectionalG`` (``turbidity`` only
multiplies ``mieCoefficient`` and stays at the example's 10).  The model's
Rayleigh and Mie colours are fixed by its three wavelengths (680, 550, 450 nm)
and Preetham's Mie constants: three.js cannot take a dust colour.

Community row: the three.js example's values (``webgl_shaders_sky.html``:
turbidity 10, rayleigh 3, mieCoefficient 0.005, mieDirectionalG 0.7), with
only the exposure adjusted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky.engines.core import (
    EngineFit,
    EngineModel,
    Parameter,
    error_header,
    fit_json,
    register_engine,
    write_texts,
    y_up_directions,
)

__all__ = ["THREEJS", "THREEJS_SOURCE", "threejs_files", "threejs_sky_rgb"]

#: The three.js version whose ``Sky.js`` the model follows.
THREEJS_SOURCE: Final = (
    "three.js r187 (npm three 0.187.0), examples/jsm/objects/Sky.js (Preetham et al. 1999 "
    "as implemented by S. Wallner, M. Upitis and zz85)"
)

_TOTAL_RAYLEIGH: Final = np.array(
    [5.804542996261093e-6, 1.3562911419845635e-5, 3.0265902468824876e-5]
)
_MIE_CONST: Final = np.array([1.8399918514433978e14, 2.7798023919660528e14, 4.0790479543861094e14])
_CUTOFF_ANGLE: Final = 1.6110731556870734
_STEEPNESS: Final = 1.5
_EE: Final = 1000.0
_RAYLEIGH_ZENITH_LENGTH: Final = 8.4e3
_MIE_ZENITH_LENGTH: Final = 1.25e3
_THREE_OVER_SIXTEENPI: Final = 0.05968310365946075
_ONE_OVER_FOURPI: Final = 0.07957747154594767

#: The three.js example's uniforms (``examples/webgl_shaders_sky.html``).
EXAMPLE_UNIFORMS: Final = {
    "turbidity": 10.0,
    "rayleigh": 3.0,
    "mieCoefficient": 0.005,
    "mieDirectionalG": 0.7,
}


def threejs_sky_rgb(
    params: Mapping[str, float],
    *,
    sun_elevation_deg: float,
    view_zenith_deg: Any,
    view_azimuth_deg: Any,
) -> np.ndarray:
    """The colour ``Sky.js`` writes (before tone mapping) times ``params["exposure"]``.

    Parameters
    ----------
    params : mapping
        ``turbidity``, ``rayleigh``, ``mieCoefficient``, ``mieDirectionalG``
        (the shader's uniforms) and ``exposure`` (``renderer.toneMappingExposure``). [-]
    sun_elevation_deg : float
        [deg]
    view_zenith_deg, view_azimuth_deg : array_like
        Directions, azimuth from the Sun's. [deg]

    Returns
    -------
    numpy.ndarray, shape ``broadcast(view_zenith_deg, view_azimuth_deg).shape + (3,)``
        Linear sRGB. [engine units times exposure]
    """
    direction, sun = y_up_directions(sun_elevation_deg, view_zenith_deg, view_azimuth_deg)
    up_dot_sun = float(sun[1])
    sun_e = _EE * max(0.0, 1.0 - math.exp(-((_CUTOFF_ANGLE - math.acos(up_dot_sun)) / _STEEPNESS)))
    sunfade = 1.0 - min(max(1.0 - math.exp(sun[1] / 450000.0), 0.0), 1.0)
    beta_r = _TOTAL_RAYLEIGH * (params["rayleigh"] - (1.0 - sunfade))
    beta_m = 0.434 * (0.2 * params["turbidity"]) * 10e-18 * _MIE_CONST * params["mieCoefficient"]
    cos_view = np.maximum(0.0, direction[..., 1])
    zenith = np.arccos(cos_view)
    inverse = 1.0 / (cos_view + 0.15 * (93.885 - np.degrees(zenith)) ** -1.253)
    s_r = (_RAYLEIGH_ZENITH_LENGTH * inverse)[..., None]
    s_m = (_MIE_ZENITH_LENGTH * inverse)[..., None]
    fex = np.exp(-(beta_r * s_r + beta_m * s_m))
    cos_theta = (direction @ sun)[..., None]
    r_phase = _THREE_OVER_SIXTEENPI * (1.0 + (cos_theta * 0.5 + 0.5) ** 2)
    g = params["mieDirectionalG"]
    m_phase = _ONE_OVER_FOURPI * (1.0 - g * g) / (1.0 - 2.0 * g * cos_theta + g * g) ** 1.5
    ratio = (beta_r * r_phase + beta_m * m_phase) / (beta_r + beta_m)
    lin = (sun_e * ratio * (1.0 - fex)) ** 1.5
    mix = min(max((1.0 - up_dot_sun) ** 5, 0.0), 1.0)
    lin = lin * ((1.0 - mix) + mix * np.sqrt(sun_e * ratio * fex))
    l0 = 0.1 * fex
    tex = (lin + l0) * 0.04 + np.array([0.0, 0.0003, 0.00075])
    return np.asarray(params["exposure"] * tex, dtype=float)


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    return {**EXAMPLE_UNIFORMS, "rayleigh": 1.0, "exposure": 1e-3}


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    return {**EXAMPLE_UNIFORMS, "exposure": 1e-3}


def _header(fit: EngineFit) -> list[str]:
    return [
        f"three.js Sky uniforms for {fit.atmosphere} ({fit.kind} by dustoptics).",
        f"Model read from: {THREEJS_SOURCE}.",
        "Use: sky.material.uniforms[name].value = value for each uniform;",
        "renderer.toneMapping = THREE.LinearToneMapping and renderer.toneMappingExposure =",
        "toneMappingExposure give radiance per unit solar illuminance [sr^-1]; multiply by your",
        "own exposure.  sunPosition: the unit vector toward the Sun, up = (0, 1, 0).",
        *error_header(fit),
    ]


def threejs_files(fit: EngineFit) -> dict[str, str]:
    """The two files' contents: ``NAME_threejs_sky.json`` and ``NAME_threejs_sky.mjs``."""
    uniforms = {k: float(fit.params[k]) for k in EXAMPLE_UNIFORMS}
    uniforms.update(cloudCoverage=0.0, showSunDisc=1.0)
    exposure = float(fit.params["exposure"])
    header = _header(fit)
    module = [
        *(f"// {line}" for line in header),
        "",
        "export const skyUniforms = {",
        *(f"  {k}: {v!r}," for k, v in uniforms.items()),
        "};",
        "",
        f"export const toneMappingExposure = {exposure!r};",
        "",
        "/** Set the uniforms on a three.js Sky (examples/jsm/objects/Sky.js). */",
        "export function applySkyUniforms(sky) {",
        "  for (const [name, value] of Object.entries(skyUniforms)) {",
        "    sky.material.uniforms[name].value = value;",
        "  }",
        "}",
        "",
    ]
    return {
        "json": fit_json(
            fit,
            header,
            "three.js Sky",
            THREEJS_SOURCE,
            uniforms=uniforms,
            toneMapping="LinearToneMapping",
            toneMappingExposure=exposure,
        ),
        "mjs": "\n".join(module),
    }


def write_threejs(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """Write ``NAME_threejs_sky.json`` and ``NAME_threejs_sky.mjs`` atomically."""
    return write_texts(fit, out_dir, "threejs_sky", threejs_files(fit), overwrite=overwrite)


THREEJS = register_engine(
    EngineModel(
        name="threejs",
        title="three.js Sky",
        source=THREEJS_SOURCE,
        parameters=(
            Parameter("rayleigh", 0.01, 64.0, log=True),
            Parameter("mieCoefficient", 1e-5, 1.0, log=True),
            Parameter("mieDirectionalG", -0.9, 0.999),
            Parameter("exposure", 1e-7, 10.0, log=True),
        ),
        community_parameters=("exposure",),
        render=threejs_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_threejs,
    ),
    suffixes=(".json", ".mjs"),
)
