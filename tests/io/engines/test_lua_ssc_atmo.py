"""OpenSpace (.asset), Celestia (.ssc) and CalcMySky (.atmo): each file read back by a small
parser of its format, the numbers checked against the set, the GLSL phase block compiled."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dustoptics.atmosphere import sets as atm
from dustoptics.io.engines.calcmysky import (
    angstrom_fit,
    calcmysky_atmo,
    calcmysky_phase_lookup,
    calcmysky_wavelengths,
)
from dustoptics.io.engines.celestia import (
    celestia_mie_phase,
    celestia_parameters,
    celestia_rayleigh_phase,
    celestia_schlick_k,
    write_celestia,
)
from dustoptics.io.engines.openspace import (
    openspace_mie_phase,
    openspace_parameters,
    write_openspace,
)
from dustoptics.io.tables.netcdf import read_hdf5

TABLES = Path(__file__).resolve().parents[3] / "tables"
GLSLANG = shutil.which("glslangValidator")


@pytest.fixture(scope="module")
def mars():
    dust = read_hdf5(TABLES / "blue-moons" / "blue-moons.nc")
    return atm.mars_atmosphere(dust_table=dust, optical_depth=0.5)


@pytest.fixture(scope="module")
def earth():
    return atm.earth_atmosphere()


# --- a tokenizer for the Lua tables of OpenSpace's assets and the blocks of Celestia's ssc ----

_TOKEN = re.compile(
    r"""\s*(?:(--[^\n]*|\#[^\n]*)|("[^"]*")|([A-Za-z_][A-Za-z0-9_.]*)|"""
    r"""(-?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|(.))"""
)


def _tokens(text: str) -> list[tuple[str, str]]:
    out = []
    for comment, string, name, number, other in _TOKEN.findall(text):
        if comment:
            continue
        if string:
            out.append(("str", string[1:-1]))
        elif name:
            out.append(("name", name))
        elif number:
            out.append(("num", number))
        elif other.strip():
            out.append(("op", other))
    return out


def _lua_value(tokens: list[tuple[str, str]], i: int) -> tuple[Any, int]:
    kind, value = tokens[i]
    if kind == "num":
        return float(value), i + 1
    if kind in ("str", "name"):
        # Attribute access (globe.Mars.Identifier) or a string: kept as text.
        return value, i + 1
    assert value == "{", tokens[i : i + 5]
    i += 1
    items: list[Any] = []
    fields: dict[str, Any] = {}
    while tokens[i] != ("op", "}"):
        if tokens[i][0] == "name" and tokens[i + 1] == ("op", "="):
            key = tokens[i][1]
            fields[key], i = _lua_value(tokens, i + 2)
        else:
            v, i = _lua_value(tokens, i)
            items.append(v)
        if tokens[i] == ("op", ","):
            i += 1
    return (fields if fields else items), i + 1


def parse_lua_local(text: str, name: str) -> Any:
    """The value of ``local NAME = {...}`` in a Lua file."""
    tokens = _tokens(text)
    for i in range(len(tokens) - 3):
        if tokens[i : i + 3] == [("name", "local"), ("name", name), ("op", "=")]:
            return _lua_value(tokens, i + 3)[0]
    raise AssertionError(f"no 'local {name} =' in the file")


def parse_ssc(text: str) -> list[dict[str, Any]]:
    """Celestia's ssc: ``[Disposition] "name" "parent" { key value ... }`` entries."""
    tokens = _tokens(text)

    def block(i: int) -> tuple[dict[str, Any], int]:
        assert tokens[i] == ("op", "{")
        i += 1
        out: dict[str, Any] = {}
        while tokens[i] != ("op", "}"):
            key = tokens[i][1]
            kind, value = tokens[i + 1]
            if value == "{":
                out[key], i = block(i + 1)
            elif value == "[":
                j = i + 2
                values = []
                while tokens[j] != ("op", "]"):
                    values.append(float(tokens[j][1]))
                    j += 1
                out[key], i = values, j + 1
            else:
                out[key], i = (float(value) if kind == "num" else value), i + 2
        return out, i + 1

    entries, i = [], 0
    while i < len(tokens):
        disposition = tokens[i][1] if tokens[i][0] == "name" else "Add"
        i += 1 if tokens[i][0] == "name" else 0
        name, parent = tokens[i][1], tokens[i + 1][1]
        body, i = block(i + 2)
        entries.append({"disposition": disposition, "name": name, "parent": parent, **body})
    return entries


# --- OpenSpace ----------------------------------------------------------------------------------


def _beta(table, which: str, wavelengths=(680.0, 550.0, 440.0)) -> np.ndarray:
    """beta at the channel wavelengths (table wavelengths here) [m^-1], from the cross-sections."""
    wl = list(table.wavelength_nm)
    idx = [wl.index(w) for w in wavelengths]
    n0 = table.cross_sections.number_density_per_m3
    return n0 * np.asarray(table.quantity(which))[idx] * 1e-12


def test_openspace_asset_reads_back_in_km(mars, tmp_path) -> None:
    (path,) = write_openspace(mars, tmp_path)
    text = path.read_text()
    assert "OpenSpace/OpenSpace commit 37e7e4f9" in text
    node = parse_lua_local(text, "Atmosphere")
    r = node["Renderable"]
    assert r["Type"] == "RenderableAtmosphere"
    assert r["PlanetRadius"] == 3390.0 and r["AtmosphereHeight"] == 120.0
    dust = mars.constituent("aerosols").table
    molecules = mars.constituent("molecules").table
    np.testing.assert_allclose(
        r["Mie"]["Coefficients"]["Scattering"], _beta(dust, "csca_um2") * 1e3, rtol=1e-12
    )
    np.testing.assert_allclose(
        r["Mie"]["Coefficients"]["Extinction"], _beta(dust, "cext_um2") * 1e3, rtol=1e-12
    )
    np.testing.assert_allclose(
        r["Rayleigh"]["Coefficients"]["Scattering"], _beta(molecules, "csca_um2") * 1e3, rtol=1e-12
    )
    assert r["Rayleigh"]["Coefficients"]["Wavelengths"] == [680.0, 550.0, 440.0]
    assert r["Mie"]["H_M"] == 11.1 and r["Rayleigh"]["H_R"] == 8.0
    assert 0.5 < r["Mie"]["G"] < 1.0
    # The fitted G is the parameters' own; a given G is written as given.
    assert openspace_parameters(mars, g=0.7).g == 0.7


def test_openspace_earth_ozone_keeps_the_column(earth, tmp_path) -> None:
    p = openspace_parameters(earth, g=0.76)
    ozone = next(c for c in earth.constituents if c.role == "ozone")
    top = earth.atmosphere_radius_m - earth.planet_radius_m
    column_m = ozone.profile.column_length_m(top_altitude_m=top)
    wl = list(ozone.table.wavelength_nm)
    # OpenSpace: tau = Extinction * 6e-7 * H_O (km); ours: beta_abs * column.
    beta = np.interp([680.0, 550.0, 440.0], wl, np.asarray(ozone.table.beta_abs_per_m))
    np.testing.assert_allclose(
        np.asarray(p.ozone_extinction) * 0.0000006 * p.h_o_km, beta * column_m, rtol=1e-9
    )
    node = parse_lua_local(
        (write_openspace(earth, tmp_path, parameters=p)[0]).read_text(), "Atmosphere"
    )
    assert node["Renderable"]["Ozone"]["H_O"] == 8.0


def test_openspace_mie_phase_is_cornette_shanks_normalized() -> None:
    mu = np.linspace(-1.0, 1.0, 400001)
    for g in (0.0, 0.5, 0.85):
        integral = 2.0 * math.pi * np.trapezoid(openspace_mie_phase(mu, g), mu)
        assert integral == pytest.approx(1.0, rel=1e-6)
    # g = 0: the Rayleigh shape 3 (1 + mu^2) / (16 pi).
    np.testing.assert_allclose(
        openspace_mie_phase(mu[::1000], 0.0),
        3.0 * (1.0 + mu[::1000] ** 2) / (16.0 * math.pi),
        rtol=1e-9,
    )


# --- Celestia -----------------------------------------------------------------------------------


def test_celestia_ssc_keeps_each_vertical_optical_depth(mars, tmp_path) -> None:
    (path,) = write_celestia(mars, tmp_path)
    (entry,) = parse_ssc(path.read_text())
    assert (entry["disposition"], entry["name"], entry["parent"]) == ("Modify", "Mars", "Sol")
    a = entry["Atmosphere"]
    h = a["MieScaleHeight"]
    assert h == 11.1  # the dust dominates Mars' optical depth
    # Celestia: tau_c = (Rayleigh_c + Mie + Absorption_c) H; ours: sum of beta_ext L.
    top = mars.atmosphere_radius_m - mars.planet_radius_m
    tau = np.zeros(3)
    for c in mars.constituents:
        length = c.profile.column_length_m(top_altitude_m=top)
        tau += _beta(c.table, "cext_um2") * length
    got = (np.asarray(a["Rayleigh"]) + a["Mie"] + np.asarray(a["Absorption"])) * h
    np.testing.assert_allclose(got, tau, rtol=1e-9)
    # Mie is the dust's scattering at 550 nm, over the same column.
    dust = mars.constituent("aerosols")
    np.testing.assert_allclose(
        a["Mie"] * h,
        _beta(dust.table, "csca_um2")[1] * dust.profile.column_length_m(top_altitude_m=top),
        rtol=1e-9,
    )
    assert 0.5 < a["MieHGAnisotropy"] < 1.0 and "MieAsymmetry" not in a


def test_celestia_phase_functions() -> None:
    # k = 1.55 g - 0.55 g^3 (setAtmosphereParameters); Schlick over 4 pi integrates to 1.
    assert float(celestia_schlick_k(0.5)) == pytest.approx(0.775 - 0.06875, abs=1e-15)
    mu = np.linspace(-1.0, 1.0, 400001)
    for g in (0.0, 0.4, 0.8):
        assert 2.0 * math.pi * np.trapezoid(celestia_mie_phase(mu, g), mu) == pytest.approx(
            1.0, rel=1e-6
        )
    assert 2.0 * math.pi * np.trapezoid(celestia_rayleigh_phase(mu), mu) == pytest.approx(1.0)


def test_celestia_earth_is_dominated_by_its_molecules_or_aerosols(earth) -> None:
    p = celestia_parameters(earth, g=0.7)
    assert p.body == "Earth" and p.rayleigh_per_km is not None
    assert all(v >= 0.0 for v in p.absorption_per_km)


# --- CalcMySky ----------------------------------------------------------------------------------

_QUANTITY = re.compile(r"^(-?[0-9.]+) *([a-zA-Z][a-zA-Z0-9^-]*)$")  # AtmosphereParameters.cpp


def parse_atmo(text: str) -> dict[str, Any]:
    """CalcMySky's .atmo, by its parser's rules (common/AtmosphereParameters.cpp at 7a7183d7)."""
    lines = text.splitlines()
    out: dict[str, Any] = {"scatterers": {}, "absorbers": {}}
    i = 0

    def body(i: int) -> tuple[str, int]:
        assert re.match(r"^\s*```\s*$", lines[i]), lines[i]
        j = i + 1
        while not re.match(r"^\s*```\s*$", lines[j]):
            j += 1
        return "\n".join(lines[i + 1 : j]) + "\n", j + 1

    while i < len(lines):
        code = lines[i].split("#")[0]
        i += 1
        if not code.strip():
            continue
        key, _, value = code.partition(":")
        key, value = key.strip().lower(), value.strip()
        if "version" not in out:
            assert key == "version", "first key must be version"
        m = re.match(r'^(scatterer|absorber) "([^"]+)"$', key)
        if not m:
            out[key] = value
            continue
        block: dict[str, str] = {}
        assert lines[i].strip() == "{"
        i += 1
        while lines[i].strip() != "}":
            code = lines[i].split("#")[0]
            i += 1
            if not code.strip():
                continue
            k, _, v = code.partition(":")
            k = " ".join(k.split()).lower()
            if k in ("number density", "phase function"):
                block[k], i = body(i)
            else:
                block[k] = v.strip()
        i += 1
        out[m.group(1) + "s"][m.group(2)] = block
    return out


def _glsl_program(scatterers: dict[str, dict[str, str]], wl_set: np.ndarray, index: int) -> str:
    """The scatterers' functions as CalcMySky's shaders.cpp wraps them, with its constants."""
    src = [
        "#version 330",
        "#extension GL_ARB_shading_language_420pack : enable",
        "#ifdef GL_ARB_shading_language_420pack",
        "# define CONST const",
        "#else",
        "# define CONST",
        "#endif",
        "const float PI=3.1415926535897932;",
        "const float km=1000;",
        "#define sqr(x) ((x)*(x))",
        "const vec4 wavelengths=vec4(" + ",".join(f"{w:g}" for w in wl_set) + ");",
        f"const int wlSetIndex={index};",
    ]
    calls = []
    for name, block in scatterers.items():
        src.append(
            f"float scattererNumberDensity_{name}(float altitude)\n{{\n{block['number density']}}}"
        )
        src.append(f"vec4 phaseFunction_{name}(float dotViewSun)\n{{\n{block['phase function']}}}")
        calls.append(f"phaseFunction_{name}(x) * scattererNumberDensity_{name}(x)")
    src += [
        "uniform float x;",
        "out vec4 color;",
        f"void main() {{ color = {' + '.join(calls)}; }}",
    ]
    return "\n".join(src) + "\n"


def test_calcmysky_atmo_parses_by_its_rules(mars) -> None:
    parsed = parse_atmo(calcmysky_atmo(mars))
    assert parsed["version"] == "6"
    wl, same = calcmysky_wavelengths(mars.wavelength_nm)
    assert same and wl.size == 48
    m = re.match(r"min=([0-9.]+)nm,max=([0-9.]+)nm,count=(\d+)", parsed["wavelengths"])
    assert m and (float(m[1]), float(m[2]), int(m[3])) == (360.0, 830.0, 48)
    for key in ("solar irradiance at toa", "ground albedo", "light pollution relative radiance"):
        assert len(parsed[key].split(",")) == 48, key
    for key in ("earth radius", "atmosphere height", "earth-sun distance", "earth-moon distance"):
        assert _QUANTITY.match(parsed[key]), (key, parsed[key])
    aerosols = parsed["scatterers"]["aerosols"]
    assert aerosols["phase function type"] == "general"
    c = _QUANTITY.match(aerosols["cross section at 1 um"])
    assert c and c[2] == "um^2"
    dust = mars.constituent("aerosols").table
    c1, alpha, err = angstrom_fit(dust.wavelength_nm, dust.quantity("cext_um2"))
    assert float(c[1]) == pytest.approx(c1, rel=1e-8) and err < 0.02
    assert float(aerosols["angstrom exponent"]) == pytest.approx(alpha, rel=1e-6)
    ssa = np.array([float(v) for v in aerosols["single scattering albedo"].split(",")])
    np.testing.assert_allclose(ssa, dust.ssa, rtol=1e-6)
    assert parsed["scatterers"]["molecules"]["phase function type"] == "achromatic"


def test_calcmysky_phase_nodes_are_the_tables(mars) -> None:
    parsed = parse_atmo(calcmysky_atmo(mars))
    glsl = parsed["scatterers"]["aerosols"]["phase function"]
    numbers = re.findall(r"vec4\(([^()]*)\)", glsl.split("vec4[")[1])
    values = np.array([[float(x) for x in v.split(",")] for v in numbers])  # (12 * 256, 4)
    n = 256
    per_wl = values.reshape(12, n, 4).transpose(0, 2, 1).reshape(48, n)
    dust = mars.constituent("aerosols").table
    nodes = 180.0 * (np.arange(n) / (n - 1)) ** 2
    np.testing.assert_allclose(per_wl, dust.phase_at(nodes), rtol=1e-6)
    # The block's lookup against the table at its own angles: within the stated difference.
    stated = float(re.search(r"interpolation ([0-9.e-]+)\.", glsl)[1])
    got = calcmysky_phase_lookup(per_wl, dust.theta_deg)
    assert np.max(np.abs(got / dust.phase - 1.0)) <= stated * 1.001
    assert stated < 0.05


@pytest.mark.skipif(GLSLANG is None, reason="glslangValidator not installed")
def test_calcmysky_glsl_blocks_compile(mars, earth, tmp_path) -> None:
    for atmosphere in (mars, earth):
        parsed = parse_atmo(calcmysky_atmo(atmosphere))
        wl, _ = calcmysky_wavelengths(atmosphere.wavelength_nm)
        for index in (0, wl.size // 4 - 1):
            path = tmp_path / f"{atmosphere.name}_{index}.frag"
            path.write_text(
                _glsl_program(parsed["scatterers"], wl[4 * index : 4 * index + 4], index)
            )
            done = subprocess.run([GLSLANG, str(path)], capture_output=True, text=True, timeout=120)
            assert done.returncode == 0, done.stdout + done.stderr
    # The check can fail: a block with an undeclared name is refused.
    parsed["scatterers"]["aerosols"]["phase function"] += "    return vec4(undeclared);\n"
    path = tmp_path / "bad.frag"
    path.write_text(_glsl_program(parsed["scatterers"], wl[:4], 0))
    assert subprocess.run([GLSLANG, str(path)], capture_output=True, timeout=120).returncode != 0


def test_calcmysky_earth_has_its_ozone_absorber(earth) -> None:
    parsed = parse_atmo(calcmysky_atmo(earth))
    wl, same = calcmysky_wavelengths(earth.wavelength_nm)
    assert not same and wl.size == 16  # CosmoScout's 15 wavelengths: resampled to 16
    ozone = parsed["absorbers"]["ozone"]
    assert len(ozone["cross section"].split(",")) == 16
    assert "if(altitude <" in ozone["number density"]
