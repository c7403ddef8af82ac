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
import resource
import numpy as np
from dustoptics.sweep.run import _allocations_reused

def faults(n=50):
    # Allocate, touch and free a 1 MiB array n times; count minor page faults
    # (1 MiB: below the 2 MiB of a transparent huge page).
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(n):
        a = np.empty(1 << 17)
        a[:] = 1.0
        del a
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

outside = faults()
with _allocations_reused():
    faults(1)  # the first one maps the memory
    inside = faults()
after = faults()
print(outside, inside, after)
"""


def run_child(env_extra: dict[str, str]) -> tuple[int, int, int]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    env.update(env_extra)
    out = subprocess.run(
        [sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True
    )
    outside, inside, after = (int(v) for v in out.stdout.split())
    return outside, inside, after


def test_freed_arrays_are_reused_inside_and_returned_after_in_a_dask_like_worker():
    # 50 arrays of 256 pages each: outside, every one faults its pages in.
    outside, inside, after = run_child({"MALLOC_TRIM_THRESHOLD_": "65536"})
    assert outside >= 50 * 256 * 0.9
    assert inside < 50 * 256 * 0.1
    # After the chunk, the environment's setting is back: fresh mappings again.
    assert after >= 50 * 256 * 0.9


def test_nothing_changes_without_a_fixed_threshold():
    # glibc's own dynamic threshold reuses freed memory anyway, outside too.
    outside, inside, after = run_child({})
    for faults in (outside, inside, after):
        assert faults < 50 * 256 * 0.1 + 256
