"""The one atomic-write mechanism of the package, and the readers' error type.

Every writer in :mod:`dustoptics.io` prepares its output completely (bytes in
memory, or a callback that writes a file by name, for h5py), then calls
:func:`write_files`:

1. refuse if any target exists and ``overwrite`` is False
   (:class:`FileExistsError` naming every existing target), before anything is
   written;
2. stage every file into a new temporary file in its target's directory
   (``.<name>.<random>.tmp``), flushed and :func:`os.fsync`-ed;
3. only when all are staged, move each into place with :func:`os.replace`
   (atomic on POSIX and Windows within one file system), then fsync the
   directory.

On any failure (including KeyboardInterrupt) the temporary files are removed,
so are targets this call had newly created, and so are directories it
created: a failed call leaves no partial file and no partial set.  With
``overwrite=True``, a target already replaced before a failure in step 3 is
not restored (the old bytes are gone); the set is then a mix of old and new
files, each of them complete.

Readers raise :class:`FormatError` (a :class:`ValueError`) naming the file
and what is wrong with it.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path

__all__ = ["FILE_MODE", "Content", "FormatError", "check_targets", "write_files"]

#: Permission bits of written files (tables are meant to be shared and read).
FILE_MODE = 0o644

#: What :func:`write_files` writes to one target: its bytes, or a callback
#: that writes the file at the (temporary) path it is given.
Content = bytes | Callable[[Path], None]


class FormatError(ValueError):
    """A file given to a reader is malformed, truncated or not of the expected format.

    The message names the file and what is wrong with it.
    """


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


def _stage(target: Path, content: Content) -> Path:
    """Write ``content`` to a new temporary file beside ``target``; return its path."""
    fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    path = Path(name)
    try:
        if isinstance(content, bytes):
            with os.fdopen(fd, "wb") as handle:
                handle.write(content)
                handle.flush()
                os.fsync(handle.fileno())
        else:
            os.close(fd)
            content(path)
            _fsync_path(path)
        os.chmod(path, FILE_MODE)  # mkstemp creates 0600
    except BaseException:
        path.unlink(missing_ok=True)
        raise
    return path


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


def write_files(contents: Mapping[Path, Content], *, overwrite: bool = False) -> list[Path]:
    """Write a set of files atomically: all staged first, then renamed into place.

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
    OSError
        Staging or renaming failed; nothing partial is left behind (see the
        module docstring).
    """
    targets = [Path(p) for p in contents]
    if len({os.path.abspath(t) for t in targets}) != len(targets):
        raise ValueError(f"write_files: duplicate targets in {[str(t) for t in targets]}")
    check_targets(targets, overwrite=overwrite)
    created_dirs: list[Path] = []
    for directory in dict.fromkeys(t.parent for t in targets):
        missing = _missing_directories(directory)
        directory.mkdir(parents=True, exist_ok=True)
        created_dirs.extend(missing)
    preexisting = {t for t in targets if t.exists()}
    staged: dict[Path, Path] = {}
    placed: list[Path] = []
    try:
        for target, content in zip(targets, contents.values()):
            staged[target] = _stage(target, content)
        # A file may have appeared while staging; check again just before renaming.
        check_targets([t for t in targets if t not in preexisting], overwrite=overwrite)
        for target in targets:
            os.replace(staged[target], target)
            del staged[target]
            placed.append(target)
        for directory in dict.fromkeys(t.parent for t in targets):
            _fsync_directory(directory)
    except BaseException:
        for temporary in staged.values():
            temporary.unlink(missing_ok=True)
        for target in placed:
            if target not in preexisting:
                target.unlink(missing_ok=True)
        for directory in sorted(created_dirs, key=lambda p: len(p.parts), reverse=True):
            with contextlib.suppress(OSError):
                directory.rmdir()
        raise
    return targets
