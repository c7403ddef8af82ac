"""A sweep in a process forked after another sweep (:mod:`dustoptics.sweep._fork`).

The child of a process that had run a sweep waited forever: Dask's module-level thread
pools (the client's offload thread, the threaded scheduler's pool) had no threads in the
child.  Each test runs a fresh interpreter, forks with ``multiprocessing``'s ``fork`` start
method and bounds the child by a timeout: a hang fails.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="needs the 'sweep' extra (dask[distributed])")
pytest.importorskip("xarray", reason="needs the 'sweep' extra (xarray)")
pytest.importorskip("zarr", reason="needs the 'sweep' extra (zarr)")

HERE = Path(__file__).resolve().parent

#: The forked child's bound: a small sweep takes 14-25 s on the busy 2-core test machine
#: (a cluster of two worker processes started, the kernels loaded in each). [s]
CHILD_TIMEOUT_S = 240

DASK_SCRIPT = textwrap.dedent(
    """
    import multiprocessing
    import dask.array as da
    import dustoptics.sweep  # registers the handler that renews Dask's pools in a child

    def total():
        return float(da.arange(1000, chunks=100).sum().compute())  # the threaded scheduler

    def child():
        assert total() == 499500.0

    if __name__ == "__main__":
        assert total() == 499500.0  # the pool's threads start here
        process = multiprocessing.get_context("fork").Process(target=child)
        process.start()
        process.join(60)
        print("child", process.exitcode, flush=True)
        if process.exitcode is None:
            process.kill()
    """
)

SWEEP_SCRIPT = textwrap.dedent(
    """
    import multiprocessing, sys
    sys.path.insert(0, {here!r})
    from _sweeps import small_toml
    from dustoptics.sweep import sweep

    def run():
        ds = sweep(
            small_toml(wavelengths_nm=[550.0], n_theta=19),
            {{"size_distribution.r_eff_um": [0.5, 1.0]}},
            workers=2,
            progress=None,
        )
        return ds["phase"].values.tobytes() + ds["csca_um2"].values.tobytes()

    def child(queue):
        queue.put(run())

    if __name__ == "__main__":
        first = run()
        context = multiprocessing.get_context("fork")
        queue = context.Queue()
        process = context.Process(target=child, args=(queue,))
        process.start()
        try:
            same = queue.get(timeout={timeout}) == first
        except Exception as exc:
            same = type(exc).__name__
        process.join(30)
        print("child", process.exitcode, "same", same, flush=True)
        if process.exitcode is None:
            process.kill()
    """
)


def _run(script: str, timeout_s: float) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=timeout_s
    )


def test_dask_computes_in_a_process_forked_after_it_computed() -> None:
    done = _run(DASK_SCRIPT, 300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip() == "child 0", done.stdout + done.stderr[-3000:]


def test_a_sweep_runs_in_a_process_forked_after_a_sweep() -> None:
    script = SWEEP_SCRIPT.format(here=str(HERE), timeout=CHILD_TIMEOUT_S)
    done = _run(script, 3 * CHILD_TIMEOUT_S)
    assert done.returncode == 0, done.stderr[-3000:]
    # The child's sweep finished and gave the parent's phase functions and cross-sections,
    # bit for bit.
    assert done.stdout.strip() == "child 0 same True", done.stdout + done.stderr[-3000:]
