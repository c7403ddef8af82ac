"""The 3-D lookup of a sweep over effective radius, proven in real GLSL tools.

The GLSL compiles with glslangValidator (Debian glslang-tools) in a
``#version 330 core`` fragment shader and a ``#version 430`` compute shader,
and runs in Mesa's llvmpipe (moderngl, EGL backend, no GPU) reading the
written ``.raw`` file uploaded as the sidecar says; at 3,000+ (radius,
angle) points it equals the bilinear interpolation of the same float32
texels computed here in float64, to float32 rounding.  The dataset has the
layout of :func:`dustoptics.sweep.sweep` with Henyey-Greenstein phase
functions (an analytic input keeps the test fast; the lookup only reads
``phase``).
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
import subprocess

import numpy as np
import pytest

from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.sweep.lookup import lookup_glsl, write_lookup

xr = pytest.importorskip("xarray", reason="needs the 'sweep' extra (xarray)")

AXIS = "size_distribution.r_eff_um"
RADII = np.array([0.5, 1.0, 1.6, 2.5, 4.0])  # unevenly spaced
WAVELENGTHS = np.array([440.0, 550.0, 680.0, 830.0])
THETA = np.linspace(0.0, 180.0, 181)


def sweep_like() -> xr.Dataset:
    mu = np.cos(np.deg2rad(THETA))
    g = 0.45 + 0.08 * RADII[:, None] - 1e-4 * (WAVELENGTHS[None, :] - 550.0)
    phase = henyey_greenstein(mu[None, None, :], g=g[:, :, None])
    err = np.full(g.shape, 3e-5)
    return xr.Dataset(
        {
            "phase": ((AXIS, "wavelength_nm", "theta_deg"), phase),
            "error_estimate": ((AXIS, "wavelength_nm"), err),
        },
        coords={AXIS: RADII, "wavelength_nm": WAVELENGTHS, "theta_deg": THETA},
        attrs={"sweep": "{}", "accuracy": "test"},
    )


@pytest.fixture(scope="module")
def lookup(tmp_path_factory):
    stem = tmp_path_factory.mktemp("lut") / "storm"
    paths = write_lookup(sweep_like(), stem)
    return stem, paths


def test_files_layout_and_sidecar(lookup):
    stem, paths = lookup
    assert [p.suffix for p in paths] == [".raw", ".json", ".glsl"]
    raw = paths[0].read_bytes()
    side = json.loads(paths[1].read_text())
    assert side["sha256"] == hashlib.sha256(raw).hexdigest()
    assert side["shape"] == [3, RADII.size, THETA.size]
    data = np.frombuffer(raw, dtype="<f4").reshape(side["shape"])
    expected = sweep_like().phase.values[:, [2, 1, 0], :].transpose(1, 0, 2)  # 680, 550, 440 nm
    assert np.array_equal(data, expected.astype(np.float32))
    assert side["axes"][1]["values"] == RADII.tolist()
    with pytest.raises(FileExistsError):
        write_lookup(sweep_like(), stem)


def test_bad_inputs_name_what_is_wrong(tmp_path):
    with pytest.raises(ValueError, match=r"channels_nm value 500 nm is not a wavelength"):
        write_lookup(sweep_like(), tmp_path / "x", channels_nm=(680.0, 550.0, 500.0))
    two = sweep_like().expand_dims({"material.hematite_fraction": [0.0, 0.03]})
    with pytest.raises(ValueError, match=r"material\.hematite_fraction: 2"):
        write_lookup(two, tmp_path / "x")
    with pytest.raises(ValueError, match=r"GLSL identifier"):
        lookup_glsl(RADII, 181, name="gl_Phase")


def _compile(source: str, stage: str) -> None:
    exe = shutil.which("glslangValidator")
    if exe is None:
        pytest.skip("glslang-tools (glslangValidator) not installed")
    result = subprocess.run(
        [exe, "--stdin", "-S", stage], input=source, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stdout + result.stderr


FRAGMENT = """
uniform sampler2DArray lut;
in vec2 rt;
out vec4 colour;
void main() { colour = vec4(DustPhase(lut, rt.x, cos(rt.y)), 1.0); }
"""

COMPUTE = """
layout(local_size_x = 64) in;
uniform sampler2DArray lut;
layout(std430, binding = 0) readonly buffer In { vec2 rt[]; };
layout(std430, binding = 1) writeonly buffer Out { vec4 p[]; };
void main() {
    uint k = gl_GlobalInvocationID.x;
    p[k] = vec4(DustPhaseTheta(lut, rt[k].x, rt[k].y), 0.0);
}
"""


def test_glslang_compiles(lookup):
    _, paths = lookup
    source = paths[2].read_text()
    _compile("#version 330 core\n" + source + FRAGMENT, "frag")
    _compile("#version 430\n" + source + COMPUTE, "comp")


def _bilinear(data: np.ndarray, r: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """The snippet's interpolation in float64 (texels as stored, float32)."""
    x = np.clip(r, RADII[0], RADII[-1])
    i_r = np.clip(np.searchsorted(RADII, x, side="right") - 1, 0, RADII.size - 2)
    t = (x - RADII[i_r]) / (RADII[i_r + 1] - RADII[i_r])
    u = np.clip(theta, 0.0, math.pi) * ((THETA.size - 1) / math.pi)
    i = np.minimum(u.astype(int), THETA.size - 2)
    f = u - i
    d = data.astype(np.float64)
    lo = d[:, i_r, i] * (1 - f) + d[:, i_r, i + 1] * f
    hi = d[:, i_r + 1, i] * (1 - f) + d[:, i_r + 1, i + 1] * f
    return (lo * (1 - t) + hi * t).T


def test_runs_in_llvmpipe_and_matches_the_interpolation(lookup):
    moderngl = pytest.importorskip("moderngl", reason="needs moderngl (the 'gl' extra)")
    try:
        ctx = moderngl.create_context(standalone=True, backend="egl", require=430)
    except Exception as exc:
        pytest.skip(
            f"EGL OpenGL 4.3 context failed ({exc}); needs Mesa EGL (libegl1, libegl-mesa0)"
        )
    _, paths = lookup
    side = json.loads(paths[1].read_text())
    raw = paths[0].read_bytes()
    data = np.frombuffer(raw, dtype="<f4").reshape(side["shape"])
    gl = side["gl"]
    texture = ctx.texture_array((gl["width"], gl["height"], gl["layers"]), 1, raw, dtype="f4")
    rng = np.random.default_rng(7)
    r = np.concatenate([rng.uniform(0.3, 4.5, 3000), RADII, RADII + 1e-3, [0.1, 9.0]]).astype(
        np.float32
    )
    theta = np.concatenate(
        [
            rng.uniform(0.0, math.pi, 3000),
            np.zeros(RADII.size),
            np.full(RADII.size, 0.7),
            [0.0, math.pi],
        ]
    ).astype(np.float32)
    n = r.size
    groups = -(-n // 64)
    rt = np.zeros((groups * 64, 2), dtype=np.float32)
    rt[:n, 0], rt[:n, 1] = r, theta
    program = ctx.compute_shader("#version 430\n" + paths[2].read_text() + COMPUTE)
    texture.use(location=0)
    program["lut"] = 0
    inp = ctx.buffer(rt.tobytes())
    out = ctx.buffer(reserve=16 * groups * 64)
    inp.bind_to_storage_buffer(0)
    out.bind_to_storage_buffer(1)
    program.run(group_x=groups)
    got = np.frombuffer(out.read(), dtype=np.float32).reshape(-1, 4)[:n, :3].astype(np.float64)
    for obj in (inp, out, program, texture):
        obj.release()
    ctx.release()
    expected = _bilinear(data, r.astype(np.float64), theta.astype(np.float64))
    # float32 arithmetic: the angle index carries ~1e-7 relative (u <= 180),
    # times the largest relative step between neighbouring samples.
    step = np.max(np.abs(np.diff(data.astype(np.float64), axis=2)) / data[:, :, 1:])
    assert np.max(np.abs(got / expected - 1.0)) <= 1e-6 + 200 * 1.2e-7 * step
    # At the table's radii and theta = 0: the texels themselves, exactly.
    nodes = slice(3000, 3000 + RADII.size)
    assert np.array_equal(got[nodes], data[:, :, 0].T.astype(np.float64))


def test_a_sweep_declaring_more_than_the_memory_budget_is_refused_before_reading(
    tmp_path, monkeypatch
):
    """The phase function (5 x 4 x 181 float64, read and transposed: 2 x 28,960 bytes) and
    its coordinates (190 values: 1,520 bytes) are counted from their declared sizes."""
    import dustoptics._validation as validation

    monkeypatch.setattr(validation, "MEMORY_BUDGET_BYTES", 2 * 28_960 + 1_520 - 1)
    with pytest.raises(
        ValueError,
        match=r"write_lookup declare 59440 bytes, beyond the memory budget of 59439 bytes",
    ):
        write_lookup(sweep_like(), tmp_path / "x")
    monkeypatch.setattr(validation, "MEMORY_BUDGET_BYTES", 2 * 28_960 + 1_520)
    assert len(write_lookup(sweep_like(), tmp_path / "y")) == 3
