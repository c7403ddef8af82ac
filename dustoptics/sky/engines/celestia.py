"""Celestia's scattering sky: its model, fitted, and its ``.ssc`` format.

The model is the sky-dome path of Celestia's generated shader
(``src/celengine/shadermanager.cpp`` at :data:`~dustoptics.io.engines.celestia.CELESTIA_SOURCE`:
``ChapmanOpticalDepth``, ``AtmosphericEffects`` and ``ScatteringPhaseFunctions``;
``CelestiaGLProgram::setAtmosphereParameters``; the defaults of
``src/celengine/render.h``: 6 segments, extinction threshold 0.000125), in
planet radii as the shader works:

- one exponential density ``exp(-(r - 1) mieH)``, ``mieH = R / MieScaleHeight``,
  for Rayleigh, Mie and absorption alike; the sky shell ends at ``MieScaleHeight
  * -ln(0.000125)`` (``getAtmosphereShellHeight``);
- the view ray from the eye to the shell in 6 equal segments; each segment's
  column is a difference of Celestia's Chapman approximation ``chapmanToSpace``
  along the ray, its light the segment integral ``(1 - exp(-ext col)) / ext``
  times the transmittance ``exp(-ext (odAtm + odSun))`` to the eye and to the
  Sun (``odSun``: ``chapmanToSpace`` at the segment's middle, toward the Sun,
  minus ``chapmanFromAtmosphereBoundary``) and the Sun's visibility (a
  smoothstep over the planet's shadow);
- ``(0.75 (1 + mu^2) Rayleigh + (1 - k^2) / (1 - k mu)^2 Mie)`` times that light,
  ``k = 1.55 g - 0.55 g^3``, ``mu`` the cosine of the scattering angle;
  ``extinction = Rayleigh + Mie + Absorption`` (all in km^-1 times the radius).

Single scattering only (Celestia has no multiple scattering).  The shader's
colour has no physical unit (its phase functions lack ``1 / (4 pi)``, the
light is the star's colour times its brightness): ``exposure`` scales it to
radiance per unit solar illuminance, the light colour being the sunlight's
(:func:`~dustoptics.sky.engines.core.sunlight_linear_srgb`).  The observer is 2 m
above the ground, as for the exact sky.

Fitted: ``Mie``, ``MieScaleHeight``, ``MieHGAnisotropy``, ``Rayleigh`` and
``Absorption`` per channel, ``exposure``; start: :func:`~dustoptics.io.engines.celestia.celestia_parameters`
(each vertical optical depth kept).  Community row: CelestiaContent's own Mars
(``Mie 0.003``, ``MieScaleHeight 11.1``, ``Rayleigh [0.00022 0.00034 0.00070]``,
``Absorption [0.002 0.002 0.003]``, no anisotropy: isotropic dust) and Earth
(``Rayleigh [0.004847 0.01149 0.02870]``, ``MieScaleHeight 8.5``, ``Mie 0.0002``,
``MieAsymmetry -0.7``, i.e. g = 0.7, ``Absorption [0.0037 0.0025 0]``), only
the exposure adjusted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.io.engines.celestia import (
    CELESTIA_CONTENT_SOURCE,
    CELESTIA_SOURCE,
    CelestiaAtmosphere,
    celestia_parameters,
    celestia_schlick_k,
    celestia_ssc,
)
from dustoptics.sky.engines.core import (
    RGB,
    EngineFit,
    EngineModel,
    Parameter,
    error_notes,
    per_channel,
    register_engine,
    rgb_of,
    smoothstep,
    sunlight_linear_srgb,
    write_texts,
)

__all__ = ["CELESTIA", "celestia_sky_rgb"]

_SEGMENTS: Final = 6  # render.h: atmosphereSegmentCount
_THRESHOLD: Final = 0.000125  # render.h: atmosphereExtinctionThreshold
_OBSERVER_ALTITUDE_KM: Final = 0.002

#: CelestiaContent's data/solarsys.ssc (see CELESTIA_CONTENT_SOURCE), per planet.
COMMUNITY: Final = {
    "mars": {
        "Mie": 0.003,
        "MieScaleHeight": 11.1,
        "MieHGAnisotropy": 0.0,
        "Rayleigh": (0.00022, 0.00034, 0.00070),
        "Absorption": (0.002, 0.002, 0.003),
    },
    "earth": {
        "Mie": 0.0002,
        "MieScaleHeight": 8.5,
        "MieHGAnisotropy": 0.7,  # MieAsymmetry -0.7, read with the opposite sign
        "Rayleigh": (0.004847, 0.01149, 0.02870),
        "Absorption": (0.0037, 0.0025, 0.0),
    },
}


def _chapman_to_space(r: np.ndarray, mu: np.ndarray, mie_h: float) -> np.ndarray:
    """``chapmanToSpace(r, mu)`` of the shader (planet radius 1). [planet radii]"""
    mu = np.clip(mu, -1.0, 1.0)
    x = r * mie_h
    density = np.exp(np.minimum((1.0 - r) * mie_h, 0.0))
    grazing = np.sqrt(1.5707963267948966 * x)
    up = (density / mie_h) * grazing / ((grazing - 1.0) * np.abs(mu) + 1.0)
    sin_zenith = np.sqrt(np.maximum(1.0e-8, 1.0 - mu * mu))
    tangent = np.exp(np.minimum((1.0 - r * sin_zenith) * mie_h, 0.0))
    down = np.maximum(
        0.0, (2.0 * tangent / mie_h) * np.sqrt(1.5707963267948966 * x * sin_zenith) - up
    )
    return np.where(mu >= 0.0, up, down)


def celestia_sky_rgb(
    params: Mapping[str, float],
    *,
    sun_elevation_deg: float,
    view_zenith_deg: Any,
    view_azimuth_deg: Any,
) -> np.ndarray:
    """Celestia's sky dome in linear sRGB times ``params["exposure"]`` (see the module docstring).

    Parameters
    ----------
    params : mapping
        ``Mie`` [km^-1], ``MieScaleHeight`` [km], ``MieHGAnisotropy``,
        ``Rayleigh_r/g/b`` and ``Absorption_r/g/b`` [km^-1], ``exposure``,
        ``planet_radius_km``. [-]
    sun_elevation_deg : float
    view_zenith_deg, view_azimuth_deg : array_like
        Directions, azimuth from the Sun's. [deg]

    Returns
    -------
    numpy.ndarray, shape ``broadcast(view_zenith_deg, view_azimuth_deg).shape + (3,)``
    """
    radius = float(params["planet_radius_km"])
    h = float(params["MieScaleHeight"])
    mie_h = radius / h
    r_sky = 1.0 + h * -math.log(_THRESHOLD) / radius
    rayleigh = rgb_of(params, "Rayleigh") * radius
    mie = float(params["Mie"]) * radius
    ext = rayleigh + mie + rgb_of(params, "Absorption") * radius
    zen = np.radians(np.asarray(view_zenith_deg, dtype=float))
    azi = np.radians(np.asarray(view_azimuth_deg, dtype=float))
    zen, azi = np.broadcast_arrays(zen, azi)
    view = np.stack([np.sin(zen) * np.cos(azi), np.sin(zen) * np.sin(azi), np.cos(zen)], axis=-1)
    e = math.radians(sun_elevation_deg)
    light = np.array([math.cos(e), 0.0, math.sin(e)])
    eye = np.array([0.0, 0.0, 1.0 + _OBSERVER_ALTITUDE_KM / radius])
    rq = view @ eye
    dist = -rq + np.sqrt(np.maximum(rq * rq - (eye @ eye - r_sky * r_sky), 0.0))
    step = dist / _SEGMENTS
    shadow_width = (r_sky + 1.0) * 0.5 * min(0.2, math.sqrt(2.0 / mie_h))
    boundary_grazing = math.sqrt(1.5707963267948966 * r_sky * mie_h)
    start_r2 = np.full(rq.shape, float(eye @ eye))
    start_proj = rq.copy()
    od_atm = np.zeros(rq.shape)
    light_sum = np.zeros(rq.shape + (3,))
    for i in range(_SEGMENTS):
        end_proj = start_proj + step
        end_r2 = np.maximum(1.0e-12, start_r2 + step * (2.0 * start_proj + step))
        start_r, end_r = np.sqrt(start_r2), np.sqrt(end_r2)
        inward = end_r2 < start_r2
        sign = np.where(inward, -1.0, 1.0)
        c0 = _chapman_to_space(start_r, sign * start_proj / start_r, mie_h)
        c1 = _chapman_to_space(end_r, sign * end_proj / end_r, mie_h)
        depth = np.maximum(0.0, np.where(inward, c1 - c0, c0 - c1))
        sample = eye + view * ((i + 0.5) * step)[..., None]
        s_rq = sample @ light
        s_r2 = np.sum(sample * sample, axis=-1)
        horizon = np.sqrt(np.maximum(0.0, s_r2 - 1.0))
        visibility = smoothstep(-shadow_width, shadow_width, s_rq + horizon)
        d = np.sqrt(np.maximum(s_rq * s_rq - (s_r2 - r_sky * r_sky), 0.0))
        s_r = np.sqrt(s_r2)
        boundary = (
            (_THRESHOLD / mie_h)
            * boundary_grazing
            / ((boundary_grazing - 1.0) * np.clip(d / r_sky, 0.0, 1.0) + 1.0)
        )
        od_sun = np.maximum(0.0, _chapman_to_space(s_r, s_rq / s_r, mie_h) - boundary)
        tau = ext * depth[..., None]
        integral = np.where(
            tau < 1.0e-3,
            depth[..., None] * (1.0 - tau * 0.5 + tau * tau / 6.0),
            (1.0 - np.exp(-tau)) / ext,
        )
        transmittance = np.exp(-ext * (od_atm + od_sun)[..., None])
        light_sum += np.where(
            (visibility > 0.0)[..., None], transmittance * integral * visibility[..., None], 0.0
        )
        od_atm = od_atm + depth
        start_r2, start_proj = end_r2, end_proj
    mu = view @ light
    k = float(celestia_schlick_k(params["MieHGAnisotropy"]))
    ph_mie = (1.0 - k * k) / (1.0 - k * mu) ** 2
    ph_rayleigh = 0.75 * (1.0 + mu * mu)
    colour = (ph_rayleigh[..., None] * rayleigh + ph_mie[..., None] * mie) * light_sum
    return np.asarray(params["exposure"] * colour * sunlight_linear_srgb(), dtype=float)


def _planet(atmosphere: Atmosphere) -> str:
    return "earth" if "earth" in atmosphere.name else "mars"


def _values(p: CelestiaAtmosphere) -> dict[str, Any]:
    return {
        "Mie": p.mie_per_km,
        "MieScaleHeight": p.mie_scale_height_km,
        "MieHGAnisotropy": p.mie_hg_anisotropy,
        "Rayleigh": p.rayleigh_per_km,
        "Absorption": p.absorption_per_km,
    }


def _flat(values: Mapping[str, Any], radius_km: float) -> dict[str, float]:
    out = {
        "Mie": float(values["Mie"]),
        "MieScaleHeight": float(values["MieScaleHeight"]),
        "MieHGAnisotropy": float(values["MieHGAnisotropy"]),
        "planet_radius_km": radius_km,
        # Celestia's phase functions lack 1 / (4 pi): this exposure makes them per sr.
        "exposure": 1.0 / (4.0 * math.pi),
    }
    for name in ("Rayleigh", "Absorption"):
        for c, v in zip(RGB, values[name], strict=True):
            out[f"{name}_{c}"] = max(float(v), 1e-9)
    return out


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    return _flat(_values(celestia_parameters(atmosphere)), atmosphere.planet_radius_m / 1000.0)


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    return _flat(COMMUNITY[_planet(atmosphere)], atmosphere.planet_radius_m / 1000.0)


def _parameters_of(fit: EngineFit) -> CelestiaAtmosphere:
    p = fit.params
    top_km = (
        fit.atmosphere_info["atmosphere_radius_m"] - fit.atmosphere_info["planet_radius_m"]
    ) / 1000.0
    return CelestiaAtmosphere(
        name=fit.atmosphere,
        body="Earth" if "earth" in fit.atmosphere else "Mars",
        parent="Sol",
        height_km=top_km,
        mie_per_km=float(p["Mie"]),
        mie_scale_height_km=float(p["MieScaleHeight"]),
        mie_hg_anisotropy=float(p["MieHGAnisotropy"]),
        rayleigh_per_km=(p["Rayleigh_r"], p["Rayleigh_g"], p["Rayleigh_b"]),
        absorption_per_km=(p["Absorption_r"], p["Absorption_g"], p["Absorption_b"]),
        notes=(
            f"{fit.kind} to dustoptics' exact spectral sky of {fit.atmosphere!r} (single "
            "scattering model of Celestia's shader; CIE Delta E 2000 over the dome):",
            *error_notes(fit),
            f"exposure (the shader's colour to radiance per unit solar illuminance) "
            f"{float(p['exposure']):.6g}",
            f"community row: {CELESTIA_CONTENT_SOURCE}",
        ),
    )


def write_celestia_fit(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """Write ``NAME_celestia.ssc`` of a fit."""
    text = celestia_ssc(_parameters_of(fit))
    return write_texts(fit, out_dir, "celestia", {"ssc": text}, overwrite=overwrite)


CELESTIA = register_engine(
    EngineModel(
        name="celestia",
        title="Celestia (scattering shader)",
        source=CELESTIA_SOURCE,
        parameters=(
            Parameter("Mie", 1e-7, 1.0, log=True, unit="km^-1"),
            Parameter("MieScaleHeight", 0.5, 60.0, log=True, unit="km"),
            Parameter("MieHGAnisotropy", -0.9, 0.95),
            *per_channel("Rayleigh", 1e-8, 1.0, "km^-1"),
            *per_channel("Absorption", 1e-9, 1.0, "km^-1"),
            Parameter("exposure", 1e-6, 1e3, log=True),
        ),
        community_parameters=("exposure",),
        render=celestia_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_celestia_fit,
    ),
    suffixes=(".ssc",),
)
