"""dustoptics.models.dust_phase_fit: the shipped closed form of the Mars dust phase function by
size, its recorded error (recomputed here from Mie), and its GLSL and WGSL functions."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _render import run_compute, wgpu_device

from dustoptics.cli import main
from dustoptics.models import dust_phase_fit as dpf
from dustoptics.scattering.phase import hg_draine_jendersie_deon2023

RADII_UM = np.geomspace(0.5, 4.0, 29)


@pytest.fixture(scope="module", params=dpf.DUST_FIT_PRESETS)
def fit(request: pytest.FixtureRequest) -> dpf.DustPhaseFit:
    return dpf.load_dust_phase_fit(request.param)


def test_the_data_file_says_what_it_is_and_where_it_comes_from() -> None:
    path = Path(dpf.__file__).parent / "data" / "fits" / dpf.DATA_FILE
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert "doi:10.1145/3587421.3595409" in doc["citation"]
    assert "scripts/dust_phase_fit.py" in doc["provenance"]
    assert "RMS" in doc["error_metric"] and "held out" in doc["error_metric"]
    assert [f["preset"] for f in doc["fits"]] == list(dpf.DUST_FIT_PRESETS)


def test_parameters_stay_in_the_models_ranges_and_the_phase_is_normalized(fit) -> None:
    p = fit.parameters(r_eff_um=RADII_UM)
    assert p.shape == (RADII_UM.size, 3, 4)
    assert np.all(np.abs(p[..., :2]) < 1.0) and np.all(p[..., 2] > -1.0)
    assert np.all((p[..., 3] > 0.0) & (p[..., 3] < 1.0))
    # 2 pi int P sin(theta) dtheta = 1 (trapezoidal in angle, 0.005 deg steps: the forward
    # peak, about 1 deg wide, is resolved).
    theta = np.linspace(0.0, math.pi, 36001)
    for r in (0.5, 1.6, 4.0):
        p = fit.phase(np.cos(theta), r_eff_um=r)
        total = 2.0 * math.pi * np.trapezoid(p * np.sin(theta), theta, axis=-1)
        np.testing.assert_allclose(total, 1.0, rtol=1e-5)


def test_outside_the_fitted_range_is_refused(fit) -> None:
    with pytest.raises(ValueError, match=r"r_eff_um must lie within \[0.5, 4\] um"):
        fit.parameters(r_eff_um=5.0)
    with pytest.raises(ValueError, match="preset must be one of"):
        dpf.load_dust_phase_fit("hybrid")


def test_the_recorded_error_is_the_error_against_mie() -> None:
    """Recompute the exact Mie phase at a held-out radius and the closed form's error there."""
    fit = dpf.load_dust_phase_fit("blue-moons")
    r = math.sqrt(0.5 * dpf.DUST_FIT_R_EFF_GRID_UM[1])  # the first midpoint, not fitted
    theta, exact, names = dpf._channel_table("blue-moons", r)
    err = dpf.phase_errors(theta, fit.phase(np.cos(np.radians(theta)), r_eff_um=r), exact)
    recorded = [e for e in fit.errors if abs(e["r_eff_um"] - r) < 1e-9]
    assert [e["channel"] for e in recorded] == list(names) and not recorded[0]["fitted"]
    # To the exact table's own accuracy (rtol 1e-4): the file was written from tables of an
    # earlier quadrature, equal to these within their stated error, not bit for bit.
    for e, (rms, worst) in zip(recorded, err, strict=True):
        assert e["rms_relative_error"] == pytest.approx(rms, rel=1e-4)
        assert e["max_relative_error"] == pytest.approx(worst, rel=1e-4)
    # The asymmetry parameter there: the closed form's against Mie's (both read linearly in
    # angle): measured within 0.003 (0.58 um, blue-moons).
    mu = np.cos(np.radians(theta))
    weights = np.sin(np.radians(theta))
    closed = fit.phase(mu, r_eff_um=r)
    g_fit = np.trapezoid(closed * mu * weights, np.radians(theta)) * 2 * math.pi
    g_mie = np.trapezoid(exact * mu * weights, np.radians(theta)) * 2 * math.pi
    np.testing.assert_allclose(g_fit, g_mie, atol=0.01)


def _reference(fit: dpf.DustPhaseFit, mu: np.ndarray, r: float) -> np.ndarray:
    p = fit.parameters(r_eff_um=r)
    return np.stack(
        [
            np.asarray(
                hg_draine_jendersie_deon2023(
                    mu, g_hg=p[c, 0], g_d=p[c, 1], alpha=p[c, 2], w_d=p[c, 3]
                )
            )
            for c in range(3)
        ],
        axis=-1,
    )


def test_glsl_compiles(fit) -> None:
    exe = shutil.which("glslangValidator")
    if exe is None:
        pytest.skip("glslang-tools (glslangValidator) not installed")
    ident = fit.preset.replace("-", "_")
    src = (
        "#version 330\n"
        + dpf.dust_phase_glsl(fit)
        + f"in float mu;\nout vec4 colour;\nvoid main() {{ colour = vec4({ident}_phase(mu, 1.6), 1.0); }}\n"
    )
    result = subprocess.run(
        [exe, "--stdin", "-S", "frag"], input=src, capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_wgsl_runs_and_matches_the_closed_form(fit) -> None:
    device = wgpu_device()
    ident = fit.preset.replace("-", "_")
    r = 1.6
    code = dpf.dust_phase_wgsl(fit) + (
        "@group(0) @binding(0) var<storage, read> nu_in: array<f32>;\n"
        "@group(0) @binding(1) var<storage, read_write> phase_out: array<vec4<f32>>;\n"
        "@compute @workgroup_size(64)\n"
        "fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n"
        f"    phase_out[id.x] = vec4<f32>({ident}_phase(nu_in[id.x], {r}), 0.0);\n"
        "}\n"
    )
    mu = np.cos(np.radians(np.linspace(0.0, 180.0, 361))).astype(np.float32)
    got = run_compute(device, code, mu)[:, :3]
    expected = _reference(fit, mu.astype(float), r)
    # float32 evaluation of the closed form: the forward peak (1 + g^2 - 2 g mu ~ 1e-4)
    # loses digits to cancellation; measured 1e-4 at most.
    np.testing.assert_allclose(got, expected, rtol=2e-3)


def test_cli_prints_the_error_table_and_writes_the_shaders(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["fit", "blue-moons", "--by-size", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "blue-moons: HG + Draine by size, r_eff 0.5 .. 4 um, v_eff 0.2" in out
    assert out.count(" held ") == 3 * 7 and out.count(" fit ") == 3 * 8
    names = sorted(p.name for p in (tmp_path / "blue-moons").iterdir())
    assert names == [
        "blue-moons_by-size.glsl",
        "blue-moons_by-size.json",
        "blue-moons_by-size.wgsl",
    ]
    assert main(["fit", "hybrid", "--by-size"]) == 2
    assert "has no closed form by size" in capsys.readouterr().err
