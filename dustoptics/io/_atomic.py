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
   alive); then write its manifest (``.complete``: the relative paths, renamed
   into place last);
3. take an exclusive :func:`fcntl.flock` on the root directory itself (no
   lock file is left behind), clean what interrupted runs left (below), check
   the targets again, move every staged file into place with
   :func:`os.replace` (keeping a hard link to each file it replaces), fsync
   the directories and remove the staging directory.  If a move fails, the
   files already moved are put back (the old ones from their links, new
   targets removed), so the old set is left whole.

Concurrent writers of the same root therefore replace the set one after the
other, never interleaved.  A failure before step 3 (an error, a full disk,
KeyboardInterrupt) removes the staging directory and leaves the old set; a
kill (``kill -9``, power loss) during step 2 leaves a staging directory
without manifest, and during step 3 one with its manifest.  The next write
into that root (holding the root's lock) recognizes both by their names and
by their free locks: it deletes an incomplete staging directory, finishes
moving a complete one (roll forward: the set becomes the new one, whole), and
deletes ``.NAME.XXXXXXXX.tmp`` files that earlier versions staged beside
their targets.  Leftovers never make a rerun refuse (see :func:`is_leftover`).

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
    "is_leftover",
    "safe_stem",
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


def _fsync_path(path: Path) -> None:
    with open(path, "rb") as handle:
        os.fsync(handle.fileno())


def _fsync_directory(directory: Path) -> None:
    """Make the renames durable (POSIX); a no-op where directories cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
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


def _roll_forward(root: Path, stage: Path) -> None:
    """Finish moving a complete staging directory's files into place."""
    try:
        names = json.loads((stage / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return
    if not isinstance(names, list):
        return
    for name in names:
        if not isinstance(name, str):
            continue
        source = stage / name
        target = root / name
        try:
            check_inside(root, target)
        except ValueError:
            continue
        if source.is_file():
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(source, target)


def clean_leftovers(root: str | os.PathLike[str], directories: tuple[Path, ...] = ()) -> list[Path]:
    """Clean what interrupted writes left in ``root`` (call it holding ``root``'s lock).

    Staging directories whose lock is free: complete ones (with a manifest)
    are rolled forward, their files moved into place; incomplete ones are
    deleted.  ``.NAME.XXXXXXXX.tmp`` files in ``root`` and in ``directories``
    are deleted.  Returns what was cleaned.
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


def _stage_file(path: Path, content: Content) -> None:
    """Write ``content`` to ``path`` (new), flushed, fsync-ed, mode :data:`FILE_MODE`."""
    if isinstance(content, bytes):
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as handle:
            handle.write(content)
            handle.flush()
            os.fsync(handle.fileno())
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


def _commit(contents: Mapping[Path, Content], *, overwrite: bool, root: Path | None) -> list[Path]:
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
    check_targets(targets, overwrite=overwrite)
    created_dirs: list[Path] = []
    for directory in dict.fromkeys([base, *(t.parent for t in targets)]):
        missing = _missing_directories(directory)
        directory.mkdir(parents=True, exist_ok=True)
        created_dirs.extend(missing)
    # Resolve again now that the directories exist (a symlink among them).
    for target in targets:
        check_inside(base, target)
    relative = [t.relative_to(base) for t in targets]
    stage = Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=base))
    stage_fd = os.open(stage, os.O_RDONLY)
    done = False
    try:
        fcntl.flock(stage_fd, fcntl.LOCK_EX)
        for rel, content in zip(relative, contents.values()):
            path = stage / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            _stage_file(path, content)
        manifest = json.dumps([str(r) for r in relative]).encode("utf-8")
        _stage_file(stage / (MANIFEST + ".part"), manifest)
        os.replace(stage / (MANIFEST + ".part"), stage / MANIFEST)
        _fsync_directory(stage)
        with _locked(base):
            clean_leftovers(base, tuple(dict.fromkeys(t.parent for t in targets)))
            # Another run may have written meanwhile; check again under the lock.
            check_targets(targets, overwrite=overwrite)
            placed: list[tuple[Path, Path | None]] = []
            try:
                for i, (rel, target) in enumerate(zip(relative, targets)):
                    backup = None
                    if target.exists() or target.is_symlink():
                        # A hard link to the old file, so that a failure can put it back.
                        backup = stage / BACKUP / str(i)
                        backup.parent.mkdir(exist_ok=True)
                        try:
                            os.link(target, backup, follow_symlinks=False)
                        except OSError:
                            backup = None
                    os.replace(stage / rel, target)
                    placed.append((target, backup))
            except BaseException:
                for target, backup in reversed(placed):
                    with contextlib.suppress(OSError):
                        if backup is not None:
                            os.replace(backup, target)
                        else:
                            target.unlink()
                raise
            for directory in dict.fromkeys(t.parent for t in targets):
                _fsync_directory(directory)
            done = True
            shutil.rmtree(stage, ignore_errors=True)
            _fsync_directory(base)
    except BaseException:
        if not done:
            shutil.rmtree(stage, ignore_errors=True)
            for directory in sorted(created_dirs, key=lambda p: len(p.parts), reverse=True):
                with contextlib.suppress(OSError):
                    directory.rmdir()
        raise
    finally:
        os.close(stage_fd)
    return [Path(p) for p in contents]


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
