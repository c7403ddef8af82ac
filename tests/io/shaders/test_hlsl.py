"""HLSL snippet: compiled by glslangValidator's HLSL front end to SPIR-V, then run.

The SPIR-V runs as a compute shader on Mesa's lavapipe Vulkan driver through wgpu
(no GPU), and every value equals numpy's float32 evaluation of the same operations and
the float64 table's interpolation (Table.phase_at) within float32 rounding.
"""

from __future__ import annotations

import numpy as np
import pytest
from _render import (
    assert_matches_float32,
    assert_matches_table,
    glslang,
    run_compute,
    test_nu,
    wgpu_device,
)
from _shader_tables import OTHER_TABLE, RUN_RESOLUTION_DEG, TABLE, exact

from dustoptics.io.shaders.common import shader_channels, shader_source
from dustoptics.io.shaders.hlsl import HLSLSyntax

HLSL_MAIN = """
StructuredBuffer<float> NuIn : register(t0);
RWStructuredBuffer<float4> PhaseOut : register(u1);
[numthreads(64, 1, 1)]
void main(uint3 id : SV_DispatchThreadID) { PhaseOut[id.x] = float4(MiePhaseFunction(NuIn[id.x]), 0.0f); }
"""


@pytest.fixture(scope="module")
def device():
    """A WebGPU device on Mesa's lavapipe Vulkan driver (skips, or fails in CI, without it)."""
    return wgpu_device()


def test_default_resolution_compiles() -> None:
    src = shader_source(TABLE, language="hlsl")
    assert "721" in src and f"// requires: {HLSLSyntax.requirements}" in src
    glslang(src + HLSL_MAIN, "comp", hlsl=True)


def test_lookup_runs_on_lavapipe(device) -> None:
    src = shader_source(TABLE, language="hlsl", resolution_deg=RUN_RESOLUTION_DEG)
    code = glslang(src + HLSL_MAIN, "comp", hlsl=True)
    nu = test_nu(181)
    got = run_compute(device, code, nu)[:, :3]
    table32 = shader_channels(TABLE, resolution_deg=RUN_RESOLUTION_DEG).phase
    ulps = assert_matches_float32(got, table32, nu)
    rel = assert_matches_table(got, exact(TABLE, nu), table32, nu)
    print(
        f"hlsl on lavapipe: {ulps:.1f} ulps from numpy float32, {rel:.2e} relative from the table"
    )


def test_constants_are_the_float32_values(device) -> None:
    """Every sample, g and the number density read back bit for bit (the input, zeros, only
    keeps the binding that the shared runner expects)."""
    src = shader_source(TABLE, language="hlsl", resolution_deg=RUN_RESOLUTION_DEG)
    main = HLSL_MAIN.replace(
        "float4(MiePhaseFunction(NuIn[id.x]), 0.0f)",
        "id.x < 181u ? float4(MIE_PHASE[id.x], NuIn[id.x])"
        " : float4(MIE_G, MIE_NUMBER_DENSITY_PER_M3 + NuIn[id.x])",
    )
    got = run_compute(device, glslang(src + main, "comp", hlsl=True), np.zeros(182, np.float32))
    ch = shader_channels(TABLE, resolution_deg=RUN_RESOLUTION_DEG)
    np.testing.assert_array_equal(got[:181, :3], ch.phase)
    np.testing.assert_array_equal(got[181, :3], ch.g.astype(np.float32))
    assert got[181, 3] == np.float32(1e6)


def test_prefix_lets_two_snippets_share_a_shader() -> None:
    a = shader_source(TABLE, language="hlsl", resolution_deg=RUN_RESOLUTION_DEG)
    b = shader_source(
        OTHER_TABLE,
        language="hlsl",
        prefix="DUST",
        function_name="DustPhase",
        resolution_deg=RUN_RESOLUTION_DEG,
    )
    assert "MIE_" not in b and "MiePhaseFunction" not in b
    main = HLSL_MAIN.replace(
        "MiePhaseFunction(NuIn[id.x])", "MiePhaseFunction(NuIn[id.x]) + DustPhase(NuIn[id.x])"
    )
    glslang(a + b + main, "comp", hlsl=True)
