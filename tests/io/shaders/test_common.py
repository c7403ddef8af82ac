"""Shader snippets in GLSL (1.30+ and ES 1.00), HLSL and WGSL, proved in real tools.

- GLSL: a full shader per stated version compiles with glslangValidator, and
  the version below the stated minimum does not (the minimum is tight);
- GLSL ES 1.00 (WebGL 1): compiles with every Appendix A limit at its minimum
  and runs in Mesa's llvmpipe (moderngl, EGL) as a fragment shader;
- HLSL: compiled by glslangValidator's HLSL front end to SPIR-V, then run;
- WGSL: validated and run by wgpu;
HLSL's SPIR-V and WGSL run as compute shaders on Mesa's lavapipe Vulkan driver
through wgpu (no GPU), and every value equals numpy's float32 evaluation of the
same operations and the float64 table's interpolation (Table.phase_at) within
float32 rounding, as the GLSL test (test_glsl.py) shows for OpenGL.
"""

from __future__ import annotations

import numpy as np
import pytest
from _render import (
    assert_matches_float32,
    assert_matches_table,
    gl_context,
    glslang,
    run_compute,
    test_nu,
    wgpu_device,
)

from dustoptics.io import FORMATS, write
from dustoptics.io.shaders.common import (
    LANGUAGES,
    REQUIREMENTS,
    shader_channels,
    shader_source,
    write_shader,
)
from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.table import Provenance, Table


def hg_table(g: tuple[float, ...] = (0.8, 0.7, 0.6)) -> Table:
    """Henyey-Greenstein phase functions at 440, 550, 680 nm on a 1 deg grid, with cross-sections."""
    theta = np.linspace(0.0, 180.0, 181)
    mu = np.cos(np.deg2rad(theta))
    return Table(
        name="hg",
        wavelength_nm=np.array([440.0, 550.0, 680.0]),
        theta_deg=theta,
        phase=np.array([henyey_greenstein(mu, g=x) for x in g]),
        g=np.array(g),
        cext_um2=np.array([2.0, 1.5, 1.0]),
        csca_um2=np.array([1.8, 1.4, 0.95]),
        number_density_per_m3=1e6,
        provenance=Provenance(inputs={"model": "hg", "g": list(g)}),
    )


TABLE = hg_table()


def exact(table: Table, nu: np.ndarray) -> np.ndarray:
    """The float64 table read by linear interpolation in angle, channels 680, 550, 440 nm."""
    theta = np.degrees(np.arccos(np.clip(nu.astype(np.float64), -1.0, 1.0)))
    return table.phase_at(np.minimum(theta, 180.0))[[2, 1, 0]].T


# ---------------------------------------------------------------- GLSL versions

GLSL_FRAGMENT = {
    "130": ("#version 130\n", "out vec4 colour;\nin float nu;\n"),
    "150": ("#version 150\n", "out vec4 colour;\nin float nu;\n"),
    "330 core": ("#version 330 core\n", "out vec4 colour;\nin float nu;\n"),
    "450": (
        "#version 450\n",
        "layout(location = 0) out vec4 colour;\nlayout(location = 0) in float nu;\n",
    ),
    "300 es": ("#version 300 es\nprecision highp float;\n", "out vec4 colour;\nin float nu;\n"),
    "310 es": ("#version 310 es\nprecision highp float;\n", "out vec4 colour;\nin float nu;\n"),
}


@pytest.mark.parametrize("version", list(GLSL_FRAGMENT))
def test_glsl_compiles_in_each_stated_version(version: str) -> None:
    src = shader_source(TABLE, language="glsl")
    assert f"// requires: {REQUIREMENTS['glsl']}" in src and not src.startswith("#")
    head, io = GLSL_FRAGMENT[version]
    glslang(head + src + io + "void main() { colour = vec4(MiePhaseFunction(nu), 1.0); }\n", "frag")


def test_glsl_minimum_version_is_tight() -> None:
    # GLSL 1.20 has no min(int, int): the stated minimum, 1.30, is the least that compiles.
    src = (
        "#version 120\n"
        + shader_source(TABLE, language="glsl")
        + ("varying float nu;\nvoid main() { gl_FragColor = vec4(MiePhaseFunction(nu), 1.0); }\n")
    )
    with pytest.raises(AssertionError, match="min"):
        glslang(src, "frag")


ES100_FRAGMENT = """
varying highp float v_nu;
void main() { gl_FragColor = vec4(MiePhaseFunction(v_nu), 1.0); }
"""

ES100_VERTEX = """
attribute highp float in_nu;
attribute highp float in_x;
varying highp float v_nu;
void main() { v_nu = in_nu; gl_Position = vec4(in_x, 0.0, 0.0, 1.0); gl_PointSize = 1.0; }
"""


def test_glsl_es100_compiles_within_appendix_a_limits() -> None:
    src = shader_source(TABLE, language="glsl100")
    code = "\n".join(line.split("//")[0] for line in src.splitlines())
    assert "[" not in code  # no array anywhere
    assert "for" not in code and "while" not in code and "sampler" not in code
    # Include-ready in both stages, with and without a default precision.
    glslang("#version 100\n" + src + ES100_FRAGMENT, "frag", es100_limits=True)
    glslang(
        "#version 100\nprecision mediump float;\n" + src + ES100_FRAGMENT, "frag", es100_limits=True
    )
    glslang(
        "#version 100\n"
        + src
        + "void main() { gl_Position = vec4(MiePhaseFunction(0.5), 1.0); }\n",
        "vert",
        es100_limits=True,
    )


def test_glsl_es100_runs_in_llvmpipe() -> None:
    """ES 1.00 in Mesa's OpenGL (which accepts #version 100 shaders): one point per nu,
    the fragment shader writes the lookup into a float32 render target."""
    import moderngl

    ctx = gl_context(require=430)
    try:
        src = shader_source(TABLE, language="glsl100")
        program = ctx.program(
            vertex_shader="#version 100\n" + ES100_VERTEX,
            fragment_shader="#version 100\n" + src + ES100_FRAGMENT,
        )
        nu = test_nu(721)
        n = nu.size
        x = ((np.arange(n) + 0.5) / n * 2.0 - 1.0).astype(np.float32)
        vbo = ctx.buffer(np.stack([nu, x], axis=1).astype(np.float32).tobytes())
        vao = ctx.vertex_array(program, [(vbo, "f f", "in_nu", "in_x")])
        target = ctx.texture((n, 1), 4, dtype="f4")
        fbo = ctx.framebuffer([target])
        fbo.use()
        ctx.viewport = (0, 0, n, 1)
        vao.render(mode=moderngl.POINTS)
        got = np.frombuffer(fbo.read(components=4, dtype="f4"), dtype=np.float32).reshape(n, 4)[
            :, :3
        ]
    finally:
        ctx.release()
    table32 = shader_channels(TABLE).phase
    ulps = assert_matches_float32(got, table32, nu)
    rel = assert_matches_table(got, exact(TABLE, nu), table32, nu)
    print(
        f"GLSL ES 1.00 on llvmpipe: {ulps:.1f} ulps from numpy float32, {rel:.2e} relative from the table"
    )


# ---------------------------------------------------------------- HLSL and WGSL on lavapipe

HLSL_MAIN = """
StructuredBuffer<float> NuIn : register(t0);
RWStructuredBuffer<float4> PhaseOut : register(u1);
[numthreads(64, 1, 1)]
void main(uint3 id : SV_DispatchThreadID) { PhaseOut[id.x] = float4(MiePhaseFunction(NuIn[id.x]), 0.0f); }
"""

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
    return wgpu_device()


# lavapipe's compile time grows faster than linearly with the constant array's
# length (measured: 1 s for 181 samples, 80 s for 361 on a loaded 2-core
# machine), so the run uses the table's own 1 deg grid (181 samples); the
# default 721 samples differ only in N and are compiled and validated below.
RUN_RESOLUTION_DEG = 1.0


@pytest.mark.parametrize("language", ["hlsl", "wgsl"])
def test_default_resolution_compiles_and_validates(device, language: str) -> None:
    src = shader_source(TABLE, language=language)
    assert "721" in src
    if language == "hlsl":
        glslang(src + HLSL_MAIN, "comp", hlsl=True)
    else:
        device.create_shader_module(code=src + WGSL_MAIN)  # wgpu's WGSL front end validates it


@pytest.mark.parametrize("language", ["hlsl", "wgsl"])
def test_lookup_runs_on_lavapipe(device, language: str) -> None:
    src = shader_source(TABLE, language=language, resolution_deg=RUN_RESOLUTION_DEG)
    if language == "hlsl":
        code: str | bytes = glslang(src + HLSL_MAIN, "comp", hlsl=True)
    else:
        code = src + WGSL_MAIN
    nu = test_nu(181)
    got = run_compute(device, code, nu)[:, :3]
    table32 = shader_channels(TABLE, resolution_deg=RUN_RESOLUTION_DEG).phase
    ulps = assert_matches_float32(got, table32, nu)
    rel = assert_matches_table(got, exact(TABLE, nu), table32, nu)
    print(
        f"{language} on lavapipe: {ulps:.1f} ulps from numpy float32, {rel:.2e} relative from the table"
    )


@pytest.mark.parametrize("language", ["hlsl", "wgsl"])
def test_constants_are_the_float32_values(device, language: str) -> None:
    """Every sample, g and the number density read back bit for bit (the input, zeros, only
    keeps the binding that the shared runner expects)."""
    src = shader_source(TABLE, language=language, resolution_deg=RUN_RESOLUTION_DEG)
    if language == "hlsl":
        main = HLSL_MAIN.replace(
            "float4(MiePhaseFunction(NuIn[id.x]), 0.0f)",
            "id.x < 181u ? float4(MIE_PHASE[id.x], NuIn[id.x])"
            " : float4(MIE_G, MIE_NUMBER_DENSITY_PER_M3 + NuIn[id.x])",
        )
        code: str | bytes = glslang(src + main, "comp", hlsl=True)
    else:
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
    other = hg_table(g=(0.5, 0.4, 0.3))
    for language in LANGUAGES:
        a = shader_source(TABLE, language=language, resolution_deg=RUN_RESOLUTION_DEG)
        b = shader_source(
            other,
            language=language,
            prefix="DUST",
            function_name="DustPhase",
            resolution_deg=RUN_RESOLUTION_DEG,
        )
        assert "MIE_" not in b and "MiePhaseFunction" not in b
        if language == "glsl":
            glslang(
                "#version 330 core\n" + a + b + "in float nu;\nout vec4 colour;\n"
                "void main() { colour = vec4(MiePhaseFunction(nu) + DustPhase(nu), 1.0); }\n",
                "frag",
            )
        elif language == "glsl100":
            glslang(
                "#version 100\n" + a + b + "varying highp float nu;\n"
                "void main() { gl_FragColor = vec4(MiePhaseFunction(nu) + DustPhase(nu), 1.0); }\n",
                "frag",
                es100_limits=True,
            )
        elif language == "hlsl":
            glslang(
                a
                + b
                + HLSL_MAIN.replace(
                    "MiePhaseFunction(NuIn[id.x])",
                    "MiePhaseFunction(NuIn[id.x]) + DustPhase(NuIn[id.x])",
                ),
                "comp",
                hlsl=True,
            )
        else:
            nu = np.array([1.0, 0.5, -1.0], dtype=np.float32)
            got = run_compute(
                device,
                a
                + b
                + WGSL_MAIN.replace(
                    "MiePhaseFunction(nu_in[id.x])",
                    "MiePhaseFunction(nu_in[id.x]) + DustPhase(nu_in[id.x])",
                ),
                nu,
            )
            np.testing.assert_allclose(got[:, :3], exact(TABLE, nu) + exact(other, nu), rtol=1e-5)


# ---------------------------------------------------------------- content, files, errors


def test_same_content_in_every_language() -> None:
    # The header (after the language's name and requirement) and the numbers are the same.
    sources = {lang: shader_source(TABLE, language=lang) for lang in LANGUAGES}
    bodies = {lang: src.split("\n", 2)[2].split("\n\n")[0] for lang, src in sources.items()}
    assert len(set(bodies.values())) == 1
    assert "fn MiePhaseFunction(nu: f32) -> vec3<f32>" in sources["wgsl"]
    assert "float3 MiePhaseFunction(float nu)" in sources["hlsl"]
    assert "highp vec3 MiePhaseFunction(highp float nu)" in sources["glsl100"]
    assert "vec3 MiePhaseFunction(float nu)" in sources["glsl"]
    for lang, src in sources.items():
        assert src == shader_source(TABLE, language=lang)  # deterministic


def test_write_shader_files_and_registry(tmp_path) -> None:
    assert {"glsl", "hlsl", "wgsl"} <= set(FORMATS)
    (h,) = write(TABLE, tmp_path, format="hlsl")
    (w,) = write(TABLE, tmp_path, format="wgsl", prefix="DUST", function_name="DustPhase")
    (g,) = write(TABLE, tmp_path, format="glsl", version="100")
    assert [p.name for p in (h, w, g)] == ["hg_phase.hlsl", "hg_phase.wgsl", "hg_phase_es100.glsl"]
    assert "fn DustPhase(nu: f32)" in w.read_text()
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_shader(TABLE, tmp_path, language="hlsl")
    (explicit,) = write_shader(TABLE, tmp_path / "x.wgsl", language="wgsl")
    assert explicit.name == "x.wgsl"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"language": "msl"},
            "language must be one of 'glsl', 'glsl100', 'hlsl', 'wgsl'; got 'msl'",
        ),
        (
            {"language": "hlsl", "function_name": "float3"},
            "function_name must be a valid HLSL identifier",
        ),
        (
            {"language": "wgsl", "function_name": "fn"},
            "function_name must be a valid WGSL identifier",
        ),
        ({"language": "wgsl", "prefix": "__X"}, "prefix must be a valid WGSL identifier"),
        (
            {"language": "hlsl", "resolution_deg": 0.04},
            r"gives 4501 samples, more than hlsl's 4096",
        ),
        (
            {"language": "wgsl", "channels_nm": (700.0, 550.0, 440.0)},
            r"channels_nm\[0\] = 700 nm is outside",
        ),
    ],
)
def test_errors_name_parameter_value_and_allowed(tmp_path, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        write_shader(TABLE, tmp_path, **kwargs)
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_cli_export_writes_every_language_with_prefix(tmp_path) -> None:
    from dustoptics.cli import main
    from dustoptics.io import write_hdf5

    h5 = write_hdf5(TABLE, tmp_path / "hg.h5")
    out = tmp_path / "out"
    assert (
        main(
            [
                "export",
                str(h5),
                "--out",
                str(out),
                "--format",
                "glsl,hlsl,wgsl",
                "--prefix",
                "DUST",
                "--glsl-version",
                "100",
                "--quiet",
            ]
        )
        == 0
    )
    names = sorted(p.name for p in (out / "hg").iterdir())
    assert names == ["hg_phase.hlsl", "hg_phase.wgsl", "hg_phase_es100.glsl"]
    for path in (out / "hg").iterdir():
        text = path.read_text()
        assert "DUST_MiePhaseFunction(" in text and "MIE_" not in text
    assert main(["export", str(h5), "--out", str(out), "--format", "wgsl,msl"]) == 2
