"""A sweep run's token: the file in a store's marker folder that says which run may write it.

Workers write a chunk into the store only while they see the token of the run that sent it
and hold a shared lock on it (:func:`dustoptics.sweep.run._writing_for`); the run's end removes
the token and waits for the writers (:class:`RunToken`).
"""

from __future__ import annotations

import fcntl
import os
import time
import uuid
from pathlib import Path

from dustoptics.sweep.store import MARKERS

__all__ = ["END_OF_RUN_WAIT_S", "RUN_TOKEN_PREFIX", "RunToken"]

#: The name of every run's token starts with this.
RUN_TOKEN_PREFIX = "run-"

#: How long the end of a run waits for workers still writing a chunk of it. [s]
END_OF_RUN_WAIT_S = 120.0


class RunToken:
    """A new file in the store's marker folder that only this run of the client
    knows: workers that see it write their chunks themselves (:func:`dustoptics.sweep.run._run_chunk`),
    each holding a shared :func:`fcntl.flock` on it while it writes
    (:func:`dustoptics.sweep.run._writing_for`).  Tokens left by runs that ended go first (this run holds
    the store: no other run is writing it).

    :meth:`end` removes the file, then takes the exclusive lock: it returns when no
    worker is writing for this run, and no worker starts after (the file is gone).
    A run that fails or is interrupted cannot cancel tasks already running on the
    cluster; without the wait such a task, having seen the token just before it was
    removed, could write a chunk after the next run had begun (the fuzz campaign's
    full disk on a cluster of threads, resumed at once: a chunk the resume had written
    lost its marker's match).
    """

    def __init__(self, store: Path):
        directory = store / MARKERS
        directory.mkdir(exist_ok=True)
        for old in directory.glob(RUN_TOKEN_PREFIX + "*"):
            old.unlink(missing_ok=True)
        self.path = directory / f"{RUN_TOKEN_PREFIX}{uuid.uuid4().hex}"
        self.path.touch()
        self.name = self.path.name
        self._fd: int | None = os.open(self.path, os.O_RDONLY)

    def end(self) -> None:
        """Remove the token and wait (at most :data:`END_OF_RUN_WAIT_S`) for the
        workers writing for this run."""
        self.path.unlink(missing_ok=True)
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            deadline = time.monotonic() + END_OF_RUN_WAIT_S
            while True:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    break
                except BlockingIOError:
                    if time.monotonic() > deadline:
                        break  # a worker stuck in a write: its marker decides, on resume
                    time.sleep(0.02)
        finally:
            os.close(fd)
