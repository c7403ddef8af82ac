"""The allocator setting that sweeps use in Dask's worker processes.

Dask starts workers with ``MALLOC_TRIM_THRESHOLD_`` set, which also fixes
glibc's mmap threshold at 128 KiB: every larger array is then a fresh mapping
whose pages fault in again.  ``_allocations_reused`` lets freed memory be
reused while a chunk runs.  Checked by counting page faults in a child
process started with Dask's setting.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc",
    reason="glibc's mallopt",
)

CHILD = r"""
import ctypes
import resource
from dustoptics.sweep.chunk import _allocations_reused

libc = ctypes.CDLL("libc.so.6")
libc.malloc.restype = ctypes.c_void_p
libc.free.argtypes = [ctypes.c_void_p]
SIZE = 32 << 20  # below the 64 MiB that _allocations_reused lets the heap serve

def faults(n=10):
    # Allocate, touch and free 32 MiB n times; count minor page faults.  The
    # C library's malloc, not numpy's (which may ask for huge pages), and a
    # size far above any hole that freed small objects can leave in the heap,
    # which glibc would reuse before mapping new memory: the count is then
    # the same in every run.
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(n):
        p = libc.malloc(SIZE)
        ctypes.memset(p, 1, SIZE)
        libc.free(p)
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

outside = faults()
with _allocations_reused():
    faults(1)  # the first one maps the memory
    inside = faults()
after = faults()
print(outside, inside, after)
"""

PAGES = 10 * (32 << 20) // 4096  # pages touched by faults()


def run_child(env_extra: dict[str, str]) -> tuple[int, int, int]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    env.update(env_extra)
    out = subprocess.run(
        [sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True
    )
    outside, inside, after = (int(v) for v in out.stdout.split())
    return outside, inside, after


def test_freed_arrays_are_reused_inside_and_returned_after_in_a_dask_like_worker():
    # Outside, every allocation is a fresh mapping whose pages fault in.
    outside, inside, after = run_child({"MALLOC_TRIM_THRESHOLD_": "65536"})
    assert outside >= PAGES * 0.9
    assert inside < PAGES * 0.1
    # After the chunk, the environment's setting is back: fresh mappings again.
    assert after >= PAGES * 0.9


def test_nothing_changes_without_a_fixed_threshold():
    # Without a threshold in the environment the context leaves glibc alone:
    # 32 MiB is above glibc's largest dynamic mmap threshold, so every
    # allocation is mapped afresh, inside as outside.
    outside, inside, after = run_child({})
    assert outside >= PAGES * 0.9
    assert abs(inside - outside) <= PAGES * 0.01 and abs(after - outside) <= PAGES * 0.01
