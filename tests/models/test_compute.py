"""The table a build configuration describes: build_table."""

from __future__ import annotations

import numpy as np
import pytest
from _model_configs import SMALL

from dustoptics.models.compute import build_table
from dustoptics.models.config import ConfigError, parse_config
from dustoptics.scattering import phase, tabulated_phase


def test_mean_cosine_of_sampled_henyey_greenstein() -> None:
    """HG(g) sampled at 0.1 deg and renormalized: mean cosine g to the sampling error."""
    theta = np.linspace(0, 180, 1801)
    for g in (-0.3, 0.0, 0.5, 0.8):
        p = tabulated_phase.renormalize(
            tabulated_phase.tabulate(phase.henyey_greenstein, theta_deg=theta, g=g), theta_deg=theta
        )
        assert tabulated_phase.mean_cosine(p, theta_deg=theta) == pytest.approx(g, abs=1e-5)


def test_progress_does_not_change_the_result() -> None:
    config = parse_config(SMALL)
    calls: list[tuple[int, int]] = []
    with_progress = build_table(
        config, workers=1, progress=lambda done, total: calls.append((done, total))
    )
    plain = build_table(config, workers=2)
    assert calls[0] == (0, 10) and calls[-1] == (10, 10)
    assert [d for d, _ in calls] == sorted(d for d, _ in calls) and len(calls) >= 3
    for key in ("phase", "g", "cext_um2", "csca_um2", "error_estimate"):
        assert with_progress.quantity(key).tobytes() == plain.quantity(key).tobytes()
    assert with_progress.provenance.to_dict() == plain.provenance.to_dict()


def test_number_density_and_sources() -> None:
    table = build_table(
        parse_config(
            SMALL.replace(
                'description = "test dust"',
                'description = "test dust"\nnumber_density_per_m3 = 2e8',
            )
        )
    )
    assert table.cross_sections.number_density_per_m3 == 2e8
    np.testing.assert_allclose(
        table.beta_ext_per_m, 2e8 * table.cross_sections.cext_um2 * 1e-12, rtol=1e-15
    )
    roles = [s.role for s in table.provenance.sources]
    assert roles == ["refractive index", "size distribution"]


def test_analytic_model_table() -> None:
    text = (
        'name = "hg"\ndescription = "HG"\n[optics]\nwavelengths_nm = [500, 600]\nn_theta = 721\n'
        '[phase]\nmodel = "henyey_greenstein"\ng = 0.6\n'
    )
    table = build_table(parse_config(text))
    assert table.cross_sections is None and table.phase.shape == (2, 721)
    np.testing.assert_allclose(
        tabulated_phase.sphere_integral(table.phase, theta_deg=table.theta_deg), 1.0, rtol=1e-13
    )
    np.testing.assert_allclose(table.g, 0.6, atol=1e-4)
    assert any("from the analytic formula" in n for n in table.provenance.notes)
    assert table.provenance.sources[0].name == "henyey_greenstein"


def test_build_rejects_non_config() -> None:
    with pytest.raises(TypeError, match="config must be a BuildConfig"):
        build_table({"name": "x"})  # type: ignore[arg-type]


def test_wolff2009_as_the_dust_and_as_the_host() -> None:
    """The Wolff et al. 2009 dust index in a configuration: alone (catalogue) and as the
    mars_dust host by name; the existing spellings of host_index still parse."""
    from dustoptics.particles.catalogue import get_material

    alone = parse_config(
        SMALL.replace(
            'model = "constant"\nn = 1.5\nk = 0.01',
            'model = "catalogue"\nname = "marsdust-wolff2009"',
        )
    )
    assert alone.material is not None
    assert alone.material.build() is get_material("marsdust-wolff2009")
    table = build_table(alone)
    # k > 0 at every row: the dust absorbs, so 0 < ssa < 1 (Bohren & Huffman 1983)
    assert table.wavelength_nm[0] == 400.0 and np.all((table.ssa > 0.0) & (table.ssa < 1.0))
    hosted = parse_config(
        SMALL.replace(
            'model = "constant"\nn = 1.5\nk = 0.01',
            'model = "mars_dust"\nhematite_fraction = 0.0\nhost_index = "marsdust-wolff2009"',
        )
    )
    assert hosted.material is not None
    assert hosted.to_inputs()["material"]["host_index"] == "marsdust-wolff2009"
    wavelength_nm = np.array([440.0, 550.0])
    np.testing.assert_array_equal(
        hosted.material.build()(wavelength_nm), get_material("marsdust-wolff2009")(wavelength_nm)
    )
    with pytest.raises(ConfigError, match="material.host_index"):
        parse_config(
            SMALL.replace(
                'model = "constant"\nn = 1.5\nk = 0.01',
                'model = "mars_dust"\nhost_index = "basalt"',
            )
        )
