"""OpenSpace's RenderableAtmosphere: its sky model, fitted, and its ``.asset`` file.

OpenSpace (:data:`~dustoptics.io.engines.openspace.OPENSPACE_SOURCE`) precomputes
Bruneton and Neyret's (2008) textures for a medium of two exponential layers:
Rayleigh scattering (R, G, B at 680, 550, 440 nm) and Mie scattering and
extinction with one Cornette-Shanks ``G`` (``miePhaseFunction`` of
``atmosphere_common.glsl``), in km and km^-1.  The model here evaluates that
medium with Hillaire's passes (:mod:`~dustoptics.sky.engines._hillaire`: single
scattering marched exactly, the higher orders by his isotropic multiple-scattering
table): OpenSpace's precomputation integrates the orders one by one, so the
model's higher orders are an approximation of OpenSpace's (the model is the
same medium, not the same solver).  OpenSpace's ozone (an exponential column
times 0.0000006) is not modelled and the fitted files have none; its
``SunIntensity`` and HDR exposure are one ``exposure`` here.

Fitted: ``Rayleigh`` scattering, Mie scattering and Mie absorption (written as
``Extinction`` = scattering + absorption) per channel, ``G`` and the exposure;
``H_R`` and ``H_M`` are the set's scale heights.  Community row: OpenSpace's own
Mars asset (``Rayleigh {0.019918, 0.01357, 0.00575}`` -- the largest at 680 nm,
Collienne's coefficients in reverse order -- ``H_R 10.43979``, Mie ``0.05361771``
grey with extinction ``/ 0.23862``, ``H_M 3.09526``, ``G 0.85``, radius 3386.19
km, 76.98 km high) and Earth asset (``Rayleigh {0.0058, 0.0135, 0.0331}``,
``H_R 8``, Mie ``0.004`` with extinction ``/ 0.9``, ``H_M 1.2``, ``G 0.85``),
exposure adjusted.  The ground albedo is the exact sky's (0.2).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.io.engines.openspace import (
    OPENSPACE_SOURCE,
    OpenSpaceAtmosphere,
    openspace_asset,
    openspace_mie_phase,
    openspace_parameters,
)
from dustoptics.sky.engines import _hillaire
from dustoptics.sky.engines.core import (
    RGB,
    EngineFit,
    EngineModel,
    Parameter,
    error_notes,
    hillaire_renderer,
    per_channel,
    register_engine,
    rgb_of,
    write_texts,
)

__all__ = ["OPENSPACE", "openspace_setup", "openspace_sky_rgb"]

_GROUND_ALBEDO: Final = 0.2

#: OpenSpace's data/assets/scene/solarsystem/planets/{mars,earth}/atmosphere.asset.
COMMUNITY: Final = {
    "mars": {
        "planet_radius_km": 3386.190,
        "atmosphere_height_km": 3463.17495 - 3386.190,
        "rayleigh": (0.019918, 0.01357, 0.00575),
        "H_R": 10.43979,
        "mie_scattering": (0.05361771,) * 3,
        "mie_extinction": (0.05361771 / 0.23862,) * 3,
        "H_M": 3.09526,
        "G": 0.85,
    },
    "earth": {
        "planet_radius_km": 6377.0,
        "atmosphere_height_km": 6447.0 - 6377.0,
        "rayleigh": (0.0058, 0.0135, 0.0331),
        "H_R": 8.0,
        "mie_scattering": (0.004,) * 3,
        "mie_extinction": (0.004 / 0.9,) * 3,
        "H_M": 1.2,
        "G": 0.85,
    },
}


def openspace_setup(params: Mapping[str, float]) -> _hillaire.HillaireSetup:
    """Hillaire's passes with OpenSpace's medium (``params`` in km and km^-1)."""
    g = float(params["G"])
    radius = params["planet_radius_km"]
    return _hillaire.HillaireSetup(
        planet_radius_km=radius,
        top_radius_km=radius + params["atmosphere_height_km"],
        rayleigh_scattering_per_km=rgb_of(params, "rayleigh"),
        rayleigh_absorption_per_km=np.zeros(3),
        rayleigh_scale_height_km=params["H_R"],
        mie_scattering_per_km=rgb_of(params, "mie_scattering"),
        mie_absorption_per_km=rgb_of(params, "mie_absorption"),
        mie_scale_height_km=params["H_M"],
        mie_phase=lambda cos_theta: openspace_mie_phase(cos_theta, g),
        ozone_absorption_per_km=np.zeros(3),
        ozone_bottom_km=10.0,
        ozone_peak_km=25.0,
        ozone_top_km=40.0,
        ground_albedo=np.full(3, params["ground_albedo"]),
    )


openspace_sky_rgb = hillaire_renderer(
    openspace_setup,
    "openspace_sky_rgb",
    """OpenSpace's sky (its medium, Hillaire's passes) per unit solar illuminance times
    ``exposure``, linear sRGB. [sr^-1]""",
)


def _flat(values: Mapping[str, Any]) -> dict[str, float]:
    out = {
        "planet_radius_km": float(values["planet_radius_km"]),
        "atmosphere_height_km": float(values["atmosphere_height_km"]),
        "H_R": float(values["H_R"]),
        "H_M": float(values["H_M"]),
        "G": float(values["G"]),
        "ground_albedo": _GROUND_ALBEDO,
        "exposure": 1.0,
    }
    for i, c in enumerate(RGB):
        sca = float(values["mie_scattering"][i])
        out[f"rayleigh_{c}"] = max(float(values["rayleigh"][i]), 1e-9)
        out[f"mie_scattering_{c}"] = max(sca, 1e-9)
        out[f"mie_absorption_{c}"] = max(float(values["mie_extinction"][i]) - sca, 1e-9)
    return out


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    p = openspace_parameters(atmosphere)
    return _flat(
        {
            "planet_radius_km": p.planet_radius_km,
            "atmosphere_height_km": p.atmosphere_height_km,
            "rayleigh": p.rayleigh_scattering_per_km,
            "H_R": p.h_r_km,
            "mie_scattering": p.mie_scattering_per_km,
            "mie_extinction": p.mie_extinction_per_km,
            "H_M": p.h_m_km,
            "G": min(max(p.g, -0.9), 0.99),
        }
    )


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    return _flat(COMMUNITY["mars" if atmosphere.name.startswith("mars") else "earth"])


def write_openspace_fit(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """``NAME_openspace.asset`` of a fit, its sky error in the comment block."""
    p = fit.params
    sca = tuple(float(v) for v in rgb_of(p, "mie_scattering"))
    ext = tuple(float(v) for v in rgb_of(p, "mie_scattering") + rgb_of(p, "mie_absorption"))
    planet = "earth" if "earth" in fit.atmosphere else "mars"
    parameters = OpenSpaceAtmosphere(
        name=fit.atmosphere,
        planet_radius_km=float(p["planet_radius_km"]),
        atmosphere_height_km=float(p["atmosphere_height_km"]),
        ground_reflectance=float(p["ground_albedo"]),
        ground_radiance_emission={"mars": 0.37, "earth": 0.6}[planet],
        sun_intensity={"mars": 13.1, "earth": 6.9}[planet],
        rayleigh_scattering_per_km=(p["rayleigh_r"], p["rayleigh_g"], p["rayleigh_b"]),
        h_r_km=float(p["H_R"]),
        mie_scattering_per_km=(sca[0], sca[1], sca[2]),
        mie_extinction_per_km=(ext[0], ext[1], ext[2]),
        h_m_km=float(p["H_M"]),
        g=float(p["G"]),
        notes=(
            f"{fit.kind} to dustoptics' exact spectral sky of {fit.atmosphere!r} (OpenSpace's "
            "medium with Hillaire's multiple scattering; CIE Delta E 2000 over the dome):",
            *error_notes(fit),
            f"the fit's exposure relative to OpenSpace's SunIntensity: {float(p['exposure']):.6g}",
            "SunIntensity, GroundRadianceEmission: OpenSpace's own asset values; no ozone "
            "(OpenSpace's ozone term is not part of the fitted model)",
        ),
    )
    asset = openspace_asset(parameters)
    return write_texts(fit, out_dir, "openspace", {"asset": asset}, overwrite=overwrite)


OPENSPACE = register_engine(
    EngineModel(
        name="openspace",
        title="OpenSpace RenderableAtmosphere",
        source=OPENSPACE_SOURCE,
        parameters=(
            *per_channel("rayleigh", 1e-9, 10.0, "km^-1"),
            *per_channel("mie_scattering", 1e-9, 10.0, "km^-1"),
            *per_channel("mie_absorption", 1e-9, 10.0, "km^-1"),
            Parameter("G", -0.9, 0.99),
            Parameter("exposure", 1e-4, 1e4, log=True),
        ),
        community_parameters=("exposure",),
        render=openspace_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_openspace_fit,
    ),
    suffixes=(".asset",),
)
