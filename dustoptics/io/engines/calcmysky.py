"""An atmosphere as a CalcMySky/ShowMySky ``.atmo`` description with GLSL phase blocks.

Read from CalcMySky's source at :data:`CALCMYSKY_SOURCE`:
``common/AtmosphereParameters.cpp`` (the parser: ``version: 6`` first;
``key: value`` lines, ``#`` starts a comment; quantities ``NUMBER UNIT`` with
the number in plain digits, no exponent; ``wavelengths: min=..nm,max=..nm,count=N``
with N a multiple of 4, ``lambda_i = min + (max - min) i / (N - 1)``; spectra as
N comma-separated values or ``file ...``; ``Scatterer "name": { ... }`` with
``number density`` and ``phase function`` as GLSL function bodies between
lines of three backticks, ``cross section at 1 um`` (an **extinction** cross
section, ``C_ext(lambda) = C_1um (lambda / 1000 nm)^-angstrom``, times the
``single scattering albedo`` spectrum for scattering), ``angstrom exponent``,
``phase function type`` (``achromatic``, ``smooth`` or ``general``);
``Absorber "name": { number density, cross section }`` with a cross-section
spectrum in m^2), ``CalCMySky/shaders.cpp`` (each body becomes ``vec4
phaseFunction_NAME(float dotViewSun) { ... }`` or ``float
scattererNumberDensity_NAME(float altitude) { ... }`` in a ``#version 330``
shader that includes the constants header: ``PI``, ``km = 1000``, ``sqr(x)``,
``CONST``, ``const vec4 wavelengths`` (the four wavelengths of the set being
computed, nm) and ``const int wlSetIndex``), and ``examples/mars.atmo`` (its
settings and its Mars dust: an HG g fitted to Ockert-Bell et al. 1997).

Our file: the table's wavelengths when they are evenly spaced and a multiple
of 4, else 16 evenly spaced over the same range with every spectrum and phase
row interpolated linearly in wavelength (said in the file); molecules with
their fitted ``A + B mu^2`` phase function (``achromatic``); aerosols with their
**tabulated** phase function (``general``): for each set of four wavelengths,
256 nodes at ``theta_j = 180 (j / 255)^2`` deg (dense near the forward peak),
linear in ``sqrt(theta)`` between nodes, selected by ``wlSetIndex``; its largest
relative difference from the table's own interpolation is in the file.  The
extinction cross-section is the power law fitted to the table's (least squares
in log), its largest relative error stated; the single-scattering albedo is the
table's.  Settings (texture sizes, integration points, scattering orders):
``examples/mars.atmo``'s.  Solar irradiance: ASTM G173 (the source mars.atmo
names) times (1 au / distance)^2.

``dustoptics build mars|earth --format calcmysky`` writes ``NAME_calcmysky.atmo``
through :mod:`dustoptics.sky.engines.calcmysky`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.atmosphere.column import (
    DensityProfile,
    ExponentialProfile,
    FixedFractionProfile,
    PiecewiseLinearProfile,
)
from dustoptics.colour import solar_irradiance_astm_g173
from dustoptics.io._atomic import safe_stem, write_files

__all__ = [
    "CALCMYSKY_SOURCE",
    "CalcMySkyScatterer",
    "angstrom_fit",
    "calcmysky_atmo",
    "calcmysky_phase_lookup",
    "calcmysky_scatterer",
    "calcmysky_wavelengths",
    "phase_glsl_body",
    "write_calcmysky",
]

#: The CalcMySky source read for this module.
CALCMYSKY_SOURCE = (
    "10110111/CalcMySky v0.4.0-4, commit 7a7183d76efe9ff44ca6462f8de3f8e1eb9f196b "
    "(2026-02-04): common/AtmosphereParameters.cpp, CalcMySky/shaders.cpp, examples/mars.atmo"
)

#: The format version its parser accepts.
FORMAT_VERSION = 6

#: Nodes of the tabulated phase function per wavelength set.
DEFAULT_NODES = 256

_AU_M = 149_597_870_700.0

#: examples/mars.atmo's settings, in its order.
_SETTINGS = (
    ("transmittance texture size for VZA", "256"),
    ("transmittance texture size for altitude", "64"),
    ("irradiance texture size for SZA", "64"),
    ("irradiance texture size for altitude", "16"),
    ("scattering texture size for VZA", "128"),
    ("scattering texture size for dot(view,sun)", "16"),
    ("scattering texture size for SZA", "128"),
    ("scattering texture size for altitude", "64"),
    ("eclipsed scattering texture size for relative azimuth", "32"),
    ("eclipsed scattering texture size for VZA", "128"),
    ("eclipsed double scattering texture size for relative azimuth", "16"),
    ("eclipsed double scattering texture size for VZA", "128"),
    ("eclipsed double scattering texture size for SZA", "16"),
    ("eclipsed double scattering number of azimuth pairs to sample", "2"),
    ("eclipsed double scattering number of elevation pairs to sample", "10"),
    ("light pollution texture size for VZA", "128"),
    ("light pollution texture size for altitude", "64"),
    ("light pollution angular integration points", "200"),
    ("transmittance integration points", "500"),
    ("radial integration points", "50"),
    ("angular integration points", "512"),
    ("angular integration points for eclipse", "512"),
    ("scattering orders", "8"),
)


def _plain(value: float, digits: int = 9) -> str:
    """A number in plain digits (CalcMySky's quantities take no exponent)."""
    return np.format_float_positional(float(value), precision=digits, unique=True, trim="-")


def _sig(value: float, digits: int = 9) -> str:
    """``digits`` significant digits, in plain positional notation."""
    if value == 0.0:
        return "0"
    decimals = max(digits - 1 - math.floor(math.log10(abs(value))), 0)
    return _plain(round(float(value), decimals), decimals)


def _up(value: float) -> str:
    """A bound as 3 significant digits rounded up (a stated error never understates)."""
    if value <= 0.0:
        return "0"
    scale = 10.0 ** (math.floor(math.log10(value)) - 2)
    return f"{math.ceil(value / scale) * scale:.3g}"


def _area(value_m2: float) -> str:
    """An area as ``NUMBER UNIT`` with 1 <= NUMBER < 1e6 in one of CalcMySky's units."""
    for unit, scale in (
        ("am^2", 1e-36),
        ("fm^2", 1e-30),
        ("pm^2", 1e-24),
        ("nm^2", 1e-18),
        ("um^2", 1e-12),
        ("mm^2", 1e-6),
        ("m^2", 1.0),
    ):
        x = value_m2 / scale
        if x < 1e6:
            return f"{_sig(x)} {unit}"
    raise ValueError(f"cross-section {value_m2!r} m^2 is too large for CalcMySky (at most 1 m^2)")


def calcmysky_wavelengths(wavelength_nm: Any) -> tuple[np.ndarray, bool]:
    """CalcMySky's wavelengths for a grid: the grid itself when evenly spaced with a multiple
    of 4 points, else 16 evenly spaced over its range; and whether it is the grid. [nm]"""
    wl = np.asarray(wavelength_nm, dtype=np.float64)
    even = np.linspace(wl[0], wl[-1], wl.size)
    if wl.size % 4 == 0 and np.allclose(wl, even, rtol=0.0, atol=1e-9):
        return even, True
    return np.linspace(wl[0], wl[-1], 16), False


def angstrom_fit(wavelength_nm: Any, cross_section_um2: Any) -> tuple[float, float, float]:
    """``C(lambda) = C_1um (lambda / 1000 nm)^-alpha`` fitted in log by least squares.

    Returns
    -------
    (C_1um [um^2], alpha [-], largest relative error over the grid [-])
    """
    x = np.log(np.asarray(wavelength_nm, dtype=np.float64) / 1000.0)
    y = np.log(np.asarray(cross_section_um2, dtype=np.float64))
    slope, intercept = np.polyfit(x, y, 1)
    fitted = np.exp(intercept + slope * x)
    error = float(np.max(np.abs(fitted / np.exp(y) - 1.0)))
    return float(np.exp(intercept)), float(-slope), error


def _nodes_deg(n: int) -> np.ndarray:
    return 180.0 * (np.arange(n) / (n - 1)) ** 2


def calcmysky_phase_lookup(values: Any, theta_deg: Any) -> np.ndarray:
    """What the GLSL phase block returns: linear in ``sqrt(theta)`` between the nodes.

    Parameters
    ----------
    values : array_like, shape (n_wavelength, n_nodes)
        The phase function at the nodes ``theta_j = 180 (j / (n - 1))^2`` deg. [sr^-1]
    theta_deg : array_like
        Scattering angles. [deg]
    """
    v = np.atleast_2d(np.asarray(values, dtype=np.float64))
    n = v.shape[1]
    t = np.sqrt(np.clip(np.asarray(theta_deg, dtype=np.float64), 0.0, 180.0) / 180.0)
    grid = np.arange(n) / (n - 1)
    return np.stack([np.interp(t, grid, row) for row in v])


def _phase_rows(table: Any, wavelength_nm: np.ndarray, theta_deg: np.ndarray) -> np.ndarray:
    """The table's phase function at ``wavelength_nm`` (linear in wavelength) and angles."""
    rows = np.asarray(table.phase_at(theta_deg), dtype=np.float64)  # (n_table_wl, n)
    wl = np.asarray(table.wavelength_nm, dtype=np.float64)
    return np.stack(
        [np.interp(wavelength_nm, wl, rows[:, j]) for j in range(rows.shape[1])], axis=-1
    )


def phase_glsl_body(name: str, values: np.ndarray, wavelength_nm: np.ndarray, error: float) -> str:
    """The ``phase function`` body of a tabulated scatterer (see the module docstring)."""
    n_sets, n = values.shape[0] // 4, values.shape[1]
    vecs = []
    for s in range(n_sets):
        block = values[4 * s : 4 * s + 4]
        for j in range(n):
            vecs.append("vec4(" + ",".join(f"{float(v):.7g}" for v in block[:, j]) + ")")
    body = ",\n        ".join(", ".join(vecs[i : i + 4]) for i in range(0, len(vecs), 4))
    return "\n".join(
        [
            f"    // dustoptics: the tabulated phase function of {name!r} [sr^-1, 1 over the",
            f"    // sphere] at {n_sets} sets of 4 wavelengths ({wavelength_nm[0]:g}-"
            f"{wavelength_nm[-1]:g} nm), {n} nodes theta_j = 180 (j/{n - 1})^2 deg per set,",
            "    // linear in sqrt(theta) between nodes; largest relative difference from the",
            f"    // table's own interpolation {_up(error)}.",
            f"    const int N = {n};",
            f"    const vec4 P[{n_sets * n}] = vec4[{n_sets * n}](",
            f"        {body});",
            "    float t = sqrt(acos(clamp(dotViewSun, -1.0, 1.0)) / PI) * float(N - 1);",
            "    int j = min(int(t), N - 2);",
            "    int base = wlSetIndex * N;",
            "    return mix(P[base + j], P[base + j + 1], t - float(j));",
        ]
    )


def _density_body(n0_per_m3: float, profile: DensityProfile, top_m: float) -> str:
    """A ``number density`` body: ``N0`` times the relative profile at ``altitude`` [m]."""
    if isinstance(profile, FixedFractionProfile):
        return _density_body(n0_per_m3, profile.base, top_m)
    n0 = f"{n0_per_m3:.9g}"
    if isinstance(profile, ExponentialProfile):
        return f"    return {n0}*exp(-altitude/{profile.scale_height_m!r});"
    if isinstance(profile, PiecewiseLinearProfile):
        z = np.asarray(profile.altitude_m, dtype=np.float64)
        d = np.asarray(profile.density, dtype=np.float64)
    else:
        z = np.linspace(0.0, top_m, 241)
        d = np.asarray(profile.relative_density(z), dtype=np.float64)
    lines = [f"    // {profile!r}, linear between nodes [m]"]
    for i in range(z.size - 1):
        slope = (d[i + 1] - d[i]) / (z[i + 1] - z[i])
        lines.append(
            f"    if(altitude < {z[i + 1]!r}) return {n0}*max(0.0, {d[i]!r} + "
            f"{slope!r}*(altitude - {z[i]!r}));"
        )
    last = 0.0 if isinstance(profile, PiecewiseLinearProfile) and d[-1] == 0.0 else d[-1]
    lines.append(f"    return {n0}*{float(last)!r};")
    return "\n".join(lines)


@dataclass(frozen=True)
class CalcMySkyScatterer:
    """One ``Scatterer`` block.

    Attributes
    ----------
    name : str
        A GLSL identifier.
    number_density : str
        The GLSL body. [m^-3]
    phase_function : str
        The GLSL body. [sr^-1]
    phase_function_type : str
        ``achromatic``, ``smooth`` or ``general``.
    cross_section_1um_um2, angstrom_exponent : float
        The extinction power law. [um^2], [-]
    single_scattering_albedo : numpy.ndarray
        At the file's wavelengths. [-]
    comments : tuple of str
    """

    name: str
    number_density: str
    phase_function: str
    phase_function_type: str
    cross_section_1um_um2: float
    angstrom_exponent: float
    single_scattering_albedo: np.ndarray
    comments: tuple[str, ...] = ()

    def text(self) -> str:
        ssa = ",".join(_sig(v, 7) for v in np.clip(self.single_scattering_albedo, 0.0, 1.0))
        return "\n".join(
            [
                f'Scatterer "{self.name}":',
                "{",
                *[f"    # {c}" for c in self.comments],
                "    number density:",
                "    ```",
                self.number_density,
                "    ```",
                "    phase function:",
                "    ```",
                self.phase_function,
                "    ```",
                f"    cross section at 1 um: {_area(self.cross_section_1um_um2 * 1e-12)}",
                f"    angstrom exponent: {_sig(self.angstrom_exponent, 7)}",
                f"    single scattering albedo: {ssa}",
                f"    phase function type: {self.phase_function_type}",
                "}",
            ]
        )


def calcmysky_scatterer(
    name: str,
    table: Any,
    profile: DensityProfile,
    wavelength_nm: np.ndarray,
    *,
    top_m: float,
    tabulated: bool,
    n_nodes: int = DEFAULT_NODES,
) -> CalcMySkyScatterer:
    """A ``Scatterer`` of a table with cross-sections and number density, at ``wavelength_nm``.

    ``tabulated``: the phase function as nodes (``general``); else ``A + B mu^2``
    fitted to the table's row nearest 550 nm (``achromatic``, for molecules).
    """
    cs = table.cross_sections
    if cs is None or cs.number_density_per_m3 is None:
        raise ValueError(
            f"table {table.name!r} needs cross-sections and a number density for CalcMySky"
        )
    wl = np.asarray(table.wavelength_nm, dtype=np.float64)
    c1, alpha, c_err = angstrom_fit(wl, table.quantity("cext_um2"))
    ssa = np.interp(wavelength_nm, wl, np.asarray(table.ssa, dtype=np.float64))
    comments = [
        f"dustoptics table {table.name!r}, input hash {table.provenance.input_hash}",
        f"extinction cross-section: power law fitted to the table's, largest relative error "
        f"{c_err:.3g} over {wl[0]:g}-{wl[-1]:g} nm",
    ]
    if tabulated:
        nodes = _nodes_deg(n_nodes)
        # The values as the file holds them (7 significant digits), so the stated error is the file's.
        values = np.array(
            [[float(f"{v:.7g}") for v in row] for row in _phase_rows(table, wavelength_nm, nodes)]
        )
        theta = np.asarray(table.theta_deg, dtype=np.float64)
        exact = _phase_rows(table, wavelength_nm, theta)
        got = calcmysky_phase_lookup(values, theta)
        error = float(np.max(np.abs(got / exact - 1.0)))
        body = phase_glsl_body(name, values, wavelength_nm, error)
        kind = "general"
    else:
        i = int(np.argmin(np.abs(wl - 550.0)))
        mu = np.cos(np.radians(np.asarray(table.theta_deg, dtype=np.float64)))
        a, b = np.linalg.lstsq(
            np.stack([np.ones_like(mu), mu * mu], axis=1), np.asarray(table.phase)[i], rcond=None
        )[0]
        fit_err = float(np.max(np.abs((a + b * mu * mu) / np.asarray(table.phase)[i] - 1.0)))
        body = (
            f"    // A + B mu^2 fitted to {table.name!r} at {wl[i]:g} nm (largest relative "
            f"error {fit_err:.3g})\n"
            f"    return vec4({float(a):.9g} + {float(b):.9g}*sqr(dotViewSun));"
        )
        kind = "achromatic"
    return CalcMySkyScatterer(
        name=name,
        number_density=_density_body(float(cs.number_density_per_m3), profile, top_m),
        phase_function=body,
        phase_function_type=kind,
        cross_section_1um_um2=c1,
        angstrom_exponent=alpha,
        single_scattering_albedo=ssa,
        comments=tuple(comments),
    )


def _spectrum(values: Any, digits: int = 7) -> str:
    return ",".join(_sig(float(v), digits) for v in values)


def calcmysky_atmo(
    atmosphere: Any,
    *,
    ground_albedo: float = 0.1,
    n_nodes: int = DEFAULT_NODES,
    moon_distance_km: float | None = None,
    notes: Sequence[str] = (),
) -> str:
    """The ``.atmo`` description of an atmosphere set (see the module docstring).

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
    ground_albedo : float
        Grey ground albedo. [-]
    n_nodes : int
        Nodes of the tabulated phase function per wavelength set.
    moon_distance_km : float, optional
        ``Earth-Moon distance`` (default: the Moon's 384400 km for Earth, Deimos'
        23460 km for Mars, as examples/mars.atmo). [km]
    notes : sequence of str
        More comment lines for the header (e.g. the sky error).
    """
    wl, same = calcmysky_wavelengths(atmosphere.wavelength_nm)
    top = float(atmosphere.atmosphere_radius_m - atmosphere.planet_radius_m)
    earth = "earth" in atmosphere.name
    moon = moon_distance_km if moon_distance_km is not None else (384400.0 if earth else 23460.0)
    sun = solar_irradiance_astm_g173(wl) * (_AU_M / atmosphere.sun_distance_m) ** 2
    lines = [
        f"version: {FORMAT_VERSION}",
        f"# dustoptics: atmosphere {atmosphere.name!r} for CalcMySky/ShowMySky.",
        f"# CalcMySky source read: {CALCMYSKY_SOURCE}.",
        "# Settings (texture sizes, integration points, orders): examples/mars.atmo's.",
        *[f"# {n}" for n in notes],
        "# Wavelengths: "
        + (
            "the tables' own."
            if same
            else f"16 evenly spaced over the tables' {wl[0]:g}-{wl[-1]:g} nm; spectra and "
            "phase rows interpolated linearly in wavelength."
        ),
        "",
        *[f"{k}: {v}" for k, v in _SETTINGS],
        "",
        f"Earth-Sun distance: {_sig(atmosphere.sun_distance_m / _AU_M, 9)} AU",
        f"Earth-Moon distance: {_plain(moon)} km",
        f"Earth radius: {_plain(atmosphere.planet_radius_m / 1000.0)} km",
        f"atmosphere height: {_plain(top / 1000.0)} km",
        "",
        f"wavelengths: min={_plain(wl[0])}nm,max={_plain(wl[-1])}nm,count={wl.size}",
        "# ASTM G173 extraterrestrial spectrum (10 nm bin means) times (1 au / distance)^2,",
        "# W/(m^2*nm)",
        f"solar irradiance at TOA: {_spectrum(sun)}",
        f"ground albedo: {_spectrum(np.full(wl.size, ground_albedo))}",
        f"light pollution relative radiance: {_spectrum(np.zeros(wl.size))}",
        "",
    ]
    for c in atmosphere.constituents:
        if c.role == "ozone":
            cs = c.table.cross_sections
            n0 = float(cs.number_density_per_m3)
            sigma = np.interp(
                wl, c.table.wavelength_nm, np.asarray(c.table.quantity("cabs_um2")) * 1e-12
            )
            lines += [
                'Absorber "ozone":',
                "{",
                f"    # dustoptics table {c.table.name!r}, {c.profile!r}",
                "    number density:",
                "    ```",
                _density_body(n0, c.profile, top),
                "    ```",
                f"    cross section: {_spectrum(sigma)}",
                "}",
                "",
            ]
            continue
        scatterer = calcmysky_scatterer(
            "molecules" if c.role == "molecules" else "aerosols",
            c.table,
            c.profile,
            wl,
            top_m=top,
            tabulated=c.role == "aerosols",
            n_nodes=n_nodes,
        )
        lines += [scatterer.text(), ""]
    return "\n".join(lines)


def write_calcmysky(
    atmosphere: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    **options: Any,
) -> list[Path]:
    """Write ``NAME_calcmysky.atmo`` (``**options``: :func:`calcmysky_atmo`'s)."""
    path = Path(out_dir) / f"{safe_stem(atmosphere.name)}_calcmysky.atmo"
    text = calcmysky_atmo(atmosphere, **options)
    return write_files({path: text.encode("utf-8")}, overwrite=overwrite)
