"""dustoptics.models.build: a configuration's table with progress, and what formats ask of it."""

from __future__ import annotations

import io
import os

import pytest
from _model_configs import SMALL

from dustoptics.models import presets
from dustoptics.models.build import TableBuilder, is_config_path
from dustoptics.models.compute import build_table
from dustoptics.models.files import load_config


@pytest.fixture
def small_file(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def small_table(tmp_path_factory):
    path = tmp_path_factory.mktemp("small") / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return build_table(load_config(path))


def test_is_config_path(small_file, tmp_path, monkeypatch):
    assert not is_config_path("hybrid")
    assert is_config_path("mine.toml")
    assert is_config_path(f"configs{os.sep}mine")
    assert is_config_path(str(small_file))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "plain").write_text(SMALL, encoding="utf-8")
    assert is_config_path("plain")  # an existing file, whatever its name


def test_from_name_reads_a_preset_or_a_file(small_file):
    assert TableBuilder.from_name("costa").config == presets.load_preset("costa")
    builder = TableBuilder.from_name(str(small_file), allow_large=True)
    assert builder.config == load_config(small_file)
    assert builder.name == "small" and builder.allow_large and builder.progress is None


def test_from_name_refuses_an_unknown_preset_listing_the_valid_ones():
    with pytest.raises(ValueError, match="nope") as caught:
        TableBuilder.from_name("nope")
    for name in presets.list_presets():
        assert name in str(caught.value)


def test_build_is_build_table_and_reports_progress(small_file, monkeypatch):
    from dustoptics import _numba_cache

    monkeypatch.setattr(_numba_cache, "compile_kernels", lambda *args, **kwargs: None)  # cached
    progress = io.StringIO()  # not a terminal: the first and last lines only
    table = TableBuilder(load_config(small_file), progress=progress).build()
    assert table.equals(build_table(load_config(small_file)))
    lines = progress.getvalue().splitlines()
    assert [line.split(",")[0] for line in lines] == [
        "small: 0/10 wavelengths",
        "small: 10/10 wavelengths",
    ]
