"""Work that depends only on the geometry, shared between the renders of one scene.

Two skies of one scene (the same Sun and streams, other optics: the exact sky
and the sky an engine draws, :func:`dustoptics.sky.approximations.preview_sky`)
need the same angular bases: the normalized associated Legendre functions at
the discrete ordinates and at the Sun (:func:`dustoptics.sky.orders.normalized_legendre`,
some 2,500 calls of scipy's ``lpmv`` per render) and the aureole's Legendre
polynomials.  Inside :func:`shared_geometry` the renderer keeps what
:func:`geometry_memo` computes, keyed by what it depends on, and the second
render takes it from there; outside any such scope nothing is kept and every
render computes all it needs, as before.  Either way the values are the same
arrays of the same bits: only who computes them changes.
"""

from __future__ import annotations

import functools
import itertools
import os
import threading
from collections.abc import Callable, Hashable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, TypeVar

from threadpoolctl import ThreadpoolController

__all__ = ["cores", "geometry_memo", "in_threads", "one_blas_thread", "shared_geometry"]

_T = TypeVar("_T")

_MEMO: ContextVar[dict[Hashable, Any] | None] = ContextVar("_MEMO", default=None)


@contextmanager
def shared_geometry() -> Iterator[None]:
    """A scope whose renders share their geometry (a scope within one keeps the outer's)."""
    memo = _MEMO.get()
    token = _MEMO.set({} if memo is None else memo)
    try:
        yield
    finally:
        _MEMO.reset(token)


def geometry_memo(key: Hashable, compute: Callable[[], _T]) -> _T:
    """``compute()``, kept under ``key`` within :func:`shared_geometry` (the caller must not
    change what it returns)."""
    memo = _MEMO.get()
    if memo is None:
        return compute()
    if key not in memo:
        memo[key] = compute()
    value: _T = memo[key]
    return value


#: Parts of a loop per thread in :func:`in_threads` (rows differ in cost: more parts than
#: threads keep the cores busy to the end).
_PARTS_PER_THREAD = 4


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def in_threads(run: Callable[..., None], n: int, *args: Any) -> None:
    """``run(lo, hi, *args)`` over contiguous parts of ``range(n)``, in one thread per core.

    For the sky's serial kernels (``nogil``) whose iterations are independent and write
    their own outputs: the bits are those of one ``run(0, n, *args)``.  Serial kernels compile
    several times faster than numba's ``parallel=True`` ones and need no threading layer.
    """
    threads = min(cores(), n)
    if threads <= 1:
        run(0, n, *args)
        return
    parts = min(n, _PARTS_PER_THREAD * threads)
    bounds = [n * i // parts for i in range(parts + 1)]
    with ThreadPoolExecutor(max_workers=threads) as pool:
        for future in [pool.submit(run, lo, hi, *args) for lo, hi in itertools.pairwise(bounds)]:
            future.result()


@functools.lru_cache(maxsize=1)
def _blas_pools() -> ThreadpoolController:
    """The BLAS thread pools loaded in this process (numpy's), found once."""
    return ThreadpoolController()


_blas_lock = threading.Lock()
_blas_depth = 0
_blas_limiter: Any = None


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """numpy's OpenBLAS on one thread within (threads nest: the last one out restores it).

    The orders of scattering make thousands of small matrix products (tens of MFLOP):
    OpenBLAS's second thread gains little on them and spins between them, burning a
    core (2.5 times the CPU time of one thread for the orders, measured on a busy
    2-core machine).  The products' bits do not depend on OpenBLAS's threads.  The
    setting is process-wide: other threads' products run on one thread meanwhile.
    Any BLAS threadpoolctl knows (OpenBLAS, MKL, BLIS) is limited.
    """
    global _blas_depth, _blas_limiter
    with _blas_lock:
        if _blas_depth == 0:
            _blas_limiter = _blas_pools().limit(limits=1, user_api="blas")
        _blas_depth += 1
    try:
        yield
    finally:
        with _blas_lock:
            _blas_depth -= 1
            if _blas_depth == 0:
                _blas_limiter.restore_original_limits()
                _blas_limiter = None
