"""What the engines that take a set's own spectra share: the set behind a fit, and its exact sky.

The framework's renderers take a flat mapping of floats.  An engine that is given
a set's own tables (CalcMySky's spectral description, Bevy's phase texture)
needs the set itself to render and to write its files: :func:`remember_set`
keeps it for the process and gives the float key its ``params`` carry
(``"set_key"``); :func:`set_of` finds it again.  :func:`exact_sky_rgb` renders a
set with the package's own solver (:func:`dustoptics.sky.scene.sky_radiance`,
the exact sky's) on the framework's directions, as linear sRGB per unit solar
illuminance.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Final

import numpy as np

from dustoptics import colour
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky.medium import Medium
from dustoptics.sky.scene import sky_radiance

__all__ = ["exact_sky_rgb", "remember_set", "set_of"]

_SETS: dict[int, Atmosphere] = {}
_MEDIA: dict[int, Medium] = {}

#: Tolerance of the orders of scattering (that of the framework's reference skies).
TOL: Final = 1e-3

#: Ground albedo of the framework's reference skies.
GROUND_ALBEDO: Final = 0.2


def remember_set(atmosphere: Atmosphere) -> float:
    """Keep ``atmosphere`` for this process; the key ``params["set_key"]`` carries. [-]"""
    for key, known in _SETS.items():
        if known is atmosphere:
            return float(key)
    key = len(_SETS) + 1
    _SETS[key] = atmosphere
    return float(key)


def set_of(params: Mapping[str, float]) -> Atmosphere:
    """The set a ``params`` mapping was made for (:func:`remember_set`)."""
    key = int(params["set_key"])
    if key not in _SETS:
        raise ValueError(f"set_key {key} was not made in this process (remember_set)")
    return _SETS[key]


def exact_sky_rgb(
    atmosphere: Atmosphere,
    *,
    sun_elevation_deg: float,
    view_zenith_deg: Any,
    view_azimuth_deg: Any,
) -> np.ndarray:
    """The set's sky by the package's solver, as linear sRGB per unit solar illuminance.

    The directions' zenith angles are solved as given; their azimuths must lie on
    a grid of one step from 0 to 180 deg (as the framework's dome).

    Returns
    -------
    numpy.ndarray, shape ``broadcast(view_zenith_deg, view_azimuth_deg).shape + (3,)`` [sr^-1]
    """
    zen, azi = np.broadcast_arrays(
        np.asarray(view_zenith_deg, dtype=float), np.asarray(view_azimuth_deg, dtype=float)
    )
    key = id(atmosphere)
    if key not in _MEDIA:
        _MEDIA[key] = Medium.from_atmosphere(atmosphere)
    unique_azi = np.unique(np.abs(azi))
    steps = np.diff(unique_azi)
    step = float(np.min(steps)) if steps.size else 15.0
    if not math.isclose(180.0 / step, round(180.0 / step), abs_tol=1e-6):
        raise ValueError(f"azimuths must lie on a grid dividing 180 deg; got step {step!r}")
    unique_zen = np.unique(zen)
    sky = sky_radiance(
        _MEDIA[key],
        sun_elevation_deg=sun_elevation_deg,
        ground_albedo=GROUND_ALBEDO,
        tol=TOL,
        view_zenith_deg=unique_zen,
        azimuth_step_deg=step,
    )
    rgb = colour.xyz_to_linear_srgb(sky.xyz())  # (n_zenith, n_azimuth, 3)
    iz = np.searchsorted(np.asarray(sky.view_zenith_deg), zen)
    ia = np.rint(np.abs(azi) / step).astype(int)
    return np.asarray(rgb[iz, ia], dtype=float)
