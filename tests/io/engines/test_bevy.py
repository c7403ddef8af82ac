"""Bevy: the chromatic phase texture in Bevy's column order, its terms, its Rust snippet."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from dustoptics.atmosphere import sets as atm
from dustoptics.io.engines.bevy import (
    bevy_falloff,
    bevy_lut_phase,
    bevy_medium,
    bevy_phase_texture,
    bevy_rust,
    bevy_texture_phase,
    read_bevy_texture_ktx2,
    write_bevy,
)
from dustoptics.io.tables.netcdf import read_hdf5

TABLES = Path(__file__).resolve().parents[3] / "tables"
RUSTC = shutil.which("rustc")
# A checkout of github.com/bevyengine/bevy, if the environment names one: its own Mars
# texture (assets/textures/mars_mie_phase.ktx2, PR #22884) is then read too.
BEVY_REPO = os.environ.get("DUSTOPTICS_BEVY_REPO")


@pytest.fixture(scope="module")
def dust():
    return read_hdf5(TABLES / "blue-moons" / "blue-moons.nc")


@pytest.fixture(scope="module")
def mars(dust):
    return atm.mars_atmosphere(dust_table=dust, optical_depth=0.5)


def _trapezoid_sphere(columns: np.ndarray) -> np.ndarray:
    mu = np.linspace(-1.0, 1.0, columns.shape[0])
    return 2.0 * math.pi * np.sum(0.5 * (columns[1:] + columns[:-1]) * np.diff(mu)[:, None], axis=0)


def test_first_column_is_backscattering_and_last_forward(dust) -> None:
    texture = bevy_phase_texture(dust, n_columns=1024)
    cols = texture.pixels[0].astype(np.float64)  # (1024, 3): R, G, B = 680, 550, 440 nm
    factor = np.asarray(texture.metadata["bevy_renormalization"]["sphere_integral_before"])
    wl = list(dust.wavelength_nm)
    # The channels are table wavelengths here, so each is one row of the table, read at
    # theta = 180 deg (mu = -1, column 0) and 0 deg (mu = 1, the last column).
    for c, w in enumerate((680.0, 550.0, 440.0)):
        row = wl.index(w)
        back, forward = dust.phase_at([180.0, 0.0])[row]
        np.testing.assert_allclose(cols[0, c] * factor[c], back, rtol=2e-7)
        np.testing.assert_allclose(cols[-1, c] * factor[c], forward, rtol=2e-7)
    assert np.all(cols[-1] > 100.0 * cols[0])  # forward-peaked dust
    # Column j is at mu_j = -1 + 2 j / (N - 1): the middle of an odd-width texture is 90 deg.
    odd = bevy_phase_texture(dust, n_columns=5).pixels[0].astype(np.float64)
    f5 = np.asarray(
        bevy_phase_texture(dust, n_columns=5).metadata["bevy_renormalization"][
            "sphere_integral_before"
        ]
    )
    np.testing.assert_allclose(
        odd[2, 1] * f5[1], dust.phase_at([90.0])[wl.index(550.0)][0], rtol=2e-7
    )


def test_bevy_reading_of_the_texture_integrates_to_one(dust) -> None:
    texture = bevy_phase_texture(dust, n_columns=1024)
    cols = texture.pixels[0].astype(np.float64)
    # Bevy's curve is linear in mu between columns: the trapezoid rule is its exact integral.
    np.testing.assert_allclose(_trapezoid_sphere(cols), 1.0, rtol=1e-6)
    np.testing.assert_allclose(texture.metadata["sphere_integral_of_samples"], 1.0, rtol=1e-6)
    # The same, integrating bevy_texture_phase finely (independent of the trapezoid sum).
    mu = np.linspace(-1.0, 1.0, 200001)
    p = bevy_texture_phase(cols, mu)
    integral = 2.0 * math.pi * np.trapezoid(p, mu, axis=0)
    np.testing.assert_allclose(integral, 1.0, rtol=1e-6)


def test_ktx2_and_exr_hold_the_same_rgba32f_columns(mars, tmp_path) -> None:
    openexr = pytest.importorskip("OpenEXR")
    files = write_bevy(mars, tmp_path)
    assert sorted(p.name for p in files) == [
        "mars_bevy.json",
        "mars_bevy_medium.rs",
        "mars_bevy_phase.exr",
        "mars_bevy_phase.ktx2",
    ]
    raw = (tmp_path / "mars_bevy_phase.ktx2").read_bytes()
    vk_format, type_size, width, height = np.frombuffer(raw[12:28], dtype="<u4")
    # Bevy's extract_chromatic_phase_textures takes TextureFormat::Rgba32Float only, which
    # its KTX2 loader makes of VK_FORMAT_R32G32B32A32_SFLOAT (109); N x 1.
    assert (int(vk_format), int(type_size), int(width), int(height)) == (109, 4, 1024, 1)
    ktx = read_bevy_texture_ktx2(tmp_path / "mars_bevy_phase.ktx2")
    assert ktx.shape == (1024, 4) and np.all(ktx[:, 3] == 1.0)
    with openexr.File(str(tmp_path / "mars_bevy_phase.exr")) as image:
        channels = image.channels()
        # The binding groups R, G, B into one "RGB" channel of shape (height, width, 3).
        exr = np.array(channels["RGB"].pixels)[0]
    np.testing.assert_array_equal(exr, ktx[:, :3])
    texture = bevy_phase_texture(mars.constituent("aerosols").table)
    np.testing.assert_array_equal(ktx[:, :3], texture.pixels[0])


def test_the_lut_mapping_is_bevys(dust) -> None:
    # medium.rs: row j at mu_j = sign(s) (1 - (1 - |s|)^2), s = 2 (j + 0.5) / R - 1;
    # functions.wesl reads v = 0.5 + 0.5 sign(mu) (1 - (1 - |mu|)^0.5): the inverse, so at
    # mu_j the LUT gives back the curve's value exactly.
    cols = bevy_phase_texture(dust).pixels[0].astype(np.float64)
    r = 256
    s = 2.0 * (np.arange(r) + 0.5) / r - 1.0
    mu_rows = np.sign(s) * (1.0 - (1.0 - np.abs(s)) ** 2)
    np.testing.assert_allclose(
        bevy_lut_phase(cols, mu_rows), bevy_texture_phase(cols, mu_rows), rtol=1e-12
    )
    # Between rows a smooth function (Rayleigh) is read within the linear-interpolation error.
    mu = np.linspace(-1.0, 1.0, 1001)
    rayleigh = np.repeat((3.0 / (16.0 * math.pi) * (1.0 + mu**2))[:, None], 3, axis=1)
    grid = np.linspace(-1.0, 1.0, 1024)
    ray_cols = np.repeat((3.0 / (16.0 * math.pi) * (1.0 + grid**2))[:, None], 3, axis=1)
    assert np.max(np.abs(bevy_lut_phase(ray_cols, mu) / rayleigh - 1.0)) < 1e-3


def test_exponential_falloff_is_the_scale_height_shifted_to_zero_at_the_top() -> None:
    height, h = 120000.0, 11100.0
    alt = np.linspace(0.0, height, 1201)
    f = bevy_falloff(1.0 - alt / height, kind="exponential", scale=h / height)
    # (exp(-z/H) - exp(-top/H)) / (1 - exp(-top/H)), so within exp(-top/H) of exp(-z/H).
    np.testing.assert_allclose(f, np.exp(-alt / h), rtol=0.0, atol=2.0 * math.exp(-height / h))
    assert f[0] == pytest.approx(1.0, abs=1e-15) and abs(f[-1]) < 1e-15
    tent = bevy_falloff(np.array([0.75, 0.6, 0.9, 0.5]), kind="tent", center=0.75, width=0.3)
    np.testing.assert_allclose(tent, [1.0, 0.0, 0.0, 0.0], atol=1e-12)


def test_terms_are_the_sets_coefficients_in_m(mars) -> None:
    medium = bevy_medium(mars)
    molecules, aerosols = medium.terms
    dust = mars.constituent("aerosols").table
    wl = list(dust.wavelength_nm)
    n0 = dust.cross_sections.number_density_per_m3
    idx = [wl.index(w) for w in (680.0, 550.0, 440.0)]
    csca = np.asarray(dust.quantity("csca_um2"))[idx]
    cabs = np.asarray(dust.quantity("cext_um2"))[idx] - csca
    np.testing.assert_allclose(aerosols.scattering_per_m, n0 * csca * 1e-12, rtol=1e-12)
    np.testing.assert_allclose(aerosols.absorption_per_m, n0 * cabs * 1e-12, rtol=1e-9)
    assert aerosols.falloff == "exponential" and aerosols.phase == "texture"
    assert aerosols.falloff_values[0] == pytest.approx(11100.0 / 120000.0)
    assert molecules.phase == "rayleigh" and molecules.absorption_per_m == (0.0, 0.0, 0.0)
    assert medium.inner_radius_m == mars.planet_radius_m
    document = medium.to_dict()
    assert document["source_read"].startswith("bevyengine/bevy 0.20.0-dev, commit 4805ca79")
    json.dumps(document, allow_nan=False)


def test_earth_ozone_is_a_tent(tmp_path) -> None:
    earth = atm.earth_atmosphere()
    medium = bevy_medium(earth)
    ozone = next(t for t in medium.terms if t.name == "ozone")
    top = earth.atmosphere_radius_m - earth.planet_radius_m
    profile = next(c.profile for c in earth.constituents if c.role == "ozone")
    p = np.linspace(0.0, 1.0, 401)
    want = profile.relative_density((1.0 - p) * top)
    np.testing.assert_allclose(ozone.falloff_at(p), want, atol=1e-12)
    assert ozone.falloff == "tent" and ozone.phase == "isotropic"


# Stand-ins of the Bevy items the snippet uses, with the fields and signatures read at
# bevyengine/bevy 4805ca79 (crates/bevy_light/src/atmosphere.rs, bevy_math's curve).
_STANDINS = """
#![allow(dead_code, unused_imports, unused_variables)]
pub mod bevy {
    pub mod prelude {
        #[derive(Clone, Copy)] pub struct Vec3(pub f32, pub f32, pub f32);
        impl Vec3 { pub fn new(x: f32, y: f32, z: f32) -> Self { Vec3(x, y, z) }
                    pub fn splat(v: f32) -> Self { Vec3(v, v, v) } }
        pub struct Image;
        pub struct Handle<T>(core::marker::PhantomData<T>);
        impl<T> Clone for Handle<T> { fn clone(&self) -> Self { Handle(core::marker::PhantomData) } }
        pub struct AssetServer;
        impl AssetServer { pub fn load<T>(&self, path: &'static str) -> Handle<T> {
            Handle(core::marker::PhantomData) } }
    }
    pub mod math { pub mod curve {
        pub struct Interval(f32, f32);
        impl Interval { pub const UNIT: Interval = Interval(0.0, 1.0); }
        pub struct SampleAutoCurve(Vec<f32>);
        impl SampleAutoCurve {
            pub fn new(domain: Interval, samples: impl IntoIterator<Item = f32>)
                -> Result<Self, ()> { Ok(SampleAutoCurve(samples.into_iter().collect())) } }
    } }
    pub mod light {
        use super::prelude::*;
        pub struct Atmosphere { pub inner_radius: f32, pub outer_radius: f32,
            pub ground_albedo: Vec3, pub medium: Handle<atmosphere::ScatteringMedium> }
        pub mod atmosphere {
            use super::super::prelude::*;
            use super::super::math::curve::SampleAutoCurve;
            pub enum Falloff { Linear, Exponential { scale: f32 },
                Tent { center: f32, width: f32 }, Curve(SampleAutoCurve) }
            impl Falloff { pub fn from_curve(curve: SampleAutoCurve) -> Self { Falloff::Curve(curve) } }
            pub enum PhaseFunction { Isotropic, Rayleigh, Mie { asymmetry: f32 },
                ChromaticTexture(Handle<Image>) }
            impl PhaseFunction { pub fn from_chromatic_texture(image: Handle<Image>) -> Self {
                PhaseFunction::ChromaticTexture(image) } }
            pub struct ScatteringTerm { pub absorption: Vec3, pub scattering: Vec3,
                pub falloff: Falloff, pub phase: PhaseFunction }
            pub struct ScatteringMedium { pub label: Option<String>, pub falloff_resolution: u32,
                pub phase_resolution: u32, pub terms: Vec<ScatteringTerm> }
            impl ScatteringMedium {
                pub fn new(falloff_resolution: u32, phase_resolution: u32,
                    terms: impl IntoIterator<Item = ScatteringTerm>) -> Self {
                    ScatteringMedium { label: None, falloff_resolution, phase_resolution,
                        terms: terms.into_iter().collect() } }
                pub fn with_label(self, label: &'static str) -> Self {
                    ScatteringMedium { label: Some(label.to_string()), ..self } }
            }
        }
    }
}
"""


@pytest.mark.skipif(RUSTC is None, reason="rustc not installed (the Rust snippet's type check)")
def test_rust_snippet_type_checks_against_bevys_items(mars, tmp_path) -> None:
    earth = atm.earth_atmosphere()
    for atmosphere in (mars, earth):
        source = _STANDINS + bevy_rust(bevy_medium(atmosphere))
        path = tmp_path / f"{atmosphere.name}.rs"
        path.write_text(source, encoding="utf-8")
        done = subprocess.run(
            [
                RUSTC,
                "--edition",
                "2021",
                "--crate-type",
                "lib",
                "--emit",
                "metadata",
                "-o",
                str(tmp_path / f"lib{atmosphere.name}.rmeta"),
                str(path),
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 0, done.stderr
    # The check can fail: a term with a field Bevy does not have is refused.
    bad = _STANDINS + bevy_rust(bevy_medium(mars)).replace("falloff:", "fallof:", 1)
    (tmp_path / "bad.rs").write_text(bad, encoding="utf-8")
    done = subprocess.run(
        [
            RUSTC,
            "--edition",
            "2021",
            "--crate-type",
            "lib",
            "--emit",
            "metadata",
            "-o",
            str(tmp_path / "libbad.rmeta"),
            str(tmp_path / "bad.rs"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode != 0


@pytest.mark.skipif(BEVY_REPO is None, reason="DUSTOPTICS_BEVY_REPO (a bevy checkout) not set")
def test_bevys_own_mars_texture_reads_like_ours() -> None:
    path = Path(BEVY_REPO) / "assets" / "textures" / "mars_mie_phase.ktx2"
    cols = read_bevy_texture_ktx2(path)
    assert cols.shape == (1024, 4)
    # Its first column is backscattering too: the forward end is far larger.
    assert np.all(cols[-1, :3] > 10.0 * cols[0, :3])
