"""The engines' files, read back by readers of their formats, and the fit on a known sky."""

from __future__ import annotations

import ast
import json
import math
import shutil
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from dustoptics.sky.engines import ENGINES, godot, threejs, unity, unreal
from dustoptics.sky.engines.core import (
    DOME_AZIMUTH_DEG,
    EngineFit,
    ReferenceSky,
    dome_zenith_deg,
    engine_xyz,
    fit_engine,
    sky_error,
    sunlight_linear_srgb,
)

HERE = Path(__file__).parent


def _fit(engine: str, params: dict[str, float]) -> EngineFit:
    return EngineFit(engine=engine, atmosphere="mars-test", kind="fitted", params=params, errors=())


def _sky_of(engine_name: str, params: dict[str, float], elevation: float) -> ReferenceSky:
    """A reference sky that *is* the engine's sky (an identity for the fit)."""
    zen = dome_zenith_deg(elevation)
    zz, aa = np.meshgrid(zen, np.array(DOME_AZIMUTH_DEG), indexing="ij")
    engine = ENGINES[engine_name]
    probe = ReferenceSky(
        "x",
        elevation,
        zz,
        aa,
        np.zeros(zz.shape + (3,)),
        np.ones(zz.shape),
        np.ones(3),
        (0, 0),
        (0, 0),
    )
    xyz = engine_xyz(engine, params, probe)
    weight = np.sin(np.radians(np.maximum(zz, 1.0)))
    near = (int(np.flatnonzero(zen == 80.0 - elevation)[0]), 0)
    white = np.array([0.95, 1.0, 1.09]) * float(xyz[..., 1].max())
    return ReferenceSky("x", elevation, zz, aa, xyz, weight / weight.sum(), white, (0, 0), near)


def test_threejs_fit_recovers_the_parameters_of_its_own_sky():
    truth = {
        **threejs.EXAMPLE_UNIFORMS,
        "rayleigh": 0.4,
        "mieCoefficient": 0.03,
        "mieDirectionalG": 0.6,
        "exposure": 0.01,
    }
    skies = [_sky_of("threejs", truth, e) for e in (45.0, 10.0)]
    start = {**threejs.EXAMPLE_UNIFORMS, "exposure": 0.003}
    planet = types.SimpleNamespace(name="x", planet_radius_m=1.0, atmosphere_radius_m=2.0)
    fit = fit_engine(threejs.THREEJS, planet, skies, start=start)  # type: ignore[arg-type]
    # An identity: the engine's own sky is reached (Delta E well under one just-noticeable 1).
    assert max(e.delta_e_mean for e in fit.errors) < 0.05
    for key in ("rayleigh", "mieCoefficient", "mieDirectionalG", "exposure"):
        assert fit.params[key] == pytest.approx(truth[key], rel=0.02), key
    # The community row adjusts the exposure only.
    community = fit_engine(threejs.THREEJS, planet, skies, kind="community", start=start)  # type: ignore[arg-type]
    assert {k for k in start if community.params[k] != start[k]} == {"exposure"}


def test_sky_error_of_the_sky_itself_is_zero():
    sky = _sky_of("godot", dict(godot.DEFAULTS), 30.0)
    err = sky_error(sky, sky.xyz)
    assert err.delta_e_mean == 0.0 and err.delta_e_p95 == 0.0 and err.luminance_ratio == 1.0
    assert err.xy_zenith_exact == err.xy_zenith_engine


def test_hillaire_single_scattering_limit_matches_the_closed_form():
    # A thin Rayleigh layer seen at the zenith with the Sun overhead: L = P_R(1) tau (to
    # first order in tau, no multiple scattering: MultiScatteringFactor 0).
    params = {
        **unreal.EARTH_DEFAULTS,
        "mie_scattering_r": 1e-12,
        "mie_scattering_g": 1e-12,
        "mie_scattering_b": 1e-12,
        "mie_absorption_r": 1e-12,
        "mie_absorption_g": 1e-12,
        "mie_absorption_b": 1e-12,
        "other_absorption_r": 0.0,
        "other_absorption_g": 0.0,
        "other_absorption_b": 0.0,
        "ground_albedo": 0.0,
    }
    setup = unreal.unreal_setup(params)
    setup = type(setup)(**{**setup.__dict__, "multiple_scattering_factor": 0.0})
    from dustoptics.sky.engines import _hillaire

    rgb = _hillaire.sky_radiance_rgb(
        setup,
        sun_elevation_deg=90.0,
        view_zenith_deg=np.array([0.0]),
        view_azimuth_deg=np.array([0.0]),
        view_samples=2000,
    )
    tau = (
        setup.rayleigh_scattering_per_km * setup.rayleigh_scale_height_km * (1 - math.exp(-60 / 8))
    )
    expected = (
        3 / (8 * math.pi) * tau * np.exp(-tau)
    )  # P_R(0 deg) = 3/(8 pi); direct beam attenuated once
    np.testing.assert_allclose(rgb[0], expected, rtol=0.005)


def test_godot_tres_is_read_by_a_godot_resource_parser(tmp_path):
    godot_parser = pytest.importorskip(
        "godot_parser", reason="the Godot resource reader (PyPI godot-parser)"
    )
    params = {
        **godot.DEFAULTS,
        "rayleigh_color_r": 0.5,
        "mie_eccentricity": 0.63,
        "energy_multiplier": 0.02,
    }
    (path,) = godot.write_godot(_fit("godot", params), tmp_path)
    resource = godot_parser.load(str(path))
    assert 'type="PhysicalSkyMaterial"' in str(resource.get_sections()[0])
    values = resource.find_section("resource")
    assert values["mie_eccentricity"] == pytest.approx(0.63)
    assert values["energy_multiplier"] == pytest.approx(0.02)
    assert "Godot 4.0-4.4" in values["metadata/comment"]
    # Stored sRGB-encoded (source_color); Godot decodes it back to the linear 0.5.
    assert float(godot.srgb_decode(values["rayleigh_color"].r)) == pytest.approx(0.5, rel=1e-5)


def test_unity_asset_is_read_by_a_unity_yaml_parser(tmp_path):
    unityparser = pytest.importorskip(
        "unityparser", reason="the Unity YAML reader (PyPI unityparser)"
    )
    params = {**unity.EARTH_DEFAULTS, "aerosol_tint_r": 0.8, "aerosol_anisotropy": 0.7}
    paths = unity.write_unity(_fit("unity", params), tmp_path)
    asset = next(p for p in paths if p.suffix == ".asset")
    doc = unityparser.UnityDocument.load_yaml(str(asset))
    profile, sky = doc.entries
    assert profile.m_Script["guid"] == unity.VOLUME_PROFILE_GUID
    assert sky.m_Script["guid"] == unity.PBS_SCRIPT_GUID
    assert float(sky.aerosolAnisotropy["m_Value"]) == pytest.approx(0.7)
    assert float(sky.aerosolTint["m_Value"]["r"]) == pytest.approx(0.8)
    # The zenith opacity gives back the extinction (PhysicallyBasedSky.cs, both directions).
    h = float(sky.airMaximumAltitude["m_Value"]) * unity.LAYER_DEPTH_TO_SCALE_HEIGHT
    ext = -math.log(1.0 - float(sky.airDensityB["m_Value"])) / h
    assert ext == pytest.approx(unity.EARTH_DEFAULTS["air_extinction_b"], rel=1e-9)
    data = json.loads(next(p for p in paths if p.suffix == ".json").read_text())
    assert data["override"]["aerosolAnisotropy"] == pytest.approx(0.7)


def test_unreal_script_sets_the_component_properties(tmp_path):
    params = dict(unreal.EARTH_DEFAULTS)
    paths = unreal.write_unreal(_fit("unreal", params), tmp_path)
    script = next(p for p in paths if p.suffix == ".py").read_text()
    ast.parse(script)
    calls: dict[str, object] = {}

    class Component:
        def set_editor_property(self, name, value):
            calls[name] = value

    class Actor:
        def get_components_by_class(self, cls):
            return [Component()]

    stub = types.SimpleNamespace(
        SkyAtmosphereComponent=object,
        EditorLevelLibrary=types.SimpleNamespace(get_selected_level_actors=lambda: [Actor()]),
        LinearColor=lambda r, g, b, a: (r, g, b, a),
        Color=lambda r, g, b, a: (r, g, b, a),
        TentDistribution=lambda **kw: kw,
    )
    sys.modules["unreal"] = stub  # type: ignore[assignment]
    try:
        exec(compile(script, "unreal_script", "exec"), {})
    finally:
        del sys.modules["unreal"]
    assert calls["rayleigh_scattering_scale"] == pytest.approx(0.0331)
    np.testing.assert_allclose(
        calls["rayleigh_scattering"][:3], [0.175287, 0.409607, 1.0], rtol=1e-12
    )
    assert calls["mie_anisotropy"] == 0.8 and calls["bottom_radius"] == 6360.0
    assert calls["other_tent_distribution"] == {
        "tip_altitude": 25.0,
        "tip_value": 1.0,
        "width": 15.0,
    }


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed")
def test_threejs_module_exports_the_uniforms(tmp_path):
    params = {**threejs.EXAMPLE_UNIFORMS, "exposure": 0.004}
    paths = threejs.write_threejs(_fit("threejs", params), tmp_path)
    module = next(p for p in paths if p.suffix == ".mjs")
    out = subprocess.run(
        [
            "node",
            "--input-type=module",
            "-e",
            f"import * as m from {json.dumps(module.as_uri())}; console.log(JSON.stringify([m.skyUniforms, m.toneMappingExposure]))",
        ],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )
    uniforms, exposure = json.loads(out.stdout)
    assert uniforms["mieDirectionalG"] == 0.7 and uniforms["cloudCoverage"] == 0.0
    assert exposure == 0.004


def test_sunlight_is_a_white_of_unit_luminance():
    rgb = sunlight_linear_srgb()
    # Y of linear sRGB (IEC 61966-2-1 row 2 of the inverse matrix) is 1 by construction.
    assert 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2] == pytest.approx(1.0, abs=2e-3)
    assert np.all(rgb > 0.8) and np.all(rgb < 1.2)
