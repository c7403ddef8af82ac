"""What each worker of a sweep's local cluster runs as it starts (a Dask preload).

A Ctrl-C in a terminal sends SIGINT to every process of the foreground group: the
process that started the sweep and the worker processes of its local cluster
(:func:`dustoptics.sweep.local_cluster`).  That process stops the sweep and closes the
cluster, which ends the workers; a worker that took the signal itself would print the
traceback of its event loop first.  The workers therefore ignore SIGINT.
"""

from __future__ import annotations

import signal
import threading


def dask_setup(worker: object) -> None:
    """Ignore SIGINT in a worker process (Dask calls this as the worker starts).

    A worker running as a thread of the starting process (``processes=False``) runs
    this outside the main thread and changes nothing.
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
