"""A sweep's Zarr store: one writer at a time, every chunk checked against its digest.

A sweep (:func:`dustoptics.sweep.sweep`) writes a Zarr (format 2) directory chunk by
chunk, and a later run of the same sweep resumes it.  This module keeps the store whole
under concurrent runs and damage.

One writer
    A run holds an exclusive lock on the store's directory
    (:func:`dustoptics.io._atomic.held_lock`: an ``flock``, which ends with the process,
    so a killed run leaves no stale lock) from the moment it creates or opens the store
    until it returns.  A new store is built in a hidden sibling folder
    (``.NAME.creating-XXXXXXXX``), locked before anything is written into it, and
    published by one rename; a run that finds the store held by another is refused with
    a message naming it.  A staging folder is removed only by a later run that finds it
    unlocked (the run that made it has ended), never while its run holds it.

Digests
    ``sweep-created.json`` lists every file written when the store was created (Zarr
    metadata, coordinates, per-point variables, the sweep's identity) with its SHA-256,
    and the chunk grid.  Each chunk's completion marker (``sweep-done/NAME``, written
    after its arrays to a temporary file that is renamed) records the SHA-256 of the
    chunk's file in every array, or null where Zarr wrote none (a chunk that is all fill
    value).  A chunk is done only if its marker is a file of JSON naming it and every
    file matches; a resume computes any other chunk again (its marker and files removed
    first), and :func:`verify_store` reports it.  A file written at creation that no
    longer matches cannot be recomputed chunk by chunk: the store is refused, naming the
    file.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import json
import os
import shutil
import uuid
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dustoptics.io._atomic import FILE_MODE, FormatError, held_lock
from dustoptics.io.describe_formats import check_zarr_store, register_store_verifier

__all__ = ["StoreBusyError", "verify_store"]

#: Folder of the chunks' completion markers.
MARKERS = "sweep-done"

#: What the store holds (the sweep, its method and chunks), compared on resume.
IDENTITY = "sweep-identity.json"

#: Digests of the files written at creation, the chunk grid and the chunked arrays.
CREATED = "sweep-created.json"

#: Format of :data:`CREATED`.
STORE_FORMAT = "dustoptics-sweep-store/1"

#: Largest marker or :data:`CREATED` file read (a larger one is damaged). [bytes]
_LARGEST_RECORD = 64 * 1024**2

_NOT_COMPUTED = "is not computed (no marker)"

#: Suffix of a marker being written (``.NAME.XXXXXXXX.partial``; not the set writer's
#: ``.tmp``, which its cleanup removes whoever is writing it).
_TEMPORARY = ".partial"


class StoreBusyError(ValueError):
    """Another run holds the sweep store (it is computing into it)."""


@dataclass(frozen=True)
class StoreLayout:
    """Which files a store's chunks write.

    Attributes
    ----------
    grid : tuple of int
        Chunks along each axis, then along wavelength.
    arrays : Mapping
        Arrays written chunk by chunk -> number of their trailing dimensions held
        whole in every chunk (1 for ``phase``'s angles, 0 for the others).
    separator : str
        Zarr's separator of chunk indices in file names.
    """

    grid: tuple[int, ...]
    arrays: Mapping[str, int]
    separator: str = "."

    def names(self) -> Iterator[str]:
        """Every chunk's name (its indices joined by dots), first axis slowest."""
        return (".".join(map(str, c)) for c in itertools.product(*map(range, self.grid)))

    def chunk_files(self, name: str) -> list[str]:
        """The chunk's file in every array, relative to the store."""
        parts = name.split(".")
        return [
            f"{array}/{self.separator.join(parts + ['0'] * extra)}"
            for array, extra in sorted(self.arrays.items())
        ]

    def to_json(self) -> dict[str, Any]:
        return {
            "grid": list(self.grid),
            "arrays": dict(sorted(self.arrays.items())),
            "separator": self.separator,
        }


def _digest(path: Path) -> str | None:
    """SHA-256 of a regular file, None if nothing is there, "" for anything else."""
    try:
        if path.is_symlink() or not path.is_file():
            return None if not path.exists() and not path.is_symlink() else ""
        digest = hashlib.sha256()
        with open(path, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                digest.update(block)
        return digest.hexdigest()
    except OSError:
        return ""


def _read_json(path: Path) -> Any:
    """The JSON in a regular file, or raise ValueError saying what is wrong."""
    if path.is_symlink() or not path.is_file():
        raise ValueError("is not a file" if path.exists() else "is missing")
    if path.stat().st_size > _LARGEST_RECORD:
        raise ValueError("is too large to be one")
    try:
        return json.loads(path.read_bytes())
    except (ValueError, RecursionError):
        raise ValueError("is not valid JSON") from None


def _remove(path: Path) -> None:
    """Remove a file, link or folder at ``path`` (nothing if absent)."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


# ---------------------------------------------------------------------- creation


def _created_record(staging: Path, layout: StoreLayout) -> dict[str, Any]:
    files = {
        str(p.relative_to(staging)): _digest(p)
        for p in sorted(staging.rglob("*"))
        if p.is_file() and not p.is_symlink()
    }
    return {"format": STORE_FORMAT, **layout.to_json(), "files": files}


def _write_plain(path: Path, data: bytes) -> None:
    """A new file in a staging folder that only this run sees (published by its rename)."""
    with open(path, "xb") as handle:
        handle.write(data)
        handle.flush()
        os.fsync(handle.fileno())


def _separator(staging: Path, array: str) -> str:
    try:
        meta = json.loads((staging / array / ".zarray").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return "."
    separator = meta.get("dimension_separator") or "."
    return separator if separator in (".", "/") else "."


def _read_created(store: Path) -> tuple[StoreLayout, dict[str, str | None]]:
    """The layout and creation digests of a store, or FormatError naming what is wrong."""
    where = store / CREATED
    try:
        record = _read_json(where)
    except ValueError as exc:
        raise FormatError(
            f"sweep store {str(store)!r}: {CREATED} {exc}; the store is damaged (or was "
            "written before stores carried digests): remove the store and run the sweep again"
        ) from None
    try:
        if record.get("format") != STORE_FORMAT:
            raise ValueError(f"format {record.get('format')!r}")
        grid = tuple(int(n) for n in record["grid"])
        arrays = {str(k): int(v) for k, v in record["arrays"].items()}
        separator = str(record["separator"])
        files = record["files"]
        if (
            not grid
            or min(grid) < 1
            or not arrays
            or separator not in (".", "/")
            or not isinstance(files, dict)
            or not all(isinstance(v, str) or v is None for v in files.values())
        ):
            raise ValueError("values out of range")
    except (AttributeError, KeyError, TypeError, ValueError) as exc:
        raise FormatError(
            f"sweep store {str(store)!r}: {CREATED} is not a record of this version ({exc}); "
            "remove the store and run the sweep again"
        ) from None
    return StoreLayout(grid, arrays, separator), {str(k): v for k, v in files.items()}


def _check_created(store: Path, files: Mapping[str, str | None]) -> None:
    for rel, expected in files.items():
        path = store / rel
        if (
            ".." in Path(rel).parts
            or Path(rel).is_absolute()
            or rel.split("/")[0] in (MARKERS, CREATED)
        ):
            raise FormatError(f"sweep store {str(store)!r}: {CREATED} lists {rel!r}")
        got = _digest(path)
        if got != expected:
            what = "is missing" if got is None else "does not match its digest"
            raise FormatError(
                f"sweep store {str(store)!r} is damaged: {rel} {what} (recorded when the "
                "store was created, it cannot be computed again chunk by chunk); remove the "
                "store and run the sweep again"
            )


def _staging_prefix(store: Path) -> str:
    return f".{store.name}.creating-"


def _clean_abandoned(store: Path) -> None:
    """Remove staging folders of this store that no run holds (their runs ended)."""
    prefix = _staging_prefix(store)
    try:
        entries = list(store.parent.iterdir())
    except OSError:
        return
    for entry in entries:
        if not entry.name.startswith(prefix) or entry.is_symlink() or not entry.is_dir():
            continue
        with contextlib.suppress(OSError), held_lock(entry) as fd:
            if fd is not None:
                shutil.rmtree(entry, ignore_errors=True)


def _same_directory(path: Path, fd: int) -> bool:
    """Whether ``path`` is still the directory open as ``fd`` (not removed or replaced)."""
    try:
        held, now = os.fstat(fd), os.stat(path)
    except OSError:
        return False
    return held.st_nlink > 0 and (held.st_dev, held.st_ino) == (now.st_dev, now.st_ino)


def _linked(store: Path) -> str:
    """Why a symbolic link is not opened as a store (a sweep holds its store by its own path:
    the lock, the staging folder beside it and the rename that publishes it)."""
    target = os.readlink(store)
    where = store.parent / target
    what = "a sweep store" if (where / IDENTITY).is_file() else "nothing a sweep wrote"
    return (
        f"{str(store)!r} is a symbolic link to {target!r} ({what}); a sweep writes and resumes "
        f"a store at its own path: give out={str(where)!r} (--out), or remove the link"
    )


def _busy(store: Path) -> StoreBusyError:
    return StoreBusyError(
        f"sweep store {str(store)!r} is being written by another run (of this or another "
        "sweep); wait for it to finish and run again to resume it, or choose another path"
    )


def _check_identity(store: Path, identity: str) -> None:
    marker = store / IDENTITY
    if marker.is_symlink() or not marker.is_file():
        raise ValueError(
            f"{str(store)!r} exists and is not a dustoptics sweep store; remove it or choose "
            "another path"
        )
    expected = identity.encode("utf-8")
    with open(marker, "rb") as handle:
        held = handle.read(len(expected) + 1)
    if held != expected:
        raise ValueError(
            f"{str(store)!r} holds a different sweep (other configuration, axes or chunks); "
            "remove it or choose another path"
        )


@contextlib.contextmanager
def held_store(
    store: Path, *, identity: str, layout: StoreLayout, create: Callable[[Path], None]
) -> Iterator[bool]:
    """Hold the store for the block, creating it if absent; yields whether it is new.

    ``create(folder)`` writes the new store's Zarr contents into an empty folder; the
    identity and :data:`CREATED` follow, and the folder is renamed into place.  An
    existing store must hold ``identity`` and match its creation digests.

    Raises
    ------
    StoreBusyError
        Another run holds the store.
    ValueError
        The path holds something else, or another sweep.
    FormatError
        A file written at creation is damaged.
    """
    with contextlib.ExitStack() as stack:
        new = _acquire(store, identity, layout, create, stack)
        yield new


def _acquire(
    store: Path,
    identity: str,
    layout: StoreLayout,
    create: Callable[[Path], None],
    stack: contextlib.ExitStack,
) -> bool:
    for _ in range(5):
        attempt = contextlib.ExitStack()
        try:
            if store.exists() or store.is_symlink():
                if store.is_symlink():
                    raise ValueError(_linked(store))
                if not store.is_dir():
                    raise ValueError(
                        f"{str(store)!r} exists and is not a dustoptics sweep store; remove it "
                        "or choose another path"
                    )
                fd = attempt.enter_context(held_lock(store))
                if fd is None:
                    raise _busy(store)
                if not _same_directory(store, fd):
                    attempt.close()  # replaced or removed meanwhile
                    continue
                _check_identity(store, identity)
                _, files = _read_created(store)
                _check_created(store, files)
                # its arrays' chunks within bounds before Zarr or Dask read any of them
                check_zarr_store(store)
                stack.enter_context(attempt)
                return False
            store.parent.mkdir(parents=True, exist_ok=True)
            _clean_abandoned(store)
            staging = store.parent / f"{_staging_prefix(store)}{uuid.uuid4().hex[:8]}"
            staging.mkdir()
            fd = attempt.enter_context(held_lock(staging))
            if fd is None or not _same_directory(staging, fd):
                attempt.close()  # another run's cleanup held or removed it meanwhile
                continue
            try:
                create(staging)
                if not _same_directory(staging, fd):
                    raise RuntimeError(f"creating {str(store)!r} replaced its locked folder")
                _write_plain(staging / IDENTITY, identity.encode("utf-8"))
                separator = _separator(staging, min(layout.arrays))
                full = StoreLayout(layout.grid, layout.arrays, separator)
                record = _created_record(staging, full)
                _write_plain(staging / CREATED, json.dumps(record, sort_keys=True).encode())
                try:
                    os.rename(staging, store)
                except OSError:
                    if not store.exists():
                        raise
                    shutil.rmtree(staging, ignore_errors=True)
                    attempt.close()  # another run published it first: open that one
                    continue
            except BaseException:
                shutil.rmtree(staging, ignore_errors=True)
                raise
            stack.enter_context(attempt)
            return True
        except FileNotFoundError:
            attempt.close()  # removed meanwhile (a finished .nc run's working store)
            continue
        except BaseException:
            attempt.close()
            raise
    raise StoreBusyError(
        f"sweep store {str(store)!r} kept changing while this run tried to open it (other "
        "runs creating and removing it); run again"
    )


# ---------------------------------------------------------------------- chunks


def read_layout(store: Path) -> StoreLayout:
    """The store's layout (from :data:`CREATED`)."""
    return _read_created(store)[0]


def chunk_problem(store: Path, layout: StoreLayout, name: str) -> str | None:
    """Why chunk ``name`` does not count as done (a phrase), or None if it does."""
    marker = store / MARKERS / name
    if not marker.exists() and not marker.is_symlink():
        return _NOT_COMPUTED
    try:
        record = _read_json(marker)
    except (OSError, ValueError) as exc:
        return f"has a marker that {exc}"
    if not isinstance(record, dict) or record.get("chunk") != [int(i) for i in name.split(".")]:
        return "has a marker that names another chunk"
    digests = record.get("sha256")
    expected = layout.chunk_files(name)
    if not isinstance(digests, dict) or sorted(digests) != sorted(expected):
        return "has a marker without the digests of its files"
    for rel in expected:
        got = _digest(store / rel)
        if got != digests[rel]:
            if got is None:
                return f"is damaged: {rel} is missing"
            return f"is damaged: {rel} does not match the digest in its marker"
    return None


def discard_chunk(store: Path, layout: StoreLayout, name: str) -> None:
    """Remove a chunk's marker and files, so that it is written afresh."""
    _remove(store / MARKERS / name)
    for rel in layout.chunk_files(name):
        _remove(store / rel)


def done_chunks(
    store: Path, layout: StoreLayout, names: Iterable[str] | None = None, *, repair: bool
) -> set[str]:
    """The chunks (of ``names``, default all) that are done; with ``repair``, every other
    chunk's marker and files are removed, so that a new run writes it afresh."""
    done = set()
    for name in layout.names() if names is None else names:
        problem = chunk_problem(store, layout, name)
        if problem is None:
            done.add(name)
        elif repair:
            discard_chunk(store, layout, name)
    if repair and (store / MARKERS).is_dir():
        for entry in (store / MARKERS).iterdir():  # markers of stopped runs, half written
            if entry.name.startswith(".") and entry.name.endswith(_TEMPORARY):
                _remove(entry)
    return done


def write_marker(store: Path, layout: StoreLayout, name: str, record: Mapping[str, Any]) -> None:
    """The chunk's completion marker: ``record`` and the digests of its files, written
    atomically after them."""
    full = dict(record)
    full["chunk"] = [int(i) for i in name.split(".")]
    full["sha256"] = {rel: _digest(store / rel) for rel in layout.chunk_files(name)}
    _replace_atomically(store / MARKERS / name, json.dumps(full, sort_keys=True).encode("utf-8"))


def _replace_atomically(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a new temporary file beside it, fsync-ed and
    renamed over it.  (Markers are single files written by many workers at once into
    one folder: each needs no staging folder of its own, nor the folder's lock.)"""
    temporary = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}{_TEMPORARY}")
    try:
        with open(temporary, "xb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(temporary, FILE_MODE)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    with contextlib.suppress(OSError):
        fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


# ---------------------------------------------------------------------- checking a store


def verify_store(path: str | os.PathLike[str]) -> int:
    """Check a sweep's store: every file it was created with, and every chunk.

    Reads every file of the store once.  A store that a run is writing is refused
    (verify it when the run has finished).

    Parameters
    ----------
    path : str or os.PathLike
        The Zarr store a sweep wrote (``out=``).

    Returns
    -------
    int
        The chunks checked (all of the sweep's). [-]

    Raises
    ------
    dustoptics.io.FormatError
        Not a sweep store, a file written at creation that changed, or a chunk that is
        not computed or whose files do not match the digests in its marker; the message
        names the file or chunk and what to do.
    StoreBusyError
        A run is writing the store.
    """
    store = Path(path)
    if not store.is_dir() or not (store / IDENTITY).is_file():
        raise FormatError(f"{str(store)!r} is not a dustoptics sweep store (no {IDENTITY})")
    with held_lock(store, shared=True) as fd:
        if fd is None:
            raise _busy(store)
        layout, files = _read_created(store)
        _check_created(store, files)
        problems = [
            (name, problem)
            for name in layout.names()
            if (problem := chunk_problem(store, layout, name)) is not None
        ]
    if problems:
        name, problem = problems[0]
        more = f" (and {len(problems) - 1} other chunks)" if len(problems) > 1 else ""
        raise FormatError(
            f"sweep store {str(store)!r}: chunk {name} {problem}{more}; run the sweep again "
            "to compute it"
        )
    return sum(1 for _ in layout.names())


# ``dustoptics info`` checks a store's chunks before it calls the store complete.
register_store_verifier(verify_store)
