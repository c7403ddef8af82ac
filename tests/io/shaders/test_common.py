"""What every shader language shares: the same content, the files, the registry, the errors.

The languages' own proofs (compilers, drivers) are in test_glsl.py, test_hlsl.py and
test_wgsl.py beside this file.
"""

from __future__ import annotations

import pytest
from _shader_tables import TABLE

from dustoptics.io import FORMATS, write
from dustoptics.io.shaders.common import LANGUAGES, shader_source, shader_syntax, write_shader

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


def test_every_language_has_its_syntax() -> None:
    for language in LANGUAGES:
        syntax = shader_syntax(language)
        assert syntax.language == language and syntax.extension == "." + language[:4]
    with pytest.raises(ValueError, match="language must be one of 'glsl', 'glsl100'"):
        shader_syntax("msl")
    with pytest.raises(ValueError, match="GLSL ES 1.00 has no array initializers"):
        shader_syntax("glsl100").float_array("X", [1.0])


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


def test_each_colour_mode_writes_a_file_of_its_own(tmp_path) -> None:
    """Three wavelengths, CIE 1931 XYZ and linear sRGB give different numbers: three files."""
    kw = {"min_band_coverage": 0.0}  # the test table's 440-680 nm do not cover the bands
    (plain,) = write(TABLE, tmp_path, format="glsl")
    (xyz,) = write(TABLE, tmp_path, format="glsl", colour="cie1931-xyz", **kw)
    (srgb,) = write(TABLE, tmp_path, format="wgsl", colour="linear-srgb-astmg173", **kw)
    assert plain.name == "hg_phase.glsl"
    assert xyz.name == "hg_phase_cie1931-xyz.glsl"
    assert srgb.name == "hg_phase_linear-srgb-astmg173.wgsl"
    assert plain.read_bytes() != xyz.read_bytes()


def test_input_hash_means_one_thing_from_the_api_and_the_command_line(tmp_path) -> None:
    """dustoptics.io.write and the command line's write_formats record the same export
    options, so the same file, its input_hash included; without options, the table's hash."""
    from dustoptics.io.outputs import write_formats
    from dustoptics.io.registry import FormatOptions

    channels = (650.0, 530.0, 450.0)
    (api,) = write(TABLE, tmp_path / "api", format="glsl", channels_nm=channels)
    (cli,) = write_formats(
        TABLE, tmp_path / "cli", ["glsl"], options=FormatOptions(channels_nm=channels)
    )
    assert api.read_bytes() == cli.read_bytes()
    assert TABLE.provenance.input_hash not in api.read_text()
    (plain,) = write(TABLE, tmp_path / "plain", format="glsl")
    assert f"input_hash (SHA-256 of the table's inputs): {TABLE.provenance.input_hash}" in (
        plain.read_text()
    )
