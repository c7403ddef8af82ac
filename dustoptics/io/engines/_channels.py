"""What the RGB engines (Bevy, OpenSpace, Celestia) take of a table: three channels.

An engine with three colour channels takes per channel a scattering and an
absorption (or extinction) coefficient and, when it has one, a phase
function.  :func:`channel_coefficients` makes them from a table with a
number density, with the channel weights of
:func:`dustoptics.io.shaders.common.choose_channels` (by default the
wavelengths 680, 550, 440 nm, as the seed's shader and Bruneton's and
OpenSpace's models use):
``beta_c = N0 sum_i W_ci C_i`` [m^-1], and the phase function of each channel
weighted by scattering, ``P_c = sum_i W_ci C_sca,i P_i / sum_i W_ci C_sca,i``
(:func:`dustoptics.colour.channel_phase`), so that ``beta_sca,c P_c`` is the
channel of ``beta_sca P``, the quantity single scattering needs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from dustoptics.colour import channel_phase
from dustoptics.io.shaders.common import choose_channels

__all__ = ["ChannelCoefficients", "channel_coefficients", "lua_number"]


@dataclass(frozen=True)
class ChannelCoefficients:
    """A table's three channels as an RGB engine takes them.

    Attributes
    ----------
    names : tuple of str
        What each channel is (``"680 nm"``, ...).
    wavelength_nm : numpy.ndarray, shape (3,)
        Each channel's wavelength or band centroid. [nm]
    scattering_per_m, absorption_per_m, extinction_per_m : numpy.ndarray, shape (3,)
        ``N0`` times the channel's cross-sections. [m^-1]
    theta_deg : numpy.ndarray, shape (n_theta,)
        The table's angles. [deg]
    phase : numpy.ndarray, shape (3, n_theta)
        Each channel's phase function, weighted by scattering; normalized
        as the table's rows. [sr^-1]
    g : numpy.ndarray, shape (3,)
        Each channel's asymmetry parameter, ``sum_i W_ci C_sca,i g_i / sum_i W_ci C_sca,i``
        (the ``<cos theta>`` of ``phase``). [-]
    """

    names: tuple[str, ...]
    wavelength_nm: np.ndarray
    scattering_per_m: np.ndarray
    absorption_per_m: np.ndarray
    extinction_per_m: np.ndarray
    theta_deg: np.ndarray
    phase: np.ndarray
    g: np.ndarray


def channel_coefficients(
    table: Any, *, channels_nm: Any = None, colour: str | None = None
) -> ChannelCoefficients:
    """The three channels of a table with cross-sections and a number density.

    Parameters
    ----------
    table : dustoptics.table.Table
        With cross-sections and ``number_density_per_m3``.
    channels_nm, colour
        The channels (:func:`dustoptics.io.shaders.common.choose_channels`).

    Returns
    -------
    ChannelCoefficients

    Raises
    ------
    ValueError
        A table without cross-sections or number density.
    """
    cs = table.cross_sections
    if cs is None or cs.number_density_per_m3 is None:
        raise ValueError(
            f"table {table.name!r} needs cross-sections and a number density "
            "(--number-density-per-m3) for an engine's scattering and absorption coefficients "
            "[m^-1]"
        )
    chosen = choose_channels(table, channels_nm=channels_nm, colour=colour)
    n0 = float(cs.number_density_per_m3)
    csca = np.asarray(table.quantity("csca_um2"), dtype=np.float64)
    cext = np.asarray(table.quantity("cext_um2"), dtype=np.float64)
    w = np.asarray(chosen.weights, dtype=np.float64)
    sca = n0 * (w @ csca) * 1e-12
    ext = n0 * (w @ cext) * 1e-12
    theta = np.asarray(table.theta_deg, dtype=np.float64)
    weight = w * csca[None, :]
    scatters = bool(np.all(weight.sum(axis=1) > 0.0))
    # A constituent that does not scatter (ozone) has its rows' plain channel average.
    phase = channel_phase(
        chosen, np.asarray(table.phase, dtype=np.float64), csca_um2=csca if scatters else None
    )
    if not scatters:
        weight = w
    g = (weight @ np.asarray(table.g, dtype=np.float64)) / weight.sum(axis=1)
    return ChannelCoefficients(
        names=tuple(chosen.names),
        wavelength_nm=np.asarray(chosen.centroid_nm, dtype=np.float64),
        scattering_per_m=sca,
        absorption_per_m=ext - sca,
        extinction_per_m=ext,
        theta_deg=theta,
        phase=phase,
        g=g,
    )


def lua_number(value: float) -> str:
    """A float as the shortest text that reads back to the same double (Lua, ssc, Rust)."""
    text = repr(float(value))
    if not np.isfinite(value):
        raise ValueError(f"cannot write the non-finite value {value!r} into an engine's file")
    return text
