"""Tests of dustoptics.particles.mixing: the mixing rules, Mixture, and the Mars dust model.

Property-based tests (hypothesis) come first, then worked values and errors.
"""

from __future__ import annotations

import cmath
import csv

import numpy as np
import pytest
from _data import data_path
from hypothesis import example, given, settings
from hypothesis import strategies as st

from dustoptics.particles.catalogue import get_material
from dustoptics.particles.materials import ConstantIndex, TabulatedIndex
from dustoptics.particles.mixing import (
    MIXING_RULES,
    Mixture,
    bruggeman,
    mars_dust,
    maxwell_garnett,
)

RULES = {"maxwell_garnett": maxwell_garnett, "bruggeman": bruggeman}
VISIBLE_NM = np.arange(360.0, 831.0, 10.0)

# Refractive indices n + ik over the range of minerals and hosts we mix:
# n in [1, 3.5], k in [0, 2] (hematite in the UV reaches n = 1.1, k = 1.15).
indices = st.builds(complex, st.floats(1.0, 3.5), st.floats(0.0, 2.0))
lossless = st.builds(complex, st.floats(1.0, 3.5), st.just(0.0))
fractions = st.floats(0.0, 1.0)
rules = st.sampled_from(sorted(RULES))
property_settings = settings(max_examples=60, deadline=None)


def clausius_mossotti_slope(eps_h: complex, eps_i: complex) -> complex:
    """d eps_eff / dv at v = 0 for spheres: 3 eps_h (eps_i - eps_h) / (eps_i + 2 eps_h)."""
    return 3 * eps_h * (eps_i - eps_h) / (eps_i + 2 * eps_h)


def mg_by_hand(n0: complex, na: complex, v: float) -> complex:
    """Maxwell Garnett as printed in the BRIEF, for host n0, inclusion nA."""
    n0s, nas = n0 * n0, na * na
    n2 = n0s * (nas + 2 * n0s + 2 * v * (nas - n0s)) / (nas + 2 * n0s - v * (nas - n0s))
    return cmath.sqrt(n2)


# ---------------------------------------------------------------------------
# Properties of both rules
# ---------------------------------------------------------------------------


@property_settings
@given(host=indices, inclusion=indices, rule=rules)
def test_limits_are_exact(host: complex, inclusion: complex, rule: str) -> None:
    mix = RULES[rule]
    assert complex(mix(host=host, inclusion=inclusion, volume_fraction=0.0)) == host
    assert complex(mix(host=host, inclusion=inclusion, volume_fraction=1.0)) == inclusion
    # and the formula itself tends to them
    assert abs(complex(mix(host=host, inclusion=inclusion, volume_fraction=1e-13)) - host) < 1e-11
    assert (
        abs(complex(mix(host=host, inclusion=inclusion, volume_fraction=1 - 1e-13)) - inclusion)
        < 1e-11
    )


@property_settings
@given(host=indices, inclusion=indices, v=fractions, rule=rules)
@example(host=1 + 0j, inclusion=1.458492703233595 + 1j, v=1.4337757096272803e-263, rule="bruggeman")
@example(host=1 + 0j, inclusion=1 + 5e-324j, v=0.5, rule="bruggeman")
def test_passive_inputs_give_passive_output(
    host: complex, inclusion: complex, v: float, rule: str
) -> None:
    m = complex(RULES[rule](host=host, inclusion=inclusion, volume_fraction=v))
    assert m.imag >= 0.0 and m.real > 0.0
    # Strictly absorbing when an input absorbs, unless its k is so small that
    # k * v underflows (a denormal k such as 5e-324 has no representable share).
    if (host.imag > 1e-280 or inclusion.imag > 1e-280) and 1e-6 <= v <= 1 - 1e-6:
        assert m.imag > 0.0


@property_settings
@given(host=indices, v=fractions, rule=rules)
def test_host_equal_to_inclusion_returns_the_host(host: complex, v: float, rule: str) -> None:
    m = complex(RULES[rule](host=host, inclusion=host, volume_fraction=v))
    assert m == pytest.approx(host, rel=1e-12)


@property_settings
@given(host=indices, inclusion=indices, rule=rules)
def test_dilute_limit_slope_is_clausius_mossotti(
    host: complex, inclusion: complex, rule: str
) -> None:
    h = 1e-7
    eps_h = host**2
    slope = (
        complex(RULES[rule](host=host, inclusion=inclusion, volume_fraction=h)) ** 2 - eps_h
    ) / h
    expected = clausius_mossotti_slope(eps_h, inclusion**2)
    assert abs(slope - expected) <= 1e-5 * (abs(expected) + abs(eps_h))


@property_settings
@given(host=indices, inclusion=indices)
def test_maxwell_garnett_equals_bruggeman_to_first_order(host: complex, inclusion: complex) -> None:
    for v in (1e-3, 1e-4):
        mg = complex(maxwell_garnett(host=host, inclusion=inclusion, volume_fraction=v)) ** 2
        br = complex(bruggeman(host=host, inclusion=inclusion, volume_fraction=v)) ** 2
        first_order = abs(clausius_mossotti_slope(host**2, inclusion**2)) * v
        # the difference is O(v^2): a vanishing fraction of the first-order change
        assert abs(mg - br) <= 50 * v * (first_order + v * abs(host**2))


@property_settings
@given(host=lossless, inclusion=lossless, v=fractions, rule=rules)
def test_lossless_mixtures_lie_within_the_wiener_bounds(
    host: complex, inclusion: complex, v: float, rule: str
) -> None:
    eps_h, eps_i = host.real**2, inclusion.real**2
    eps = complex(RULES[rule](host=host, inclusion=inclusion, volume_fraction=v)) ** 2
    harmonic = 1 / ((1 - v) / eps_h + v / eps_i)
    arithmetic = (1 - v) * eps_h + v * eps_i
    assert abs(eps.imag) <= 1e-12 * abs(eps)
    assert harmonic * (1 - 1e-12) <= eps.real <= arithmetic * (1 + 1e-12)
    assert min(eps_h, eps_i) * (1 - 1e-12) <= eps.real <= max(eps_h, eps_i) * (1 + 1e-12)


# ---------------------------------------------------------------------------
# Bruggeman: root choice
# ---------------------------------------------------------------------------


@property_settings
@given(host=indices, inclusion=indices, v=fractions)
def test_bruggeman_solves_its_equation_and_is_symmetric(
    host: complex, inclusion: complex, v: float
) -> None:
    eps = complex(bruggeman(host=host, inclusion=inclusion, volume_fraction=v)) ** 2
    eps_h, eps_i = host**2, inclusion**2
    residual = v * (eps_i - eps) / (eps_i + 2 * eps) + (1 - v) * (eps_h - eps) / (eps_h + 2 * eps)
    assert abs(residual) < 1e-10
    swapped = complex(bruggeman(host=inclusion, inclusion=host, volume_fraction=1 - v)) ** 2
    assert swapped == pytest.approx(eps, rel=1e-9, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    host=st.builds(complex, st.floats(1.0, 4.0), st.floats(0.0, 3.0)),
    inclusion=st.builds(complex, st.floats(1.0, 4.0), st.floats(0.0, 3.0)),
)
def test_bruggeman_root_is_continuous_from_host_to_inclusion(
    host: complex, inclusion: complex
) -> None:
    v = np.linspace(0.0, 1.0, 2001)
    eps = bruggeman(host=host, inclusion=inclusion, volume_fraction=v) ** 2
    scale = max(abs(host**2), abs(inclusion**2))
    assert np.max(np.abs(np.diff(eps))) < 0.01 * scale
    assert np.all(eps.imag >= -1e-12 * scale)


# ---------------------------------------------------------------------------
# Arrays, worked values, errors
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("rule", sorted(RULES))
def test_rules_broadcast_and_keep_scalars_0d(rule: str) -> None:
    mix = RULES[rule]
    host = np.array([[1.5], [1.6], [1.7]])
    fraction = np.array([0.0, 0.01, 0.1, 1.0])
    out = mix(host=host, inclusion=2.9 + 0.46j, volume_fraction=fraction)
    assert out.shape == (3, 4) and out.dtype == np.complex128
    for i in range(3):
        for j in range(4):
            single = mix(
                host=complex(host[i, 0]), inclusion=2.9 + 0.46j, volume_fraction=float(fraction[j])
            )
            assert complex(out[i, j]) == pytest.approx(complex(single), rel=1e-15)
    scalar = mix(host=1.5, inclusion=2.9 + 0.46j, volume_fraction=0.03)
    assert scalar.shape == () and scalar.dtype == np.complex128


def test_maxwell_garnett_hand_value_for_the_blue_moons_dust() -> None:
    # Host 1.5, Querry (1985) extraordinary hematite at 550 nm (2.927 + 0.460i), 3 % by volume.
    expected = mg_by_hand(1.5, 2.927 + 0.460j, 0.03)
    assert complex(
        maxwell_garnett(host=1.5, inclusion=2.927 + 0.460j, volume_fraction=0.03)
    ) == pytest.approx(expected, rel=1e-15)
    assert complex(mars_dust()(550.0)) == pytest.approx(expected, rel=1e-15)
    assert expected == pytest.approx(1.5336717 + 0.0071677j, abs=1e-7)


def test_mars_dust_matches_the_hand_formula_on_the_reference_table() -> None:
    path = data_path("refractive-index", "ri_hematite_querry1985_extraordinary.csv")
    lines = [
        line for line in path.read_text(encoding="utf-8").splitlines() if not line.startswith("#")
    ]
    table = {
        round(float(r["wavelength_um"]) * 1000, 6): complex(float(r["n"]), float(r["k"]))
        for r in csv.DictReader(lines)
    }
    dust = mars_dust()
    for wavelength in VISIBLE_NM:
        assert complex(dust(wavelength)) == pytest.approx(
            mg_by_hand(1.5, table[wavelength], 0.03), rel=1e-14
        )


@pytest.mark.parametrize("rule", sorted(RULES))
@pytest.mark.parametrize(
    ("arguments", "pattern"),
    [
        (
            {"host": 1.5, "inclusion": 2.9, "volume_fraction": 1.1},
            r"volume_fraction must be in the closed interval \[0, 1\]; got \[?1\.1",
        ),
        (
            {"host": 1.5, "inclusion": 2.9, "volume_fraction": -0.1},
            r"volume_fraction must be in the closed interval \[0, 1\]",
        ),
        (
            {"host": 1.5, "inclusion": 2.9, "volume_fraction": np.nan},
            "volume_fraction must be finite",
        ),
        (
            {"host": 1.5 - 0.1j, "inclusion": 2.9, "volume_fraction": 0.1},
            r"host must be .* k >= 0.*\(1\.5-0\.1j\)",
        ),
        ({"host": 1.5, "inclusion": -2.9, "volume_fraction": 0.1}, r"inclusion must be .*n > 0"),
        (
            {"host": 1.5, "inclusion": complex(np.nan, 0), "volume_fraction": 0.1},
            "inclusion must be finite",
        ),
        (
            {"host": [1.5, 1.6], "inclusion": [2.9, 3.0, 3.1], "volume_fraction": 0.1},
            r"must broadcast together; got shapes \(2,\), \(3,\)",
        ),
    ],
)
def test_rules_reject_bad_input(rule: str, arguments: dict[str, object], pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        RULES[rule](**arguments)  # type: ignore[arg-type]


def test_rules_are_keyword_only() -> None:
    with pytest.raises(TypeError):
        maxwell_garnett(1.5, 2.9, 0.1)  # type: ignore[misc]
    with pytest.raises(TypeError):
        bruggeman(1.5, 2.9, 0.1)  # type: ignore[misc]


# ---------------------------------------------------------------------------
# Mixture
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("rule", MIXING_RULES)
def test_mixture_evaluates_its_rule_per_wavelength(rule: str) -> None:
    hematite = get_material("querry-ordinary")
    mixture = Mixture(host=1.5 + 0.001j, inclusion=hematite, volume_fraction=0.1, rule=rule)
    expected = RULES[rule](host=1.5 + 0.001j, inclusion=hematite(VISIBLE_NM), volume_fraction=0.1)
    np.testing.assert_array_equal(mixture(VISIBLE_NM), expected)
    assert mixture.wavelength_range_nm == hematite.wavelength_range_nm
    assert mixture.name == f"{rule}(0.1 hematite-querry1985-ordinary in constant 1.5+0.001j)"
    assert hematite.citation in mixture.citation
    assert ("Maxwell Garnett" if rule == "maxwell_garnett" else "Bruggeman") in mixture.citation


def test_mixture_limits_and_string_components() -> None:
    hematite = get_material("querry-extraordinary")
    np.testing.assert_array_equal(
        Mixture(host=1.5, inclusion=hematite, volume_fraction=0.0)(VISIBLE_NM),
        np.full(48, 1.5 + 0j),
    )
    np.testing.assert_array_equal(
        Mixture(host=1.5, inclusion="querry-extraordinary", volume_fraction=1.0)(VISIBLE_NM),
        hematite(VISIBLE_NM),
    )
    mixture = Mixture(host=1.5, inclusion="querry-extraordinary", volume_fraction=0.03)
    assert mixture.inclusion is hematite and mixture.host == ConstantIndex(value=1.5)


def test_mixture_range_is_the_intersection() -> None:
    host = TabulatedIndex(
        name="host-table", citation="test", wavelength_nm=[300.0, 700.0], n=[1.5, 1.5], k=[0.0, 0.0]
    )
    mixture = Mixture(host=host, inclusion="querry-extraordinary", volume_fraction=0.03)
    assert mixture.wavelength_range_nm == (300.0, 700.0)
    with pytest.raises(
        ValueError,
        match=r"maxwell_garnett\(0\.03 hematite-querry1985-extraordinary in host-table\).*\[300, 700\] nm.*800",
    ):
        mixture(800.0)


@pytest.mark.parametrize(
    ("arguments", "error", "pattern"),
    [
        (
            {"rule": "looyenga"},
            ValueError,
            r"rule must be one of 'maxwell_garnett', 'bruggeman'; got 'looyenga'",
        ),
        (
            {"volume_fraction": 1.5},
            ValueError,
            r"volume_fraction must be in the closed interval \[0\.0, 1\.0\]; got 1\.5",
        ),
        ({"host": 1.5 - 0.1j}, ValueError, r"host must have imaginary part k >= 0"),
        (
            {"inclusion": "unobtainium"},
            ValueError,
            r"Valid names: .*hematite-querry1985-extraordinary",
        ),
        ({"host": None}, TypeError, r"host must be a RefractiveIndex"),
    ],
)
def test_mixture_rejects_bad_input(
    arguments: dict[str, object], error: type[Exception], pattern: str
) -> None:
    base: dict[str, object] = {
        "host": 1.5,
        "inclusion": "querry-extraordinary",
        "volume_fraction": 0.03,
    }
    with pytest.raises(error, match=pattern):
        Mixture(**{**base, **arguments})  # type: ignore[arg-type]


# ---------------------------------------------------------------------------
# mars_dust
# ---------------------------------------------------------------------------


def test_mars_dust_defaults_are_the_blue_moons_model() -> None:
    dust = mars_dust()
    m = complex(dust(550.0))
    assert 1.5 < m.real < 1.6 and 0.0 < m.imag < 0.05
    reference = Mixture(
        host=1.5, inclusion=get_material("hematite-querry1985-extraordinary"), volume_fraction=0.03
    )
    np.testing.assert_array_equal(dust(VISIBLE_NM), reference(VISIBLE_NM))
    assert dust.wavelength_range_nm == (210.0, 55555.6)
    assert "doi:10.1364/AO.53.001808" in dust.citation and "Querry" in dust.citation
    # Hematite absorbs blue more than red: the model's k falls from 440 to 680 nm.
    assert complex(dust(440.0)).imag > complex(dust(680.0)).imag


@pytest.mark.parametrize(
    ("hematite", "catalogue_name"),
    [
        ("querry-extraordinary", "hematite-querry1985-extraordinary"),
        ("querry-ordinary", "hematite-querry1985-ordinary"),
        ("querry-average", "hematite-querry1985-average"),
        ("hematite-querry1985-ordinary", "hematite-querry1985-ordinary"),
    ],
)
def test_mars_dust_hematite_choices(hematite: str, catalogue_name: str) -> None:
    dust = mars_dust(
        hematite=hematite, hematite_fraction=0.05, host_index=1.5 + 0.001j, rule="bruggeman"
    )
    assert dust.inclusion is get_material(catalogue_name)
    expected = bruggeman(
        host=1.5 + 0.001j, inclusion=get_material(catalogue_name)(VISIBLE_NM), volume_fraction=0.05
    )
    np.testing.assert_array_equal(dust(VISIBLE_NM), expected)


@pytest.mark.parametrize(
    ("arguments", "pattern"),
    [
        (
            {"hematite_fraction": 1.2},
            r"hematite_fraction must be in the closed interval \[0\.0, 1\.0\]; got 1\.2",
        ),
        ({"hematite_fraction": -0.01}, r"hematite_fraction must be in the closed interval"),
        (
            {"hematite": "goethite"},
            r"hematite must be one of 'querry-extraordinary', 'querry-ordinary', 'querry-average'.*got 'goethite'",
        ),
        ({"hematite": "magnetite-querry1985"}, r"hematite must be one of"),
        ({"rule": "mg"}, r"rule must be one of 'maxwell_garnett', 'bruggeman'"),
        ({"host_index": 1.5 - 0.01j}, r"host_index must have imaginary part k >= 0"),
        ({"host_index": 0.0}, r"host_index must have real part n > 0"),
    ],
)
def test_mars_dust_rejects_bad_input(arguments: dict[str, object], pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        mars_dust(**arguments)  # type: ignore[arg-type]


def test_mars_dust_host_must_be_an_index() -> None:
    with pytest.raises(TypeError, match="host_index must be a RefractiveIndex"):
        mars_dust(host_index=[1.5])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="host_index must be .* catalogue name .*got 'basalt'"):
        mars_dust(host_index="basalt")


def test_mars_dust_wolff2009_host_and_dust() -> None:
    """Wolff et al. 2009 as the host; with no hematite it is the dust itself, exactly
    (Maxwell Garnett at v = 0 returns the host, an identity of the rule)."""
    wolff = get_material("marsdust-wolff2009")
    wavelength_nm = np.array([440.0, 550.0, 700.0])
    dust = mars_dust(host_index="marsdust-wolff2009", hematite_fraction=0.0)
    np.testing.assert_array_equal(dust(wavelength_nm), wolff(wavelength_nm))
    mixed = mars_dust(host_index="marsdust-wolff2009")
    expected = maxwell_garnett(
        host=wolff(wavelength_nm),
        inclusion=get_material("querry-extraordinary")(wavelength_nm),
        volume_fraction=0.03,
    )
    np.testing.assert_array_equal(mixed(wavelength_nm), expected)
    assert "Wolff" in mixed.citation
