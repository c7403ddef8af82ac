"""Sweep specifications: one name per input, and every sweep bounded before any work
(issue 29, items 3 and 4)."""

from __future__ import annotations

import time

import pytest
from _sweeps import small_toml

import dustoptics._validation as validation
from dustoptics._validation import BudgetError
from dustoptics.scattering import optics
from dustoptics.sweep.spec import Axis, _load_points, canonical_key, load_sweep

TINY = small_toml(wavelengths_nm=[450.0, 650.0], n_theta=37)
R_EFF = "size_distribution.r_eff_um"


# ---------------------------------------------------------------- one name per input


@pytest.mark.parametrize(
    ("spelling", "canonical"),
    [
        ("size_distribution.r_eff_um\n", R_EFF),
        (" size_distribution . r_eff_um ", R_EFF),
        ("size_distribution.modes[01].r_eff_um", "size_distribution.modes[1].r_eff_um"),
        ("size_distribution.modes[ 1 ].v_eff", "size_distribution.modes[1].v_eff"),
    ],
)
def test_axis_names_have_one_canonical_form(spelling, canonical):
    assert canonical_key(spelling) == canonical
    assert Axis(spelling, (1.0,)).key == canonical


def test_an_axis_spelled_otherwise_names_the_canonical_dimension():
    spec = load_sweep(TINY, {"size_distribution.r_eff_um\n": [0.8, 1.6]})
    assert [a.key for a in spec.axes] == [R_EFF]


@pytest.mark.parametrize(
    ("config", "first", "second"),
    [
        (TINY, R_EFF, "size_distribution.r_eff_um\n"),
        (TINY, R_EFF, " size_distribution.r_eff_um"),
        (
            "cosmoscout-mars",
            "size_distribution.modes[1].r_eff_um",
            "size_distribution.modes[01].r_eff_um",
        ),
    ],
)
def test_two_spellings_of_one_input_are_refused_naming_both(config, first, second):
    """The issue's case: both axes were accepted and every point was labelled with
    values it was not computed at."""
    with pytest.raises(ValueError, match=r"twice") as info:
        load_sweep(config, {first: [0.8, 1.6], second: [1.0, 2.0]})
    assert repr(first) in str(info.value) and repr(second) in str(info.value)


def test_a_sweep_table_with_a_quoted_and_a_bare_key_for_one_input_is_refused():
    """TOML reads ``"a.b"`` as one key and ``a.b`` as a table: a [sweep] table with both
    silently kept one of them."""
    text = (
        TINY
        + '\n[sweep]\n"size_distribution.r_eff_um" = [0.8, 1.6]\nsize_distribution.r_eff_um = [1.0, 2.0]\n'
    )
    with pytest.raises(ValueError, match=r"twice") as info:
        load_sweep(text)
    message = str(info.value)
    assert '"size_distribution.r_eff_um"' in message and " size_distribution.r_eff_um;" in message


def test_an_argument_axis_replaces_the_tables_axis_of_the_same_input():
    text = TINY + '\n[sweep]\n"size_distribution.r_eff_um" = [0.8, 1.6]\n'
    spec = load_sweep(text, {"size_distribution.r_eff_um\n": [1.0, 2.0, 3.0]})
    assert [(a.key, a.values) for a in spec.axes] == [(R_EFF, (1.0, 2.0, 3.0))]


# ---------------------------------------------------------------- bounded before any work


def test_a_point_a_single_build_refuses_is_refused_naming_it():
    """r_eff 2000 um ran in a worker until it failed allocating 5.13 GiB."""
    with pytest.raises(
        BudgetError, match=r"sweep point \(size_distribution\.r_eff_um = 2000\.0\)"
    ) as info:
        load_sweep(TINY, {R_EFF: [1.0, 2000.0]})
    assert "allow_large=True" in str(info.value)


@pytest.mark.parametrize("num", [1000, 10**9, 10**30])
def test_huge_sweeps_are_refused_from_their_sizes_at_once(num):
    """A million points took minutes to validate; num = 10**9 raised MemoryError.
    Both are refused from the axes' lengths before any point or value is made."""
    start = time.perf_counter()
    with pytest.raises(BudgetError, match=r"points") as info:
        load_sweep(
            TINY,
            {
                R_EFF: {"start": 0.5, "stop": 4.0, "num": num},
                "size_distribution.v_eff": {"start": 0.1, "stop": 0.4, "num": 1000},
            },
        )
    assert time.perf_counter() - start < 1.0
    assert "\n" not in str(info.value)


def test_more_points_than_this_machine_can_hold_are_refused_even_when_allowed():
    with pytest.raises(BudgetError, match=r"more than this machine's"):
        load_sweep(TINY, {R_EFF: {"start": 0.5, "stop": 4.0, "num": 10**12}}, allow_large=True)


def test_the_whole_sweeps_work_is_held_against_the_budget(monkeypatch, tmp_path):
    """Each point passes a single build's budget, their sum does not: the sweep is
    refused before its store or cluster exists; allow_large lets it through."""
    from dustoptics.sweep import run

    over = {R_EFF: [0.8, 1.2, 1.6]}
    costs = [c.work for c in _load_points(TINY, over)[3]]
    monkeypatch.setattr(optics, "WORK_BUDGET", (max(costs) + sum(costs)) / 2)
    started: list[str] = []
    monkeypatch.setattr(run, "_compute", lambda *a, **k: started.append("computed"))
    out = tmp_path / "s.zarr"
    with pytest.raises(
        BudgetError, match=r"the sweep would need about .* 3 points .*allow_large=True"
    ):
        run.sweep(TINY, over, out=out, progress=None)
    assert not out.exists() and not started
    run.sweep(TINY, over, out=out, progress=None, allow_large=True)
    assert started == ["computed"]


def test_the_result_held_in_memory_is_held_against_the_budget(monkeypatch, tmp_path):
    """A result loaded into memory (no store, or a netCDF file) must fit the memory
    budget; a Zarr store, read lazily, need not.  (The budget is lowered below this
    small result; the points and their solvers are left out of it.)"""
    from dustoptics.sweep import run, spec

    over = {R_EFF: [0.8, 1.6]}
    swept, _, configs, _ = _load_points(TINY, over)
    template = run._template(swept, configs, run._layout(swept, 2, 1, 400), "shared")
    monkeypatch.setattr(validation, "MEMORY_BUDGET_BYTES", template.nbytes // 2)
    monkeypatch.setattr(spec, "CLIENT_BYTES_PER_POINT", 1)
    monkeypatch.setattr(spec, "check_cost", lambda *a, **k: optics.RequestCost(0, 0, 1, 1, 1))
    monkeypatch.setattr(run, "_compute", lambda *a, **k: None)
    with pytest.raises(BudgetError, match=r"the sweep's result would need .* Zarr store"):
        run.sweep(TINY, over, out=tmp_path / "s.nc", chunk_wavelengths=1, progress=None)
    assert not any(tmp_path.iterdir())
    run.sweep(TINY, over, out=tmp_path / "s.zarr", chunk_wavelengths=1, progress=None)


def test_a_store_that_cannot_fit_on_its_disk_is_refused(monkeypatch, tmp_path):
    import shutil

    from dustoptics.sweep import run

    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(run.shutil, "disk_usage", lambda path: usage._replace(free=1000))
    monkeypatch.setattr(run, "_compute", lambda *a, **k: None)
    out = tmp_path / "s.zarr"
    with pytest.raises(BudgetError, match=r"needs about .* GiB more .* 9.31e-07 GiB free"):
        run.sweep(TINY, {R_EFF: [0.8, 1.6]}, out=out, progress=None)
    assert not out.exists()


def test_allow_large_must_be_a_bool():
    with pytest.raises(TypeError, match=r"allow_large must be True or False"):
        load_sweep(TINY, {R_EFF: [1.0]}, allow_large="yes")


def test_an_axis_value_beyond_the_float_range_is_a_clean_error():
    with pytest.raises(ValueError, match=r"values must be finite"):
        load_sweep(TINY, {R_EFF: [10**400]})


def test_a_sweep_key_nested_deeper_than_any_input_is_refused_not_a_recursion_error():
    """A [sweep.a.a.a...] table 2,000 deep exhausted Python's stack (RecursionError)."""
    text = TINY + "\n[" + ".".join(["sweep"] + ["a"] * 2000) + "]\nx = [1, 2]\n"
    with pytest.raises(ValueError, match=r"nested 9 tables deep; .* at most 8 deep"):
        load_sweep(text)


def test_a_configuration_file_is_read_through_the_guarded_reader(tmp_path):
    """A FIFO is refused without blocking, like a device or an oversized file."""
    import os

    from dustoptics._files import FormatError

    fifo = tmp_path / "sweep.toml"
    os.mkfifo(fifo)
    with pytest.raises((FormatError, ValueError), match="sweep.toml"):
        load_sweep(str(fifo))
