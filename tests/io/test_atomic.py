"""Tests for dustoptics.io._atomic (atomic multi-file writes) and dustoptics.io._text."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from dustoptics.io import _text
from dustoptics.io._atomic import FILE_MODE, FormatError, check_targets, write_files


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
    # The callback wrote a temporary file in the target directory, hidden and then renamed.
    assert seen[0].parent == b.parent and seen[0].name.startswith(".b.h5.")
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


def test_overwrite_failure_keeps_complete_files(tmp_path, monkeypatch):
    """With overwrite=True a failed rename leaves each file complete (old or new), never partial."""
    for name in "ab":
        (tmp_path / name).write_text(f"old {name}\n")
    real, calls = os.replace, []

    def fail_second(*args):
        calls.append(args)
        if len(calls) == 2:
            raise OSError("simulated")
        return real(*args)

    monkeypatch.setattr(os, "replace", fail_second)
    with pytest.raises(OSError, match="simulated"):
        write_files({tmp_path / "a": b"new a\n", tmp_path / "b": b"new b\n"}, overwrite=True)
    assert _listing(tmp_path) == ["a", "b"]  # no temporary files
    assert (tmp_path / "a").read_text() == "new a\n"
    assert (tmp_path / "b").read_text() == "old b\n"


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
