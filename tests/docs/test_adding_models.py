"""The worked examples of docs/contributing/adding.rst, read from the page and run.

Each example is taken from its ``:caption:`` code block, so the page cannot drift from
what works: a new size distribution (checked against an independent form and built
from TOML), a new phase model (fitted, its derivatives and mean cosine checked) and a
new preset (listed, shown and built).  Every registration is undone after its test.
"""

from __future__ import annotations

import math
import re
import shutil
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dustoptics.cli import main
from dustoptics.models import presets
from dustoptics.models.compute import build_table
from dustoptics.models.config import parse_config
from dustoptics.particles import sizedist
from dustoptics.particles.sizedist import DeirmendjianGamma, get_size_distribution
from dustoptics.scattering import phase, tabulated_phase
from dustoptics.scattering.fit import fit_phase

PAGE = Path(__file__).resolve().parents[2] / "docs" / "contributing" / "adding.rst"


def block(caption: str) -> str:
    """The code block of the page with this caption, dedented."""
    text = PAGE.read_text(encoding="utf-8")
    match = re.search(
        rf"\.\. code-block:: \w+\n   :caption: {re.escape(caption)}\n\n((?:   .*\n|\n)+)", text
    )
    assert match, f"no code block captioned {caption!r} in {PAGE}"
    return textwrap.dedent(match.group(1)).strip() + "\n"


@pytest.fixture
def weibull() -> Iterator[type]:
    namespace: dict[str, Any] = {"__name__": "weibull_example"}
    exec(compile(block("weibull.py"), "weibull.py", "exec", dont_inherit=True), namespace)
    try:
        yield namespace["Weibull"]
    finally:
        sizedist._REGISTRY.pop("weibull", None)
        sizedist._ALIASES.pop("rosin_rammler1933", None)


@pytest.fixture
def schlick() -> Iterator[dict[str, Any]]:
    namespace: dict[str, Any] = {"__name__": "schlick_example"}
    exec(compile(block("schlick.py"), "schlick.py", "exec", dont_inherit=True), namespace)
    try:
        yield namespace
    finally:
        phase._REGISTRY.pop("schlick1993", None)
        phase._ALIASES.pop("schlick", None)


def test_a_new_size_distribution_registers_itself_and_builds_from_toml(weibull: type) -> None:
    assert get_size_distribution("weibull") is weibull
    assert get_size_distribution("rosin_rammler1933") is weibull
    s, k = 0.3, 2.0
    dist = weibull(scale_um=s, shape=k)
    # Independent form: Weibull(s, k) is Deirmendjian's a r^(k-1) exp(-r^k / s^k).
    same = DeirmendjianGamma(alpha=k - 1.0, b=s**-k, gamma=k)
    r = np.linspace(0.01, 2.0, 50)
    np.testing.assert_allclose(dist.pdf(r), same.pdf(r), rtol=1e-12)
    expected = s * math.gamma(1 + 3 / k) / math.gamma(1 + 2 / k)
    assert dist.r_eff_um == pytest.approx(expected, rel=1e-13)
    assert same.r_eff_um == pytest.approx(expected, rel=1e-12)
    config = parse_config(block("weibull.toml"))
    assert config.size_distribution.build() == dist
    table = build_table(config, workers=1)
    np.testing.assert_allclose(table.quadrature.r_eff_quadrature_um, expected, rtol=1e-3)
    assert table.provenance.inputs["size_distribution"] == {
        "model": "weibull",
        "scale_um": 0.3,
        "shape": 2.0,
    }


def test_without_the_class_the_toml_names_an_unknown_model() -> None:
    with pytest.raises(ValueError, match="size_distribution.model: must be one of"):
        parse_config(block("weibull.toml"))


def test_a_new_phase_model_is_fitted_and_read_by_toml(schlick: dict[str, Any]) -> None:
    record = phase.get_analytic_model("schlick")
    assert record is phase.ANALYTIC_MODELS["schlick1993"]
    theta = np.linspace(0.0, 180.0, 361)
    mu = np.cos(np.deg2rad(theta))
    # Normalization and mean cosine against a quadrature on a fine grid.
    fine = np.linspace(-1.0, 1.0, 200_001)
    values = schlick["schlick1993"](fine, k=0.6)
    assert 2 * math.pi * np.trapezoid(values, fine) == pytest.approx(1.0, abs=1e-8)
    assert 2 * math.pi * np.trapezoid(values * fine, fine) == pytest.approx(
        float(schlick["schlick1993_asymmetry"](k=0.6)), abs=1e-8
    )
    # Derivatives against central differences.
    p = np.array([[0.6], [-0.3]])
    _, jac = record.gradient(mu, p)
    step = 1e-6
    num = (record.kernel(mu, p + step) - record.kernel(mu, p - step)) / (2 * step)
    np.testing.assert_allclose(jac[..., 0], num, rtol=1e-6)
    # A tabulated Schlick function is fitted back to its k.
    table = tabulated_phase.renormalize(
        np.atleast_2d(schlick["schlick1993"](mu, k=0.6)), theta_deg=theta
    )
    result = fit_phase(theta, table, model="schlick")
    assert result.model == "schlick1993" and result.citation == record.citation
    assert result.parameter("k")[0] == pytest.approx(0.6, abs=1e-8)
    # The TOML configuration reads the same registry.
    config = parse_config(
        'name = "s"\ndescription = "d"\n[optics]\nwavelengths_nm = [500.0]\nn_theta = 19\n'
        '[phase]\nmodel = "schlick1993"\nk = 0.6\n'
    )
    assert config.phase.model == "schlick1993"


def test_a_new_preset_is_one_file(tmp_path: Path, monkeypatch, capsys) -> None:
    folder = tmp_path / "presets"
    shutil.copytree(Path(str(presets._directory())), folder)
    (folder / "hg-07.toml").write_text(block("hg-07.toml"), encoding="utf-8")
    monkeypatch.setattr(presets, "_directory", lambda: folder)
    presets.preset_registry.cache_clear()
    try:
        assert "hg-07" in presets.list_presets()
        assert presets.preset_registry()["hg-07"].summary.startswith("Henyey-Greenstein aerosol")
        assert main(["presets"]) == 0
        assert "hg-07" in capsys.readouterr().out
        table = presets.build_preset("hg-07")
        expected = tabulated_phase.renormalize(
            tabulated_phase.tabulate(phase.henyey_greenstein, theta_deg=table.theta_deg, g=0.7),
            theta_deg=table.theta_deg,
        )
        np.testing.assert_allclose(table.phase[0], np.ravel(expected), rtol=1e-12)
    finally:
        monkeypatch.undo()
        presets.preset_registry.cache_clear()
    assert "hg-07" not in presets.list_presets()
