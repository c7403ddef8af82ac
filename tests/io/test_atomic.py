"""Tests for dustoptics.io._atomic (atomic multi-file writes) and dustoptics.io._text."""

from __future__ import annotations

import os
import shutil
import signal
import stat
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dustoptics.io import _text
from dustoptics.io._atomic import (
    FILE_MODE,
    FormatError,
    check_targets,
    clean_leftovers,
    file_set,
    is_leftover,
    scratch,
    write_files,
)


def _listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir()) if directory.exists() else []


# ------------------------------------------------------------------ writing


def test_writes_bytes_and_callbacks(tmp_path):
    seen = []

    def writer(path: Path) -> None:
        seen.append(path)
        path.write_bytes(b"from a callback\n")

    a, b = tmp_path / "out" / "a.csv", tmp_path / "out" / "b.h5"
    assert write_files({a: b"bytes\n", b: writer}) == [a, b]
    assert a.read_bytes() == b"bytes\n"
    assert b.read_bytes() == b"from a callback\n"
    # The callback wrote the file in a hidden staging directory inside the target directory.
    assert seen[0].parent.parent == b.parent and seen[0].parent.name.startswith(
        ".dustoptics-stage-"
    )
    assert seen[0].name == "b.h5"
    assert stat.S_IMODE(a.stat().st_mode) == FILE_MODE == stat.S_IMODE(b.stat().st_mode)
    assert _listing(tmp_path / "out") == ["a.csv", "b.h5"]


def test_existing_outputs_are_named_and_kept(tmp_path):
    (tmp_path / "a").write_text("keep a\n")
    (tmp_path / "c").write_text("keep c\n")
    targets = {tmp_path / name: b"new\n" for name in ("a", "b", "c")}
    with pytest.raises(FileExistsError, match=r"/a, .*/c already exist .*overwrite=True.*--force"):
        write_files(targets)
    assert _listing(tmp_path) == ["a", "c"]  # checked before anything is written
    assert (tmp_path / "a").read_text() == "keep a\n"
    write_files(targets, overwrite=True)
    assert [(tmp_path / n).read_text() for n in ("a", "b", "c")] == ["new\n"] * 3


def test_check_targets(tmp_path):
    (tmp_path / "x").write_text("")
    check_targets([tmp_path / "x"], overwrite=True)
    check_targets([tmp_path / "y"], overwrite=False)
    with pytest.raises(FileExistsError, match=r"/x already exists"):
        check_targets([tmp_path / "x", tmp_path / "y"], overwrite=False)


def test_duplicate_targets_are_refused(tmp_path):
    with pytest.raises(ValueError, match="duplicate targets"):
        write_files({tmp_path / "a": b"1", tmp_path / "sub" / ".." / "a": b"2"})


@pytest.mark.parametrize(
    "error", [OSError(28, "No space left on device (simulated)"), KeyboardInterrupt()]
)
def test_failure_while_staging_leaves_nothing(tmp_path, error):
    def failing(path: Path) -> None:
        path.write_bytes(b"half a file")
        raise error

    fresh = tmp_path / "fresh" / "nested"
    targets = {fresh / "a": b"complete\n", fresh / "b": failing, fresh / "c": b"never staged\n"}
    with pytest.raises(type(error)):
        write_files(targets)
    assert not (tmp_path / "fresh").exists()  # no partial file, no temporary, no created directory
    existing = tmp_path / "existing"
    existing.mkdir()
    with pytest.raises(type(error)):
        write_files({existing / "a": b"complete\n", existing / "b": failing})
    assert _listing(existing) == []


@pytest.mark.parametrize("victim", ["fsync", "replace"])
def test_failure_mid_write_leaves_no_partial_set(tmp_path, monkeypatch, victim):
    real = getattr(os, victim)
    calls = []

    def fail_second(*args, **kwargs):
        calls.append(args)
        if len(calls) == 2:
            raise OSError(28, "No space left on device (simulated)")
        return real(*args, **kwargs)

    monkeypatch.setattr(os, victim, fail_second)
    targets = {tmp_path / "a": b"1\n", tmp_path / "b": b"2\n", tmp_path / "c": b"3\n"}
    with pytest.raises(OSError, match="simulated"):
        write_files(targets)
    assert _listing(tmp_path) == []  # the first file, already renamed, is removed again
    monkeypatch.undo()
    write_files(targets)  # and a retry succeeds
    assert _listing(tmp_path) == ["a", "b", "c"]


def test_writes_inside_a_scratch_directory_are_not_fsynced(tmp_path, monkeypatch):
    """scratch(): a private directory whose files a later write copies needs no fsync; every
    other write (the set around it, the same set afterwards) is fsync-ed as before."""
    real, synced = os.fsync, []

    def counting(fd):
        synced.append(os.readlink(f"/proc/self/fd/{fd}") if os.path.exists("/proc") else fd)
        return real(fd)

    monkeypatch.setattr(os, "fsync", counting)
    inside, outside = tmp_path / "scratch", tmp_path / "kept"
    contents = {"a": b"1\n", "sub/b": b"2\n"}
    with scratch(inside):
        write_files({inside / k: v for k, v in contents.items()})
        in_block = len(synced)
        write_files({outside / k: v for k, v in contents.items()})
    assert in_block == 0
    after_block = len(synced)
    assert after_block > 0  # outside the directory, inside the block: fsync-ed
    assert all(not str(p).startswith(str(inside)) for p in synced)
    write_files({inside / "c": b"3\n"})  # after the block: fsync-ed again
    assert len(synced) > after_block
    assert _listing(inside) == ["a", "c", "sub"] and (inside / "sub" / "b").read_bytes() == b"2\n"


@pytest.mark.parametrize("fail_at", [2, 3])
def test_overwrite_failure_keeps_the_old_set(tmp_path, monkeypatch, fail_at):
    """With overwrite=True a failed rename leaves the old set, whole."""
    for name in "ab":
        (tmp_path / name).write_text(f"old {name}\n")
    real, calls = os.replace, []

    def fail_second(*args):
        calls.append(args)
        if len(calls) == fail_at:
            raise OSError("simulated")
        return real(*args)

    monkeypatch.setattr(os, "replace", fail_second)
    with pytest.raises(OSError, match="simulated"):
        write_files({tmp_path / "a": b"new a\n", tmp_path / "b": b"new b\n"}, overwrite=True)
    assert _listing(tmp_path) == ["a", "b"]  # no temporary files
    # The old set, whole: the file already replaced is put back from its link.
    assert (tmp_path / "a").read_text() == "old a\n"
    assert (tmp_path / "b").read_text() == "old b\n"
    assert len(calls) >= 2


def test_format_error_is_a_value_error():
    assert issubclass(FormatError, ValueError)


# ------------------------------------------------------------------ exact text


@given(
    st.floats(allow_nan=False, allow_infinity=False, min_value=-1e290, max_value=1e290),
    st.sampled_from([-12, -9, 0, 9, 12]),
)
def test_shifted_text_reads_back_exactly(x, exponent):
    text = _text.shift(x, exponent)
    assert _text.parse(Path("f.csv"), 2, "c", text, exponent) == x


def test_shift_is_the_correctly_rounded_product():
    # 1.5 um^2 = 1.5e-12 m^2 exactly in decimal; the float of that text is the
    # correctly rounded value of 1.5e-12.
    assert _text.shift(1.5, -12) == "1.5e-12"
    assert float(_text.shift(0.1, -12)) == 1e-13


def test_parse_names_the_file_line_and_column():
    with pytest.raises(FormatError, match=r"f.csv: line 3, column 2 \(g\): not a number: 'x'"):
        _text.parse(Path("f.csv"), 3, "2 (g)", "x")
    with pytest.raises(FormatError, match="not a finite number: 'nan'"):
        _text.parse(Path("f.csv"), 3, "2 (g)", "nan")


@pytest.mark.parametrize(
    ("data", "message"),
    [(b"", "empty"), (b"a,b\n1,2", "does not end with a newline"), (b"a,\xff\n", "not an ASCII")],
)
def test_read_rows_rejects_bad_files(tmp_path, data, message):
    path = tmp_path / "bad.csv"
    path.write_bytes(data)
    with pytest.raises(FormatError, match=f"bad.csv: .*{message}"):
        _text.read_rows(path)


# ------------------------------------------------------------------ sets, leftovers, locks


def _kill_during(
    tmp_path: Path, victim: str, nth: int, contents: dict, overwrite: bool = True
) -> None:
    """Run write_files in a forked child that dies (os._exit) at the nth call of os.<victim>."""
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        real = getattr(os, victim)
        calls = []

        def die(*args, **kwargs):
            calls.append(args)
            if len(calls) == nth:
                os._exit(9)
            return real(*args, **kwargs)

        setattr(os, victim, die)
        try:
            write_files(contents, overwrite=overwrite)
        finally:
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 9


@pytest.mark.parametrize(
    ("victim", "nth"), [("fsync", 2), ("replace", 1), ("replace", 2), ("replace", 3)]
)
def test_a_killed_write_leaves_the_old_or_the_new_set_after_the_next_run(tmp_path, victim, nth):
    out = tmp_path / "out"
    write_files({out / "a": b"old a\n", out / "b": b"old b\n", out / "c": b"old c\n"})
    new = {out / "a": b"new a\n", out / "b": b"new b\n", out / "c": b"new c\n"}
    _kill_during(tmp_path, victim, nth, new)
    assert any(is_leftover(p.name) for p in out.iterdir())  # the kill left its staging
    cleaned = clean_leftovers(out)
    assert cleaned and _listing(out) == ["a", "b", "c"]
    texts = {(out / n).read_text() for n in "abc"}
    # Killed before the manifest: the old set; after it (while moving): rolled forward to the new.
    assert texts in ({"old a\n", "old b\n", "old c\n"}, {"new a\n", "new b\n", "new c\n"})
    if victim == "replace" and nth >= 2:
        assert texts == {"new a\n", "new b\n", "new c\n"}


def test_leftovers_do_not_block_a_rerun_and_are_cleaned(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / ".a.h5.abcd1234.tmp").write_bytes(b"half")  # an earlier version's temporary
    (out / ".dustoptics-stage-deadbeef").mkdir()  # a staging directory whose lock is free
    (out / ".dustoptics-stage-deadbeef" / "a.h5").write_bytes(b"half")
    write_files({out / "a.h5": b"whole\n"})
    assert _listing(out) == ["a.h5"]


def test_a_live_staging_directory_is_not_touched(tmp_path):
    import fcntl

    out = tmp_path / "out"
    live = out / ".dustoptics-stage-alive123"
    live.mkdir(parents=True)
    fd = os.open(live, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        assert clean_leftovers(out) == []
        write_files({out / "x": b"1\n"})
        assert live.exists()
    finally:
        os.close(fd)
    clean_leftovers(out)
    assert not live.exists()


def test_file_set_writes_all_or_nothing(tmp_path):
    out = tmp_path / "out"
    write_files({out / "a": b"old a\n", out / "b": b"old b\n"})
    with pytest.raises(RuntimeError, match="third format"), file_set(out, overwrite=True):
        write_files({out / "a": b"new a\n"}, overwrite=True)
        write_files({out / "b": b"new b\n"}, overwrite=True)
        raise RuntimeError("the third format rejects the table")
    assert [(out / n).read_text() for n in "ab"] == ["old a\n", "old b\n"]
    with file_set(out, overwrite=True):
        write_files({out / "a": b"new a\n"}, overwrite=True)
        assert (out / "a").read_text() == "old a\n"  # nothing written before the set is whole
        write_files({out / "sub" / "b": b"new b\n"}, overwrite=True)
    assert (out / "a").read_text() == "new a\n" and (out / "sub" / "b").read_text() == "new b\n"


@pytest.mark.parametrize("name", ["../escaped", "/abs/olute"])
def test_a_file_set_refuses_targets_outside_its_root(tmp_path, name):
    out = tmp_path / "out"
    with pytest.raises(ValueError, match="outside the output directory"), file_set(out):
        write_files({out / name / "a.csv": b"x\n"})
    assert not (tmp_path / "escaped").exists()


def test_a_symlink_out_of_the_root_is_refused(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "name").symlink_to(elsewhere)
    with pytest.raises(ValueError, match="outside the output directory"), file_set(out):
        write_files({out / "name" / "a.csv": b"x\n"})
    assert _listing(elsewhere) == []


def test_concurrent_sets_never_mix(tmp_path):
    """Processes replacing the same set at once: every file of the result comes from one of them."""
    out = tmp_path / "out"
    names = [f"f{i}" for i in range(6)]
    pids = []
    for k in range(4):
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child
            try:
                for _ in range(5):
                    write_files({out / n: f"{k}\n".encode() for n in names}, overwrite=True)
            finally:
                os._exit(0)
        pids.append(pid)
    for pid in pids:
        os.waitpid(pid, 0)
    assert len({(out / n).read_text() for n in names}) == 1
    assert _listing(out) == names


def test_full_disk_leaves_the_old_set(tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_files({out / "a": b"old a\n", out / "b": b"old b\n"})

    def full(path: Path) -> None:
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space left"):
        write_files({out / "a": b"new a\n", out / "b": full}, overwrite=True)
    assert _listing(out) == ["a", "b"] and (out / "a").read_text() == "old a\n"


# ------------------------------------------------------------------ readers' limits (issue 15)


def test_a_phase_csv_of_blank_lines_is_a_format_error(tmp_path):
    from dustoptics.io.csv.seed import read_phase_csv

    path = tmp_path / "MiePhaseFunctionSpectrum.csv"
    path.write_text("\n\n\n")
    with pytest.raises(FormatError, match="line 1 is blank"):
        read_phase_csv(path)


def test_a_cell_beyond_the_csv_field_limit_is_a_format_error(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text("a," + "9" * (200 * 1024) + "\n")
    with pytest.raises(FormatError, match="not a valid CSV file.*field larger than field limit"):
        _text.read_rows(path)


def test_too_many_cells_are_refused_before_parsing(tmp_path, monkeypatch):
    monkeypatch.setattr(_text, "MAX_CSV_CELLS", 10)
    path = tmp_path / "wide.csv"
    path.write_text(",".join("1" * 20) + "\n")
    with pytest.raises(FormatError, match="more than the 10"):
        _text.read_rows(path)


@pytest.mark.parametrize("special", ["fifo", "/dev/zero", "directory"])
def test_fifos_devices_and_directories_are_refused_before_reading(tmp_path, special):
    if special == "fifo":
        path = tmp_path / "ozone.csv"
        os.mkfifo(path)  # opening it for reading would block without O_NONBLOCK
    elif special == "directory":
        path = tmp_path
    else:
        path = Path(special)
    with pytest.raises(FormatError, match="not a regular file"):
        _text.read_checked(path)


def test_a_file_beyond_the_size_limit_is_refused(tmp_path):
    path = tmp_path / "big.json"
    path.write_bytes(b" " * 1001)
    with pytest.raises(FormatError, match="larger than the 1000-byte limit"):
        _text.read_checked(path, limit=1000)


def test_deeply_nested_json_is_refused_without_recursion(tmp_path):
    from dustoptics.io import read_seed_csv

    path = tmp_path / "table_summary.json"
    path.write_text("[" * 100_000 + "]" * 100_000, encoding="ascii")
    with pytest.raises(FormatError, match="nested deeper than 32"):
        _text.load_json(path)
    with pytest.raises(FormatError, match="not a valid JSON table summary"):
        read_seed_csv(tmp_path)
    path.write_text('{"a": "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[["}', encoding="ascii")
    assert _text.load_json(path) == {"a": "[" * 40}  # brackets inside strings do not count


def test_printable_escapes_what_a_terminal_would_obey():
    text = "name\x1b]0;title\x07\x1b[2J\x9b31m\u202eevil\r\n"
    shown = _text.printable(text)
    assert shown == "name\\x1b]0;title\\x07\\x1b[2J\\x9b31m\\u202eevil\\x0d\\x0a"
    assert shown.isprintable()


# ------------------------------------------------------------------ kill -9 at every step (issue 29)

_NAMES = [f"f{i}" for i in range(7)]


def _steps(tmp_path: Path, monkeypatch, contents: dict, overwrite: bool = True) -> list[str]:
    """The steps a write of ``contents`` goes through (recorded on a scratch copy)."""
    from dustoptics.io import _atomic

    scratch = tmp_path / "scratch"
    shutil.copytree(next(iter(contents)).parent, scratch, dirs_exist_ok=True)
    seen: list[str] = []
    monkeypatch.setattr(_atomic, "_STEP_HOOK", seen.append)
    write_files({scratch / p.name: c for p, c in contents.items()}, overwrite=overwrite)
    monkeypatch.setattr(_atomic, "_STEP_HOOK", None)
    shutil.rmtree(scratch)
    return seen


def _killed_at(step: int, write) -> None:
    """Run ``write()`` in a forked child that is killed (SIGKILL) at its ``step``-th step."""
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        from dustoptics.io import _atomic

        count = iter(range(10**6))

        def hook(name: str) -> None:
            if next(count) == step:
                os.kill(os.getpid(), signal.SIGKILL)

        _atomic._STEP_HOOK = hook
        try:
            write()
        finally:
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL, status


def _set_state(out: Path, sets: dict[str, dict[str, bytes]]) -> str:
    """Which of ``sets`` the folder holds whole ("" for none of the names; AssertionError if mixed)."""
    present = {n: (out / n).read_bytes() for n in _NAMES if (out / n).exists()}
    if not present:
        return ""
    for label, files in sets.items():
        if present == files:
            return label
    raise AssertionError(f"a mixed or partial set: {sorted(present)} of {sets}")


@pytest.mark.parametrize("existing", [True, False], ids=["replace a set", "a new set"])
def test_a_set_killed_at_any_step_reads_whole_or_is_refused(tmp_path, monkeypatch, existing):
    from dustoptics.io._atomic import whole_set

    old = {n: f"old {n}\n".encode() for n in _NAMES}
    new = {n: f"new {n}\n".encode() for n in _NAMES}
    template = tmp_path / "template"
    template.mkdir()
    if existing:
        for n, data in old.items():
            (template / n).write_bytes(data)
    steps = _steps(tmp_path, monkeypatch, {template / n: d for n, d in new.items()})
    assert steps[0] == "staged f0" and "journal" in steps and steps[-1] == "published"
    publishing = steps.index("journal")
    for k, step in enumerate(steps):
        out = tmp_path / f"killed-at-{k}"
        shutil.copytree(template, out)
        _killed_at(
            k, lambda out=out: write_files({out / n: d for n, d in new.items()}, overwrite=True)
        )
        sets = {"old": old, "new": new} if existing else {"new": new}
        try:
            with whole_set(out):
                state = _set_state(out, sets)
            refused = False
        except FormatError as exc:
            assert "interrupted write" in str(exc) and step.startswith(("journal", "move")), step
            refused = True
        # Killed while moving, the set is mixed: a reader must have refused it.
        assert refused or state in ("old", "new", ""), step
        # A later, unrelated write into the folder settles it: the killed run's set whole if it
        # had begun to publish, else untouched; never rolled forward before its journal.
        write_files({out / "unrelated": b"another run\n"})
        with whole_set(out):
            state = _set_state(out, sets)
        expected = "new" if k >= publishing else ("old" if existing else "")
        assert state == expected, (step, state)
        assert sorted(p.name for p in out.iterdir()) == sorted(
            ([*_NAMES] if state else []) + ["unrelated"]
        ), step


def test_a_later_placement_completes_the_killed_run_first_never_mixing_three(tmp_path, monkeypatch):
    """Run A killed while moving; run B (other contents, some equal to the oldest set's) then
    places its files with force: the folder holds B's set, whole, never A's files among B's."""
    from dustoptics.io import _atomic
    from dustoptics.io.outputs import place_outputs

    def render(files: dict[str, bytes]):
        def write(directory: Path) -> list[Path]:
            for n, data in files.items():
                (directory / n).write_bytes(data)
            return [directory / n for n in files]

        return write

    run0 = {n: f"0 {n}\n".encode() for n in _NAMES}
    run_a = {n: f"A {n}\n".encode() for n in _NAMES}
    run_b = {n: (run0[n] if i % 2 else f"B {n}\n".encode()) for i, n in enumerate(_NAMES)}
    out = tmp_path / "out"
    place_outputs(render(run0), out, force=False)
    seen: list[str] = []
    monkeypatch.setattr(_atomic, "_STEP_HOOK", seen.append)
    place_outputs(render(run_a), tmp_path / "scratch", force=True)
    monkeypatch.setattr(_atomic, "_STEP_HOOK", None)
    for k in [i for i, s in enumerate(seen) if s.startswith("move ")][1:]:
        shutil.rmtree(out)
        place_outputs(render(run0), out, force=False)
        _killed_at(k, lambda: place_outputs(render(run_a), out, force=True))
        with pytest.raises(FileExistsError, match="differ"):
            place_outputs(render(run_b), out, force=False)
        placed = place_outputs(render(run_b), out, force=True)
        assert {n: (out / n).read_bytes() for n in _NAMES} == run_b, seen[k]
        assert sorted(p.name for p in out.iterdir()) == _NAMES
        assert len(placed.written) == len(_NAMES)  # A's files, completed first, all differ


def test_info_refuses_a_set_killed_while_moving(tmp_path):
    import dustoptics as do
    from dustoptics.io.describe import describe_path
    from dustoptics.io.outputs import write_formats

    def table(name: str, r: float) -> do.Table:
        return do.compute_optics(
            1.5, do.Monodisperse(radius_um=r), [550.0, 680.0], [0.0, 90.0, 180.0], name=name
        )

    out = tmp_path / "out"
    write_formats(table("t", 0.5), out, ["hdf5", "csv"])
    assert "name:            t" in describe_path(out)
    new = table("t", 0.7)
    from dustoptics.io import _atomic

    seen: list[str] = []
    _atomic._STEP_HOOK = seen.append
    try:
        write_formats(new, tmp_path / "scratch", ["hdf5", "csv"])
    finally:
        _atomic._STEP_HOOK = None
    second_move = [i for i, s in enumerate(seen) if s.startswith("move ")][1]
    _killed_at(second_move, lambda: write_formats(new, out, ["hdf5", "csv"], overwrite=True))
    with pytest.raises(FormatError, match=r"interrupted write left this set incomplete in .*out"):
        describe_path(out)
    with pytest.raises(FormatError, match="interrupted write"):
        describe_path(out / "t.h5")
    write_files({out / "notes.txt": b"later\n"})  # the next write completes it
    assert do.open_table(out / "t.h5").equals(new)
    assert "name:            t" in describe_path(out / "t.h5")


def test_a_new_staging_directory_is_locked_before_another_writer_can_clean(tmp_path, monkeypatch):
    """Another writer cleans leftovers holding the root's lock: by the time it has that lock,
    a new staging directory must hold its own (else it is taken for a killed run's)."""
    import tempfile
    import threading

    from dustoptics.io import _atomic

    real, seen = tempfile.mkdtemp, []

    def other_writer(root: Path, stage: str) -> None:
        with _atomic._locked(root):  # a separate open of the folder: it waits like a process
            try:
                fd = os.open(stage, os.O_RDONLY)
            except FileNotFoundError:  # the write got the root's lock back first and finished
                seen.append("gone")
                return
            try:
                seen.append("free" if _atomic._try_lock(fd) else "held")
            finally:
                os.close(fd)

    def racing(*args, **kwargs):
        stage = real(*args, **kwargs)
        thread = threading.Thread(target=other_writer, args=(Path(kwargs["dir"]), stage))
        thread.start()
        threads.append(thread)
        thread.join(0.3)  # the other writer cleans now, if it can
        return stage

    threads: list[threading.Thread] = []
    monkeypatch.setattr(_atomic.tempfile, "mkdtemp", racing)
    out = tmp_path / "out"
    out.mkdir()
    write_files({out / "a": b"1\n", out / "b": b"2\n"})
    for thread in threads:
        thread.join()
    # Never "free": whenever the other writer holds the root's lock, the staging directory is
    # either locked by its writer or already gone (on a busy machine the write may take the
    # root's lock back first and finish).
    assert seen in (["held"], ["gone"]), (
        "the staging directory was unlocked when another writer could clean"
    )
    assert _listing(out) == ["a", "b"]
