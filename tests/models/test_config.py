"""Build configurations: the schema, and errors that name the key and line."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _model_configs import SMALL, edit

from dustoptics.models import presets
from dustoptics.models.config import BuildConfig, ConfigError, parse_config


def _line_of(text: str, fragment: str) -> int:
    """1-based line of the first line starting with ``fragment`` (independent of the parser)."""
    lines = text.splitlines()
    for i, line in enumerate(lines, start=1):
        if line.startswith(fragment):
            return i
    return next(
        i for i, ln in enumerate(lines, start=1) if fragment in ln and not ln.startswith("#")
    )


def _short(value: object) -> str | None:
    """Test ids: the short parameters, not the configuration texts."""
    return "" if isinstance(value, str) and "\n" in value else None


# ------------------------------------------------------------------ errors

COSMO = presets.preset_text("cosmoscout-mars")
HYBRID = presets.preset_text("hybrid")
COLLIENNE = presets.preset_text("collienne")
BLUE = presets.preset_text("blue-moons")


@pytest.mark.parametrize(
    ("text", "key", "fragment", "reason"),
    [
        # unknown key, inside the second array-of-tables element; allowed keys listed
        (
            edit(COSMO, "v_eff = 0.35", "v_eff = 0.35\nr_eff = 3"),
            "size_distribution.modes[1].r_eff",
            "r_eff = 3",
            "unknown key .*allowed keys: model, r_eff_um, v_eff, relative_number_density",
        ),
        # out of range
        (
            edit(BLUE, "v_eff = 0.2 ", "v_eff = 0.7 "),
            "size_distribution.v_eff",
            "v_eff = 0.7",
            r"must be in the open interval \(0, 0.5\); got 0.7",
        ),
        (
            edit(COSMO, "v_eff = 0.35", "v_eff = -0.35"),
            "size_distribution.modes[1].v_eff",
            "v_eff = -0.35",
            "must be > 0; got -0.35",
        ),
        (
            edit(COLLIENNE, "g = 0.8", "g = 1.0"),
            "phase.g",
            "g = 1.0",
            r"must be in the open interval \(-1.0, 1.0\); got 1.0",
        ),
        (edit(COLLIENNE, "g = 0.8", "g = -1.5"), "phase.g", "g = -1.5", "open interval"),
        (
            edit(HYBRID, "weight = 0.5", "weight = 1.5"),
            "phase.weight",
            "weight = 1.5",
            r"must be in the closed interval \[0, 1\]; got 1.5",
        ),
        (
            edit(HYBRID, "weight = 0.5", "weight = -0.1"),
            "phase.weight",
            "weight = -0.1",
            "closed interval",
        ),
        (
            edit(BLUE, "hematite_fraction = 0.03", "hematite_fraction = 1.03"),
            "material.hematite_fraction",
            "hematite_fraction = 1.03",
            r"closed interval \[0, 1\]",
        ),
        (edit(BLUE, "rtol = 1e-4", "rtol = 0.5"), "optics.rtol", "rtol = 0.5", "open interval"),
        (
            edit(BLUE, "n_theta = 1801", "n_theta = 1"),
            "optics.n_theta",
            "n_theta = 1",
            "integer >= 2",
        ),
        # wrong type
        (
            edit(BLUE, "rtol = 1e-4", 'rtol = "small"'),
            "optics.rtol",
            'rtol = "small"',
            "must be a number; got 'small' \\(string\\)",
        ),
        (
            edit(BLUE, "n_theta = 1801", "n_theta = 1801.0"),
            "optics.n_theta",
            "n_theta = 1801.0",
            "must be an integer",
        ),
        (
            edit(BLUE, "r_eff_um = 1.6", "r_eff_um = true"),
            "size_distribution.r_eff_um",
            "r_eff_um = true",
            "must be a number; got True \\(boolean\\)",
        ),
        # bad choice: lists the valid ones
        (
            edit(BLUE, 'weighting = "scattering"', 'weighting = "area"'),
            "optics.weighting",
            'weighting = "area"',
            "must be one of 'scattering', 'number'; got 'area'",
        ),
        (
            edit(BLUE, 'model = "mie"', 'model = "miie"'),
            "phase.model",
            'model = "miie"',
            "must be one of 'mie', 'hybrid', 'costa2021_mars_dhg', ",
        ),
        (
            edit(HYBRID, 'outside = "clamp"', 'outside = "extrapolate"'),
            "phase.outside",
            'outside = "extrapolate"',
            "must be one of 'quadratic', 'clamp', 'error'",
        ),
        # grid checks
        (
            edit(BLUE, "step = 10 }", "step = 7 }"),
            "optics.wavelengths_nm.step",
            "step = 7",
            "whole steps",
        ),
        (
            edit(BLUE, "{ start = 360, stop = 830, step = 10 }", "[550, 450]"),
            "optics.wavelengths_nm",
            "wavelengths_nm = [550, 450]",
            "strictly increasing",
        ),
        (
            edit(BLUE, "n_theta = 1801", "n_theta = 1801\ntheta_step_deg = 0.1"),
            "optics.theta_step_deg",
            "theta_step_deg = 0.1",
            "not both",
        ),
        (
            edit(BLUE, "n_theta = 1801", "theta_step_deg = 0.7"),
            "optics.theta_step_deg",
            "theta_step_deg = 0.7",
            "divide 180",
        ),
        # options an analytic model does not use are errors, not ignored
        (
            edit(COLLIENNE, "[optics]", '[optics]\nweighting = "number"'),
            "optics.weighting",
            'weighting = "number"',
            "not used by phase.model = 'cornette_shanks1992'",
        ),
        (
            edit(
                COLLIENNE, 'name = "collienne"', 'name = "collienne"\nnumber_density_per_m3 = 1e8'
            ),
            "number_density_per_m3",
            "number_density_per_m3",
            "not used",
        ),
    ],
    ids=_short,
)
def test_errors_name_key_and_line(text: str, key: str, fragment: str, reason: str) -> None:
    with pytest.raises(ConfigError, match=reason) as info:
        parse_config(text, source="my.toml")
    err = info.value
    assert err.key == key
    assert err.line == _line_of(text, fragment)
    assert err.source == "my.toml"
    assert str(err).startswith(f"my.toml:{err.line}: {key}: ")


@pytest.mark.parametrize(
    ("text", "key", "header"),
    [
        # missing keys point at the table header they belong in
        (edit(COSMO, "r_eff_um = 1.4", ""), "size_distribution.modes[1].r_eff_um", None),
        (
            edit(BLUE, 'model = "modified_gamma"', ""),
            "size_distribution.model",
            "[size_distribution]",
        ),
        (edit(COLLIENNE, "g = 0.8", ""), "phase.g", "[phase]"),
        (edit(BLUE, "[material]", "[materials]"), "materials", "[materials]"),
    ],
    ids=_short,
)
def test_missing_and_unknown_keys(text: str, key: str, header: str | None) -> None:
    with pytest.raises(ConfigError) as info:
        parse_config(text)
    assert info.value.key == key
    if header is None:  # the second [[size_distribution.modes]] header
        lines = [
            i
            for i, ln in enumerate(text.splitlines(), 1)
            if ln.startswith("[[size_distribution.modes]]")
        ]
        assert info.value.line == lines[1]
    else:
        assert info.value.line == _line_of(text, header)


def test_missing_top_level_key_has_no_line() -> None:
    with pytest.raises(ConfigError, match=r"^<string>: name: missing required key$") as info:
        parse_config('description = "x"\n[phase]\nmodel = "rayleigh"\n')
    assert info.value.line is None


def test_unknown_top_level_key_lists_allowed() -> None:
    with pytest.raises(
        ConfigError, match="unknown key; allowed keys: name, description, choices"
    ) as info:
        parse_config('name = "x"\ndescription = "x"\ncolour = "red"\n')
    assert (info.value.key, info.value.line) == ("colour", 3)


def test_malformed_toml_line_from_tomllib() -> None:
    text = edit(BLUE, "n_theta = 1801", "n_theta = ")
    with pytest.raises(ConfigError, match="invalid TOML") as info:
        parse_config(text, source="my.toml")
    assert info.value.key is None
    assert info.value.line == _line_of(text, "n_theta = ")
    assert str(info.value).startswith(f"my.toml:{info.value.line}: invalid TOML: ")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("x = " + "[" * 3000 + "]" * 3000, "invalid TOML: nested too deeply to read"),
        ("x = " + "1" * 5000, "invalid TOML: Exceeds the limit"),
    ],
    ids=["3000 levels deep", "5000 digits"],
)
def test_toml_too_deep_or_too_long_is_a_config_error(extra: str, message: str) -> None:
    with pytest.raises(ConfigError, match=f"^my.toml: {message}"):
        parse_config(SMALL + "\n" + extra + "\n", source="my.toml")


def test_an_integer_beyond_the_float_range_is_named() -> None:
    text = edit(SMALL, "r_eff_um = 0.2", "r_eff_um = 1" + "0" * 400)
    with pytest.raises(
        ConfigError,
        match="size_distribution.r_eff_um: must be a finite number; got an integer beyond",
    ):
        parse_config(text)


def test_config_error_is_value_error() -> None:
    assert issubclass(ConfigError, ValueError)


def test_line_scanner_ignores_brackets_and_keys_in_strings() -> None:
    text = (
        'name = "x"\n'
        'description = "a [b] = c"\n'
        'choices = [\n  "g = 0.5 [not a key]",\n  """\n[phase]\nmodel = 1\n""",\n]\n'
        "[phase]\n"
        'model = "cornette_shanks1992"\n'
        "g = 2\n"
    )
    with pytest.raises(ConfigError) as info:
        parse_config(text)
    assert (info.value.key, info.value.line) == ("phase.g", 12)


# ----------------------------------------------------------- the schema


def test_defaults_filled_in() -> None:
    config = parse_config(
        'name = "d"\ndescription = "d"\n[material]\nmodel = "mars_dust"\n'
        '[size_distribution]\nmodel = "modified_gamma"\nr_eff_um = 1.6\nv_eff = 0.2\n'
    )
    inputs = config.to_inputs()
    assert inputs["phase"] == {"model": "mie"}
    assert inputs["material"] == {
        "model": "mars_dust",
        "hematite_fraction": 0.03,
        "host_index": {"n": 1.5, "k": 0.0},
        "hematite": "hematite-querry1985-extraordinary",
        "rule": "maxwell_garnett",
    }
    assert inputs["optics"]["weighting"] == "scattering"
    assert inputs["optics"]["rtol"] == 1e-4
    assert inputs["optics"]["cross_section_rtol"] == 1e-6
    assert inputs["optics"]["n_theta"] == 1801
    assert inputs["optics"]["wavelengths_nm"] == list(np.arange(360.0, 831.0, 10.0))
    # the physics of blue-moons, which states everything explicitly
    blue = presets.load_preset("blue-moons").to_inputs()
    assert {k: inputs[k] for k in ("material", "size_distribution", "optics", "phase")} == {
        k: blue[k] for k in ("material", "size_distribution", "optics", "phase")
    }


def test_equivalent_spellings_give_the_same_inputs() -> None:
    reference = presets.load_preset("blue-moons").to_inputs()
    wl = ", ".join(f"{w:g}" for w in range(360, 831, 10))
    variants = [
        edit(BLUE, "n_theta = 1801", "theta_step_deg = 0.1"),
        edit(BLUE, "{ start = 360, stop = 830, step = 10 }", f"[{wl}]"),
        edit(BLUE, "host_index = { n = 1.5, k = 0.0 }", "host_index = 1.5"),
        edit(
            BLUE,
            'hematite = "querry-extraordinary"',
            'hematite = "hematite-querry1985-extraordinary"',
        ),
        edit(BLUE, 'description = "', 'description = "edited: '),
    ]
    for text in variants:
        assert parse_config(text).to_inputs() == reference


def test_hybrid_defaults_weight_and_analytic() -> None:
    text = edit(HYBRID, "weight = 0.5", "").replace('analytic = "costa2021_mars_dhg"', "")
    text = text.replace('outside = "clamp"', "")
    ph = parse_config(text).phase
    assert (ph.weight, ph.analytic, dict(ph.parameters)) == (
        0.5,
        "costa2021_mars_dhg",
        {"outside": "quadratic"},
    )


def test_material_forms() -> None:
    catalogue = BLUE.replace(
        '[material]\nmodel = "mars_dust"',
        '[material]\nmodel = "catalogue"\nname = "magnetite-querry1985"\n#',
    )
    catalogue = "\n".join(
        ln
        for ln in catalogue.splitlines()
        if not ln.startswith(("hematite_fraction", "host_index", "hematite =", "rule ="))
    )
    assert parse_config(catalogue).material.build().name == "magnetite-querry1985"
    bad = catalogue.replace('name = "magnetite-querry1985"', 'name = "unobtainium"')
    with pytest.raises(
        ConfigError, match="material.name: must be one of 'hematite-querry1985-extraordinary'"
    ):
        parse_config(bad)
    constant = parse_config(SMALL).material
    assert constant.build() == complex(1.5, 0.01)
    with pytest.raises(ConfigError, match=r"material.k: must be >= 0"):
        parse_config(SMALL.replace("k = 0.01", "k = -0.01"))
    with pytest.raises(
        ConfigError,
        match=r"material.hematite_fraction: unknown key for material.model = 'constant'; allowed keys: model, n, k",
    ):
        parse_config(SMALL.replace("k = 0.01", "k = 0.01\nhematite_fraction = 0.1"))


def test_config_is_frozen() -> None:
    config = presets.load_preset("blue-moons")
    assert isinstance(config, BuildConfig)
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.name = "x"  # type: ignore[misc]
    with pytest.raises(TypeError):
        config.material.parameters["hematite_fraction"] = 0.5  # type: ignore[index]


def test_a_configuration_with_a_sweep_table_reads_as_its_own_point() -> None:
    """A sweep's file builds as one point, its own values, and a warning names the axes;
    a [sweep] that is not a table is refused naming the key."""
    with_axes = BLUE + '\n[sweep]\n"size_distribution.r_eff_um" = [1.0, 1.5]\n'
    with pytest.warns(
        UserWarning, match=r"\[sweep\] table \(1 axis: 'size_distribution.r_eff_um'\)"
    ):
        point = parse_config(with_axes, source="storm.toml")
    assert dataclasses.replace(point, source="<string>") == parse_config(BLUE)
    with pytest.raises(ConfigError, match="sweep"):
        parse_config(BLUE + "\nsweep = 3\n")
