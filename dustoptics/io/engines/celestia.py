"""An atmosphere as a Celestia ``.ssc`` ``Atmosphere`` block.

Read from Celestia's source at :data:`CELESTIA_SOURCE`:
``src/celengine/solarsys.cpp`` (``ReadAtmosphere``: keys ``Height`` and
``MieScaleHeight`` as lengths, in km by default; ``Mie`` one number;
``MieHGAnisotropy`` (``MieAsymmetry`` is deprecated and read with the opposite
sign); ``Rayleigh`` and ``Absorption`` three numbers; ``RayleighScaleHeight`` is
not read), ``src/celengine/shadermanager.cpp``
(``CelestiaGLProgram::setAtmosphereParameters``: every coefficient is multiplied
by the body's radius in km, so they are in km^-1; the one scale height
``MieScaleHeight`` sets the density ``exp(-h / H)`` of **all** of Rayleigh, Mie
and absorption; extinction = Rayleigh + Mie + Absorption; the phase functions
are Schlick's ``(1 - k^2) / (1 - k mu)^2`` with ``k = 1.55 g - 0.55 g^3`` and
``0.75 (1 + mu^2)``, both without the ``1 / (4 pi)`` -- the same factor, so their
ratio is right; scattered colour ``phRayleigh Rayleigh + phMie Mie``; ``mu`` the
cosine of the scattering angle) and the Mars and Earth entries of
CelestiaContent's ``data/solarsys.ssc`` at :data:`CELESTIA_CONTENT_SOURCE`
(Mars: ``Mie 0.003``, ``MieScaleHeight 11.1``, ``Rayleigh [0.00022 0.00034
0.00070]``, ``Absorption [0.002 0.002 0.003]``, no anisotropy (isotropic dust)).

Mapping (channels R, G, B at 680, 550, 440 nm, as Celestia's Earth comment
states): ``MieScaleHeight`` is the scale height (of equal column) of the
constituent with the largest vertical optical depth at 550 nm, and every
coefficient is ``beta L / H`` (``L`` its own column length), so each vertical
optical depth is kept; ``Rayleigh`` = the molecules' scattering; ``Mie`` = the
aerosols' scattering at 550 nm (Celestia's Mie is grey); ``Absorption`` = the
rest of the extinction per channel (aerosol extinction + ozone absorption -
``Mie``), so the extinction of each channel is kept (a negative remainder is
set to 0 and said); ``MieHGAnisotropy`` = a Henyey-Greenstein fit at 550 nm
unless given (Celestia turns it into Schlick's k).

Files: ``NAME_celestia.ssc``, a ``Modify "Mars" "Sol"`` (or ``"Earth"``) entry that
only replaces the scattering keys (put it in Celestia's ``extras`` folder);
``dustoptics build mars|earth --format celestia`` writes it through
:mod:`dustoptics.sky.engines.celestia`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io.engines._channels import channel_coefficients, lua_number
from dustoptics.io.engines.openspace import _scale_height_km
from dustoptics.scattering.fit import fit_table

__all__ = [
    "CELESTIA_CHANNELS_NM",
    "CELESTIA_CONTENT_SOURCE",
    "CELESTIA_SOURCE",
    "CelestiaAtmosphere",
    "celestia_mie_phase",
    "celestia_parameters",
    "celestia_rayleigh_phase",
    "celestia_schlick_k",
    "celestia_ssc",
    "write_celestia",
]

#: The Celestia source read for this module.
CELESTIA_SOURCE = (
    "CelestiaProject/Celestia 1.7.0-dev, commit ec2c717606810b48096b5c11b29e594556ed9aa4 "
    "(2026-08-07): src/celengine/solarsys.cpp, src/celengine/shadermanager.cpp"
)

#: The CelestiaContent source read (Mars and Earth in data/solarsys.ssc).
CELESTIA_CONTENT_SOURCE = (
    "CelestiaProject/CelestiaContent commit d156a8b5ed3f03add56c706880cc879b99ba26f9 "
    "(2026-06-25): data/solarsys.ssc"
)

#: Channel wavelengths of Celestia's Earth Rayleigh coefficients (its comment). [nm]
CELESTIA_CHANNELS_NM = (680.0, 550.0, 440.0)


def celestia_schlick_k(g: Any) -> np.ndarray:
    """Celestia's Schlick parameter of an HG asymmetry, ``k = 1.55 g - 0.55 g^3``. [-]"""
    x = np.asarray(g, dtype=np.float64)
    return np.asarray(1.55 * x - 0.55 * x**3, dtype=np.float64)


def celestia_mie_phase(mu: Any, g: float) -> np.ndarray:
    """Celestia's Mie phase function over ``4 pi``: ``(1 - k^2) / (4 pi (1 - k mu)^2)``. [sr^-1]

    Celestia's shader omits the ``1 / (4 pi)`` of both its phase functions; it is
    put back here (Schlick's function so normalized integrates to 1).
    """
    k = float(celestia_schlick_k(g))
    m = np.asarray(mu, dtype=np.float64)
    return np.asarray((1.0 - k * k) / (4.0 * math.pi * (1.0 - k * m) ** 2), dtype=np.float64)


def celestia_rayleigh_phase(mu: Any) -> np.ndarray:
    """Celestia's Rayleigh phase function over ``4 pi``: ``0.75 (1 + mu^2) / (4 pi)``. [sr^-1]"""
    m = np.asarray(mu, dtype=np.float64)
    return np.asarray(0.75 * (1.0 + m * m) / (4.0 * math.pi), dtype=np.float64)


@dataclass(frozen=True)
class CelestiaAtmosphere:
    """The scattering keys of a Celestia ``Atmosphere`` block, in its units.

    Attributes
    ----------
    name : str
    body, parent : str
        The ``Modify "body" "parent"`` entry (``"Mars"``, ``"Sol"``).
    height_km : float or None
        ``Height`` [km]; None leaves the body's own.
    mie_per_km : float
        ``Mie``. [km^-1]
    mie_scale_height_km : float
        ``MieScaleHeight`` (of every term). [km]
    mie_hg_anisotropy : float
        ``MieHGAnisotropy``, in (-1, 1). [-]
    rayleigh_per_km : tuple of 3 floats or None
        ``Rayleigh`` (R, G, B); None leaves the body's own. [km^-1]
    absorption_per_km : tuple of 3 floats
        ``Absorption``. [km^-1]
    notes : tuple of str
    """

    name: str
    body: str
    parent: str
    height_km: float | None
    mie_per_km: float
    mie_scale_height_km: float
    mie_hg_anisotropy: float
    rayleigh_per_km: tuple[float, float, float] | None
    absorption_per_km: tuple[float, float, float]
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not -1.0 < self.mie_hg_anisotropy < 1.0:
            raise ValueError(
                f"mie_hg_anisotropy must be in (-1, 1); got {self.mie_hg_anisotropy!r}"
            )


def hg_g(table: Any, wavelength_nm: float = 550.0) -> tuple[float, float]:
    """Henyey-Greenstein g fitted to a table at one wavelength, and its rms relative error. [-]"""
    fit = fit_table(
        table, model="henyey-greenstein", colour="wavelengths", channels_nm=(wavelength_nm,) * 3
    )
    return float(fit.parameters[0, 0]), float(fit.rms_relative_error[0])


def _absorption(extinction: np.ndarray, mie: float, notes: list[str]) -> tuple[float, ...]:
    rest = extinction - mie
    if np.any(rest < 0.0):
        notes.append(
            "Absorption: the extinction left after Mie is negative in a channel "
            f"({', '.join(f'{v:.4g}' for v in rest)} km^-1); set to 0 there (Celestia's Mie is grey)"
        )
    return tuple(float(v) for v in np.maximum(rest, 0.0))


def celestia_parameters(
    atmosphere: Any, *, g: float | None = None, channels_nm: Any = CELESTIA_CHANNELS_NM
) -> CelestiaAtmosphere:
    """Celestia's scattering keys for an atmosphere set (see the module docstring)."""
    top = float(atmosphere.atmosphere_radius_m - atmosphere.planet_radius_m)
    coeff = {
        c.role: (channel_coefficients(c.table, channels_nm=channels_nm), c)
        for c in atmosphere.constituents
    }
    depth = {
        role: float(cc.extinction_per_m[1]) * float(c.profile.column_length_m(top_altitude_m=top))
        for role, (cc, c) in coeff.items()
    }
    main = max(depth, key=lambda role: depth[role])
    h_km, how = _scale_height_km(coeff[main][1].profile, top)
    notes = [
        f"MieScaleHeight: the {main}' ({how}); every coefficient is beta L / H, which keeps "
        "each vertical optical depth"
    ]

    def scaled(role: str, values: np.ndarray) -> np.ndarray:
        c = coeff[role][1]
        length_km = float(c.profile.column_length_m(top_altitude_m=top)) / 1000.0
        return values * 1000.0 * length_km / h_km

    mol, _ = coeff["molecules"]
    aer, aer_c = coeff["aerosols"]
    rayleigh = scaled("molecules", mol.scattering_per_m)
    mie = float(scaled("aerosols", aer.scattering_per_m)[1])
    extinction = scaled("aerosols", aer.extinction_per_m) + scaled(
        "molecules", mol.absorption_per_m
    )
    if "ozone" in coeff:
        extinction = extinction + scaled("ozone", coeff["ozone"][0].absorption_per_m)
    absorption = _absorption(extinction, mie, notes)
    if g is None:
        g, rms = hg_g(aer_c.table)
        notes.append(
            f"MieHGAnisotropy: Henyey-Greenstein fit at 550 nm, rms relative error {rms:.3g}"
        )
    notes += [
        f"{role}: {c.table.name!r} ({c.table.provenance.input_hash}), {c.profile!r}"
        for role, (_, c) in coeff.items()
    ]
    body = "Earth" if "earth" in atmosphere.name else "Mars"
    return CelestiaAtmosphere(
        name=atmosphere.name,
        body=body,
        parent="Sol",
        height_km=top / 1000.0,
        mie_per_km=mie,
        mie_scale_height_km=h_km,
        mie_hg_anisotropy=float(g),
        rayleigh_per_km=(float(rayleigh[0]), float(rayleigh[1]), float(rayleigh[2])),
        absorption_per_km=(absorption[0], absorption[1], absorption[2]),
        notes=tuple(notes),
    )


def celestia_ssc(p: CelestiaAtmosphere) -> str:
    """The ``.ssc`` text: a comment block and a ``Modify`` entry with the ``Atmosphere`` block."""

    def vec(values: tuple[float, float, float]) -> str:
        return "[ " + " ".join(lua_number(v) for v in values) + " ]"

    lines = [
        f"# dustoptics: {p.name!r} as Celestia's scattering atmosphere.",
        f"# Celestia source read: {CELESTIA_SOURCE}.",
        "# Units: km, km^-1; channels R, G, B = 680, 550, 440 nm; one scale height for every",
        "# term; Mie phase Schlick(k = 1.55 g - 0.55 g^3) of MieHGAnisotropy g.",
        *[f"# {n}" for n in p.notes],
        f'Modify "{p.body}" "{p.parent}"',
        "{",
        "\tAtmosphere",
        "\t{",
    ]
    if p.height_km is not None:
        lines.append(f"\t\tHeight\t{lua_number(p.height_km)}")
    lines += [
        f"\t\tMie\t{lua_number(p.mie_per_km)}",
        f"\t\tMieScaleHeight\t{lua_number(p.mie_scale_height_km)}",
        f"\t\tMieHGAnisotropy\t{lua_number(p.mie_hg_anisotropy)}",
    ]
    if p.rayleigh_per_km is not None:
        lines.append(f"\t\tRayleigh\t{vec(p.rayleigh_per_km)}")
    lines += [f"\t\tAbsorption\t{vec(p.absorption_per_km)}", "\t}", "}"]
    return "\n".join(lines) + "\n"


def write_celestia(
    atmosphere: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    parameters: CelestiaAtmosphere | None = None,
    **options: Any,
) -> list[Path]:
    """Write ``NAME_celestia.ssc`` (parameters: given, e.g. fitted to the sky, or
    :func:`celestia_parameters` with ``**options``)."""
    p = parameters if parameters is not None else celestia_parameters(atmosphere, **options)
    path = Path(out_dir) / f"{safe_stem(atmosphere.name)}_celestia.ssc"
    return write_files({path: celestia_ssc(p).encode("utf-8")}, overwrite=overwrite)
