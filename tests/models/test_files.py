"""Configuration files users write: load_config, and the check against the presets."""

from __future__ import annotations

import importlib
import warnings
from dataclasses import replace

import pytest
from _model_configs import edit

import dustoptics as do
from dustoptics.models import compute, files, presets
from dustoptics.models.config import ConfigError
from dustoptics.models.files import PresetCopyWarning, load_config, preset_copy_problems

COLLIENNE = presets.preset_text("collienne")


def test_load_config_names_the_file(tmp_path) -> None:
    path = tmp_path / "my.toml"
    path.write_text(edit(COLLIENNE, "g = 0.8", "g = 1.2"), encoding="utf-8")
    with pytest.raises(ConfigError, match=rf"^{path}:\d+: phase.g: "):
        load_config(path)
    path.write_text(COLLIENNE, encoding="utf-8")
    assert load_config(path).to_inputs() == presets.load_preset("collienne").to_inputs()


def test_an_edited_copy_of_a_preset_warns(tmp_path) -> None:
    path = tmp_path / "my.toml"
    path.write_text(edit(COLLIENNE, "g = 0.8", "g = 0.7"), encoding="utf-8")
    with pytest.warns(PresetCopyWarning, match=r"carries the name.* of preset 'collienne'") as w:
        load_config(path)
    assert w[0].filename == __file__  # points at the caller's line


def test_preset_copy_problems_flag_edited_copies_only():
    """An edited copy keeping a preset's name, or both its sources and choices, is flagged;
    the presets themselves (hybrid and hybrid-seed share sources) and relabelled copies not."""
    for name in presets.list_presets():
        assert preset_copy_problems(presets.load_preset(name)) == []
    preset = presets.load_preset("blue-moons")
    edited = replace(preset, number_density_per_m3=1e8)
    assert preset_copy_problems(replace(edited, name="mine")) == [
        "carries the sources and choices of preset 'blue-moons' but its number_density_per_m3 "
        "differ from the preset's: the table would be labelled with a model it is not. Give the "
        "configuration its own name, and sources and choices that describe it"
    ]
    assert preset_copy_problems(replace(edited, name="mine", choices=("my own",))) == []
    assert preset_copy_problems(replace(preset, name="mine")) == []  # unchanged numbers


# ------------------------------------------------------------ old import paths

MOVED = {
    "build_table": compute,
    "load_config": files,
    "preset_copy_problems": files,
    "PresetCopyWarning": files,
}


@pytest.mark.parametrize("name", sorted(MOVED))
def test_the_old_config_path_is_gone(name: str) -> None:
    """Building and reading files live in their own modules only (never released elsewhere)."""
    config = importlib.import_module("dustoptics.models.config")
    assert not hasattr(config, name)
    assert hasattr(MOVED[name], name)


def test_the_public_names_do_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert do.load_config is load_config and do.build_table is compute.build_table
