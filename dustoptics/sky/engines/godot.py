"""Godot 4's PhysicalSkyMaterial: its model and format (a ``.tres`` resource).

Implemented from the sky shader that ``PhysicalSkyMaterial::_update_shader``
builds in ``scene/resources/sky_material.cpp`` of Godot 4.0 to 4.4 (the
shader Godot 4.4.1-stable ships): Preetham-style extinction with the
``optical_mass`` of Kasten and Young, ``sun_energy = (1 - exp(-elevation))
LIGHT0_ENERGY``, the Rayleigh phase of ``cos_theta * 0.5 + 0.5``, a
Henyey-Greenstein Mie phase, the ``pow(..., 1.5)`` in-scattering, the
three.js-derived ``mix(..., pow(..., 0.5), (1 - zenith_angle)^5)`` factor,
the ground-colour blend below 0.1 of ``EYEDIR.y``, and ``COLOR = pow(Lin + L0,
1 / (1.2 + 1.2 sun_fade)) * exposure`` (``exposure`` is the material's
``energy_multiplier``).  The colours carry ``source_color``: Godot converts
them from sRGB to linear before the shader sees them, and so does this model
(the ``.tres`` holds them sRGB-encoded, as the inspector shows them).  The
Sun disc and the night sky are left out; ``LIGHT0_ENERGY`` is 1 (the
DirectionalLight3D's default energy).  Godot's development branch after 4.4
changed ``sun_energy`` and ``optical_mass``; these files are for 4.0-4.4.

The fit adjusts ``rayleigh_coefficient``, ``rayleigh_color``,
``mie_coefficient``, ``mie_eccentricity``, ``mie_color`` and
``energy_multiplier`` (one for every Sun elevation); ``turbidity`` only
multiplies ``mie_coefficient`` and stays 10.

Community row: the material's defaults (rayleigh 2, colour (0.3, 0.405,
0.6), mie 0.005, eccentricity 0.8, colour (0.69, 0.729, 0.812), turbidity 10,
ground (0.1, 0.07, 0.034)) with, for a dust, both colours set to the dust's
tint (:func:`~dustoptics.sky.engines.core.dust_tint_linear_srgb`); only the
energy multiplier adjusted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics import colour
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky.engines.core import (
    RGB,
    EngineFit,
    EngineModel,
    Parameter,
    dust_tint_linear_srgb,
    error_header,
    register_engine,
    rgb_of,
    smoothstep,
    write_texts,
    y_up_directions,
)

__all__ = ["GODOT", "GODOT_SOURCE", "godot_sky_rgb", "godot_tres", "srgb_decode"]

GODOT_SOURCE: Final = (
    "Godot 4.0-4.4 (4.4.1-stable) scene/resources/sky_material.cpp, "
    "PhysicalSkyMaterial::_update_shader"
)


def srgb_decode(encoded: Any) -> np.ndarray:
    """The sRGB transfer function's inverse (IEC 61966-2-1), as Godot's ``source_color``."""
    c = np.asarray(encoded, dtype=float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _encode(linear: np.ndarray) -> np.ndarray:
    return np.asarray(colour.srgb_encode(np.clip(linear, 0.0, 1.0)))


#: The material's defaults; colours linear (``*_r, *_g, *_b``, decoded from the sRGB defaults).
DEFAULTS: Final = {
    "rayleigh_coefficient": 2.0,
    **{
        f"rayleigh_color_{c}": float(v)
        for c, v in zip(RGB, srgb_decode([0.3, 0.405, 0.6]), strict=True)
    },
    "mie_coefficient": 0.005,
    "mie_eccentricity": 0.8,
    **{
        f"mie_color_{c}": float(v)
        for c, v in zip(RGB, srgb_decode([0.69, 0.729, 0.812]), strict=True)
    },
    "turbidity": 10.0,
    **{
        f"ground_color_{c}": float(v)
        for c, v in zip(RGB, srgb_decode([0.1, 0.07, 0.034]), strict=True)
    },
    "energy_multiplier": 1.0,
}


def godot_sky_rgb(
    params: Mapping[str, float],
    *,
    sun_elevation_deg: float,
    view_zenith_deg: Any,
    view_azimuth_deg: Any,
) -> np.ndarray:
    """The colour the PhysicalSkyMaterial writes (``COLOR``), linear. [engine units]"""
    eye, light = y_up_directions(sun_elevation_deg, view_zenith_deg, view_azimuth_deg)
    zenith_angle = min(max(light[1], -1.0), 1.0)
    sun_energy = max(0.0, 1.0 - math.exp(-(math.pi / 2 - math.acos(zenith_angle))))
    sun_fade = 1.0 - min(max(1.0 - math.exp(light[1]), 0.0), 1.0)
    rc, mc, ground = (rgb_of(params, f"{n}_color") for n in ("rayleigh", "mie", "ground"))
    rayleigh_beta = (params["rayleigh_coefficient"] - (1.0 - sun_fade)) * rc * 0.0001
    mie_beta = params["turbidity"] * params["mie_coefficient"] * mc * 0.000434
    up_eye = eye[..., 1]
    zenith = np.arccos(np.maximum(0.0, up_eye))
    optical_mass = 1.0 / (np.cos(zenith) + 0.15 * (93.885 - np.degrees(zenith)) ** -1.253)
    extinction = np.exp(
        -(
            rayleigh_beta * (8.4e3 * optical_mass)[..., None]
            + mie_beta * (1.25e3 * optical_mass)[..., None]
        )
    )
    cos_theta = (eye @ light)[..., None]
    r_phase = 3.0 / (16.0 * math.pi) * (1.0 + (cos_theta * 0.5 + 0.5) ** 2)
    g = params["mie_eccentricity"]
    m_phase = 0.0795774715459 * (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta) ** 1.5
    ratio = (rayleigh_beta * r_phase + mie_beta * m_phase) / (rayleigh_beta + mie_beta)
    lin = (sun_energy * ratio * (1.0 - extinction)) ** 1.5
    mix = min(max((1.0 - zenith_angle) ** 5, 0.0), 1.0)
    lin = lin * ((1.0 - mix) + mix * np.sqrt(sun_energy * ratio * extinction))
    blend = smoothstep(-0.1, 0.1, up_eye)[..., None]
    lin = lin * (ground * (1.0 - blend) + blend)
    out = lin ** (1.0 / (1.2 + 1.2 * sun_fade)) * params["energy_multiplier"]
    return np.asarray(out, dtype=float)


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    return {**DEFAULTS, "energy_multiplier": 0.01}


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    out = {**DEFAULTS, "energy_multiplier": 0.01}
    if atmosphere.name.startswith("mars"):
        tint = dust_tint_linear_srgb(atmosphere)
        for i, c in enumerate(RGB):
            out[f"rayleigh_color_{c}"] = out[f"mie_color_{c}"] = float(tint[i])
    return out


def _color(params: Mapping[str, float], name: str) -> str:
    enc = _encode(rgb_of(params, name))
    return f"Color({enc[0]:.6g}, {enc[1]:.6g}, {enc[2]:.6g}, 1)"


def _comment(fit: EngineFit) -> str:
    lines = [
        f"PhysicalSkyMaterial for {fit.atmosphere} ({fit.kind} by dustoptics).",
        f"Model read from: {GODOT_SOURCE}.",
        "Colours sRGB-encoded as the inspector shows them (source_color). A",
        "DirectionalLight3D of energy 1 is the Sun; energy_multiplier maps the sky to",
        "radiance per unit solar illuminance [sr^-1] (times Godot's own exposure).",
        *error_header(fit),
    ]
    return "\n".join(lines)


def _godot_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{escaped}"'


def godot_tres(fit: EngineFit) -> str:
    """The ``.tres`` resource (Godot 4 text resource, ``format=3``).

    The comment block is the resource's ``metadata/comment`` (Godot keeps it
    with the material; ``;`` comments are dropped when Godot saves the file).
    """
    p = fit.params
    lines = [
        '[gd_resource type="PhysicalSkyMaterial" format=3]',
        "",
        "[resource]",
        f"metadata/comment = {_godot_string(_comment(fit))}",
        f"rayleigh_coefficient = {p['rayleigh_coefficient']:.6g}",
        f"rayleigh_color = {_color(p, 'rayleigh_color')}",
        f"mie_coefficient = {p['mie_coefficient']:.6g}",
        f"mie_eccentricity = {p['mie_eccentricity']:.6g}",
        f"mie_color = {_color(p, 'mie_color')}",
        f"turbidity = {p['turbidity']:.6g}",
        "sun_disk_scale = 1.0",
        f"ground_color = {_color(p, 'ground_color')}",
        f"energy_multiplier = {p['energy_multiplier']:.6g}",
        "",
    ]
    return "\n".join(lines)


def write_godot(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """Write ``NAME_godot_physical_sky.tres`` atomically."""
    return write_texts(
        fit, out_dir, "godot_physical_sky", {"tres": godot_tres(fit)}, overwrite=overwrite
    )


GODOT = register_engine(
    EngineModel(
        name="godot",
        title="Godot 4 PhysicalSkyMaterial",
        source=GODOT_SOURCE,
        parameters=(
            Parameter("rayleigh_coefficient", 0.01, 64.0, log=True),
            *(Parameter(f"rayleigh_color_{c}", 0.0, 1.0) for c in RGB),
            Parameter("mie_coefficient", 1e-5, 1.0, log=True),
            Parameter("mie_eccentricity", -0.99, 0.99),
            *(Parameter(f"mie_color_{c}", 0.0, 1.0) for c in RGB),
            Parameter("energy_multiplier", 1e-5, 128.0, log=True),
        ),
        community_parameters=("energy_multiplier",),
        render=godot_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_godot,
    ),
    suffixes=(".tres",),
)
