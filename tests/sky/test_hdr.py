"""dustoptics.sky.hdr: the sky as a linear OpenEXR environment map, read back by OpenEXR,
rendered by Blender's Cycles and read by three.js's EXRLoader in Chromium."""

from __future__ import annotations

import functools
import http.server
import json
import math
import shutil
import subprocess
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dustoptics import colour
from dustoptics.cli import main
from dustoptics.sky import hdr, scene
from dustoptics.sky.compare import mars_sky_atmosphere
from dustoptics.sky.medium import Medium

OpenEXR = pytest.importorskip("OpenEXR")

HERE = Path(__file__).parent
MARS_SUN_DISTANCE_M = 227.9e9  # the Mars atmosphere's sun_distance_m (dustoptics.atmosphere.sets)


_SKY_RADIANCE = scene.sky_radiance


def _coarse_sky(atmosphere: Any, **kwargs: Any) -> scene.SkyRadiance:
    """A real sky on a coarse grid (5 deg zenith, 10 deg azimuth, tolerance 1e-2): ~7 s."""
    return _SKY_RADIANCE(
        atmosphere,
        tol=1e-2,
        view_zenith_deg=np.linspace(0.0, 90.0, 19),
        azimuth_step_deg=10.0,
        **{
            k: v
            for k, v in kwargs.items()
            if k not in ("tol", "view_zenith_deg", "azimuth_step_deg")
        },
    )


@pytest.fixture(scope="module")
def sky() -> scene.SkyRadiance:
    atm = mars_sky_atmosphere("hybrid", optical_depth=0.5)
    assert atm.sun_distance_m == MARS_SUN_DISTANCE_M
    return _coarse_sky(Medium.from_atmosphere(atm), sun_elevation_deg=30.0)


@pytest.fixture(scope="module")
def env(sky: scene.SkyRadiance) -> hdr.EnvironmentMap:
    return hdr.environment_map(sky, sun_distance_m=MARS_SUN_DISTANCE_M, height=64)


def _read(path: Path) -> tuple[np.ndarray, dict[str, Any]]:
    with OpenEXR.File(str(path)) as f:
        header = dict(f.header())
        pixels = f.channels()["RGB"].pixels
    return pixels, header


def _solid_angles(height: int) -> np.ndarray:
    """Solid angle of each equirectangular pixel, dphi (sin(top) - sin(bottom)). [sr]"""
    top = np.radians(90.0 - 180.0 * np.arange(height) / height)
    bottom = np.radians(90.0 - 180.0 * (np.arange(height) + 1) / height)
    return (np.sin(top) - np.sin(bottom))[:, None] * (2.0 * np.pi / (2 * height))


def _pixel_directions(height: int) -> np.ndarray:
    """Unit directions (height, 2 height, 3) of the pixel centres; x toward the Sun, z up."""
    elevation, longitude = (np.radians(a) for a in hdr.direction_of_pixels(height))
    e, p = np.meshgrid(elevation, longitude, indexing="ij")
    return np.stack([np.cos(e) * np.cos(p), np.cos(e) * np.sin(p), np.sin(e)], axis=-1)


def test_solar_illuminance_is_the_published_constant_and_falls_as_the_inverse_square() -> None:
    # Darula, Kittler & Gueymard 2005 (Solar Energy 79, 559-565): solar illuminance constant
    # 133.8 klx, from the ASTM E490 spectrum; ours integrates ASTM G173 over 360-830 nm.
    at_1au = hdr.solar_illuminance_lux(sun_distance_m=hdr.ASTRONOMICAL_UNIT_M)
    assert at_1au == pytest.approx(133.8e3, rel=0.01)
    mars = hdr.solar_illuminance_lux(sun_distance_m=1.5 * hdr.ASTRONOMICAL_UNIT_M)
    assert mars == pytest.approx(at_1au / 2.25, rel=1e-12)
    with pytest.raises(ValueError, match="sun_distance_m"):
        hdr.solar_illuminance_lux(sun_distance_m=0.0)


def test_the_map_is_the_skys_luminance_in_cd_m2(sky: scene.SkyRadiance, env: Any) -> None:
    e_top = hdr.solar_illuminance_lux(sun_distance_m=MARS_SUN_DISTANCE_M)
    assert env.rgb.shape == (64, 128, 3)
    # The row nearest the zenith (elevation 88.6 deg), column toward the Sun and opposite it:
    # the sky's own XYZ there (its bilinear interpolation), in linear Rec. 709 and cd m-2.
    elevation, longitude = hdr.direction_of_pixels(64)
    for col in (64, 0):
        xyz = sky._interpolate(sky.xyz(), 90.0 - elevation[0], longitude[col])
        np.testing.assert_allclose(
            env.rgb[0, col], colour.xyz_to_linear_srgb(xyz) * e_top, rtol=1e-12
        )
    # Rec. 709 luminance of the pixels is the luminance factor times the illuminance.
    y = env.rgb @ np.array([0.2126, 0.7152, 0.0722])
    y_sky = sky._interpolate(sky.xyz(), 90.0 - elevation[10], longitude)[:, 1] * e_top
    np.testing.assert_allclose(y[10], y_sky, rtol=2e-3)  # sRGB matrix rounded to 4 digits
    # Mirror symmetry about the Sun's vertical plane (columns j and width - 1 - j).
    np.testing.assert_allclose(env.rgb[:32], env.rgb[:32, ::-1], rtol=1e-12)


def test_the_ground_reflects_the_skys_and_the_suns_light(env: Any) -> None:
    # Lambertian ground of albedo 0.2: L = 0.2 / pi (E_sun sin(elevation) + sky on the ground),
    # the sky's horizontal illuminance integrated over the map's upper half (grey albedo, so the
    # luminances add as the spectra do).
    h = env.rgb.shape[0]
    y = env.rgb @ np.array([0.2126, 0.7152, 0.0722])
    up = _pixel_directions(h)[..., 2]
    sky_on_ground = float(np.sum((y * np.clip(up, 0, None) * _solid_angles(h))[: h // 2]))
    sun_on_ground = env.sun_illuminance_lux * math.sin(math.radians(30.0))
    expected = 0.2 / math.pi * (sun_on_ground + sky_on_ground)
    assert env.ground_luminance_cd_m2 == pytest.approx(expected, rel=0.02)
    assert np.allclose(y[h // 2 :], env.ground_luminance_cd_m2, rtol=2e-3)


@pytest.mark.parametrize(("precision", "dtype"), [("half", np.float16), ("float", np.float32)])
def test_exr_holds_the_map_with_its_units_and_primaries(
    env: Any, tmp_path: Path, precision: str, dtype: type
) -> None:
    path = tmp_path / "map.exr"
    data = hdr.exr_bytes(env, precision=precision)
    assert data == hdr.exr_bytes(env, precision=precision)  # deterministic bytes
    path.write_bytes(data)
    pixels, header = _read(path)
    assert pixels.dtype == dtype and pixels.shape == (64, 128, 3)
    np.testing.assert_array_equal(pixels, (env.rgb / 1000.0).astype(dtype))
    assert header["whiteLuminance"] == 1000.0
    np.testing.assert_allclose(
        header["chromaticities"], (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290), rtol=1e-6
    )
    assert header["exposure"] == pytest.approx(env.exposure * 1000.0, rel=1e-6)
    meta = json.loads(header["dustoptics"])
    assert meta["sun_in_map"] is False and meta["sun_elevation_deg"] == pytest.approx(30.0)
    assert meta["units"].startswith("kcd m-2")


def test_exr_refuses_what_it_cannot_hold(env: Any) -> None:
    with pytest.raises(ValueError, match="precision must be one of 'half', 'float'; got 'int'"):
        hdr.exr_bytes(env, precision="int")
    bright = hdr.EnvironmentMap(**{**env.__dict__, "rgb": env.rgb * 1e4})
    with pytest.raises(ValueError, match="beyond the half-float range"):
        hdr.exr_bytes(bright, precision="half")
    assert len(hdr.exr_bytes(bright, precision="float")) > 0


def test_the_cubemap_faces_look_where_opengl_says(env: Any) -> None:
    n = 8
    strip = hdr.cubemap(env, size=n)
    assert strip.shape == (n, 6 * n, 3)
    faces = [strip[:, k * n : (k + 1) * n] for k in range(6)]
    # +Y (up): the zenith rows' mean; -Y (down): the uniform ground.
    np.testing.assert_allclose(faces[3], np.broadcast_to(env.rgb[-1, 0], (n, n, 3)), rtol=1e-12)
    zenith = env.rgb[0].mean(axis=0)
    np.testing.assert_allclose(
        faces[2][n // 2 - 1 : n // 2 + 1, n // 2 - 1 : n // 2 + 1].mean((0, 1)), zenith, rtol=0.05
    )
    # +X looks toward the Sun's azimuth, -X away: the sunward face is the brighter (aureole),
    # its upper half is sky and its lower half ground; +Z and -Z mirror each other.
    assert faces[0][: n // 2].sum() > 1.5 * faces[1][: n // 2].sum()
    np.testing.assert_allclose(faces[0][n // 2 :], np.broadcast_to(env.rgb[-1, 0], (n // 2, n, 3)))
    np.testing.assert_allclose(faces[4], faces[5][:, ::-1], rtol=1e-9)


def test_sky_cli_writes_the_environment_maps(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("xarray")
    monkeypatch.setattr(scene, "sky_radiance", _coarse_sky)
    out = tmp_path / "sky"
    argv = ["sky", "mars", "--sun-elevation", "30", "--no-png", "--out", str(out), "--quiet"]
    assert main([*argv, "--exr", "half", "--exr-height", "32", "--cubemap"]) == 0
    names = sorted(p.name for p in (out / "mars-hybrid").iterdir())
    assert names == [
        "mars-hybrid_environment.exr",
        "mars-hybrid_environment_cube.exr",
        "mars-hybrid_sky.nc",
    ]
    pixels, _ = _read(out / "mars-hybrid" / "mars-hybrid_environment.exr")
    assert pixels.shape == (32, 64, 3) and pixels.dtype == np.float16
    cube, _ = _read(out / "mars-hybrid" / "mars-hybrid_environment_cube.exr")
    assert cube.shape == (16, 96, 3)
    assert main([*argv, "--cubemap"]) == 2  # usage: a cube map of no map


# ---- Blender (Cycles) lights a white sphere with the map ------------------------------------


def _sphere_prediction(env_pixels: np.ndarray, size: int, toward_sun: float) -> tuple[Any, Any]:
    """Radiance E(n) / pi of a white Lambertian sphere seen by the script's camera.

    E(n) = sum over the map's pixels of L cos+(n . omega) dOmega; the camera looks along +Y,
    image right +X, up +Z; the map's centre column looks toward +X * ``toward_sun``.
    """
    h = env_pixels.shape[0]
    omega = _pixel_directions(h) * np.array([toward_sun, 1.0, 1.0])
    c = -1.0 + 2.0 * (np.arange(size) + 0.5) / size
    x, z = np.meshgrid(c, -c)
    inside = x**2 + z**2 < 0.9**2  # away from the antialiased rim
    normals = np.stack([x, -np.sqrt(np.clip(1 - x**2 - z**2, 0, 1)), z], axis=-1)[inside]
    cosine = np.clip(np.einsum("pk,hwk->phw", normals, omega), 0.0, None)
    weights = cosine * _solid_angles(h)
    return np.einsum("phw,hwc->pc", weights, env_pixels.astype(float)) / np.pi, inside


@pytest.mark.skipif(shutil.which("blender") is None, reason="needs Blender (Debian's blender)")
def test_blender_lights_a_white_sphere_with_the_irradiance_of_the_map(
    env: Any, tmp_path: Path
) -> None:
    path = tmp_path / "map.exr"
    path.write_bytes(hdr.exr_bytes(env, precision="float"))
    size, samples = 48, 256
    subprocess.run(
        [
            "blender",
            "-b",
            "--factory-startup",
            "--python",
            str(HERE / "blender_sphere.py"),
            "--",
            str(path),
            str(tmp_path / "render.exr"),
            str(size),
            str(samples),
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    render = _read(tmp_path / "render.exr")[0].astype(float)
    pixels, _ = _read(path)
    predicted, inside = _sphere_prediction(pixels, size, toward_sun=1.0)
    got = render[inside]
    relative = got / predicted - 1.0
    print(
        "blender: disc mean render / prediction - 1 (R, G, B):",
        got.mean(axis=0) / predicted.mean(axis=0) - 1.0,
        f"median |pixel error| {np.median(np.abs(relative)):.4f}, "
        f"95th percentile {np.percentile(np.abs(relative), 95):.4f}",
    )
    # Measured (Blender 3.4.1, 256 samples): disc means within 0.03 %, pixels' median 0.4 %.
    np.testing.assert_allclose(got.mean(axis=0), predicted.mean(axis=0), rtol=0.005)
    assert float(np.median(np.abs(relative))) < 0.02
    # The test can tell a wrong mapping: the Sun's side turned to -X is far off.
    mirrored, _ = _sphere_prediction(pixels, size, toward_sun=-1.0)
    assert float(np.median(np.abs(got / mirrored - 1.0))) > 0.1


# ---- three.js's EXRLoader in headless Chromium ------------------------------------------------

READER = HERE / "exr_reader"
_CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.skipif(_CHROMIUM is None, reason="needs Chromium (headless)")
@pytest.mark.skipif(
    not (READER / "node_modules" / "three").is_dir(),
    reason="needs npm three: npm ci --prefix tests/sky/exr_reader",
)
@pytest.mark.parametrize("precision", ["half", "float"])
def test_threejs_exrloader_reads_the_map_in_chromium(
    sky: scene.SkyRadiance, tmp_path: Path, precision: str
) -> None:
    small = hdr.environment_map(sky, sun_distance_m=MARS_SUN_DISTANCE_M, height=16)
    served = tmp_path / "site"
    shutil.copytree(READER, served, symlinks=True)
    (served / "map.exr").write_bytes(hdr.exr_bytes(small, precision=precision))
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(served))
    handler.log_message = lambda *a: None  # type: ignore[attr-defined]
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        url = f"http://127.0.0.1:{server.server_address[1]}/read.html?file=map.exr"
        dom = subprocess.run(
            [
                str(_CHROMIUM),
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--virtual-time-budget=20000",
                "--dump-dom",
                url,
            ],
            check=True,
            capture_output=True,
            text=True,
            timeout=120,
        ).stdout
    finally:
        server.shutdown()
        server.server_close()
    text = dom.split('<pre id="out">', 1)[1].split("</pre>", 1)[0]
    result = json.loads(text)
    assert "error" not in result, result
    assert (result["width"], result["height"]) == (32, 16)
    assert result["format"] == "RGBA" and result["type"] == "float"
    assert result["colorSpace"] == "srgb-linear"
    rgba = np.asarray(result["data"], dtype=np.float32).reshape(16, 32, 4)
    pixels, _ = _read(served / "map.exr")
    # EXRLoader puts the bottom row first (WebGL's texture origin); alpha is 1.
    np.testing.assert_array_equal(rgba[::-1, :, :3], pixels.astype(np.float32))
    assert np.all(rgba[..., 3] == 1.0)
