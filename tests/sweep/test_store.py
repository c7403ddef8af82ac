"""Sweep stores under concurrent runs and damage (issue 29, items 1 and 2).

One run writes a store at a time: another is refused with a message naming it, and no
run removes another's staging folder.  Every chunk's marker carries the digests of its
files: a resume computes a damaged chunk again, :func:`verify_store` names it, and a
damaged file written at creation is refused in one line.  The sweeps are tiny (2 points,
2 wavelengths, 37 angles) on a cluster of threads in this process.
"""

from __future__ import annotations

import json
import shutil
import threading
from pathlib import Path

import numpy as np
import pytest
from _sweeps import small_toml, store_bytes

distributed = pytest.importorskip(
    "distributed", reason="needs the 'sweep' extra (dask[distributed])"
)
xr = pytest.importorskip("xarray", reason="needs the 'sweep' extra (xarray)")
pytest.importorskip("zarr", reason="needs the 'sweep' extra (zarr)")

from dustoptics.io import FormatError  # noqa: E402
from dustoptics.io._atomic import held_lock  # noqa: E402
from dustoptics.sweep import local_cluster, sweep, verify_store  # noqa: E402
from dustoptics.sweep.store import StoreBusyError  # noqa: E402

TINY = small_toml(wavelengths_nm=[450.0, 650.0], n_theta=37)
OVER = {"size_distribution.r_eff_um": [0.8, 1.6]}
OTHER = {"size_distribution.r_eff_um": [0.9, 1.7]}


@pytest.fixture(scope="module")
def client():
    with (
        local_cluster(1, threads=2, processes=False) as cluster,
        distributed.Client(cluster) as c,
    ):
        yield c


def run(client, out, over=OVER, **kwargs):
    kwargs.setdefault("progress", None)
    return sweep(TINY, over, out=out, client=client, chunk_wavelengths=1, **kwargs)


@pytest.fixture(scope="module")
def reference(client, tmp_path_factory) -> Path:
    """A finished store of 2 chunks (0.0 and 0.1: one per wavelength)."""
    out = tmp_path_factory.mktemp("reference") / "ref.zarr"
    run(client, out)
    return out


@pytest.fixture
def copy(reference, tmp_path) -> Path:
    target = tmp_path / "copy.zarr"
    shutil.copytree(reference, target)
    return target


# ---------------------------------------------------------------- one writer


def holding_run(client, out, over=OVER):
    """A run in a thread that holds ``out`` until released: (thread, release, outcome)."""
    held, release = threading.Event(), threading.Event()
    outcome: dict = {}

    def progress(done, total):
        held.set()
        assert release.wait(60)

    def target():
        try:
            outcome["result"] = run(client, out, over, progress=progress)
        except BaseException as exc:
            outcome["error"] = exc

    thread = threading.Thread(target=target)
    thread.start()
    assert held.wait(60), outcome
    return thread, release, outcome


@pytest.mark.parametrize("name", ["held.zarr", "held.nc"])
def test_a_run_holding_the_store_refuses_another(client, tmp_path, name):
    """While a run holds a store (here its zarr working store for a .nc), a second run
    of the same sweep, or of another, is refused naming the store, and leaves it alone;
    the first run finishes a whole store."""
    out = tmp_path / name
    store = out if name.endswith(".zarr") else tmp_path / f"{name}.zarr-partial"
    thread, release, outcome = holding_run(client, out)
    try:
        for over in (OVER, OTHER):
            with pytest.raises(StoreBusyError, match=r"being written by another run") as info:
                run(client, out, over)
            assert str(store) in str(info.value)
        assert store.is_dir()  # the working store of the first run is still there
    finally:
        release.set()
        thread.join()
    assert "error" not in outcome, outcome
    if name.endswith(".zarr"):
        assert verify_store(out) == 2
    else:
        assert out.is_file() and not store.exists()
        assert np.all(np.isfinite(xr.open_dataset(out, engine="h5netcdf").phase.values))


def test_two_runs_creating_one_store_leave_one_whole_store(client, tmp_path, monkeypatch):
    """A second run (of another sweep) starts and finishes while the first is creating
    the same new store: the first is then refused with a clear message (not an OSError
    or a broken store), and the store is the second run's, whole."""
    out = tmp_path / "race.zarr"
    write = xr.Dataset.to_zarr
    calls: list[str] = []
    other: dict = {}

    def to_zarr(self, store, *args, **kwargs):
        calls.append(str(store))
        if len(calls) == 1:  # the first run is creating: the second runs meanwhile
            thread = threading.Thread(target=lambda: other.update(ds=run(client, out, OTHER)))
            thread.start()
            thread.join()
        return write(self, store, *args, **kwargs)

    monkeypatch.setattr(xr.Dataset, "to_zarr", to_zarr)
    with pytest.raises(ValueError, match=r"holds a different sweep") as info:
        run(client, out, OVER)
    assert str(out) in str(info.value)
    assert "ds" in other
    assert verify_store(out) == 2
    ds = xr.open_zarr(out)
    assert list(ds["size_distribution.r_eff_um"].values) == OTHER["size_distribution.r_eff_um"]
    assert [p.name for p in tmp_path.iterdir()] == ["race.zarr"]  # no staging folder left


def test_no_run_removes_a_staging_folder_another_run_holds(client, tmp_path):
    """A store's staging folder that a live run holds stays; one whose run ended goes;
    folders of other names (an earlier version's ``NAME.creating``) are not touched."""
    out = tmp_path / "s.zarr"
    live = tmp_path / ".s.zarr.creating-deadbeef"
    ended = tmp_path / ".s.zarr.creating-0badc0de"
    old = tmp_path / "s.zarr.creating"
    for folder in (live, ended, old):
        folder.mkdir()
        (folder / "file").write_text("staged")
    with held_lock(live) as fd:
        assert fd is not None
        run(client, out)
        assert (live / "file").read_text() == "staged"
    assert not ended.exists()
    assert (old / "file").read_text() == "staged"
    assert verify_store(out) == 2


def test_a_store_that_is_not_a_directory_is_refused(client, tmp_path):
    out = tmp_path / "file.zarr"
    out.write_text("not a store")
    with pytest.raises(ValueError, match=r"is not a dustoptics sweep store"):
        run(client, out)
    assert out.read_text() == "not a store"


# ---------------------------------------------------------------- digests


def flip_a_byte(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x10
    path.write_bytes(bytes(data))


def replace_by_a_folder(path: Path) -> None:
    path.unlink()
    path.mkdir()
    (path / "x").write_text("x")


DAMAGE = {
    "a flipped byte in a chunk": ("phase/0.1.0", flip_a_byte, r"phase/0\.1\.0 does not match"),
    "a deleted chunk": ("g/0.1", Path.unlink, r"g/0\.1 is missing"),
    "a marker holding garbage": (
        "sweep-done/0.1",
        lambda p: p.write_bytes(b"\x00garbage{"),
        r"marker that is not valid JSON",
    ),
    "a marker replaced by a folder": (
        "sweep-done/0.1",
        replace_by_a_folder,
        r"marker that is not a file",
    ),
    "a marker of another chunk": (
        "sweep-done/0.1",
        lambda p: p.write_bytes((p.parent / "0.0").read_bytes()),
        r"marker that names another chunk",
    ),
}


@pytest.mark.parametrize("damage", list(DAMAGE))
def test_a_damaged_chunk_is_named_by_verify_and_computed_again_by_a_resume(
    client, reference, copy, damage
):
    """The damage is found by verify_store, which names the chunk and the file; a
    resume computes that chunk (and no other) again, and the store equals the
    undamaged one byte for byte."""
    rel, act, message = DAMAGE[damage]
    act(copy / rel)
    with pytest.raises(FormatError, match=rf"chunk 0\.1 .*{message}.*run the sweep again"):
        verify_store(copy)
    calls: list[tuple[int, int]] = []
    run(client, copy, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(2, 4), (4, 4)]  # chunk 0.0 kept, chunk 0.1 computed again
    assert verify_store(copy) == 2
    assert store_bytes(copy) == store_bytes(reference)


def test_values_read_back_after_a_resume_are_the_computed_ones(client, reference, copy):
    """The issue's case: a flipped byte in a phase chunk read back as a value 89 % off
    after a resume that kept it.  Now the resumed store's values are the reference's."""
    flip_a_byte(copy / "phase" / "0.0.0")
    ds = run(client, copy).load()
    assert np.array_equal(ds.phase.values, xr.open_zarr(reference).phase.values)


@pytest.mark.parametrize(
    ("rel", "act"),
    [
        (".zmetadata", lambda p: p.write_bytes(b"{garbage")),
        ("provenance/0", flip_a_byte),
        ("sweep-created.json", lambda p: p.write_bytes(b"[" * 100_000)),
    ],
)
def test_a_damaged_file_written_at_creation_is_refused_in_one_line(client, copy, rel, act):
    """What a chunk cannot recompute (metadata, coordinates, per-point variables, the
    record of digests) is refused by a resume and by verify_store, naming the file,
    in one line and without a traceback of the JSON parser."""
    act(copy / rel)
    for check in (lambda: run(client, copy), lambda: verify_store(copy)):
        with pytest.raises(FormatError, match=rf"{rel}.*remove .*store") as info:
            check()
        assert "\n" not in str(info.value)


def test_verify_store_names_a_chunk_not_computed_and_refuses_non_stores(copy, tmp_path):
    (copy / "sweep-done" / "0.0").unlink()
    with pytest.raises(FormatError, match=r"chunk 0\.0 is not computed"):
        verify_store(copy)
    with pytest.raises(FormatError, match=r"not a dustoptics sweep store"):
        verify_store(tmp_path)


def test_verify_store_refuses_a_store_being_written(copy):
    with held_lock(copy) as fd:
        assert fd is not None
        with pytest.raises(StoreBusyError, match=r"being written by another run"):
            verify_store(copy)


def test_markers_record_the_digest_of_every_array_of_their_chunk(reference):
    marker = json.loads((reference / "sweep-done" / "0.1").read_text())
    assert marker["chunk"] == [0, 1]
    assert sorted(marker["sha256"]) == sorted(
        f"{name}/0.1" + (".0" if name == "phase" else "")
        for name in (
            "phase",
            "cext_um2",
            "csca_um2",
            "g",
            "error_estimate",
            "cross_section_error_estimate",
            "n_nodes",
        )
    )
    assert all(len(d) == 64 for d in marker["sha256"].values())


def test_markers_written_at_once_by_many_workers_all_arrive(tmp_path):
    """Workers write markers into one folder at the same moment; each arrives whole.
    (Through the set writer, one writer's cleanup could take another's fresh staging
    folder before it was locked, and that chunk's task failed.)"""
    from concurrent.futures import ThreadPoolExecutor

    from dustoptics.sweep.store import MARKERS, StoreLayout, chunk_problem, write_marker

    layout = StoreLayout((1, 64), {"phase": 1, "g": 0})
    names = list(layout.names())
    for name in names:
        for rel in layout.chunk_files(name):
            (tmp_path / rel).parent.mkdir(exist_ok=True)
            (tmp_path / rel).write_bytes(name.encode())
    (tmp_path / MARKERS).mkdir()

    def write(name: str) -> None:
        write_marker(tmp_path, layout, name, {"seconds": 1.0})

    with ThreadPoolExecutor(8) as pool:
        list(pool.map(write, names * 3))
    assert [n for n in names if chunk_problem(tmp_path, layout, n) is not None] == []
    assert sorted(p.name for p in (tmp_path / MARKERS).iterdir()) == sorted(names)


def test_info_calls_a_store_complete_only_after_checking_every_chunk(copy, capsys):
    """``dustoptics info`` said "2 of 2 done (complete)", exit 0, for a store with a flipped
    byte, which verify_store catches; now it checks the chunks first."""
    from dustoptics.cli import main

    assert main(["info", str(copy)]) == 0
    assert "2 of 2 done (complete: every chunk checked against its digests)" in (
        capsys.readouterr().out
    )
    flip_a_byte(copy / "phase" / "0.0.0")
    assert main(["info", str(copy)]) == 1
    err = capsys.readouterr().err
    assert "chunk 0.0" in err and "complete" not in err
