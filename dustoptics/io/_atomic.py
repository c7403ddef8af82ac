"""The one atomic-write mechanism of the package, and the readers' error type.

Every writer in :mod:`dustoptics.io` prepares its output completely (bytes in
memory, or a callback that writes a file by name, for h5py), then calls
:func:`write_files`.  A set of files is written as one transaction:

1. refuse if any target exists and ``overwrite`` is False
   (:class:`FileExistsError` naming every existing target), and refuse any
   target that resolves outside the set's root directory (symbolic links
   included), before anything is written;
2. stage every file into a new hidden staging directory inside the root
   (``ROOT/.dustoptics-stage-XXXXXXXX/``, the files at their paths relative to
   the root), each flushed and :func:`os.fsync`-ed, while holding an
   exclusive :func:`fcntl.flock` on that directory (it marks the staging as
   alive);
3. take an exclusive :func:`fcntl.flock` on the root directory itself (no
   lock file is left behind), settle what interrupted runs left (below),
   decide what to write (check the targets again; :func:`place_outputs
   <dustoptics.io.outputs.place_outputs>` compares them with the files there
   now), then publish: write the staging directory's journal (``.complete``:
   the relative paths), move every staged file into place with
   :func:`os.replace` (keeping a hard link to each file it replaces), fsync
   the directories, remove the journal and the staging directory.  If a move
   fails, the files already moved are put back (the old ones from their
   links, new targets removed), so the old set is left whole.

Concurrent writers of the same root therefore replace the set one after the
other, never interleaved.  A failure before the journal (an error, a full
disk, KeyboardInterrupt) removes the staging directory and leaves the old
set.  A kill (``kill -9``, power loss) before the journal leaves a staging
directory without one, which the next write into that root deletes: nothing
of that run appears.  A kill while publishing leaves a staging directory with
its journal and some files not yet moved: the set in the root is then part
old, part new, and

- a reader that checks (:func:`whole_set`, which ``dustoptics info`` uses)
  refuses it, naming the files and the staging directory;
- the next write into that root (holding the root's lock, before it looks
  at anything there) completes the interrupted run alone (roll forward: the
  journal's files not yet moved are moved, and the set becomes that run's,
  whole), then writes its own.  A staging directory whose run never began to
  publish is never rolled forward.

It also deletes ``.NAME.XXXXXXXX.tmp`` files that earlier versions staged
beside their targets.  Leftovers never make a rerun refuse (see
:func:`is_leftover`).

:func:`file_set` groups several writers (several formats of one table, an
atmosphere's CSV set and its settings) into one such transaction: inside it,
:func:`write_files` only collects; the set is written when the block ends
without an error, and nothing is written otherwise.

Writers name their files after the table (:func:`safe_stem`).  Readers raise
:class:`FormatError` (a :class:`ValueError`) naming the file and what is wrong
with it.
"""

from __future__ import annotations

import contextlib
import contextvars
import errno
import fcntl
import json
import os
import re
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from dustoptics._files import FormatError
from dustoptics._validation import check_inside

__all__ = [
    "FILE_MODE",
    "Content",
    "FormatError",
    "check_targets",
    "clean_leftovers",
    "file_set",
    "held_lock",
    "interrupted_sets",
    "is_leftover",
    "safe_stem",
    "scratch",
    "whole_set",
    "write_files",
]

#: Prefix of the staging directories (see the module docstring).
STAGE_PREFIX = ".dustoptics-stage-"

#: The manifest that marks a staging directory complete.
MANIFEST = ".complete"

#: Subdirectory of a staging directory holding links to the files replaced.
BACKUP = ".replaced"

#: Temporary files that earlier versions staged beside their targets.
_LEGACY_TMP = re.compile(r"^\..+\.[A-Za-z0-9_]{8}\.tmp$")

#: Permission bits of written files (tables are meant to be shared and read).
FILE_MODE = 0o644

#: What :func:`write_files` writes to one target: its bytes, or a callback
#: that writes the file at the (temporary) path it is given.
Content = bytes | Callable[[Path], None]


def safe_stem(name: str) -> str:
    """A file-name stem from a table name: characters other than [A-Za-z0-9._-] become '_'.

    Leading dots are dropped (no hidden files); nothing left gives ``"table"``.

    >>> safe_stem("mars dust/1"), safe_stem("..x"), safe_stem("")
    ('mars_dust_1', 'x', 'table')
    """
    stem = re.sub(r"[^A-Za-z0-9._-]", "_", name).lstrip(".")
    return stem or "table"


def check_targets(paths: list[Path] | tuple[Path, ...], *, overwrite: bool) -> None:
    """Refuse to replace existing files unless ``overwrite`` is True.

    Parameters
    ----------
    paths : sequence of pathlib.Path
        The files a writer is about to write.
    overwrite : bool
        Whether existing files may be replaced.

    Raises
    ------
    FileExistsError
        Some targets exist and ``overwrite`` is False; the message names all
        of them.
    """
    if overwrite:
        return
    existing = [str(p) for p in paths if p.exists() or p.is_symlink()]
    if existing:
        raise FileExistsError(
            f"{', '.join(existing)} already exist{'s' if len(existing) == 1 else ''} "
            "(pass overwrite=True, or --force on the command line, to replace)"
        )


#: The private temporary directory of :func:`scratch`, or None.
_SCRATCH: contextvars.ContextVar[str | None] = contextvars.ContextVar(
    "dustoptics_scratch", default=None
)


@contextlib.contextmanager
def scratch(directory: str | os.PathLike[str]) -> Iterator[None]:
    """Inside the block, files and directories written inside ``directory`` are not fsync-ed.

    For a private temporary directory whose files a later write copies to where they go
    (:func:`~dustoptics.io.outputs.place_outputs` renders a build's files there, then
    compares them with the files in place and writes the new ones, fsync-ed): their
    durability is that write's.  Each file of a ``dustoptics build`` was fsync-ed twice,
    with its directories (20 fsyncs for the default preset's 4 files); the steps, locks
    and checks stay the same.
    """
    token = _SCRATCH.set(os.path.abspath(directory))
    try:
        yield
    finally:
        _SCRATCH.reset(token)


def _fsync(fd: int, path: str | os.PathLike[str]) -> None:
    """:func:`os.fsync`, unless ``path`` is inside the :func:`scratch` directory."""
    root = _SCRATCH.get()
    if root is not None:
        where = os.path.abspath(path)
        if where == root or where.startswith(root + os.sep):
            return
    os.fsync(fd)


def _fsync_path(path: Path) -> None:
    with open(path, "rb") as handle:
        _fsync(handle.fileno(), path)


def _fsync_directory(directory: Path) -> None:
    """Make the renames durable (POSIX); a no-op where directories cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        _fsync(fd, directory)
    except OSError:
        pass
    finally:
        os.close(fd)


def is_leftover(name: str) -> bool:
    """Whether a directory entry called ``name`` is what an interrupted write left.

    Staging directories (``.dustoptics-stage-*``) and ``.NAME.XXXXXXXX.tmp``
    files; callers that check whether a directory already holds a set ignore
    them (the next write cleans them).
    """
    return name.startswith(STAGE_PREFIX) or bool(_LEGACY_TMP.match(name))


def _try_lock(fd: int, *, shared: bool = False) -> bool:
    try:
        fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
    except OSError as exc:
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            return False
        raise
    return True


def _journal(stage: Path) -> list[str] | None:
    """The relative paths a staging directory's journal lists, or None without a journal."""
    try:
        names = json.loads((stage / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    if not isinstance(names, list):
        return None
    return [name for name in names if isinstance(name, str)]


def _roll_forward(root: Path, stage: Path) -> None:
    """Complete an interrupted run: move its journal's files not yet moved into place."""
    names = _journal(stage) or []
    for name in names:
        source = stage / name
        target = root / name
        try:
            check_inside(root, target)
        except ValueError:
            continue
        if source.is_file() and not source.is_symlink():
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(source, target)
    for directory in dict.fromkeys([root, *((root / n).parent for n in names)]):
        _fsync_directory(directory)


def clean_leftovers(root: str | os.PathLike[str], directories: tuple[Path, ...] = ()) -> list[Path]:
    """Clean what interrupted writes left in ``root`` (call it holding ``root``'s lock).

    Staging directories whose lock is free: one with a journal (its run was
    killed while publishing) is rolled forward, the files it had not yet
    moved moved into place, so that the set becomes that run's, whole; one
    without (its run never began to publish) is deleted.
    ``.NAME.XXXXXXXX.tmp`` files in ``root`` and in ``directories`` are
    deleted.  Returns what was cleaned.
    """
    base = Path(root)
    cleaned: list[Path] = []
    if not base.is_dir():
        return cleaned
    for entry in sorted(base.iterdir()):
        if entry.name.startswith(STAGE_PREFIX) and entry.is_dir() and not entry.is_symlink():
            fd = os.open(entry, os.O_RDONLY)
            try:
                if not _try_lock(fd):
                    continue  # another process is staging into it
                if (entry / MANIFEST).is_file():
                    _roll_forward(base, entry)
                shutil.rmtree(entry, ignore_errors=True)
                cleaned.append(entry)
            finally:
                os.close(fd)
    for directory in dict.fromkeys((base, *directories)):
        if not directory.is_dir():
            continue
        for entry in directory.iterdir():
            if _LEGACY_TMP.match(entry.name) and entry.is_file() and not entry.is_symlink():
                entry.unlink(missing_ok=True)
                cleaned.append(entry)
    return cleaned


#: Directories :func:`whole_set` checks: the one given (or a file's) and its parents up to
#: this many in all (a set's files lie at most two folders below its root).
_ROOT_LEVELS = 3

#: Seconds :func:`whole_set` waits for a writer that is publishing a set.
WAIT_FOR_WRITER_S = 30.0


def interrupted_sets(path: str | os.PathLike[str]) -> list[tuple[Path, list[Path]]]:
    """The interrupted sets ``path`` belongs to: (staging directory, files not yet moved).

    A set is interrupted when a run was killed while publishing it (see the
    module docstring): its staging directory holds a journal and files not
    yet moved.  Only sets with a file at ``path`` (a file) or inside it (a
    directory) count; ``path``'s directory and its parents up to
    :data:`_ROOT_LEVELS` in all are searched.  Call it holding those
    directories' locks (:func:`whole_set` does), or a writer may be
    publishing meanwhile.
    """
    target = Path(os.path.abspath(path))
    start = target if target.is_dir() else target.parent
    found = []
    for root in [start, *start.parents][:_ROOT_LEVELS]:
        try:
            entries = sorted(e for e in root.iterdir() if e.name.startswith(STAGE_PREFIX))
        except OSError:
            continue
        for stage in entries:
            names = _journal(stage) if stage.is_dir() and not stage.is_symlink() else None
            if not names:
                continue
            ours = [n for n in names if (root / n) == target or target in (root / n).parents]
            left = [root / n for n in names if (stage / n).is_file()]
            if ours and left:
                found.append((stage, left))
    return found


def _lock_or_unsupported(fd: int) -> bool:
    """Take a shared lock without waiting; True also where the file system has no flock."""
    try:
        return _try_lock(fd, shared=True)
    except OSError:
        return True


@contextlib.contextmanager
def whole_set(
    path: str | os.PathLike[str], *, timeout_s: float = WAIT_FOR_WRITER_S
) -> Iterator[None]:
    """Read the set ``path`` belongs to inside the block, or refuse it if a run left it incomplete.

    Holds a shared :func:`fcntl.flock` on ``path``'s directory and its parents
    (up to :data:`_ROOT_LEVELS` in all), so no writer publishes into them
    during the block; waits up to ``timeout_s`` for one that is publishing.

    Raises
    ------
    FormatError
        A run was killed while publishing the set (:func:`interrupted_sets`):
        the message names the files not yet moved and the staging directory;
        or a writer held a directory longer than ``timeout_s``.
    """
    target = Path(os.path.abspath(path))
    start = target if target.is_dir() else target.parent
    with contextlib.ExitStack() as stack:
        for root in [start, *start.parents][:_ROOT_LEVELS]:
            try:
                fd = os.open(root, os.O_RDONLY)
            except OSError:
                continue
            stack.callback(os.close, fd)
            deadline = time.monotonic() + timeout_s
            while not _lock_or_unsupported(fd):
                if time.monotonic() > deadline:
                    raise FormatError(
                        f"{target}: another process has been writing into {root} for "
                        f"{timeout_s:g} s; try again when it has finished"
                    )
                time.sleep(0.05)
        for stage, left in interrupted_sets(target):
            shown = ", ".join(p.name for p in left[:4]) + (
                f" and {len(left) - 4} more" if len(left) > 4 else ""
            )
            raise FormatError(
                f"{target}: an interrupted write left this set incomplete in {stage.parent} "
                f"({shown} not yet in place; their new versions wait in {stage.name}); "
                "write the set again: the next write into that folder completes or replaces it"
            )
        yield


def _stage_file(path: Path, content: Content) -> None:
    """Write ``content`` to ``path`` (new), flushed, fsync-ed, mode :data:`FILE_MODE`.

    An :class:`OSError` that names no file (``write``'s ENOSPC, ``fsync``'s EIO) is raised
    again naming ``path``: a user sees which file of which folder could not be written.
    """
    try:
        _write_new(path, content)
    except OSError as exc:
        if exc.filename is not None or exc.errno is None:
            raise
        raise type(exc)(exc.errno, f"{exc.strerror} (writing)", str(path)) from None


def _write_new(path: Path, content: Content) -> None:
    if isinstance(content, bytes):
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as handle:
            handle.write(content)
            handle.flush()
            _fsync(handle.fileno(), path)
    else:
        content(path)
        if not path.is_file():
            raise OSError(f"{path}: the writer did not create the file")
        _fsync_path(path)
    os.chmod(path, FILE_MODE)


def _missing_directories(directory: Path) -> list[Path]:
    """``directory`` and its missing parents, deepest first."""
    missing = []
    current = directory.absolute()
    while not current.exists():
        missing.append(current)
        if current.parent == current:
            break
        current = current.parent
    return missing


@contextlib.contextmanager
def _locked(directory: Path) -> Iterator[None]:
    """Hold an exclusive flock on ``directory`` (blocking)."""
    fd = os.open(directory, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


@contextlib.contextmanager
def held_lock(directory: str | os.PathLike[str], *, shared: bool = False) -> Iterator[int | None]:
    """Hold a flock on ``directory`` for the block if no other holder conflicts; never waits.

    Yields the directory's open descriptor while the lock is held (the lock follows the
    directory through a rename), or None when another open of it holds a conflicting lock
    (an exclusive one; any one unless ``shared``).  The lock ends with the block.  The
    sweep stores (:mod:`dustoptics.sweep.store`) are held this way by the run that writes
    them.
    """
    fd = os.open(directory, os.O_RDONLY)
    try:
        yield fd if _try_lock(fd, shared=shared) else None
    finally:
        os.close(fd)  # releases the lock


#: Called with the name of each step of a write (tests stop or slow a writer there).
_STEP_HOOK: Callable[[str], None] | None = None


def _step(name: str) -> None:
    if _STEP_HOOK is not None:
        _STEP_HOOK(name)


def _commit(
    contents: Mapping[Path, Content],
    *,
    overwrite: bool,
    root: Path | None,
    select: Callable[[list[Path]], list[Path]] | None = None,
) -> list[Path]:
    """Write ``contents`` as one set (the module docstring's steps); the targets written.

    ``select(targets)``, called under the root's lock after leftovers are
    settled, returns the targets to write (the others are dropped); it may
    raise to write nothing.  Without it, existing targets are refused unless
    ``overwrite`` before anything is staged.
    """
    targets = [Path(os.path.abspath(p)) for p in contents]
    if len(set(targets)) != len(targets):
        raise ValueError(f"write_files: duplicate targets in {[str(t) for t in contents]}")
    if not targets:
        return []
    base = (
        Path(os.path.abspath(root))
        if root is not None
        else Path(os.path.commonpath([str(t.parent) for t in targets]))
    )
    for target in targets:
        check_inside(base, target)
        if target.name.startswith(STAGE_PREFIX) or target.name == MANIFEST:
            raise ValueError(f"write_files: {str(target)!r} uses a name reserved for staging")
    if select is None:
        check_targets(targets, overwrite=overwrite)
    created_dirs: list[Path] = []
    for directory in dict.fromkeys([base, *(t.parent for t in targets)]):
        missing = _missing_directories(directory)
        directory.mkdir(parents=True, exist_ok=True)
        created_dirs.extend(missing)
    # Resolve again now that the directories exist (a symlink among them).
    for target in targets:
        check_inside(base, target)
    relative = dict(zip(targets, (t.relative_to(base) for t in targets)))
    with _locked(base):
        # Created and locked under the root's lock, which another writer's cleanup holds:
        # that cleanup never sees this staging directory before its lock is taken.
        stage = Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=base))
        try:
            stage_fd = os.open(stage, os.O_RDONLY)
            fcntl.flock(stage_fd, fcntl.LOCK_EX)
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            raise
    done = False
    written: list[Path] = []
    try:
        for target, content in zip(targets, contents.values()):
            path = stage / relative[target]
            path.parent.mkdir(parents=True, exist_ok=True)
            _stage_file(path, content)
            _step(f"staged {relative[target]}")
        _fsync_directory(stage)
        with _locked(base):
            _step("locked")
            clean_leftovers(base, tuple(dict.fromkeys(t.parent for t in targets)))
            # Decide under the lock, on what is there now.
            chosen = targets if select is None else select(list(targets))
            check_targets(chosen, overwrite=overwrite)
            # The journal: from here on the set is being published.
            journal = json.dumps([str(relative[t]) for t in chosen]).encode("utf-8")
            _stage_file(stage / (MANIFEST + ".part"), journal)
            os.replace(stage / (MANIFEST + ".part"), stage / MANIFEST)
            _fsync_directory(stage)
            _step("journal")
            placed: list[tuple[Path, Path | None]] = []
            try:
                for i, target in enumerate(chosen):
                    backup = None
                    if target.exists() or target.is_symlink():
                        # A hard link to the old file, so that a failure can put it back.
                        backup = stage / BACKUP / str(i)
                        backup.parent.mkdir(exist_ok=True)
                        try:
                            os.link(target, backup, follow_symlinks=False)
                        except OSError:
                            backup = None
                    _step(f"move {relative[target]}")
                    os.replace(stage / relative[target], target)
                    placed.append((target, backup))
            except BaseException:
                for target, backup in reversed(placed):
                    with contextlib.suppress(OSError):
                        if backup is not None:
                            os.replace(backup, target)
                        else:
                            target.unlink()
                raise
            for directory in dict.fromkeys(t.parent for t in chosen):
                _fsync_directory(directory)
            _step("moved")
            done = True
            written = chosen
            (stage / MANIFEST).unlink()
            _fsync_directory(stage)
            _step("published")
            shutil.rmtree(stage, ignore_errors=True)
            _fsync_directory(base)
    except BaseException:
        if not done:
            with contextlib.suppress(OSError):
                (stage / MANIFEST).unlink()
            shutil.rmtree(stage, ignore_errors=True)
            for directory in sorted(created_dirs, key=lambda p: len(p.parts), reverse=True):
                with contextlib.suppress(OSError):
                    directory.rmdir()
        raise
    finally:
        os.close(stage_fd)
    chosen_set = set(written)
    return [Path(p) for p, t in zip(contents, targets) if t in chosen_set]


@dataclass
class _Batch:
    root: Path
    overwrite: bool
    contents: dict[Path, Content] = field(default_factory=dict)


_BATCH: contextvars.ContextVar[_Batch | None] = contextvars.ContextVar(
    "dustoptics_file_set", default=None
)


@contextlib.contextmanager
def file_set(root: str | os.PathLike[str], *, overwrite: bool = False) -> Iterator[None]:
    """Write every :func:`write_files` call inside the block as one set under ``root``.

    Inside the block, :func:`write_files` checks its targets (inside ``root``,
    existing ones refused unless ``overwrite``), keeps the contents and
    returns the paths; when the block ends without an error the whole set is
    staged and moved into place (see the module docstring); on an error
    nothing is written.

    Parameters
    ----------
    root : path-like
        Directory every target must stay inside (resolved, symbolic links
        included); staging and locking happen there.
    overwrite : bool
        Replace existing targets.
    """
    batch = _Batch(Path(os.path.abspath(root)), bool(overwrite))
    token = _BATCH.set(batch)
    try:
        yield
    finally:
        _BATCH.reset(token)
    _commit(batch.contents, overwrite=batch.overwrite, root=batch.root)


def write_files(contents: Mapping[Path, Content], *, overwrite: bool = False) -> list[Path]:
    """Write a set of files atomically: all staged first, then moved into place under a lock.

    Parameters
    ----------
    contents : mapping of pathlib.Path to bytes or callable
        Target path -> its bytes, or a callable ``writer(path)`` that creates
        the complete file at the temporary ``path`` it is given (it may
        truncate and reopen it, as ``h5py.File(path, "w")`` does).  Missing
        directories are created.
    overwrite : bool, optional
        Replace existing targets.  Default False.

    Returns
    -------
    list of pathlib.Path
        The targets, in the order given.

    Raises
    ------
    FileExistsError
        A target exists and ``overwrite`` is False (nothing is written).
    ValueError
        Duplicate targets, or (inside :func:`file_set`) a target outside its root.
    OSError
        Staging or renaming failed; the old set is left (see the module docstring).
    """
    batch = _BATCH.get()
    if batch is None:
        return _commit(contents, overwrite=overwrite, root=None)
    targets = [Path(os.path.abspath(p)) for p in contents]
    for target in targets:
        check_inside(batch.root, target)
        if target in batch.contents:
            raise ValueError(f"write_files: {str(target)!r} is written twice in one set")
    check_targets(targets, overwrite=batch.overwrite or overwrite)
    batch.contents.update(zip(targets, contents.values()))
    return [Path(p) for p in contents]
