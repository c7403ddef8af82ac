"""Real shader compilers and drivers for the format tests (no GPU needed).

- glslangValidator (Debian glslang-tools): GLSL, GLSL ES and, with ``-D``,
  HLSL, compiled to SPIR-V;
- Mesa's llvmpipe OpenGL driver through moderngl and EGL;
- Mesa's lavapipe Vulkan driver through wgpu (WebGPU; WGSL and SPIR-V).

Also the float32 reference of the shaders' lookup, shared by the GLSL, GLSL ES,
HLSL and WGSL tests.  A missing tool skips the test with a message naming it,
except in CI (``CI=true``), where it fails: CI must run every proof.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import pytest

from dustoptics.io.shaders.common import ACOS_AS4446

EPS32 = float(np.finfo(np.float32).eps)  # 2^-23: float32 spacing at 1

# Every ES 1.00 Appendix A limit at its minimum (glslang's defaults allow all):
# no general indexing of uniforms, attributes, varyings, samplers or variables,
# no while/do-while loops, only loops with constant bounds.
ES100_APPENDIX_A_CONFIG = """\
nonInductiveForLoops 0
whileLoops 0
doWhileLoops 0
generalUniformIndexing 0
generalAttributeMatrixVectorIndexing 0
generalVaryingIndexing 0
generalSamplerIndexing 0
generalVariableIndexing 0
generalConstantMatrixVectorIndexing 0
"""


def missing(what: str) -> NoReturn:
    """Skip (fail in CI) because a tool the proof needs is absent."""
    if os.environ.get("CI") == "true":
        pytest.fail(f"{what}; CI must have it (see .ci/run)")
    pytest.skip(what)


def glslang(source: str, stage: str, *, hlsl: bool = False, es100_limits: bool = False) -> bytes:
    """Compile with glslangValidator; returns the SPIR-V for HLSL, else b"" (assert success)."""
    exe = shutil.which("glslangValidator")
    if exe is None:
        missing("glslang-tools (glslangValidator) not installed")
    with tempfile.TemporaryDirectory() as tmp:
        ext = {"frag": "frag", "vert": "vert", "comp": "comp"}[stage]
        src = Path(tmp) / (f"shader.{ext}.hlsl" if hlsl else f"shader.{ext}")
        src.write_text(source, encoding="ascii")
        args = [exe, "-S", stage]
        if hlsl:
            spv = Path(tmp) / "shader.spv"
            args += ["-D", "-e", "main", "-V", "-o", str(spv)]
        if es100_limits:
            conf = Path(tmp) / "limits.conf"
            conf.write_text(_default_config(exe) + ES100_APPENDIX_A_CONFIG)
            args.append(str(conf))
        result = subprocess.run(
            [*args, str(src)], check=False, capture_output=True, text=True, timeout=120
        )
        assert result.returncode == 0, result.stdout + result.stderr
        return spv.read_bytes() if hlsl else b""


def _default_config(exe: str) -> str:
    """glslang's default resource limits without its (permissive) 'limits' block."""
    text = subprocess.run([exe, "-c"], check=True, capture_output=True, text=True).stdout
    return "".join(
        line + "\n"
        for line in text.splitlines()
        if line.split()[:1] and line.split()[0] not in ES100_APPENDIX_A_CONFIG
    )


def gl_context(require: int = 430) -> Any:
    """A standalone OpenGL context on Mesa through EGL (llvmpipe without a GPU)."""
    try:
        import moderngl
    except ImportError:
        missing("moderngl not installed (pip install moderngl, the 'gl' extra)")
    try:
        return moderngl.create_context(standalone=True, backend="egl", require=require)
    except Exception as exc:
        missing(
            f"EGL OpenGL {require} context failed ({exc}); needs Mesa EGL: Debian libegl1, "
            "libegl-mesa0, libgl1-mesa-dri"
        )


def wgpu_device() -> Any:
    """A WebGPU device on a Vulkan driver (Mesa lavapipe without a GPU)."""
    try:
        import wgpu
    except ImportError:
        missing("wgpu not installed (pip install wgpu, the 'shaders' extra)")
    try:
        adapter = wgpu.gpu.request_adapter_sync(power_preference="high-performance")
        return adapter.request_device_sync()
    except Exception as exc:
        missing(f"no WebGPU adapter ({exc}); needs Mesa's lavapipe: Debian mesa-vulkan-drivers")


def run_compute(device: Any, code: str | bytes, nu: np.ndarray) -> np.ndarray:
    """Run a compute shader (WGSL text or SPIR-V bytes) with entry ``main``, 64 threads a group,
    reading ``nu`` from binding 0 and writing one vec4 per value to binding 1."""
    import wgpu

    n = nu.size
    groups = -(-n // 64)
    padded = np.zeros(groups * 64, dtype=np.float32)
    padded[:n] = nu
    module = device.create_shader_module(code=code)
    pipeline = device.create_compute_pipeline(
        layout="auto", compute={"module": module, "entry_point": "main"}
    )
    inp = device.create_buffer_with_data(data=padded.tobytes(), usage=wgpu.BufferUsage.STORAGE)
    out = device.create_buffer(
        size=16 * padded.size, usage=wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC
    )
    group = device.create_bind_group(
        layout=pipeline.get_bind_group_layout(0),
        entries=[
            {"binding": 0, "resource": {"buffer": inp}},
            {"binding": 1, "resource": {"buffer": out}},
        ],
    )
    encoder = device.create_command_encoder()
    compute = encoder.begin_compute_pass()
    compute.set_pipeline(pipeline)
    compute.set_bind_group(0, group)
    compute.dispatch_workgroups(groups)
    compute.end()
    device.queue.submit([encoder.finish()])
    return np.frombuffer(device.queue.read_buffer(out), dtype=np.float32).reshape(-1, 4)[:n].copy()


# ---------------------------------------------------------------- the lookup in numpy float32


def test_nu(n_angles: int) -> np.ndarray:
    """4,096 cosines uniform in angle, the ends and 0, each node's cosine and its float32 neighbours,
    and values just beyond +-1 (which the clamp maps to +-1)."""
    base = np.cos(np.linspace(0.0, math.pi, 4096)).astype(np.float32)
    nodes = np.cos(np.deg2rad(np.linspace(0.0, 180.0, n_angles))).astype(np.float32)
    up = np.nextafter(nodes, np.float32(2))
    down = np.nextafter(nodes, np.float32(-2))
    special = np.array([1.0, -1.0, 0.0, -0.0, 1.0 + EPS32, -1.0 - EPS32], dtype=np.float32)
    return np.concatenate([base, nodes, up, down, special])


test_nu.__test__ = False  # type: ignore[attr-defined]  (a helper, not a test)


def acos32(c: np.ndarray) -> np.ndarray:
    """The snippets' polynomial acos, evaluated in float32 as the shaders write it."""
    a = np.abs(c)
    p = np.float32(ACOS_AS4446[-1])
    for coef in ACOS_AS4446[-2::-1]:
        p = p * a + np.float32(coef)
    theta = np.sqrt(np.float32(1.0) - a) * p
    return np.where(c < 0, np.float32(math.pi) - theta, theta).astype(np.float32)


def reference32(
    table32: np.ndarray, nu: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shaders' interpolation in numpy float32, given its angle ``theta``; also
    |P[i+1] - P[i]| and x."""
    n = table32.shape[0]
    scale = np.float32((n - 1) / math.pi)
    x = np.clip(theta * scale, np.float32(0), np.float32(n - 1)).astype(np.float32)
    i = np.minimum(x.astype(np.int64), n - 2)
    f = (x - i.astype(np.float32))[:, None]
    value = table32[i] * (np.float32(1) - f) + table32[i + 1] * f
    return value.astype(np.float32), np.abs(table32[i + 1] - table32[i]), x


def assert_matches_float32(got: np.ndarray, table32: np.ndarray, nu: np.ndarray) -> float:
    """The shader's values equal numpy's float32 evaluation of the same operations.

    Tolerance (per value): 4 float32 ulps of the larger neighbour (two products
    and a sum, which a compiler may fuse into FMAs, each rounding at most half an
    ulp), plus |P[i+1] - P[i]| times 8 ulps of x relative (acos's Horner steps
    and the scaling, also possibly fused, move x by a few ulps).  Returns the
    largest difference in ulps of the value.
    """
    c = np.clip(nu, np.float32(-1), np.float32(1))
    ref, step, x = reference32(table32, nu, acos32(c))
    big = np.maximum(np.abs(ref), np.abs(ref) + step)
    tol = 4 * np.spacing(big) + step * (8 * EPS32 * np.maximum(x, 1.0))[:, None]
    diff = np.abs(got - ref)
    assert np.all(diff <= tol), f"max excess {np.max(diff - tol)}"
    return float(np.max(diff / np.spacing(np.maximum(big, np.float32(np.finfo(np.float32).tiny)))))


def assert_matches_table(
    got: np.ndarray, exact: np.ndarray, table32: np.ndarray, nu: np.ndarray
) -> float:
    """The shader against the float64 table read by linear interpolation (Table.phase_at).

    Tolerance: 4 float32 ulps of the value (the constants' float32 rounding and
    the interpolation's) plus |P[i+1] - P[i]| times the error of x: the
    polynomial's acos error, 2.5e-7 rad in float32 (measured against float64
    over [-1, 1]) times (N - 1)/pi, and 8 ulps of x for the scaling.  Returns
    the largest relative difference.
    """
    n = table32.shape[0]
    _, step, x = reference32(table32, nu, acos32(np.clip(nu, np.float32(-1), np.float32(1))))
    tol = (
        4 * np.spacing(np.abs(exact).astype(np.float32))
        + step * (2.5e-7 * (n - 1) / math.pi + 8 * EPS32 * np.maximum(x, 1.0))[:, None]
    )
    diff = np.abs(got - exact)
    assert np.all(diff <= tol), f"max excess {np.max(diff - tol)}"
    return float(np.max(diff / np.abs(exact)))
