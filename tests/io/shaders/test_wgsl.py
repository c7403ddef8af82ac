"""WGSL snippet: validated and run by wgpu.

It runs as a compute shader on Mesa's lavapipe Vulkan driver through wgpu (no GPU), and
every value equals numpy's float32 evaluation of the same operations and the float64
table's interpolation (Table.phase_at) within float32 rounding.
"""

from __future__ import annotations

import numpy as np
import pytest
from _render import assert_matches_float32, assert_matches_table, run_compute, test_nu, wgpu_device
from _shader_tables import OTHER_TABLE, RUN_RESOLUTION_DEG, TABLE, exact

from dustoptics.io.shaders.common import shader_channels, shader_source
from dustoptics.io.shaders.wgsl import WGSLSyntax

WGSL_MAIN = """
@group(0) @binding(0) var<storage, read> nu_in: array<f32>;
@group(0) @binding(1) var<storage, read_write> phase_out: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    phase_out[id.x] = vec4<f32>(MiePhaseFunction(nu_in[id.x]), 0.0);
}
"""


@pytest.fixture(scope="module")
def device():
    """A WebGPU device on Mesa's lavapipe Vulkan driver (skips, or fails in CI, without it)."""
    return wgpu_device()


def test_default_resolution_validates(device) -> None:
    src = shader_source(TABLE, language="wgsl")
    assert "721" in src and f"// requires: {WGSLSyntax.requirements}" in src
    device.create_shader_module(code=src + WGSL_MAIN)  # wgpu's WGSL front end validates it


def test_lookup_runs_on_lavapipe(device) -> None:
    src = shader_source(TABLE, language="wgsl", resolution_deg=RUN_RESOLUTION_DEG)
    nu = test_nu(181)
    got = run_compute(device, src + WGSL_MAIN, nu)[:, :3]
    table32 = shader_channels(TABLE, resolution_deg=RUN_RESOLUTION_DEG).phase
    ulps = assert_matches_float32(got, table32, nu)
    rel = assert_matches_table(got, exact(TABLE, nu), table32, nu)
    print(
        f"wgsl on lavapipe: {ulps:.1f} ulps from numpy float32, {rel:.2e} relative from the table"
    )


def test_constants_are_the_float32_values(device) -> None:
    """Every sample, g and the number density read back bit for bit (the input, zeros, only
    keeps the binding that the shared runner expects)."""
    src = shader_source(TABLE, language="wgsl", resolution_deg=RUN_RESOLUTION_DEG)
    code = src + WGSL_MAIN.replace(
        "vec4<f32>(MiePhaseFunction(nu_in[id.x]), 0.0)",
        "select(vec4<f32>(MIE_G, MIE_NUMBER_DENSITY_PER_M3 + nu_in[id.x]), "
        "vec4<f32>(MIE_PHASE[min(id.x, 180u)], nu_in[id.x]), id.x < 181u)",
    )
    got = run_compute(device, code, np.zeros(182, dtype=np.float32))
    ch = shader_channels(TABLE, resolution_deg=RUN_RESOLUTION_DEG)
    np.testing.assert_array_equal(got[:181, :3], ch.phase)
    np.testing.assert_array_equal(got[181, :3], ch.g.astype(np.float32))
    assert got[181, 3] == np.float32(1e6)


def test_prefix_lets_two_snippets_share_a_shader(device) -> None:
    a = shader_source(TABLE, language="wgsl", resolution_deg=RUN_RESOLUTION_DEG)
    b = shader_source(
        OTHER_TABLE,
        language="wgsl",
        prefix="DUST",
        function_name="DustPhase",
        resolution_deg=RUN_RESOLUTION_DEG,
    )
    assert "MIE_" not in b and "MiePhaseFunction" not in b
    main = WGSL_MAIN.replace(
        "MiePhaseFunction(nu_in[id.x])", "MiePhaseFunction(nu_in[id.x]) + DustPhase(nu_in[id.x])"
    )
    nu = np.array([1.0, 0.5, -1.0], dtype=np.float32)
    got = run_compute(device, a + b + main, nu)
    np.testing.assert_allclose(got[:, :3], exact(TABLE, nu) + exact(OTHER_TABLE, nu), rtol=1e-5)
