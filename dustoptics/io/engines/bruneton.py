"""An atmosphere as the parameters of Bruneton's precomputed atmospheric scattering (2017).

E. Bruneton's open-source implementation [1]_ (BSD-3-Clause) builds its
precomputed textures from one constructor, ``atmosphere::Model(...)``
(``atmosphere/model.h``), whose parameters, in order, are: ``wavelengths``
[nm], ``solar_irradiance`` [W m^-2 nm^-1], ``sun_angular_radius`` [rad],
``bottom_radius`` and ``top_radius`` [m], ``rayleigh_density`` (layers),
``rayleigh_scattering`` [m^-1], ``mie_density``, ``mie_scattering`` and
``mie_extinction`` [m^-1], ``mie_phase_function_g`` (Cornette-Shanks),
``absorption_density``, ``absorption_extinction`` [m^-1], ``ground_albedo``,
``max_sun_zenith_angle`` [rad], ``length_unit_in_meters``,
``num_precomputed_wavelengths``, ``combine_scattering_textures`` and
``half_precision``.  Each density profile is at most two
``DensityProfileLayer(width, exp_term, exp_scale, linear_term,
constant_term)``, the density at altitude ``h`` being
``clamp(exp_term exp(exp_scale h) + linear_term h + constant_term, 0, 1)``
in the layer that holds ``h`` (the last layer extends to the top); widths in
m, ``exp_scale`` and ``linear_term`` in m^-1.  Every per-wavelength
coefficient is the value where the profile is 1.

:func:`bruneton_parameters` maps an :class:`~dustoptics.atmosphere.sets.Atmosphere`
onto those parameters; :func:`write_bruneton` writes them as JSON (his names,
SI units, with provenance), as a C++ header of literal constants to pass to
his constructor, and as the GLSL snippet of the dust's tabulated phase
function with the one-line change his ``MiePhaseFunction`` needs:

.. code-block:: glsl

    vec3 MiePhaseFunction(Number g, Number nu) { return DustMiePhaseFunction(nu); }

replacing the Cornette-Shanks function of ``atmosphere/functions.glsl`` (its
callers multiply the result by a ``vec3`` of Mie scattering, so a ``vec3``
of the three channels fits them).  The snippet goes in ``functions.glsl``
immediately above ``MiePhaseFunction`` (its line 744 at d9954923), where his
Makefile turns the file into ``functions.glsl.inc``; there every program his
``Model`` compiles sees it.  The other place that works is the header
``model.cc`` builds (``glsl_header_factory_``), right after its
``"#version 330\n"`` line, which must stay first (so the snippet cannot be
"prepended" to that header).  Either way his ``atmosphere/reference``
C++ build, which includes ``functions.glsl`` as C++, no longer compiles; the
demo and the ``Model`` do.  The snippet's channels
are his rendering wavelengths ``kLambdaR, kLambdaG, kLambdaB`` = 680, 550,
440 nm, which are also the precomputation's wavelengths when
``num_precomputed_wavelengths <= 3``.  With more precomputed wavelengths (his
luminance mode) each pass has other wavelengths and the snippet would give
them the 680/550/440 nm channels: use 3, or keep his Cornette-Shanks
function with ``mie_phase_function_g``, which is fitted here to the dust's
phase function at 550 nm (:mod:`dustoptics.scattering.fit`; its errors are
in the JSON).

What his precomputation must use for the set is chosen by
:func:`dustoptics.io.engines.precomputation.precomputation_sampling` at his
three wavelengths and stated in both files (JSON ``precomputation``; C++
constants ``kScatteringTextureNuSize``, ``kNumScatteringOrders``,
``kScatteringDensitySampleCount``): ``SCATTERING_TEXTURE_NU_SIZE`` in
``atmosphere/constants.h``, ``Init(K)``, the scattering-density
``SAMPLE_COUNT`` of ``ComputeScatteringDensity`` in ``functions.glsl`` (16 in
his file) and the ``SAMPLE_COUNT`` of ``ComputeIndirectIrradiance`` at the same
angular step (32 in his file), ``combine_scattering_textures = false`` (his combined texture keeps
only the red channel of single Mie scattering and rebuilds green and blue
from a Rayleigh-shaped spectrum, which a dust sky does not have) and three
precomputed wavelengths.  The C++ header checks the NU size against
``constants.h`` when that file is included first (``static_assert``).
A value given that the set cannot live with (e.g. ``nu_size=8`` for dust) is
refused before anything is written, with the smallest that does.

Choices not in the atmosphere, with their defaults (Bruneton's demo
``atmosphere/demo/demo.cc``): ground albedo 0.1, maximum Sun zenith angle
102 deg (his comment's Earth value), length unit 1000 m, Sun angular radius
0.00935/2 rad at 1 au scaled by 1 au over the planet's Sun distance; the
solar irradiance is ASTM G173's extraterrestrial spectrum
(:func:`dustoptics.colour.solar_irradiance_astm_g173`, the bins his demo
uses) times (1 au / distance)^2.

References
----------
.. [1] E. Bruneton, "Precomputed atmospheric scattering: a new
   implementation" (2017), https://github.com/ebruneton/precomputed_atmospheric_scattering
   (BSD-3-Clause); E. Bruneton and F. Neyret, "Precomputed atmospheric
   scattering," Computer Graphics Forum 27(4), 1079-1086 (2008),
   doi:10.1111/j.1467-8659.2008.01245.x.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics._validation import check_closed_interval, check_positive
from dustoptics.atmosphere.column import (
    DensityProfile,
    ExponentialProfile,
    FixedFractionProfile,
    PiecewiseLinearProfile,
)
from dustoptics.colour import solar_irradiance_astm_g173
from dustoptics.io._atomic import write_files
from dustoptics.io.describe_formats import describe_bruneton, is_bruneton
from dustoptics.io.engines.precomputation import (
    BRUNETON_DEFAULTS,
    PrecomputationSampling,
    precomputation_sampling,
)
from dustoptics.io.registry import Format, register
from dustoptics.io.shaders.glsl import glsl_snippet
from dustoptics.scattering.fit import fit_table

__all__ = [
    "ASTRONOMICAL_UNIT_M",
    "BRUNETON_CHANNELS_NM",
    "BrunetonLayer",
    "BrunetonParameters",
    "bruneton_cpp",
    "bruneton_density_layers",
    "bruneton_mie",
    "bruneton_parameters",
    "bruneton_phase_glsl",
    "bruneton_precomputation",
    "bruneton_precomputation_dict",
    "write_bruneton",
]

#: The astronomical unit (IAU 2012 Resolution B2). [m]
ASTRONOMICAL_UNIT_M = 149_597_870_700.0

#: Bruneton's rendering wavelengths kLambdaR, kLambdaG, kLambdaB (model.h). [nm]
BRUNETON_CHANNELS_NM = (680.0, 550.0, 440.0)

#: Sun angular radius at 1 au in Bruneton's demo (kSunAngularRadius). [rad]
_SUN_ANGULAR_RADIUS_1AU_RAD = 0.00935 / 2.0

#: Wavelength of the fitted Cornette-Shanks g (the middle rendering channel). [nm]
_G_FIT_WAVELENGTH_NM = 550.0

_PHASE_FUNCTION_NAME = "DustMiePhaseFunction"
_ONE_LINE_CHANGE = "vec3 MiePhaseFunction(Number g, Number nu) { return DustMiePhaseFunction(nu); }"


@dataclass(frozen=True)
class BrunetonLayer:
    """One ``DensityProfileLayer`` of Bruneton's model, in SI units.

    The relative density at altitude ``h`` [m] in this layer is
    ``clamp(exp_term * exp(exp_scale_per_m * h) + linear_term_per_m * h +
    constant_term, 0, 1)``.
    """

    width_m: float
    exp_term: float
    exp_scale_per_m: float
    linear_term_per_m: float
    constant_term: float

    def density(self, altitude_m: Any) -> np.ndarray:
        """Relative density of this layer's formula at ``altitude_m`` [m]. [-]"""
        h = np.asarray(altitude_m, dtype=np.float64)
        value = (
            self.exp_term * np.exp(self.exp_scale_per_m * h)
            + self.linear_term_per_m * h
            + self.constant_term
        )
        return np.clip(value, 0.0, 1.0)

    def to_dict(self) -> dict[str, float]:
        """His field names (SI units)."""
        return {
            "width": self.width_m,
            "exp_term": self.exp_term,
            "exp_scale": self.exp_scale_per_m,
            "linear_term": self.linear_term_per_m,
            "constant_term": self.constant_term,
        }


def _profile_density(layers: tuple[BrunetonLayer, ...], altitude_m: np.ndarray) -> np.ndarray:
    """Bruneton's GetProfileDensity: the first layer below its width, else the second."""
    if len(layers) == 1:
        return layers[0].density(altitude_m)
    return np.where(
        altitude_m < layers[0].width_m, layers[0].density(altitude_m), layers[1].density(altitude_m)
    )


def bruneton_density_layers(
    profile: DensityProfile | None, *, top_altitude_m: float
) -> tuple[BrunetonLayer, ...]:
    """A density profile as at most two of Bruneton's layers, checked to reproduce it.

    Parameters
    ----------
    profile : DensityProfile or None
        Exponential, piecewise linear (at most two sloped pieces, zero
        elsewhere), or a fixed fraction of one of those; None for a constituent
        that is absent (a zero layer).
    top_altitude_m : float
        Top of the atmosphere above the ground: the layers are checked on
        [0, top] against the profile (to 1e-12). [m]

    Returns
    -------
    tuple of BrunetonLayer

    Raises
    ------
    ValueError
        For a profile Bruneton's model cannot represent (more than two
        pieces, a sum of modes, ...), naming it.
    """
    top = check_positive("top_altitude_m", top_altitude_m, unit="m")
    if profile is None:
        return (BrunetonLayer(0.0, 0.0, 0.0, 0.0, 0.0),)
    if isinstance(profile, FixedFractionProfile):
        return bruneton_density_layers(profile.base, top_altitude_m=top)
    if isinstance(profile, ExponentialProfile):
        layers: tuple[BrunetonLayer, ...] = (
            BrunetonLayer(0.0, 1.0, -1.0 / profile.scale_height_m, 0.0, 0.0),
        )
    elif isinstance(profile, PiecewiseLinearProfile):
        z = np.asarray(profile.altitude_m)
        d = np.asarray(profile.density)
        pieces = [
            (z[i], z[i + 1], d[i], d[i + 1])
            for i in range(z.size - 1)
            if not (d[i] == 0.0 and d[i + 1] == 0.0)
        ]
        if not 1 <= len(pieces) <= 2:
            raise ValueError(
                f"profile {profile!r} has {len(pieces)} pieces where it is not zero; Bruneton's "
                "model takes at most two layers"
            )
        found = []
        for z0, z1, d0, d1 in pieces:
            slope = (d1 - d0) / (z1 - z0)
            found.append((float(z1), float(slope), float(d0 - slope * z0)))
        width = found[0][0] if len(found) == 2 else 0.0
        layers = tuple(
            BrunetonLayer(
                float(width) if i == 0 and len(found) == 2 else 0.0, 0.0, 0.0, float(s), float(c)
            )
            for i, (_, s, c) in enumerate(found)
        )
    else:
        raise ValueError(
            f"profile {profile!r} cannot be written as Bruneton's DensityProfileLayer terms "
            "(exponential, piecewise linear with at most two pieces, or a fixed fraction of one)"
        )
    h = np.linspace(0.0, top, 20001)
    if isinstance(profile, PiecewiseLinearProfile) and profile.density[-1] != 0.0:
        h = h[h <= profile.altitude_m[-1]]
    got = _profile_density(layers, h)
    want = np.asarray(profile.relative_density(h), dtype=np.float64)
    if not np.allclose(got, want, rtol=0.0, atol=1e-12):
        worst = float(np.max(np.abs(got - want)))
        raise ValueError(
            f"profile {profile!r} is not reproduced by Bruneton's clamped layers (largest "
            f"difference {worst:.3g}); it cannot be exported to his model"
        )
    return layers


@dataclass(frozen=True)
class BrunetonParameters:
    """The arguments of Bruneton's ``atmosphere::Model`` for one atmosphere.

    His parameter names, SI units; the per-wavelength arrays share
    ``wavelength_nm``.

    Attributes
    ----------
    name : str
        The atmosphere's name.
    wavelength_nm : numpy.ndarray
        ``wavelengths``. [nm]
    solar_irradiance_w_m2_nm : numpy.ndarray
        ``solar_irradiance`` at the planet. [W m^-2 nm^-1]
    sun_angular_radius_rad : float
        ``sun_angular_radius``. [rad]
    bottom_radius_m, top_radius_m : float
        ``bottom_radius``, ``top_radius``. [m]
    rayleigh_density : tuple of BrunetonLayer
        ``rayleigh_density``.
    rayleigh_scattering_per_m : numpy.ndarray
        ``rayleigh_scattering`` where the density is 1. [m^-1]
    mie_density : tuple of BrunetonLayer
        ``mie_density``.
    mie_scattering_per_m, mie_extinction_per_m : numpy.ndarray
        ``mie_scattering``, ``mie_extinction`` where the density is 1. [m^-1]
    mie_phase_function_g : float
        ``mie_phase_function_g``: Cornette-Shanks g fitted to the aerosols
        at 550 nm. [-]
    mie_phase_function_fit : dict
        That fit's parameters and errors (``FitResult.to_dict``).
    absorption_density : tuple of BrunetonLayer
        ``absorption_density``.
    absorption_extinction_per_m : numpy.ndarray
        ``absorption_extinction`` where the density is 1. [m^-1]
    ground_albedo : numpy.ndarray
        ``ground_albedo``. [-]
    max_sun_zenith_angle_rad : float
        ``max_sun_zenith_angle``. [rad]
    length_unit_in_meters : float
        ``length_unit_in_meters``. [m]
    provenance : dict
        Sources, input hashes and notes of the constituents' tables.
    """

    name: str
    wavelength_nm: np.ndarray
    solar_irradiance_w_m2_nm: np.ndarray
    sun_angular_radius_rad: float
    bottom_radius_m: float
    top_radius_m: float
    rayleigh_density: tuple[BrunetonLayer, ...]
    rayleigh_scattering_per_m: np.ndarray
    mie_density: tuple[BrunetonLayer, ...]
    mie_scattering_per_m: np.ndarray
    mie_extinction_per_m: np.ndarray
    mie_phase_function_g: float
    mie_phase_function_fit: dict[str, Any]
    absorption_density: tuple[BrunetonLayer, ...]
    absorption_extinction_per_m: np.ndarray
    ground_albedo: np.ndarray
    max_sun_zenith_angle_rad: float
    length_unit_in_meters: float
    provenance: dict[str, Any]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping under Bruneton's parameter names."""

        def floats(values: np.ndarray) -> list[float]:
            return [float(v) for v in values]

        return {
            "model": "E. Bruneton, precomputed_atmospheric_scattering (2017), atmosphere::Model",
            "name": self.name,
            "wavelengths": floats(self.wavelength_nm),
            "solar_irradiance": floats(self.solar_irradiance_w_m2_nm),
            "sun_angular_radius": self.sun_angular_radius_rad,
            "bottom_radius": self.bottom_radius_m,
            "top_radius": self.top_radius_m,
            "rayleigh_density": [layer.to_dict() for layer in self.rayleigh_density],
            "rayleigh_scattering": floats(self.rayleigh_scattering_per_m),
            "mie_density": [layer.to_dict() for layer in self.mie_density],
            "mie_scattering": floats(self.mie_scattering_per_m),
            "mie_extinction": floats(self.mie_extinction_per_m),
            "mie_phase_function_g": self.mie_phase_function_g,
            "absorption_density": [layer.to_dict() for layer in self.absorption_density],
            "absorption_extinction": floats(self.absorption_extinction_per_m),
            "ground_albedo": floats(self.ground_albedo),
            "max_sun_zenith_angle": self.max_sun_zenith_angle_rad,
            "length_unit_in_meters": self.length_unit_in_meters,
            "units": {
                "wavelengths": "nm",
                "solar_irradiance": "W m-2 nm-1",
                "sun_angular_radius": "rad",
                "bottom_radius": "m",
                "top_radius": "m",
                "density layers": "width m, exp_term 1, exp_scale m-1, linear_term m-1, "
                "constant_term 1; density = clamp(exp_term exp(exp_scale h) + linear_term h + "
                "constant_term, 0, 1)",
                "rayleigh_scattering, mie_scattering, mie_extinction, absorption_extinction": (
                    "m-1 where the layer density is 1"
                ),
                "max_sun_zenith_angle": "rad",
                "length_unit_in_meters": "m",
            },
            "mie_phase_function": {
                "cornette_shanks_fit": self.mie_phase_function_fit,
                "tabulated": f"{self.name}_bruneton_mie_phase.glsl, with the change "
                f"'{_ONE_LINE_CHANGE}' in atmosphere/functions.glsl",
            },
            "provenance": self.provenance,
        }


def _readonly(values: Any) -> np.ndarray:
    arr = np.array(values, dtype=np.float64)
    arr.setflags(write=False)
    return arr


def _check_channels(table: Any) -> None:
    wl = np.asarray(table.wavelength_nm)
    low, high = min(BRUNETON_CHANNELS_NM), max(BRUNETON_CHANNELS_NM)
    if wl[0] > low or wl[-1] < high:
        raise ValueError(
            f"the aerosol table spans {wl[0]:g}-{wl[-1]:g} nm; Bruneton's rendering wavelengths "
            f"{BRUNETON_CHANNELS_NM} nm must lie within it (compute the table on a wider grid)"
        )


def _mie_g_fit(table: Any) -> tuple[float, dict[str, Any]]:
    fit = fit_table(
        table,
        model="cornette-shanks1992",
        colour="wavelengths",
        channels_nm=(_G_FIT_WAVELENGTH_NM,) * 3,
    )
    return float(fit.parameters[0, 0]), {
        **{k: v for k, v in fit.to_dict().items() if k != "rows"},
        "row": fit.to_dict()["rows"][0],
    }


def bruneton_mie(table: Any) -> dict[str, Any]:
    """The Mie part of Bruneton's parameters from one aerosol table.

    Parameters
    ----------
    table : dustoptics.table.Table
        Aerosols with cross-sections and ``number_density_per_m3`` (the
        density where their profile is 1), covering 440-680 nm.

    Returns
    -------
    dict
        ``wavelengths`` [nm], ``mie_scattering`` and ``mie_extinction``
        [m^-1], ``mie_phase_function_g`` (Cornette-Shanks fit at 550 nm) and
        that fit's errors.
    """
    if (
        table.cross_sections is None or table.cross_sections.number_density_per_m3 is None
    ) or table.cross_sections is None:
        raise ValueError(
            f"table {table.name!r} needs cross-sections and a number density for Bruneton's "
            "mie_scattering and mie_extinction [m^-1]"
        )
    _check_channels(table)
    g, fit = _mie_g_fit(table)
    return {
        "wavelengths": [float(v) for v in table.wavelength_nm],
        "mie_scattering": [float(v) for v in table.beta_sca_per_m],
        "mie_extinction": [float(v) for v in table.beta_ext_per_m],
        "mie_phase_function_g": g,
        "cornette_shanks_fit": fit,
    }


def bruneton_parameters(
    atmosphere: Any,
    *,
    ground_albedo: float = 0.1,
    max_sun_zenith_angle_deg: float = 102.0,
    length_unit_in_meters: float = 1000.0,
) -> BrunetonParameters:
    """Bruneton's ``atmosphere::Model`` arguments for an atmosphere set.

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
        Molecules, aerosols and (optionally) ozone on one wavelength grid.
    ground_albedo : float
        Ground albedo at every wavelength, in [0, 1] (his demo's 0.1). [-]
    max_sun_zenith_angle_deg : float
        Largest Sun zenith angle precomputed, in (90, 180] (his Earth
        value 102). [deg]
    length_unit_in_meters : float
        The shaders' length unit (his demo's 1000). [m]

    Returns
    -------
    BrunetonParameters

    Raises
    ------
    ValueError
        A density profile his layers cannot represent, an aerosol table
        without cross-sections or not covering 440-680 nm, or wavelengths
        outside the solar spectrum's 360-840 nm.
    """
    albedo = check_closed_interval("ground_albedo", ground_albedo, 0.0, 1.0)
    zenith = check_positive("max_sun_zenith_angle_deg", max_sun_zenith_angle_deg, unit="deg")
    if not 90.0 < zenith <= 180.0:
        raise ValueError(
            f"max_sun_zenith_angle_deg must be in (90, 180] deg; got {max_sun_zenith_angle_deg!r}"
        )
    unit = check_positive("length_unit_in_meters", length_unit_in_meters, unit="m")
    wl = np.asarray(atmosphere.wavelength_nm, dtype=np.float64)
    top = atmosphere.atmosphere_radius_m - atmosphere.planet_radius_m
    scale = ASTRONOMICAL_UNIT_M / atmosphere.sun_distance_m
    molecules = atmosphere.constituent("molecules")
    aerosols = atmosphere.constituent("aerosols")
    ozone = next((c for c in atmosphere.constituents if c.role == "ozone"), None)
    _check_channels(aerosols.table)
    mie = bruneton_mie(aerosols.table)
    absorption = np.zeros(wl.size)
    if ozone is not None:
        absorption = np.asarray(ozone.table.beta_abs_per_m, dtype=np.float64)
    mol_abs = np.asarray(molecules.table.beta_abs_per_m, dtype=np.float64)
    if np.any(mol_abs > 0.0):
        raise ValueError(
            f"molecules {molecules.table.name!r} absorb; Bruneton's model has no molecular "
            "absorption term other than the absorbing layer (ozone)"
        )
    provenance: dict[str, Any] = {
        c.role: {
            "table": c.table.name,
            "input_hash": c.table.provenance.input_hash,
            "sources": [s.citation for s in c.table.provenance.sources],
            "notes": list(c.table.provenance.notes),
            "profile": repr(c.profile),
        }
        for c in atmosphere.constituents
    }
    provenance["solar_irradiance"] = (
        "ASTM G173-03 extraterrestrial spectrum, 10 nm bin means (dustoptics.colour."
        f"solar_irradiance_astm_g173) times (1 au / {atmosphere.sun_distance_m:g} m)^2"
    )
    provenance["choices"] = (
        f"ground albedo {albedo:g}, max Sun zenith angle {zenith:g} deg, length unit {unit:g} m, "
        f"Sun angular radius 0.00935/2 rad at 1 au (Bruneton's demo) scaled by 1 au / distance"
    )
    return BrunetonParameters(
        name=atmosphere.name,
        wavelength_nm=_readonly(wl),
        solar_irradiance_w_m2_nm=_readonly(solar_irradiance_astm_g173(wl) * scale**2),
        sun_angular_radius_rad=_SUN_ANGULAR_RADIUS_1AU_RAD * scale,
        bottom_radius_m=float(atmosphere.planet_radius_m),
        top_radius_m=float(atmosphere.atmosphere_radius_m),
        rayleigh_density=bruneton_density_layers(molecules.profile, top_altitude_m=top),
        rayleigh_scattering_per_m=_readonly(molecules.table.beta_sca_per_m),
        mie_density=bruneton_density_layers(aerosols.profile, top_altitude_m=top),
        mie_scattering_per_m=_readonly(mie["mie_scattering"]),
        mie_extinction_per_m=_readonly(mie["mie_extinction"]),
        mie_phase_function_g=mie["mie_phase_function_g"],
        mie_phase_function_fit=mie["cornette_shanks_fit"],
        absorption_density=bruneton_density_layers(
            ozone.profile if ozone is not None else None, top_altitude_m=top
        ),
        absorption_extinction_per_m=_readonly(absorption),
        ground_albedo=_readonly(np.full(wl.size, albedo)),
        max_sun_zenith_angle_rad=math.radians(zenith),
        length_unit_in_meters=unit,
        provenance=provenance,
    )


def bruneton_precomputation(
    atmosphere: Any,
    *,
    tolerance: float = 0.005,
    nu_size: int | None = None,
    num_scattering_orders: int | None = None,
    scattering_density_sample_count: int | None = None,
) -> PrecomputationSampling:
    """NU size, orders and scattering-density directions his precomputation needs for the set.

    :func:`~dustoptics.io.engines.precomputation.precomputation_sampling` at
    his three wavelengths 680, 550, 440 nm (``num_precomputed_wavelengths =
    3``).  A value given is checked, not chosen: one below what the set needs
    raises ``ValueError`` naming the smallest that does.

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
    tolerance : float, default 0.005
        Error allowed to the orders and to the scattering-density rule. [-]
    nu_size, num_scattering_orders, scattering_density_sample_count : int, optional
        ``SCATTERING_TEXTURE_NU_SIZE``, ``Init(K)`` and ``SAMPLE_COUNT`` of
        ``ComputeScatteringDensity`` to use instead of the chosen ones.

    Returns
    -------
    PrecomputationSampling
    """
    return precomputation_sampling(
        atmosphere,
        tolerance=tolerance,
        wavelength_nm=BRUNETON_CHANNELS_NM,
        nu_size=nu_size,
        num_scattering_orders=num_scattering_orders,
        scattering_density_sample_count=scattering_density_sample_count,
    )


def bruneton_precomputation_dict(sampling: PrecomputationSampling) -> dict[str, Any]:
    """The ``precomputation`` section of the JSON: each value, where it goes, why.

    Returns
    -------
    dict
        His names (``constants.h``: texture sizes; ``Init``; ``functions.glsl``:
        ``SAMPLE_COUNT`` of ``ComputeScatteringDensity``; the ``Model``
        arguments ``num_precomputed_wavelengths``, ``combine_scattering_textures``,
        ``half_precision``), the place of the phase snippet, and the rules'
        errors (:meth:`PrecomputationSampling.to_dict`).
    """
    sizes = dict(BRUNETON_DEFAULTS)
    sizes["scattering_texture_nu_size"] = sampling.scattering_texture_nu_size
    sizes["scattering_texture_mu_s_size"] = sampling.scattering_texture_mu_s_size
    return {
        "constants.h": {
            "TRANSMITTANCE_TEXTURE_WIDTH": sizes["transmittance_texture_width"],
            "TRANSMITTANCE_TEXTURE_HEIGHT": sizes["transmittance_texture_height"],
            "SCATTERING_TEXTURE_R_SIZE": sizes["scattering_texture_r_size"],
            "SCATTERING_TEXTURE_MU_SIZE": sizes["scattering_texture_mu_size"],
            "SCATTERING_TEXTURE_MU_S_SIZE": sizes["scattering_texture_mu_s_size"],
            "SCATTERING_TEXTURE_NU_SIZE": sizes["scattering_texture_nu_size"],
            "IRRADIANCE_TEXTURE_WIDTH": sizes["irradiance_texture_width"],
            "IRRADIANCE_TEXTURE_HEIGHT": sizes["irradiance_texture_height"],
        },
        "scattering_texture_nu_size": sampling.scattering_texture_nu_size,
        "num_scattering_orders": sampling.num_scattering_orders,
        "init": f"model->Init({sampling.num_scattering_orders})",
        "scattering_density_sample_count": sampling.scattering_density_sample_count,
        "functions.glsl": {
            "ComputeScatteringDensity SAMPLE_COUNT": sampling.scattering_density_sample_count,
            "where": "const int SAMPLE_COUNT = 16; in ComputeScatteringDensity (line 1187 at "
            "d9954923): S zenith x 2S azimuth incident directions",
            "ComputeIndirectIrradiance SAMPLE_COUNT": sampling.indirect_irradiance_sample_count,
            "where (irradiance)": "const int SAMPLE_COUNT = 32; in ComputeIndirectIrradiance "
            "(line 1487 at d9954923): S/2 zenith x 2S azimuth directions, the same angular step",
            "mie phase function": "paste <name>_bruneton_mie_phase.glsl immediately above "
            "'InverseSolidAngle MiePhaseFunction(Number g, Number nu) {' (line 744) and replace "
            f"that function by the line '{_ONE_LINE_CHANGE}'; or insert the snippet into the "
            'header model.cc builds, right after its "#version 330\\n" line',
        },
        "model_arguments": {
            "num_precomputed_wavelengths": 3,
            "combine_scattering_textures": False,
            "half_precision": False,
        },
        "why": {
            "combine_scattering_textures": "false: the combined texture keeps only the red "
            "channel of single Mie scattering and extrapolates green and blue with the Rayleigh "
            "spectrum of the multiple scattering, wrong when dust dominates it",
            "num_precomputed_wavelengths": "3: the tabulated phase function has the channels "
            "680, 550, 440 nm, which are the precomputation's wavelengths only in this mode",
            "half_precision": "false: float32 textures (his demo's half precision also limits "
            "the Sun zenith angle to 102 deg)",
            "SCATTERING_TEXTURE_MU_SIZE": "his 128, not less: the view zenith angles 0-35 deg "
            "fall in the first texels above the horizon (his mapping spaces them by the distance "
            "to the top), and a texel whose valid range of nu (the cosine of the angle from the "
            "Sun) excludes the looked-up nu is read at its clamped nu; with 32 the sky 30 deg "
            "from the zenith is interpolated with the zenith's texel, too bright 90 deg from "
            "the Sun and too dark near it for the forward-scattering dust",
        },
        **sampling.to_dict(),
    }


def _cpp_double(value: float) -> str:
    text = repr(float(value))
    return text if ("." in text or "e" in text or "inf" in text or "nan" in text) else text + ".0"


def _cpp_vector(name: str, values: np.ndarray) -> str:
    items = ", ".join(_cpp_double(v) for v in values)
    return f"const std::vector<double> {name} = {{{items}}};"


def _cpp_layers(name: str, layers: tuple[BrunetonLayer, ...]) -> str:
    body = ", ".join(
        "atmosphere::DensityProfileLayer("
        + ", ".join(
            _cpp_double(v)
            for v in (
                layer.width_m,
                layer.exp_term,
                layer.exp_scale_per_m,
                layer.linear_term_per_m,
                layer.constant_term,
            )
        )
        + ")"
        for layer in layers
    )
    return f"inline std::vector<atmosphere::DensityProfileLayer> {name}() {{ return {{{body}}}; }}"


def _identifier(name: str) -> str:
    text = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return text if text and not text[0].isdigit() else f"atm_{text}"


def bruneton_cpp(params: BrunetonParameters, sampling: PrecomputationSampling | None = None) -> str:
    """C++ header: the parameters as constants to pass to ``atmosphere::Model``.

    Everything is in SI units as his constructor documents them (lengths in
    m, coefficients in m^-1); his ``Model`` divides by
    ``length_unit_in_meters`` itself.  Include it after ``atmosphere/model.h``.
    With ``sampling`` (:func:`bruneton_precomputation`) it also states the
    precomputation the set needs (``kScatteringTextureNuSize``,
    ``kNumScatteringOrders``, ``kScatteringDensitySampleCount``,
    ``kIndirectIrradianceSampleCount``) and, when
    ``atmosphere/constants.h`` is included before it, checks his NU size with
    a ``static_assert``.
    """
    ns = f"dustoptics_{_identifier(params.name)}"
    lines = [
        f"// dustoptics: atmosphere {params.name!r} as the arguments of Bruneton's",
        "// precomputed_atmospheric_scattering atmosphere::Model (atmosphere/model.h).",
        "// Units: nm, W m^-2 nm^-1, rad, m, m^-1 (as the constructor's comments state).",
        "// Include after atmosphere/model.h (and after atmosphere/constants.h, to check its NU",
        "// size); see the JSON beside this file for the provenance and the precomputation.",
        "#include <vector>",
        "",
        f"namespace {ns} {{",
        _cpp_vector("kWavelengths", params.wavelength_nm),
        _cpp_vector("kSolarIrradiance", params.solar_irradiance_w_m2_nm),
        f"constexpr double kSunAngularRadius = {_cpp_double(params.sun_angular_radius_rad)};",
        f"constexpr double kBottomRadius = {_cpp_double(params.bottom_radius_m)};",
        f"constexpr double kTopRadius = {_cpp_double(params.top_radius_m)};",
        _cpp_layers("RayleighDensity", params.rayleigh_density),
        _cpp_vector("kRayleighScattering", params.rayleigh_scattering_per_m),
        _cpp_layers("MieDensity", params.mie_density),
        _cpp_vector("kMieScattering", params.mie_scattering_per_m),
        _cpp_vector("kMieExtinction", params.mie_extinction_per_m),
        f"constexpr double kMiePhaseFunctionG = {_cpp_double(params.mie_phase_function_g)};",
        _cpp_layers("AbsorptionDensity", params.absorption_density),
        _cpp_vector("kAbsorptionExtinction", params.absorption_extinction_per_m),
        _cpp_vector("kGroundAlbedo", params.ground_albedo),
        f"constexpr double kMaxSunZenithAngle = {_cpp_double(params.max_sun_zenith_angle_rad)};",
        f"constexpr double kLengthUnitInMeters = {_cpp_double(params.length_unit_in_meters)};",
        "constexpr unsigned int kNumPrecomputedWavelengths = 3;  // the phase snippet's channels",
        "constexpr bool kCombineScatteringTextures = false;  // dust: single Mie in 3 channels",
        "constexpr bool kHalfPrecision = false;",
    ]
    if sampling is not None:
        nu = sampling.scattering_texture_nu_size
        lines += [
            "",
            f"// The precomputation this atmosphere needs (tolerance {sampling.tolerance:g}):",
            "// SCATTERING_TEXTURE_NU_SIZE in atmosphere/constants.h, Init(kNumScatteringOrders),",
            "// and SAMPLE_COUNT of ComputeScatteringDensity in atmosphere/functions.glsl.",
            f"constexpr int kScatteringTextureNuSize = {nu};",
            f"constexpr unsigned int kNumScatteringOrders = {sampling.num_scattering_orders};",
            "constexpr int kScatteringDensitySampleCount = "
            f"{sampling.scattering_density_sample_count};",
            "// SAMPLE_COUNT of ComputeIndirectIrradiance (his 32): the same angular step.",
            "constexpr int kIndirectIrradianceSampleCount = "
            f"{sampling.indirect_irradiance_sample_count};",
            "#ifdef ATMOSPHERE_CONSTANTS_H_",
            f"static_assert(atmosphere::SCATTERING_TEXTURE_NU_SIZE >= {nu},",
            f'    "set SCATTERING_TEXTURE_NU_SIZE to {nu} in atmosphere/constants.h");',
            "#endif",
        ]
    lines += [
        "",
        "// new atmosphere::Model(kWavelengths, kSolarIrradiance, kSunAngularRadius, kBottomRadius,",
        "//     kTopRadius, RayleighDensity(), kRayleighScattering, MieDensity(), kMieScattering,",
        "//     kMieExtinction, kMiePhaseFunctionG, AbsorptionDensity(), kAbsorptionExtinction,",
        "//     kGroundAlbedo, kMaxSunZenithAngle, kLengthUnitInMeters,",
        "//     kNumPrecomputedWavelengths, kCombineScatteringTextures, kHalfPrecision);",
        "inline atmosphere::Model* MakeModel() {",
        "  return new atmosphere::Model(kWavelengths, kSolarIrradiance, kSunAngularRadius,",
        "      kBottomRadius, kTopRadius, RayleighDensity(), kRayleighScattering, MieDensity(),",
        "      kMieScattering, kMieExtinction, kMiePhaseFunctionG, AbsorptionDensity(),",
        "      kAbsorptionExtinction, kGroundAlbedo, kMaxSunZenithAngle, kLengthUnitInMeters,",
        "      kNumPrecomputedWavelengths, kCombineScatteringTextures, kHalfPrecision);",
        "}",
        f"}}  // namespace {ns}",
    ]
    return "\n".join(lines) + "\n"


def bruneton_phase_glsl(table: Any) -> str:
    """GLSL snippet of the aerosols' phase function for Bruneton's shaders.

    ``vec3 DustMiePhaseFunction(float nu)`` with the table's channels at his
    rendering wavelengths 680, 550, 440 nm (:func:`dustoptics.io.shaders.glsl.glsl_snippet`,
    prefix ``DUST_MIE``), preceded by the one-line change of his
    ``MiePhaseFunction`` as a comment.
    """
    _check_channels(table)
    snippet = glsl_snippet(
        table,
        channels_nm=BRUNETON_CHANNELS_NM,
        prefix="DUST_MIE",
        function_name=_PHASE_FUNCTION_NAME,
    )
    header = [
        "// For Bruneton's precomputed_atmospheric_scattering (2017): paste this snippet into",
        "// atmosphere/functions.glsl immediately above",
        "//   InverseSolidAngle MiePhaseFunction(Number g, Number nu) {",
        "// (line 744 at d9954923; or into the header model.cc builds, right after its",
        '// "#version 330\\n" line) and replace that MiePhaseFunction by this one line:',
        f"//   {_ONE_LINE_CHANGE}",
        "// Channels are his kLambdaR, kLambdaG, kLambdaB (680, 550, 440 nm): exact with",
        "// num_precomputed_wavelengths <= 3 (the passes then use these wavelengths).",
        "",
    ]
    return "\n".join(header) + snippet


def write_bruneton(
    atmosphere: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    tolerance: float = 0.005,
    nu_size: int | None = None,
    num_scattering_orders: int | None = None,
    scattering_density_sample_count: int | None = None,
    **options: Any,
) -> list[Path]:
    """Write ``NAME_bruneton.json``, ``NAME_bruneton_parameters.h`` and ``NAME_bruneton_mie_phase.glsl``.

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
    out_dir : path
        Directory (created if missing); the three files appear together or
        not at all.
    overwrite : bool
        Replace existing files.
    tolerance, nu_size, num_scattering_orders, scattering_density_sample_count
        The precomputation (:func:`bruneton_precomputation`), written into
        the JSON (``precomputation``) and the C++ header; a value the set
        cannot live with is refused before anything is written.
    **options
        Passed to :func:`bruneton_parameters`.

    Returns
    -------
    list of pathlib.Path
    """
    sampling = bruneton_precomputation(
        atmosphere,
        tolerance=tolerance,
        nu_size=nu_size,
        num_scattering_orders=num_scattering_orders,
        scattering_density_sample_count=scattering_density_sample_count,
    )
    params = bruneton_parameters(atmosphere, **options)
    base = Path(out_dir)
    stem = re.sub(r"[^A-Za-z0-9._-]", "_", atmosphere.name)
    aerosols = atmosphere.constituent("aerosols").table
    document = params.to_dict()
    document["precomputation"] = bruneton_precomputation_dict(sampling)
    files = {
        base / f"{stem}_bruneton.json": (
            json.dumps(document, indent=2, allow_nan=False) + "\n"
        ).encode("utf-8"),
        base / f"{stem}_bruneton_parameters.h": bruneton_cpp(params, sampling).encode("ascii"),
        base / f"{stem}_bruneton_mie_phase.glsl": bruneton_phase_glsl(aerosols).encode("ascii"),
    }
    return write_files(files, overwrite=overwrite)


def _write_bruneton_table(
    table: Any, out_dir: Any, *, overwrite: bool = False, **_: Any
) -> list[Path]:
    """The ``bruneton`` format of one aerosol table: its Mie parameters and phase snippet."""
    base = Path(out_dir)
    stem = re.sub(r"[^A-Za-z0-9._-]", "_", table.name)
    mie = {
        "model": "E. Bruneton, precomputed_atmospheric_scattering (2017), atmosphere::Model",
        "units": {"wavelengths": "nm", "mie_scattering, mie_extinction": "m-1 at the density 1"},
        "number_density_per_m3": table.quantity("number_density_per_m3"),
        "input_hash": table.provenance.input_hash,
        **bruneton_mie(table),
    }
    files = {
        base / f"{stem}_bruneton_mie.json": (
            json.dumps(mie, indent=2, allow_nan=False) + "\n"
        ).encode("utf-8"),
        base / f"{stem}_bruneton_mie_phase.glsl": bruneton_phase_glsl(table).encode("ascii"),
    }
    return write_files(files, overwrite=overwrite)


RECORD = register(
    Format(
        name="bruneton",
        summary="Bruneton's (2017) aerosol: NAME_bruneton_mie.json, .glsl (needs N0)",
        write=_write_bruneton_table,
        suffixes=(".json", ".glsl"),
        needs=frozenset({"cross_sections", "number_density"}),
        recognise=is_bruneton,
        describe=describe_bruneton,
    )
)
