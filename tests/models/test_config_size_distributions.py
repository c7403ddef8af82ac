"""Every registered size-distribution family, from a TOML configuration to a built table.

Each family is written as a ``[size_distribution]`` section, parsed, built into a small table,
and its effective radius checked three ways: the distribution the configuration builds, the
table's own quadrature (``r_eff_quadrature_um``, the Mie integral's radius nodes) and an
independent value (a closed form, or scipy's adaptive quadrature of the density written out
here).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _model_configs import SMALL
from scipy import integrate

from dustoptics.models.compute import build_table
from dustoptics.models.config import ConfigError, parse_config
from dustoptics.particles.sizedist import SIZE_DISTRIBUTION_ALIASES, SIZE_DISTRIBUTIONS

_SECTION = """[size_distribution]
model = "modified_gamma"
r_eff_um = 0.2
v_eff = 0.1
"""


def _r_eff_by_quad(pdf, low: float, high: float) -> float:
    """<r^3> / <r^2> of a density on [low, high], by scipy's adaptive quadrature."""
    m3 = integrate.quad(lambda r: r**3 * pdf(r), low, high, epsabs=0, epsrel=1e-12, limit=200)[0]
    m2 = integrate.quad(lambda r: r**2 * pdf(r), low, high, epsabs=0, epsrel=1e-12, limit=200)[0]
    return m3 / m2


def _mg_pdf(r: float) -> float:
    """Hansen & Travis's gamma, r_eff = 0.2 um, v_eff = 0.1 (unnormalized)."""
    a, b = 0.2, 0.1
    return r ** ((1 - 3 * b) / b) * math.exp(-r / (a * b))


def _gamma_moment(r_eff: float, v_eff: float, k: int) -> float:
    """<r^k> of Hansen & Travis's gamma: shape (1 - 2 v) / v, scale r v. [um^k]"""
    shape, scale = (1 - 2 * v_eff) / v_eff, r_eff * v_eff
    return scale**k * math.gamma(shape + k) / math.gamma(shape)


# Family -> (TOML section, independent effective radius [um]).
CASES: dict[str, tuple[str, float]] = {
    "modified_gamma": ('model = "modified_gamma"\nr_eff_um = 0.2\nv_eff = 0.1\n', 0.2),
    # Gamma(shape k, scale s): r_eff = s (k + 2) (Hansen & Travis 1974, eq. 2.56).
    "gamma": ('model = "gamma"\nshape = 8.0\nscale_um = 0.025\n', 0.025 * 10.0),
    # Log-normal: r_eff = r_g exp(5 sigma^2 / 2) (Hansen & Travis 1974, eq. 2.53).
    "log_normal": (
        'model = "log_normal"\nmedian_radius_um = 0.15\nsigma = 0.3\n',
        0.15 * math.exp(2.5 * 0.09),
    ),
    "modified_log_normal": ('model = "modified_log_normal"\nr_eff_um = 0.25\nv_eff = 0.1\n', 0.25),
    "monodisperse": ('model = "monodisperse"\nradius_um = 0.3\n', 0.3),
    # a r^alpha exp(-b r^gamma) with gamma = 1 is Gamma(alpha + 1, 1 / b): r_eff = (alpha + 3) / b.
    "deirmendjian_gamma": (
        'model = "deirmendjian_gamma"\nalpha = 4.0\nb = 35.0\ngamma = 1.0\n',
        7.0 / 35.0,
    ),
    # r^-3 on [0.1, 0.5]: <r^3> / <r^2> = (0.5 - 0.1) / ln 5.
    "power_law": (
        'model = "power_law"\nexponent = 3.0\nr_min_um = 0.1\nr_max_um = 0.5\n',
        0.4 / math.log(5.0),
    ),
    "truncated": (
        'model = "truncated"\nr_min_um = 0.1\nr_max_um = 0.3\n'
        'parent = { model = "modified_gamma", r_eff_um = 0.2, v_eff = 0.1 }\n',
        _r_eff_by_quad(_mg_pdf, 0.1, 0.3),
    ),
    # Two Hansen-Travis modes, equal numbers: sum <r^3> / sum <r^2> from the gamma moments.
    "multimodal": (
        'model = "multimodal"\n\n'
        '[[size_distribution.modes]]\nmodel = "modified_gamma"\nr_eff_um = 0.1\nv_eff = 0.1\n'
        "relative_number_density = 1.0\n\n"
        '[[size_distribution.modes]]\nmodel = "modified_gamma"\nr_eff_um = 0.3\nv_eff = 0.1\n'
        "relative_number_density = 1.0\n",
        (_gamma_moment(0.1, 0.1, 3) + _gamma_moment(0.3, 0.1, 3))
        / (_gamma_moment(0.1, 0.1, 2) + _gamma_moment(0.3, 0.1, 2)),
    ),
    # Flat between 0.1 and 0.3 um: (r^4 / 4) / (r^3 / 3) between the ends.
    "tabulated": (
        'model = "tabulated"\nradius_um = [0.1, 0.2, 0.3]\ndn_dr = [1.0, 1.0, 1.0]\n',
        ((0.3**4 - 0.1**4) / 4) / ((0.3**3 - 0.1**3) / 3),
    ),
}


def _config_text(section: str) -> str:
    return SMALL.replace(_SECTION, "[size_distribution]\n" + section)


def test_every_family_that_toml_can_name_is_tested_here() -> None:
    assert set(CASES) == set(SIZE_DISTRIBUTIONS) - {"density_function"}
    assert len(CASES) == 10


@pytest.mark.parametrize("family", sorted(CASES))
def test_family_from_toml_to_table(family: str) -> None:
    section, expected_um = CASES[family]
    text = _config_text(section)
    assert text != SMALL or family == "modified_gamma"
    config = parse_config(text)
    dist = config.size_distribution.build()
    assert dist.model == family
    assert dist.r_eff_um == pytest.approx(expected_um, rel=1e-9)
    table = build_table(config, workers=1)
    # The table's radius quadrature integrates the same distribution.
    np.testing.assert_allclose(table.quadrature.r_eff_quadrature_um, expected_um, rtol=2e-3)
    assert table.provenance.inputs["size_distribution"]["model"] == family


def test_an_alias_names_its_family_and_the_table_records_the_family() -> None:
    """Hansen & Travis's gamma (``ModifiedGamma``; scatrs calls it ``Gamma``) by its alias."""
    assert SIZE_DISTRIBUTION_ALIASES["hansen_travis1974_gamma"] == "modified_gamma"
    config = parse_config(
        _config_text('model = "hansen_travis1974_gamma"\nr_eff_um = 0.2\nv_eff = 0.1\n')
    )
    assert config.size_distribution.to_inputs() == {
        "model": "modified_gamma",
        "r_eff_um": 0.2,
        "v_eff": 0.1,
    }


@pytest.mark.parametrize(
    ("section", "key", "match"),
    [
        (
            'model = "power_law"\nexponent = 3.0\nr_min_um = 0.5\nr_max_um = 0.1\n',
            "size_distribution",
            "r_max_um must be finite and > r_min_um",
        ),
        (
            'model = "deirmendjian_gamma"\nalpha = -2.0\nb = 1.0\ngamma = 1.0\n',
            "size_distribution.alpha",
            r"must be in the open interval \(-1, inf\)",
        ),
        (
            'model = "tabulated"\nradius_um = [0.1, "x"]\ndn_dr = [1.0, 1.0]\n',
            r"size_distribution.radius_um\[1\]",
            "must be a number",
        ),
        (
            'model = "truncated"\nr_min_um = 0.1\nr_max_um = 0.3\nparent = 1.0\n',
            "size_distribution.parent",
            "must be a table",
        ),
        (
            'model = "truncated"\nr_min_um = 0.1\nr_max_um = 0.3\n'
            'parent = { model = "monodisperse", radius_um = 0.2, sigma = 1.0 }\n',
            "size_distribution.parent",
            "sigma",
        ),
    ],
)
def test_new_families_name_the_bad_key(section: str, key: str, match: str) -> None:
    with pytest.raises(ConfigError, match=match) as caught:
        parse_config(_config_text(section))
    assert caught.value.key is not None and caught.value.key.startswith(key.replace("\\", ""))
