"""GLSL snippet (GLSL 1.30+ and ES 1.00): content, determinism, errors, and proof in real tools.

The proof has two parts (issue 5, item 4):

- the snippet compiles with glslangValidator (Debian glslang-tools) inside a
  ``#version 330 core`` fragment shader and a ``#version 430`` compute shader;
- it runs in a real OpenGL driver, Mesa's llvmpipe through moderngl with the
  EGL backend (no GPU needed), and the values it computes at 4,096+ values of
  nu match a numpy float32 implementation of the same interpolation and the
  float64 table's own interpolation (:meth:`Table.phase_at`).

Elsewhere these tests skip, naming the missing package.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess

import numpy as np
import pytest
from _render import assert_matches_float32, assert_matches_table, gl_context, glslang, test_nu
from _shader_tables import OTHER_TABLE, RUN_RESOLUTION_DEG, TABLE, exact

import dustoptics as do
from dustoptics.io.shaders.common import shader_channels, shader_source
from dustoptics.io.shaders.glsl import (
    ACOS_AS4446,
    GLSLSyntax,
    glsl_channels,
    glsl_float,
    glsl_snippet,
    write_glsl,
)
from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.table import CrossSections, Provenance, Table

EPS32 = float(np.finfo(np.float32).eps)  # 2^-23: float32 spacing at 1


# ---------------------------------------------------------------- tables


@pytest.fixture(scope="module")
def mie_table() -> Table:
    """Small Mie table: 3 wavelengths (the seed's channels), 721 angles (its grid)."""
    optics = do.compute_optics(
        1.5 + 0.01j,
        do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2),
        [440.0, 550.0, 680.0],
        np.linspace(0.0, 180.0, 721),
        rtol=1e-3,
        name="test-dust",
    )
    return optics.replace(cross_sections={"number_density_per_m3": 1e6})


def hg_table(
    *,
    g: tuple[float, ...] = (0.8, 0.7, 0.6),
    wavelength_nm: tuple[float, ...] = (440.0, 550.0, 680.0),
    n_theta: int = 181,
    cross_sections: bool = False,
) -> Table:
    """Phase-only (or with made-up cross-sections) table of Henyey-Greenstein functions."""
    theta = np.linspace(0.0, 180.0, n_theta)
    mu = np.cos(np.deg2rad(theta))
    phase = np.array([henyey_greenstein(mu, g=x) for x in g])
    extra = {}
    if cross_sections:
        extra["cross_sections"] = CrossSections(
            cext_um2=np.linspace(2.0, 1.0, len(g)), csca_um2=np.linspace(1.8, 0.95, len(g))
        )
    return Table(
        name="hg",
        wavelength_nm=np.array(wavelength_nm),
        theta_deg=theta,
        phase=phase,
        g=np.array(g),
        provenance=Provenance(inputs={"model": "hg", "g": list(g)}),
        **extra,
    )


def parse_array(source: str, name: str = "MIE_PHASE") -> np.ndarray:
    """The float32 values of the snippet's constant array, parsed from its literals."""
    body = source.split(f"const vec3 {name}[")[1].split(");")[0]
    rows = re.findall(r"vec3\(([^)]*)\)", body)
    return np.array(
        [[np.float32(float(v)) for v in row.split(",")] for row in rows], dtype=np.float32
    )


# ---------------------------------------------------------------- content


def test_float_literals_round_trip_exactly() -> None:
    # Values across float32's range, including the extremes and a denormal.
    values = np.array(
        [
            0.0,
            1.0,
            0.1,
            1 / 3,
            2.0**-149,
            np.finfo(np.float32).max,
            1e-12,
            7.957747e-02,
            13.71990818,
        ],
        dtype=np.float32,
    )
    for v in values:
        text = glsl_float(v)
        assert "." in text and "e" in text  # GLSL reads a float, never an int
        assert np.float32(float(text)) == v
    with pytest.raises(ValueError, match="finite as float32"):
        glsl_float(1e39)  # beyond float32's 3.4e38


def test_snippet_layout_and_values(mie_table: Table) -> None:
    src = glsl_snippet(mie_table)
    assert src.isascii() and src.endswith("}\n")
    assert "const int MIE_PHASE_N = 721;" in src
    assert "vec3 MiePhaseFunction(float nu)" in src
    assert (
        f"// input_hash (SHA-256 of the table's inputs): {mie_table.provenance.input_hash}" in src
    )
    assert "2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian)" in src
    assert "resolution: 0.25 deg, 721 samples" in src
    assert "the table's own 721 angles (no resampling)" in src
    arr = parse_array(src)
    assert arr.shape == (721, 3)
    # Channels 680, 550, 440 nm are grid members: the table's rows in that order.
    expected = mie_table.phase[[2, 1, 0]].T.astype(np.float32)
    np.testing.assert_array_equal(arr, expected)
    ch = glsl_channels(mie_table)
    np.testing.assert_array_equal(ch.phase, expected)
    np.testing.assert_array_equal(ch.g, mie_table.g[[2, 1, 0]])
    np.testing.assert_array_equal(ch.cext_m2, mie_table.cross_sections.cext_um2[[2, 1, 0]] * 1e-12)
    for name in (
        "MIE_G",
        "MIE_CEXT_M2",
        "MIE_CSCA_M2",
        "MIE_CABS_M2",
        "MIE_SSA",
        "MIE_BETA_EXT_PER_M",
        "MIE_BETA_SCA_PER_M",
        "MIE_BETA_ABS_PER_M",
    ):
        assert f"const vec3 {name} = vec3(" in src
    beta = re.search(r"const vec3 MIE_BETA_EXT_PER_M = vec3\(([^)]*)\)", src).group(1)
    np.testing.assert_array_equal(
        [np.float32(float(v)) for v in beta.split(",")],
        (mie_table.beta_ext_per_m[[2, 1, 0]]).astype(np.float32),
    )
    # The sphere integral the header reports: converged table, no resampling.
    np.testing.assert_allclose(ch.sphere_integral, 1.0, atol=2e-3)


def test_phase_only_table_omits_cross_sections() -> None:
    src = glsl_snippet(hg_table())
    assert "const vec3 MIE_G = " in src
    for name in ("CEXT", "CSCA", "CABS", "SSA", "BETA", "NUMBER_DENSITY"):
        assert f"MIE_{name}" not in src


def test_resampling_and_interpolated_channel() -> None:
    table = hg_table(n_theta=181)
    src = glsl_snippet(table, channels_nm=(680.0, 500.0, 440.0), resolution_deg=0.5)
    assert "const int MIE_PHASE_N = 361;" in src
    assert "the table's 181 angles read by linear interpolation in angle" in src
    arr = parse_array(src)
    theta = np.linspace(0.0, 180.0, 361)
    p = table.phase_at(theta)
    t = (500.0 - 440.0) / (550.0 - 440.0)  # linear weight of the 550 nm row
    expected = np.stack([p[2], (1 - t) * p[0] + t * p[1], p[0]], axis=1).astype(np.float32)
    np.testing.assert_array_equal(arr, expected)
    assert "500 nm: linear in wavelength between the table's rows at 440 nm" in src


def test_deterministic_bytes(mie_table: Table) -> None:
    assert glsl_snippet(mie_table) == glsl_snippet(mie_table)
    assert glsl_snippet(mie_table, colour="cie1931-xyz", min_band_coverage=0.0) == glsl_snippet(
        mie_table, colour="cie1931-xyz", min_band_coverage=0.0
    )


def test_prefix_and_function_name_let_two_snippets_coexist() -> None:
    a = glsl_snippet(hg_table())
    b = glsl_snippet(hg_table(g=(0.5, 0.4, 0.3)), prefix="DUST", function_name="DustPhase")
    assert "const vec3 DUST_PHASE[DUST_PHASE_N]" in b and "vec3 DustPhase(float nu)" in b
    assert "MIE_" not in b and "MiePhaseFunction" not in b
    _compile(
        "#version 330 core\n" + a + b + "in float nu;\nout vec4 colour;\n"
        "void main() { colour = vec4(MiePhaseFunction(nu) + DustPhase(nu), 1.0); }\n",
        "frag",
    )


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"channels_nm": (700.0, 550.0, 440.0)},
            r"channels_nm\[0\] = 700 nm is outside the table's wavelength range 440-680 nm",
        ),
        ({"channels_nm": (430.0, 550.0, 440.0)}, r"channels_nm\[0\] = 430 nm is outside"),
        ({"channels_nm": (680.0, 550.0)}, "channels_nm must be three wavelengths"),
        ({"channels_nm": (680.0, 550.0, 440.0), "colour": "cie1931-xyz"}, "either channels_nm"),
        ({"colour": "srgb"}, "colour must be one of 'cie1931-xyz'"),
        ({"colour": "cie1931-xyz"}, r"holds only \(xbar 0\.93"),
        ({"resolution_deg": 0.7}, "resolution_deg must divide 180 deg"),
        ({"resolution_deg": 0.0}, "resolution_deg must be > 0"),
        ({"prefix": "2MIE"}, "prefix must be a valid GLSL identifier"),
        (
            {"prefix": "MIE_"},
            "prefix must be a valid GLSL identifier",
        ),  # MIE__PHASE: '__' is reserved
        ({"function_name": "gl_Phase"}, "function_name must be a valid GLSL identifier"),
        ({"function_name": "float"}, "function_name must be a valid GLSL identifier"),
        ({"function_name": "MIE_PHASE"}, "function_name must differ"),
        ({"acos": "fast"}, "acos must be one of 'polynomial', 'builtin'"),
    ],
)
def test_errors_name_parameter_value_and_allowed(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        glsl_snippet(hg_table(), **kwargs)


@pytest.mark.parametrize("colour", ["cie1931-xyz", "linear-srgb-astmg173"])
def test_colour_channels_of_grey_table_equal_the_table(colour: str) -> None:
    # Identity: the same phase function at every wavelength gives it back in each channel.
    wl = tuple(np.arange(360.0, 831.0, 10.0))
    table = hg_table(g=(0.7,) * len(wl), wavelength_nm=wl)
    ch = glsl_channels(table, colour=colour)
    single = table.phase_at(np.linspace(0.0, 180.0, 721))[0].astype(np.float32)
    for c in range(3):
        # Weights sum to 1 to rounding (sRGB weights have negative lobes, whose
        # sum of magnitudes is below 3): 8 float32 ulps covers the float64 sum's error.
        np.testing.assert_allclose(ch.phase[:, c], single, rtol=8 * EPS32, atol=0)
    np.testing.assert_allclose(ch.g, 0.7, rtol=1e-13)
    src = glsl_snippet(table, colour=colour)
    assert f"channels (.x, .y, .z): {colour}" in src


def test_write_glsl_atomic_and_no_overwrite(tmp_path, mie_table: Table) -> None:
    (path,) = write_glsl(mie_table, tmp_path / "out")
    assert path == tmp_path / "out" / "test-dust_phase.glsl"
    assert path.read_text(encoding="ascii") == glsl_snippet(mie_table)
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_glsl(mie_table, tmp_path / "out", resolution_deg=1.0)
    assert path.read_text(encoding="ascii") == glsl_snippet(mie_table)  # untouched
    write_glsl(mie_table, tmp_path / "out", resolution_deg=1.0, overwrite=True)
    assert "const int MIE_PHASE_N = 181;" in path.read_text(encoding="ascii")
    (explicit,) = write_glsl(
        mie_table, tmp_path / "dust.glsl", colour="cie1931-xyz", min_band_coverage=0.0
    )
    assert explicit == tmp_path / "dust.glsl"
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


# ---------------------------------------------------------------- glslangValidator


def _compile(source: str, stage: str) -> None:
    exe = shutil.which("glslangValidator")
    if exe is None:
        pytest.skip("glslang-tools (glslangValidator) not installed")
    result = subprocess.run(
        [exe, "--stdin", "-S", stage],
        check=False,
        input=source,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stdout + result.stderr


FRAGMENT_MAIN = """
in float nu;
out vec4 colour;
void main() { colour = vec4(MiePhaseFunction(nu), 1.0); }
"""

COMPUTE_MAIN = """
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Nu { float nu[]; };
layout(std430, binding = 1) writeonly buffer Phase { vec4 phase[]; };
void main() {
    uint k = gl_GlobalInvocationID.x;
    phase[k] = vec4(MiePhaseFunction(nu[k]), acos(clamp(nu[k], -1.0, 1.0)));
}
"""


@pytest.mark.parametrize("acos", ["polynomial", "builtin"])
@pytest.mark.parametrize("colour", [None, "cie1931-xyz", "linear-srgb-astmg173"])
def test_glslang_compiles_fragment_and_compute(
    mie_table: Table, acos: str, colour: str | None
) -> None:
    src = glsl_snippet(mie_table, acos=acos, colour=colour, min_band_coverage=0.0)
    _compile("#version 330 core\n" + src + FRAGMENT_MAIN, "frag")
    _compile("#version 450\n" + src + FRAGMENT_MAIN, "frag")
    _compile("#version 430\n" + src + COMPUTE_MAIN, "comp")


def test_glslang_compiles_phase_only_snippet() -> None:
    _compile("#version 330 core\n" + glsl_snippet(hg_table()) + FRAGMENT_MAIN, "frag")


# ---------------------------------------------------------------- OpenGL (Mesa llvmpipe via EGL)


@pytest.fixture(scope="module")
def gl():
    try:
        import moderngl
    except ImportError:
        pytest.skip("moderngl not installed (pip install moderngl, the 'gl' extra)")
    try:
        ctx = moderngl.create_context(standalone=True, backend="egl", require=430)
    except Exception as exc:
        pytest.skip(
            f"EGL OpenGL 4.3 context failed ({exc}); needs Mesa EGL: Debian libegl1, "
            "libegl-mesa0, libgl1-mesa-dri"
        )
    yield ctx
    ctx.release()


def _run(ctx, source: str, nu: np.ndarray) -> np.ndarray:
    """Evaluate the snippet at ``nu`` in a compute shader: columns P.x, P.y, P.z, acos(nu)."""
    n = nu.size
    groups = -(-n // 64)
    padded = np.zeros(groups * 64, dtype=np.float32)
    padded[:n] = nu
    program = ctx.compute_shader("#version 430\n" + source + COMPUTE_MAIN)
    inp = ctx.buffer(padded.tobytes())
    out = ctx.buffer(reserve=16 * padded.size)
    inp.bind_to_storage_buffer(0)
    out.bind_to_storage_buffer(1)
    program.run(group_x=groups)
    result = np.frombuffer(out.read(), dtype=np.float32).reshape(-1, 4)[:n].copy()
    for obj in (inp, out, program):
        obj.release()
    return result


def _test_nu(n_angles: int) -> np.ndarray:
    """4,096 cosines uniform in angle, the ends and 0, each node's cosine and its float32 neighbours,
    and values just beyond +-1 (which the clamp maps to +-1)."""
    base = np.cos(np.linspace(0.0, math.pi, 4096)).astype(np.float32)
    nodes = np.cos(np.deg2rad(np.linspace(0.0, 180.0, n_angles))).astype(np.float32)
    up = np.nextafter(nodes, np.float32(2))
    down = np.nextafter(nodes, np.float32(-2))
    special = np.array([1.0, -1.0, 0.0, -0.0, 1.0 + EPS32, -1.0 - EPS32], dtype=np.float32)
    return np.concatenate([base, nodes, up, down, special])


def _acos32(c: np.ndarray) -> np.ndarray:
    """The snippet's polynomial acos, evaluated in float32 as the shader writes it."""
    a = np.abs(c)
    p = np.float32(ACOS_AS4446[-1])
    for coef in ACOS_AS4446[-2::-1]:
        p = p * a + np.float32(coef)
    theta = np.sqrt(np.float32(1.0) - a) * p
    return np.where(c < 0, np.float32(math.pi) - theta, theta).astype(np.float32)


def _reference32(
    table32: np.ndarray, nu: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The shader's interpolation in numpy float32, given its angle ``theta``; also P[i+1] - P[i]."""
    n = table32.shape[0]
    scale = np.float32((n - 1) / math.pi)
    x = np.clip(theta * scale, np.float32(0), np.float32(n - 1)).astype(np.float32)
    i = np.minimum(x.astype(np.int64), n - 2)
    f = (x - i.astype(np.float32))[:, None]
    value = table32[i] * (np.float32(1) - f) + table32[i + 1] * f
    return value.astype(np.float32), np.abs(table32[i + 1] - table32[i]), x


def _ulps(diff: np.ndarray, scale: np.ndarray) -> np.ndarray:
    return diff / np.spacing(np.maximum(scale, np.float32(np.finfo(np.float32).tiny)))


def test_shader_constants_are_the_float32_values(gl, mie_table: Table) -> None:
    # Read every array element back through the driver's parser: bit-exact.
    src = glsl_snippet(mie_table)
    main = """
layout(local_size_x = 64) in;
layout(std430, binding = 1) writeonly buffer Out { vec4 v[]; };
void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k < uint(MIE_PHASE_N)) v[k] = vec4(MIE_PHASE[k], 0.0);
    else if (k == uint(MIE_PHASE_N)) v[k] = vec4(MIE_G, 0.0);
    else if (k == uint(MIE_PHASE_N) + 1u) v[k] = vec4(MIE_BETA_EXT_PER_M, MIE_NUMBER_DENSITY_PER_M3);
}
"""
    program = gl.compute_shader("#version 430\n" + src + main)
    out = gl.buffer(reserve=16 * 768)
    out.bind_to_storage_buffer(1)
    program.run(group_x=12)
    got = np.frombuffer(out.read(), dtype=np.float32).reshape(-1, 4)
    ch = glsl_channels(mie_table)
    np.testing.assert_array_equal(got[:721, :3], ch.phase)
    np.testing.assert_array_equal(got[721, :3], ch.g.astype(np.float32))
    np.testing.assert_array_equal(got[722, :3], (1e6 * ch.cext_m2).astype(np.float32))
    assert got[722, 3] == np.float32(1e6)


@pytest.mark.parametrize("colour", [None, "cie1931-xyz", "linear-srgb-astmg173"])
def test_shader_matches_numpy_float32_interpolation(
    gl, mie_table: Table, colour: str | None
) -> None:
    """Polynomial acos: the shader equals numpy's float32 evaluation of the same operations.

    Tolerance (per value): 4 float32 ulps of the larger neighbour (two products and
    a sum, which the driver may fuse into FMAs, each rounding at most half an ulp),
    plus |P[i+1] - P[i]| times 8 ulps of x relative (acos's Horner steps and
    the scaling, also possibly fused, move x by a few ulps).
    """
    ch = glsl_channels(mie_table, colour=colour, min_band_coverage=0.0)
    nu = _test_nu(721)
    got = _run(gl, glsl_snippet(mie_table, colour=colour, min_band_coverage=0.0), nu)
    c = np.clip(nu, np.float32(-1), np.float32(1))
    ref, step, x = _reference32(ch.phase, nu, _acos32(c))
    big = np.maximum(np.abs(ref), np.abs(ref) + step)
    tol = 4 * np.spacing(big) + step * (8 * EPS32 * np.maximum(x, 1.0))[:, None]
    diff = np.abs(got[:, :3] - ref)
    assert np.all(diff <= tol), f"max excess {np.max(diff - tol)}"
    # Ends and 0 exactly as the table's samples (x = 0, N - 1 and 360 exactly in float32).
    for value, node in ((1.0, 0), (-1.0, 720), (0.0, 360), (1.0 + EPS32, 0), (-1.0 - EPS32, 720)):
        k = int(np.flatnonzero(nu == np.float32(value))[0])
        np.testing.assert_allclose(got[k, :3], ch.phase[node], rtol=4 * EPS32)
    print(f"max shader - numpy float32: {np.max(_ulps(diff, big)):.1f} ulps of the value")


def test_shader_matches_table_interpolation_float64(gl, mie_table: Table) -> None:
    """The shader against the float64 table read by linear interpolation (Table.phase_at).

    Tolerance: 4 float32 ulps of the value (the constants' float32 rounding and
    the interpolation's) plus |P[i+1] - P[i]| times the error of x: the
    polynomial's acos error, 2.5e-7 rad in float32 (measured against float64
    over [-1, 1]) times (N - 1)/pi, and 8 ulps of x for the scaling.
    """
    nu = _test_nu(721)
    got = _run(gl, glsl_snippet(mie_table), nu)
    theta = np.degrees(np.arccos(np.clip(nu.astype(np.float64), -1.0, 1.0)))
    exact = mie_table.phase_at(np.minimum(theta, 180.0))[[2, 1, 0]].T
    ch = glsl_channels(mie_table)
    _, step, x = _reference32(ch.phase, nu, _acos32(np.clip(nu, np.float32(-1), np.float32(1))))
    tol = (
        4 * np.spacing(np.abs(exact).astype(np.float32))
        + step * (2.5e-7 * 720 / math.pi + 8 * EPS32 * np.maximum(x, 1.0))[:, None]
    )
    diff = np.abs(got[:, :3] - exact)
    assert np.all(diff <= tol), f"max excess {np.max(diff - tol)}"
    print(f"max shader - float64 table: {np.max(diff / np.abs(exact)):.2e} relative")


def test_builtin_acos_shader_matches_numpy_given_driver_acos(gl, mie_table: Table) -> None:
    """With GLSL's acos the interpolation still matches, given the driver's angle.

    The driver's acos (returned in the 4th component) is used for the reference,
    since its precision is the driver's; the rest is as in the polynomial test.
    """
    nu = _test_nu(721)
    got = _run(gl, glsl_snippet(mie_table, acos="builtin"), nu)
    ch = glsl_channels(mie_table)
    ref, step, x = _reference32(ch.phase, nu, got[:, 3])
    big = np.maximum(np.abs(ref), np.abs(ref) + step)
    tol = 4 * np.spacing(big) + step * (8 * EPS32 * np.maximum(x, 1.0))[:, None]
    assert np.all(np.abs(got[:, :3] - ref) <= tol)
    acos_error = np.max(np.abs(got[:, 3] - np.arccos(np.clip(nu.astype(np.float64), -1, 1))))
    print(f"driver acos error: {acos_error:.2e} rad")


# ---------------------------------------------------------------- versions (glslangValidator, llvmpipe)

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
    assert f"// requires: {GLSLSyntax.requirements}" in src and not src.startswith("#")
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


@pytest.mark.parametrize("language", ["glsl", "glsl100"])
def test_prefix_lets_two_snippets_with_cross_sections_share_a_shader(language: str) -> None:
    a = shader_source(TABLE, language=language, resolution_deg=RUN_RESOLUTION_DEG)
    b = shader_source(
        OTHER_TABLE,
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
    else:
        glslang(
            "#version 100\n" + a + b + "varying highp float nu;\n"
            "void main() { gl_FragColor = vec4(MiePhaseFunction(nu) + DustPhase(nu), 1.0); }\n",
            "frag",
            es100_limits=True,
        )
