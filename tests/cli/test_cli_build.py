"""``dustoptics build`` of a table: formats, files left up to date, usage errors, provenance."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from _cli import SMALL, config_fixture, run_build  # noqa: F401 (fixture config)

import dustoptics as do
from dustoptics.cli import main
from dustoptics.io import read_hdf5, read_seed_csv, read_texture
from dustoptics.io.csv.cosmoscout import check_cosmoscout_set, read_cosmoscout_constituent
from dustoptics.models import presets


def test_build_writes_every_format_and_they_agree(config, tmp_path, capsys):
    out = tmp_path / "out"
    args = ["--format", "hdf5,csv,glsl,texture,cosmoscout", "--number-density-per-m3", "1e8"]
    assert run_build(config, out, *args) == 0
    folder = out / "small-dust"
    h5 = read_hdf5(folder / "small-dust.h5")
    csv = read_seed_csv(folder)
    assert h5.equals(csv)
    assert h5.cross_sections.number_density_per_m3 == 1e8
    # The table is what the library computes from the same configuration, the number
    # density given on the command line included (an input: it is in the input hash).
    ref = do.build_table(dataclasses.replace(do.load_config(config), number_density_per_m3=1e8))
    np.testing.assert_array_equal(h5.phase, ref.phase)
    assert h5.provenance.input_hash == ref.provenance.input_hash
    assert "MiePhaseFunction" in (folder / "small-dust_phase.glsl").read_text()
    texture = read_texture(folder / "small-dust_phase_theta.json")
    assert texture.phase.shape[0] == 3
    assert check_cosmoscout_set(folder) == ["small-dust"]
    constituent = read_cosmoscout_constituent(folder, "small-dust")
    # beta = N0 <C_sca> at the first texel centre z0 = 120 km / 1024 / 2 (the defaults: an
    # exponential of scale height 10 km sampled at (i + 1/2) T / N), where the density is 1;
    # <C_sca> in um^2 = 1e-12 m^2.
    peak = np.exp(-0.5 * 120e3 / 1024 / 10e3)
    np.testing.assert_allclose(
        constituent.beta_sca_per_m, 1e8 * peak * ref.cross_sections.csca_um2 * 1e-12, rtol=1e-15
    )
    assert constituent.density.max() == 1.0


def test_build_progress_and_summary(config, tmp_path, capsys):
    assert main(["build", str(config), "--out", str(tmp_path), "--format", "hdf5"]) == 0
    captured = capsys.readouterr()
    assert "small-dust: 3/3 wavelengths" in captured.err
    assert f"small-dust: wrote 1 file to {tmp_path / 'small-dust'}" in captured.out
    # One file up to date, then two formats: singular for one, plural for more.
    assert main(["build", str(config), "--out", str(tmp_path), "--format", "hdf5"]) == 0
    assert "small-dust: 1 file up to date in " in capsys.readouterr().out
    assert main(["build", str(config), "--out", str(tmp_path), "--format", "hdf5,glsl"]) == 0
    out = capsys.readouterr().out
    assert "small-dust: wrote 1 file to " in out and "small-dust: 1 file up to date in " in out
    assert "1 files" not in out


def test_two_builds_give_identical_bytes(config, tmp_path):
    for out in ("a", "b"):
        assert run_build(config, tmp_path / out, "--format", "hdf5,csv,glsl") == 0
    names = sorted(p.name for p in (tmp_path / "a" / "small-dust").iterdir())
    for name in names:
        a = (tmp_path / "a" / "small-dust" / name).read_bytes()
        assert a == (tmp_path / "b" / "small-dust" / name).read_bytes(), name


def test_rebuild_to_the_same_bytes_is_up_to_date(config, tmp_path, capsys):
    """A second build finds the files it would write already there: they stay untouched."""
    assert run_build(config, tmp_path, "--format", "hdf5,csv") == 0
    folder = tmp_path / "small-dust"
    stats = {p.name: p.stat() for p in folder.iterdir()}
    capsys.readouterr()
    assert main(["build", str(config), "--out", str(tmp_path), "--format", "hdf5,csv"]) == 0
    out = capsys.readouterr().out
    assert f"small-dust: 4 files up to date in {folder} (left untouched)" in out
    assert "wrote" not in out
    for p in folder.iterdir():  # same inode, same modification time: not rewritten
        assert (p.stat().st_ino, p.stat().st_mtime_ns) == (
            stats[p.name].st_ino,
            stats[p.name].st_mtime_ns,
        )


def test_same_table_from_other_software_versions_is_up_to_date(config, tmp_path, capsys):
    """An HDF5 file of the same table whose recorded software versions differ (a fresh
    clone's tables/, built elsewhere) is up to date: its bytes differ, its table does not."""
    from dustoptics.io import write_hdf5

    assert run_build(config, tmp_path, "--format", "hdf5") == 0
    path = tmp_path / "small-dust" / "small-dust.h5"
    table = read_hdf5(path)
    other = dict(table.provenance.software, numpy="0.0.0-elsewhere")
    elsewhere = table.replace(provenance=dataclasses.replace(table.provenance, software=other))
    write_hdf5(elsewhere, path, overwrite=True)
    before = path.read_bytes()
    assert read_hdf5(path).provenance.software["numpy"] == "0.0.0-elsewhere"
    assert run_build(config, tmp_path, "--format", "hdf5") == 0
    assert path.read_bytes() == before


def test_a_different_existing_file_needs_force(config, tmp_path, capsys):
    assert run_build(config, tmp_path, "--format", "hdf5") == 0
    path = tmp_path / "small-dust" / "small-dust.h5"
    fresh = path.read_bytes()
    table = read_hdf5(path)
    from dustoptics.io import write_hdf5

    write_hdf5(table.replace(phase=table.phase * (1 + 1e-6)), path, overwrite=True)
    stale = path.read_bytes()
    capsys.readouterr()
    assert run_build(config, tmp_path, "--format", "hdf5,csv") == 1
    err = capsys.readouterr().err
    assert "use --force" in err and str(path) in err
    assert path.read_bytes() == stale
    assert not (tmp_path / "small-dust" / "table_summary.json").exists()  # nothing written
    assert run_build(config, tmp_path, "--format", "hdf5", "--force") == 0
    assert path.read_bytes() == fresh


def test_unknown_preset_is_a_usage_error(capsys):
    assert main(["build", "nope"]) == 2
    err = capsys.readouterr().err
    assert "nope" in err
    for name in presets.list_presets():
        assert name in err


def test_config_error_names_key_and_line(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(SMALL.replace("v_eff = 0.2", "v_eff = 0.7"), encoding="utf-8")
    assert main(["build", str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    line = SMALL.splitlines().index("v_eff = 0.2") + 1
    assert f"bad.toml:{line}" in err and "size_distribution.v_eff" in err


@pytest.mark.parametrize(
    ("args", "parameter", "message"),
    [
        (["--format", "pdf"], "--format", "unknown format 'pdf'"),
        (["--format", "hdf5,nope"], "--format", "unknown format 'nope'"),
        (["--resolution-deg", "-1"], "--resolution-deg", "> 0"),
        (["--n-angles", "1"], "--n-angles", ">= 2"),
        (["--channels-nm", "red"], "--channels-nm", "comma-separated"),
        (["--sampling", "log"], "--sampling", "invalid choice"),
    ],
)
def test_bad_options_exit_2_naming_the_parameter(
    config, tmp_path, capsys, args, parameter, message
):
    assert main(["build", str(config), "--out", str(tmp_path / "o"), *args]) == 2
    err = capsys.readouterr().err
    assert f"argument {parameter}: " in err and message in err
    assert not (tmp_path / "o").exists()


def test_cosmoscout_without_number_density_is_a_usage_error(config, tmp_path, capsys):
    assert run_build(config, tmp_path, "--format", "cosmoscout") == 2
    assert "--number-density-per-m3" in capsys.readouterr().err
    assert (
        not any((tmp_path / "small-dust").iterdir()) if (tmp_path / "small-dust").exists() else True
    )


def test_single_preset_cosmoscout_from_optical_depth(config, tmp_path):
    out = tmp_path / "out"
    args = ["--format", "hdf5,cosmoscout", "--optical-depth", "0.4", "--scale-height-m", "11100"]
    assert run_build(config, out, *args) == 0
    table = read_hdf5(out / "small-dust" / "small-dust.h5")
    column = table.provenance.inputs["column"]
    assert column["optical_depth"] == 0.4 and column["reference_wavelength_nm"] == 550.0
    # Identity: tau = N0 <C_ext>(550 nm) L, L = H (1 - exp(-top / H)), top 120 km.
    length = 11100.0 * (1 - np.exp(-120e3 / 11100.0))
    tau = (
        table.cross_sections.number_density_per_m3
        * table.cross_sections.cext_um2[1]
        * 1e-12
        * length
    )
    np.testing.assert_allclose(tau, 0.4, rtol=1e-12)
    both = [*args, "--number-density-per-m3", "1e8", "--force"]
    assert run_build(config, out, *both) == 2


def test_physics_error_exits_1_without_traceback(tmp_path, capsys):
    path = tmp_path / "uv.toml"
    path.write_text(SMALL.replace("[440.0, 550.0, 680.0]", "[100.0, 550.0]"), encoding="utf-8")
    assert main(["build", str(path), "--out", str(tmp_path), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("dustoptics: error: ") and "Traceback" not in err
    assert "100" in err


def test_preset_build_matches_the_library(tmp_path):
    assert main(["build", "costa", "--out", str(tmp_path), "--quiet", "--format", "hdf5"]) == 0
    table = read_hdf5(tmp_path / "costa" / "costa.h5")
    assert table.equals(presets.build_preset("costa"))
    assert table.cross_sections is None


def test_number_density_option_is_recorded_and_changes_the_input_hash(config, tmp_path):
    """--number-density-per-m3 changes numbers (beta = N C): build and export record it."""
    assert run_build(config, tmp_path / "plain", "--format", "hdf5") == 0
    assert (
        run_build(config, tmp_path / "dense", "--format", "hdf5", "--number-density-per-m3", "2e8")
        == 0
    )
    plain = read_hdf5(tmp_path / "plain" / "small-dust" / "small-dust.h5")
    dense = read_hdf5(tmp_path / "dense" / "small-dust" / "small-dust.h5")
    assert plain.provenance.inputs["number_density_per_m3"] is None
    assert dense.provenance.inputs["number_density_per_m3"] == 2e8
    assert dense.cross_sections.number_density_per_m3 == 2e8
    assert dense.provenance.input_hash != plain.provenance.input_hash
    # export: the same record for the same input.
    source = tmp_path / "plain" / "small-dust" / "small-dust.h5"
    argv = ["export", str(source), "--out", str(tmp_path / "exp"), "--format", "hdf5", "--quiet"]
    assert main([*argv, "--number-density-per-m3", "2e8"]) == 0
    exported = read_hdf5(tmp_path / "exp" / "small-dust" / "small-dust.h5")
    assert exported.cross_sections.number_density_per_m3 == 2e8
    assert exported.provenance.input_hash == dense.provenance.input_hash


def test_format_options_that_change_numbers_are_recorded_per_format(config, tmp_path):
    """--channels-nm changes the GLSL constants and --n-angles the texture: each file records
    its own options (and an input hash that changes with them); the HDF5 file is unaffected."""
    assert run_build(config, tmp_path / "a", "--format", "hdf5,glsl,texture") == 0
    options = ["--channels-nm", "600,500,450", "--n-angles", "181"]
    assert run_build(config, tmp_path / "b", "--format", "hdf5,glsl,texture", *options) == 0
    a, b = tmp_path / "a" / "small-dust", tmp_path / "b" / "small-dust"
    assert (a / "small-dust.h5").read_bytes() == (b / "small-dust.h5").read_bytes()
    table_hash = read_hdf5(a / "small-dust.h5").provenance.input_hash

    def glsl_hash(folder):
        text = (folder / "small-dust_phase.glsl").read_text()
        return text.split("input_hash (SHA-256 of the table's inputs): ")[1].split()[0]

    assert glsl_hash(a) == table_hash  # no option given: the table's own hash
    assert glsl_hash(b) != table_hash
    sidecar = json.loads((b / "small-dust_phase_theta.json").read_text())
    assert sidecar["provenance"]["inputs"]["export"] == {"format": "texture", "n_angles": 181}
    assert sidecar["input_hash"] != table_hash
    glsl_inputs = do.table.canonical_json(
        {
            **read_hdf5(a / "small-dust.h5").provenance.inputs,
            "export": {"format": "glsl", "channels_nm": [600.0, 500.0, 450.0]},
        }
    )
    import hashlib

    assert glsl_hash(b) == hashlib.sha256(glsl_inputs.encode()).hexdigest()


def test_edited_copy_of_a_preset_warns_and_says_so_in_provenance(tmp_path, capsys):
    """presets --show gives a copy; edited but still carrying the preset's name, sources and
    choices, it warns (and the table's notes say so); with labels of its own, it does not."""
    assert main(["presets", "--show", "costa"]) == 0
    text = capsys.readouterr().out
    unchanged = tmp_path / "unchanged.toml"
    unchanged.write_text(text, encoding="utf-8")
    assert main(["build", str(unchanged), "--out", str(tmp_path / "u"), "--format", "hdf5"]) == 0
    assert "warning" not in capsys.readouterr().err

    edited_text = text.replace("n_theta = 1801", "n_theta = 181", 1)
    assert edited_text != text
    edited = tmp_path / "edited.toml"
    edited.write_text(edited_text, encoding="utf-8")
    assert main(["build", str(edited), "--out", str(tmp_path / "e"), "--format", "hdf5"]) == 0
    err = capsys.readouterr().err
    assert "dustoptics: warning: configuration" in err
    assert "of preset 'costa' but its optics differ" in err
    table = read_hdf5(tmp_path / "e" / "costa" / "costa.h5")
    assert any("of preset 'costa' but its optics differ" in n for n in table.provenance.notes)

    relabelled = tmp_path / "mine.toml"
    relabelled.write_text(_relabel(edited_text), encoding="utf-8")
    assert main(["build", str(relabelled), "--out", str(tmp_path / "m"), "--format", "hdf5"]) == 0
    assert "warning" not in capsys.readouterr().err


def _relabel(text: str) -> str:
    """The TOML with its own name and without the preset's sources and choices."""
    import tomllib

    data = tomllib.loads(text)
    out = ['name = "my-dust"', 'description = "an edited copy, relabelled"']
    for section in ("material", "size_distribution", "optics", "phase"):
        if section in data:
            out.append(f"[{section}]")
            out += [f"{k} = {_toml(v)}" for k, v in data[section].items()]
    return "\n".join(out) + "\n"


def _toml(value) -> str:
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (["build", "mars", "--channels-nm", "600,500,450"], "--channels-nm"),
        (["build", "mars", "--number-density-per-m3", "1e8"], "--number-density-per-m3"),
        (["build", "mars", "--ozone-csv", "o3.csv"], "--ozone-csv"),
        (["build", "earth", "--dust", "hybrid"], "--dust"),
        (["build", "earth", "--optical-depth", "0.3"], "--optical-depth"),
        (["build", "costa", "--dust", "hybrid"], "--dust"),
        (["build", "costa", "--wavelengths-nm", "400,500"], "--wavelengths-nm"),
        (["build", "costa", "--optical-depth", "0.3"], "--optical-depth"),
        (["build", "costa", "--format", "glsl", "--optical-depth", "0.3"], "--optical-depth"),
    ],
)
def test_options_that_would_change_nothing_are_refused(argv, named, tmp_path, capsys):
    """One grammar: an option is honoured or refused, never silently ignored."""
    assert main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"{named} changes nothing in 'build {argv[1]}'" in err
    assert not any(tmp_path.iterdir())


def test_first_build_says_it_compiles_the_kernels(config, tmp_path, capsys, monkeypatch):
    """While numba's cache lacks kernels, build has them compiled first (compile_kernels
    reports each on stderr) and says how long the build took; later builds and --quiet say
    nothing.  (tests/test_numba_cache.py builds from a real empty cache.)"""
    from dustoptics import _numba_cache

    calls = []

    def compile_kernels(groups, *, progress=None, processes=None):
        calls.append((list(groups), progress))
        if len(calls) > 1:
            return None  # in the cache now
        if progress is not None:
            progress.write("dustoptics: compiling 1 kernels, once for this installation ...\n")
        return _numba_cache.CompileReport((), 1, 0.0)

    monkeypatch.setattr(_numba_cache, "compile_kernels", compile_kernels)
    assert main(["build", str(config), "--out", str(tmp_path / "a"), "--format", "hdf5"]) == 0
    err = capsys.readouterr().err
    assert "dustoptics: compiling 1 kernels, once for this installation" in err
    assert "dustoptics: this first build took" in err
    assert calls[0][0] == ["optics"]
    assert main(["build", str(config), "--out", str(tmp_path / "b"), "--format", "hdf5"]) == 0
    assert "compil" not in capsys.readouterr().err
    calls.clear()
    assert run_build(config, tmp_path / "c", "--format", "hdf5") == 0  # --quiet
    assert capsys.readouterr().err == ""
    assert calls[0][1] is None


def test_build_writes_netcdf_by_default(config, tmp_path):
    """NAME.nc (the file name the CF conventions ask for) and the seed CSVs; .h5 on request."""
    assert run_build(config, tmp_path) == 0
    folder = tmp_path / "small-dust"
    assert sorted(p.name for p in folder.iterdir()) == [
        "MieExtinctionSpectrum.csv",
        "MiePhaseFunctionSpectrum.csv",
        "small-dust.nc",
        "table_summary.json",
    ]
    assert do.open_table(folder / "small-dust.nc").equals(read_seed_csv(folder))
    assert run_build(config, tmp_path, "--format", "hdf5") == 0
    assert (folder / "small-dust.h5").read_bytes() == (folder / "small-dust.nc").read_bytes()


def _no_work(monkeypatch):
    from dustoptics.models.build import TableBuilder

    def no_work(self):
        raise AssertionError("computed before the request was checked")

    monkeypatch.setattr(TableBuilder, "build", no_work)


def test_disort_and_libradtran_from_a_configuration_that_asks_for_the_expansion(tmp_path):
    path = tmp_path / "rt.toml"
    path.write_text(SMALL.replace("n_theta = 19", "n_theta = 19\nexpansion = true"), "utf-8")
    argv = ["--format", "netcdf,disort,libradtran", "--number-density-per-m3", "1e8"]
    assert run_build(path, tmp_path, *argv) == 0
    folder = tmp_path / "small-dust"
    assert sorted(p.name for p in folder.iterdir()) == [
        "small-dust.nc",
        "small-dust_aerosol_explicit.dat",
        "small-dust_aerosol_layer.dat",
        "small-dust_disort.txt",
    ]
    table = do.open_table(folder / "small-dust.nc")
    assert table.provenance.inputs["optics"]["expansion"] is True
    np.testing.assert_allclose(table.expansion.alpha1[:, 0], 1.0)
    # alpha1_1 = 3 g, each side within its own error estimate: g converges at rtol, the
    # coefficients at rtol/100 (alpha1_l / (2 l + 1) bounded by expansion_error_estimate).
    bound = 3 * (
        table.quadrature.cross_section_error_estimate + table.expansion.expansion_error_estimate
    )
    assert np.all(np.abs(table.expansion.alpha1[:, 1] - 3 * table.g) <= bound)
    assert np.all(bound < 1e-4)


def test_rt_formats_refuse_a_model_without_the_expansion_before_any_work(
    tmp_path, capsys, monkeypatch
):
    _no_work(monkeypatch)
    argv = ["build", "hybrid", "--out", str(tmp_path / "o"), "--format", "disort", "--quiet"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--format disort needs" in err and len(err.splitlines()) == 1, err
    assert "which only a Mie model has (phase.model = 'mie'" in err
    assert not (tmp_path / "o").exists()


def test_rt_formats_ask_a_mie_model_for_the_expansion(config, tmp_path, capsys):
    """The configuration does not ask for the expansion; --format disort does, and the build
    computes it, says so and records it: the same table as the configuration asking for it."""
    argv = ["build", str(config), "--format", "disort,netcdf"]
    assert main([*argv, "--out", str(tmp_path / "asked")]) == 0
    note = (
        "--format disort needs the phase function's expansion coefficients: computed "
        "(optics.expansion = true)"
    )
    assert f"dustoptics: {note}" in capsys.readouterr().err
    asked = do.open_table(tmp_path / "asked" / "small-dust" / "small-dust.nc")
    assert note in asked.provenance.notes and asked.expansion is not None
    own = tmp_path / "own.toml"
    own.write_text(SMALL.replace("n_theta = 19", "n_theta = 19\nexpansion = true"), "utf-8")
    assert run_build(own, tmp_path / "own", "--format", "disort,netcdf") == 0
    table = do.open_table(tmp_path / "own" / "small-dust" / "small-dust.nc")
    assert table.provenance.input_hash == asked.provenance.input_hash
    disort = "small-dust/small-dust_disort.txt"
    assert (tmp_path / "asked" / disort).read_bytes() == (tmp_path / "own" / disort).read_bytes()


def test_the_expansion_is_a_mie_models_key(tmp_path, capsys):
    path = tmp_path / "hybrid.toml"
    text = SMALL.replace("n_theta = 19", "n_theta = 19\nexpansion = 16")
    path.write_text(text.replace('model = "mie"', 'model = "hybrid"'), "utf-8")
    assert run_build(path, tmp_path) == 2
    assert "optics.expansion: is available for phase.model = 'mie' only" in capsys.readouterr().err


@pytest.mark.parametrize(("name", "status"), [("small dust", 1), ("a\\\\b", 2), ("x y", 1)])
def test_a_name_no_file_can_carry_is_refused_before_any_work(
    tmp_path, capsys, monkeypatch, name, status
):
    """A space fails at write time (the netCDF file is named by it); a path separator is a
    configuration error.  Both are refused before the table is computed."""
    _no_work(monkeypatch)
    path = tmp_path / "named.toml"
    path.write_text(SMALL.replace('name = "small-dust"', f'name = "{name}"'), "utf-8")
    assert run_build(path, tmp_path / "o") == status
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "file name" in err, err
    assert not (tmp_path / "o").exists()


def test_an_existing_table_of_other_inputs_is_refused_before_any_work(
    config, tmp_path, capsys, monkeypatch
):
    """The table file (NAME.nc) records its inputs: another configuration under the same
    name is refused without --force before the table is computed, not after."""
    assert run_build(config, tmp_path) == 0
    other = tmp_path / "other.toml"
    other.write_text(SMALL.replace("r_eff_um = 1.0", "r_eff_um = 1.2"), "utf-8")
    _no_work(monkeypatch)
    assert run_build(other, tmp_path) == 1
    err = capsys.readouterr().err
    assert "hold another table (other inputs, or unreadable); use --force" in err
    assert "small-dust.nc" in err and "table_summary.json" in err
    monkeypatch.undo()
    # The same inputs go ahead (and find the files up to date); --force replaces.
    assert main(["build", str(config), "--out", str(tmp_path), "--format", "netcdf,csv"]) == 0
    assert "4 files up to date" in capsys.readouterr().out
    assert run_build(other, tmp_path, "--force") == 0
    table = do.open_table(tmp_path / "small-dust" / "small-dust.nc")
    assert table.provenance.inputs["size_distribution"]["r_eff_um"] == 1.2


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["costa", "--format", "cosmoscout", "--number-density-per-m3", "1e8"], "changes nothing"),
        (["costa", "--format", "bruneton"], "needs cross-sections, which 'costa' does not have"),
        (["CONFIG", "--format", "bruneton"], "--format bruneton needs a number density"),
        (["CONFIG", "--format", "cosmoscout"], "--number-density-per-m3"),
    ],
)
def test_what_a_format_needs_is_checked_before_any_work(
    config, tmp_path, capsys, monkeypatch, argv, needle
):
    _no_work(monkeypatch)
    target = str(config) if argv[0] == "CONFIG" else argv[0]
    assert main(["build", target, *argv[1:], "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert needle in err, err
    assert not (tmp_path / "o").exists()


def test_the_presets_say_how_to_get_disort_and_libradtran_files(tmp_path, capsys, monkeypatch):
    """Following blue-moons' comment: a copy with a name of its own and the expansion line
    passes every check of --format disort,libradtran without a warning (the expansion adds
    coefficients to the same model: the copy's sources and choices still describe it)."""
    assert main(["presets", "--show", "blue-moons"]) == 0
    text = capsys.readouterr().out
    assert "#   expansion = true" in text
    mine = text.replace('name = "blue-moons"', 'name = "my-dust"', 1)
    mine = mine.replace("#   expansion = true", "expansion = true", 1)
    path = tmp_path / "my-dust.toml"
    path.write_text(mine, "utf-8")
    _no_work(monkeypatch)
    argv = ["build", str(path), "--out", str(tmp_path / "o"), "--format", "disort,libradtran"]
    with pytest.raises(AssertionError, match="computed before the request was checked"):
        main([*argv, "--number-density-per-m3", "1e8"])
    assert "warning" not in capsys.readouterr().err
    assert do.load_config(path).optics.expansion is True


def test_r_eff_in_metres_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    """r_eff_um = 1.6e-6 (metres) is a one-line error naming the key and the unit meant,
    from the configuration and from the API alike, as wavelengths in micrometres are."""
    _no_work(monkeypatch)
    path = tmp_path / "metres.toml"
    path.write_text(SMALL.replace("r_eff_um = 1.0", "r_eff_um = 1.6e-6"), "utf-8")
    assert run_build(path, tmp_path / "o") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "size_distribution" in err, err
    assert "r_eff_um must be in micrometres" in err and "(1.6e-06 m = 1.6 um)" in err
    assert not (tmp_path / "o").exists()
    with pytest.raises(ValueError, match=r"was it in metres\? \(1.6e-06 m = 1.6 um\)"):
        do.ModifiedGamma(r_eff_um=1.6e-6, v_eff=0.2)
    with pytest.raises(ValueError, match="r_eff_um .* must be in micrometres"):
        do.LogNormal(median_radius_um=1.2e-6, sigma=0.5)
