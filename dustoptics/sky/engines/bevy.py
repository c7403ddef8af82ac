"""Bevy's atmosphere: its sky model, fitted, and its files (ScatteringMedium and phase texture).

Bevy's atmosphere (:data:`~dustoptics.io.engines.bevy.BEVY_SOURCE`) is Hillaire's
(2020) model: a transmittance LUT, a multiple-scattering LUT of 64 directions
and 20 samples per ray (``multiscattering_lut.wesl``, ``AtmosphereSettings``
defaults), and a ray march with samples at ``(s + 0.3) / N`` of the ray
(``MIDPOINT_RATIO``).  Its medium is the ``ScatteringMedium``'s LUTs: the sum of
the terms' ``scattering * phase * falloff``, the phase read through Bevy's
nonlinear phase mapping (:func:`~dustoptics.io.engines.bevy.bevy_lut_phase`, 256
rows).  The model is the shared numpy implementation of Hillaire's passes
(:mod:`~dustoptics.sky.engines._hillaire`, uniform samples, 8 x 8 stratified
directions) with that medium: Rayleigh ``PhaseFunction::Rayleigh`` and the dust's
``PhaseFunction::ChromaticTexture`` (one phase function per channel), exponential
falloffs, Earth's ozone as a tent.  Bevy's exponential falloff reaches 0 at the
top (a relative difference ``exp(-height / H)``, 2e-5 for Mars' dust) and its
sky-view LUT marches 16 samples (the model 32): neither is modelled.

Fitted: the ``scattering`` of the molecules' term and the ``scattering`` and
``absorption`` of the dust's, per channel [m^-1]; the phase texture is the set's
own (:func:`~dustoptics.io.engines.bevy.bevy_phase_texture`, first column 180
deg), not fitted.  Bevy is physical (a directional light in lux): no exposure.

Community row: Bevy's own ``ScatteringMedium::mars`` (its coefficients; its
double-exponential dust falloff ``0.75 exp(1 - exp(h / 4 km)) + 0.25 exp(1 -
exp(h / 20 km))`` as the exponential of the same column, which the model's
layers need) with its hand-made texture (PR #22884, ``bevy_mars_mie_phase.json``),
and for Earth ``ScatteringMedium::earth`` in ``Atmosphere::earth`` (its falloff
scales are fractions of 60 km but Bevy applies them to the atmosphere's 100 km:
Rayleigh 13.3 km, Mie 2 km as Bevy draws them; its Mie ``absorption`` 3.996e-6
is larger than its ``scattering`` 0.444e-6, the reverse of Hillaire's and
Unreal's Earth).  The ground albedo is the exact sky's (0.2) in both rows.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.io._atomic import write_files
from dustoptics.io.engines.bevy import (
    BEVY_SOURCE,
    bevy_files,
    bevy_lut_phase,
    bevy_medium,
    bevy_phase_texture,
)
from dustoptics.sky.engines import _hillaire
from dustoptics.sky.engines._sets import remember_set, set_of
from dustoptics.sky.engines.core import (
    RGB,
    EngineFit,
    EngineModel,
    error_notes,
    hillaire_renderer,
    per_channel,
    register_engine,
    rgb_of,
)

__all__ = ["BEVY", "bevy_mars_texture", "bevy_setup", "bevy_sky_rgb"]

_GROUND_ALBEDO: Final = 0.2
_TEXTURES: dict[int, np.ndarray] = {}


@cache
def bevy_mars_texture() -> np.ndarray:
    """Bevy's hand-made Mars phase texture (1024 x RGB, first column 180 deg). [sr^-1]"""
    text = resources.files("dustoptics.sky.engines").joinpath("bevy_mars_mie_phase.json")
    columns = np.asarray(json.loads(text.read_text("utf-8"))["columns_rgb"], dtype=float)
    columns.setflags(write=False)
    return columns


def _texture(params: Mapping[str, float]) -> np.ndarray | None:
    """The dust's texture columns: the set's (``texture`` 0), Bevy's Mars (1), none (HG, 2)."""
    kind = int(params["texture"])
    if kind == 1:
        return bevy_mars_texture()
    if kind == 2:
        return None
    key = int(params["set_key"])
    if key not in _TEXTURES:
        table = set_of(params).constituent("aerosols").table
        _TEXTURES[key] = bevy_phase_texture(table).pixels[0].astype(float)
    return _TEXTURES[key]


def bevy_setup(params: Mapping[str, float]) -> _hillaire.HillaireSetup:
    """Hillaire's passes with Bevy's medium (``params``: m^-1 and km, see :data:`BEVY`)."""
    columns = _texture(params)
    if columns is None:
        mie_phase = _hillaire.henyey_greenstein(params["mie_asymmetry"])
    else:

        def mie_phase(cos_theta: np.ndarray) -> np.ndarray:
            return bevy_lut_phase(columns, cos_theta)

    radius = params["inner_radius_km"]
    return _hillaire.HillaireSetup(
        planet_radius_km=radius,
        top_radius_km=radius + params["atmosphere_height_km"],
        rayleigh_scattering_per_km=rgb_of(params, "rayleigh_scattering") * 1000.0,
        rayleigh_absorption_per_km=np.zeros(3),
        rayleigh_scale_height_km=params["rayleigh_scale_height_km"],
        mie_scattering_per_km=rgb_of(params, "dust_scattering") * 1000.0,
        mie_absorption_per_km=rgb_of(params, "dust_absorption") * 1000.0,
        mie_scale_height_km=params["dust_scale_height_km"],
        mie_phase=mie_phase,
        ozone_absorption_per_km=rgb_of(params, "ozone_absorption") * 1000.0,
        ozone_bottom_km=params["ozone_peak_km"] - params["ozone_half_width_km"],
        ozone_peak_km=params["ozone_peak_km"],
        ozone_top_km=params["ozone_peak_km"] + params["ozone_half_width_km"],
        ground_albedo=np.full(3, params["ground_albedo"]),
        distribution="uniform",
        directions="stratified",
        ms_samples=20,
    )


bevy_sky_rgb = hillaire_renderer(
    bevy_setup,
    "bevy_sky_rgb",
    """Bevy's sky per unit solar illuminance, linear sRGB [sr^-1] (a directional light of
    the sunlight's colour).""",
)


def _base(atmosphere: Atmosphere) -> dict[str, float]:
    medium = bevy_medium(atmosphere)
    terms = {t.name: t for t in medium.terms}
    height_km = (atmosphere.atmosphere_radius_m - atmosphere.planet_radius_m) / 1000.0
    out = {
        "set_key": remember_set(atmosphere),
        "texture": 0.0,
        "mie_asymmetry": 0.0,
        "inner_radius_km": atmosphere.planet_radius_m / 1000.0,
        "atmosphere_height_km": height_km,
        "ground_albedo": _GROUND_ALBEDO,
        "ozone_peak_km": 25.0,
        "ozone_half_width_km": 15.0,
    }
    for name, role in (("rayleigh", "molecules"), ("dust", "aerosols")):
        term = terms[role]
        if term.falloff != "exponential":
            raise ValueError(
                f"Bevy's model takes an exponential {role} profile; got {term.falloff}"
            )
        out[f"{name}_scale_height_km"] = term.falloff_values[0] * height_km
        for i, c in enumerate(RGB):
            out[f"{name}_scattering_{c}"] = max(term.scattering_per_m[i], 1e-12)
            if name == "dust":
                out[f"dust_absorption_{c}"] = max(term.absorption_per_m[i], 1e-12)
    ozone = terms.get("ozone")
    for i, c in enumerate(RGB):
        out[f"ozone_absorption_{c}"] = ozone.absorption_per_m[i] if ozone is not None else 0.0
    if ozone is not None:
        center, width = ozone.falloff_values
        out["ozone_peak_km"] = (1.0 - center) * height_km
        out["ozone_half_width_km"] = 0.5 * width * height_km
    return out


def _initial(atmosphere: Atmosphere) -> dict[str, float]:
    return _base(atmosphere)


def _bevy_mars_dust_column_km() -> float:
    """Column of Bevy's Mars dust falloff over its 120 km, the equal-column scale height. [km]"""
    h = np.linspace(0.0, 120.0, 240001)
    f = 0.75 * np.exp(1.0 - np.exp(h / 4.0)) + 0.25 * np.exp(1.0 - np.exp(h / 20.0))
    return float(np.trapezoid(f, h))


def _community(atmosphere: Atmosphere) -> dict[str, float]:
    out = _base(atmosphere)
    if atmosphere.name.startswith("mars"):
        # ScatteringMedium::mars and Atmosphere::mars at 4805ca79.
        values = {
            "rayleigh_scattering": (9.91e-8, 2.32e-7, 5.65e-7),
            "dust_scattering": (30.67e-6, 25.39e-6, 20.93e-6),
            "dust_absorption": (1.26e-6, 5.25e-6, 9.33e-6),
        }
        out.update(
            texture=1.0,
            inner_radius_km=3389.5,
            atmosphere_height_km=120.0,
            rayleigh_scale_height_km=8.0,
            dust_scale_height_km=_bevy_mars_dust_column_km(),
        )
    else:
        # ScatteringMedium::earth in Atmosphere::earth (outer - inner = 100 km).
        values = {
            "rayleigh_scattering": (5.802e-6, 13.558e-6, 33.100e-6),
            "dust_scattering": (0.444e-6,) * 3,
            "dust_absorption": (3.996e-6,) * 3,
            "ozone_absorption": (0.650e-6, 1.881e-6, 0.085e-6),
        }
        out.update(
            texture=2.0,
            mie_asymmetry=0.8,
            inner_radius_km=6360.0,
            atmosphere_height_km=100.0,
            rayleigh_scale_height_km=8.0 / 60.0 * 100.0,
            dust_scale_height_km=1.2 / 60.0 * 100.0,
            ozone_peak_km=25.0,
            ozone_half_width_km=15.0,
        )
    for name, triple in values.items():
        for c, v in zip(RGB, triple, strict=True):
            out[f"{name}_{c}"] = float(v)
    return out


def write_bevy_fit(fit: EngineFit, out_dir: Any, *, overwrite: bool = False) -> list[Path]:
    """Bevy's four files (:func:`dustoptics.io.engines.bevy.write_bevy`) with the fitted
    coefficients and the fit's error in the comment block and the JSON."""
    p = fit.params
    medium = bevy_medium(set_of(p), ground_albedo=float(p["ground_albedo"]))

    def triple(name: str) -> tuple[float, float, float]:
        v = rgb_of(p, name)
        return (float(v[0]), float(v[1]), float(v[2]))

    terms = tuple(
        dataclasses.replace(t, scattering_per_m=triple("rayleigh_scattering"))
        if t.name == "molecules"
        else dataclasses.replace(
            t,
            scattering_per_m=triple("dust_scattering"),
            absorption_per_m=triple("dust_absorption"),
        )
        if t.name == "aerosols"
        else t
        for t in medium.terms
    )
    notes = (
        f"{fit.kind} to dustoptics' exact spectral sky (Hillaire's passes with Bevy's medium; "
        "CIE Delta E 2000 over the dome): the scattering of each term and the dust's absorption",
        *error_notes(fit),
        *medium.notes,
    )
    medium = dataclasses.replace(medium, terms=terms, notes=notes)
    return write_files(bevy_files(medium, Path(out_dir)), overwrite=overwrite)


BEVY = register_engine(
    EngineModel(
        name="bevy",
        title="Bevy atmosphere (ScatteringMedium)",
        source=BEVY_SOURCE,
        parameters=(
            *per_channel("rayleigh_scattering", 1e-10, 1e-2, "m^-1"),
            *per_channel("dust_scattering", 1e-10, 1e-2, "m^-1"),
            *per_channel("dust_absorption", 1e-10, 1e-2, "m^-1"),
        ),
        community_parameters=(),
        render=bevy_sky_rgb,
        initial=_initial,
        community=_community,
        write=write_bevy_fit,
    ),
    suffixes=(".ktx2", ".exr", ".rs", ".json"),
)
