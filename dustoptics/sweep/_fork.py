"""A sweep in a process forked after another sweep: Dask's thread pools renewed in the child.

``fork`` copies a process with only the thread that called it.  Dask keeps two thread pools
at module level that a sweep starts: ``distributed.utils._offload_executor`` (one thread;
the client serializes messages on it) and ``dask.threaded.default_pool`` (the threaded
scheduler, which reads the finished store back: ``xarray``'s ``load``).  In a child forked
after their threads started, each pool still counts its threads, which do not exist there,
and so never starts new ones: work given to it waits forever.  A sweep in such a child
(``multiprocessing`` with the ``fork`` start method, the default on Linux before Python
3.14) started its cluster, sent its tasks and then hung (measured with dask and distributed
2026.8.0: on the client's messages, and once those were renewed, on reading the store).
Dask leaves fork safety to the caller (dask/dask#3813); the pools are replaced in the child
here, by a handler that :func:`os.register_at_fork` runs in every forked child of a process
that imported :mod:`dustoptics.sweep`.

The child gets new, empty pools (threads start on first use, as in a fresh process).  What
else the parent held is not carried over: a ``Client`` or cluster of the parent is the
parent's (its sockets and worker processes belong to the parent); a child starts its own,
as :func:`dustoptics.sweep.sweep` does when given no client.
"""

from __future__ import annotations

import os
import sys
import threading
from concurrent.futures import ThreadPoolExecutor

__all__ = ["renew_pools"]


def renew_pools() -> list[str]:
    """Replace Dask's module-level thread pools with new ones (run in a forked child).

    Returns
    -------
    list of str
        The pools replaced, by module attribute (for tests); a module not imported, or
        an attribute a Dask version lacks, is skipped.
    """
    renewed = []
    utils = sys.modules.get("distributed.utils")
    if isinstance(getattr(utils, "_offload_executor", None), ThreadPoolExecutor):
        utils._offload_executor = ThreadPoolExecutor(  # type: ignore[union-attr]
            max_workers=1, thread_name_prefix="Dask-Offload"
        )
        renewed.append("distributed.utils._offload_executor")
    threaded = sys.modules.get("dask.threaded")
    if threaded is not None and hasattr(threaded, "default_pool"):
        # None: the scheduler makes its pool on its next use, in this process.  The lock
        # is new too: a thread of the parent may have held it at the fork.
        setattr(threaded, "default_pool", None)  # noqa: B010 (a module's global)
        if hasattr(threaded, "pools_lock"):
            setattr(threaded, "pools_lock", threading.Lock())  # noqa: B010
        if hasattr(threaded, "pools"):
            threaded.pools.clear()
        renewed.append("dask.threaded.default_pool")
    return renewed


def _after_fork_in_child() -> None:  # pragma: no cover - runs in forked children
    renew_pools()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_after_fork_in_child)
