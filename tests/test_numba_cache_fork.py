"""Threads and fork: a process that rendered a sky forks children that compute.

numba's default threading layer on Linux, GNU OpenMP, killed any child forked after a sky
was rendered as soon as the child rendered one ("fork() called from a process already using
GNU OpenMP"), when the sky's kernels were ``parallel=True``.  They are now serial kernels
that the sky runs in threads (:func:`dustoptics.sky._shared.in_threads`): rendering a sky
starts no threading layer at all, so even with GNU OpenMP chosen a forked child renders the
same sky.
The threading layer is chosen once per process, so each test runs a fresh interpreter.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import textwrap

import pytest

#: A generous bound for a fresh interpreter that imports dustoptics, loads the sky's
#: kernels from numba's cache (or compiles them: up to 90 s on the busy 2-core test
#: machine after their source changed) and renders three small skies. [s]
TIMEOUT_S = 600

SCRIPT = textwrap.dedent(
    """
    import multiprocessing, sys, threading
    import numba
    import numpy as np
    from dustoptics.atmosphere.sets import earth_atmosphere
    from dustoptics.sky.scene import sky_radiance

    ATMOSPHERE = earth_atmosphere(wavelength_nm=[440.0, 550.0, 680.0])

    def render():
        sky = sky_radiance(
            ATMOSPHERE,
            sun_elevation_deg=60.0,
            view_zenith_deg=np.array([0.0, 45.0]),
            azimuth_step_deg=45.0,
        )
        return np.asarray(sky.radiance)

    def child(queue):
        queue.put(render().tobytes())

    if __name__ == "__main__":
        first = render()
        try:
            print("layer", numba.threading_layer(), flush=True)
        except ValueError:  # numba: "Threading layer is not initialized."
            print("layer none", flush=True)
        if sys.argv[1] == "threads":
            results = [None] * 3
            def run(i):
                results[i] = render()
            threads = [threading.Thread(target=run, args=(i,)) for i in range(3)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            print("threads", all(np.array_equal(r, first) for r in results), flush=True)
        context = multiprocessing.get_context("fork")
        queue = context.Queue()
        process = context.Process(target=child, args=(queue,))
        process.start()
        same = queue.get(timeout=300) == first.tobytes()
        process.join(300)
        print("child", process.exitcode, "same", same, flush=True)
    """
)


def _run(mode: str, env_layer: str | None) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_THREADING_LAYER"}
    if env_layer is not None:
        env["NUMBA_THREADING_LAYER"] = env_layer
    return subprocess.run(
        [sys.executable, "-c", SCRIPT, mode],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        env=env,
    )


def test_a_process_that_rendered_a_sky_forks_a_child_that_renders_it_again() -> None:
    done = _run("threads", None)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    # The sky's kernels are serial (run in threads): no threading layer was started.
    assert lines[0] == "layer none", done.stdout
    # Three threads rendering at once: the same radiance, and no abort.
    assert lines[1] == "threads True", done.stdout
    # The forked child rendered the same sky, bit for bit, and exited 0.
    assert lines[2] == "child 0 same True", done.stdout + done.stderr[-3000:]


def test_with_gnu_openmp_chosen_a_forked_child_renders_the_same_sky() -> None:
    try:
        omppool = importlib.import_module("numba.np.ufunc.omppool")
    except ImportError:
        pytest.skip("numba without its OpenMP threading layer")
    if getattr(omppool, "openmp_vendor", "GNU") != "GNU":
        pytest.skip("an OpenMP runtime that survives fork")
    done = _run("omp", "omp")
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.splitlines()
    # The layer is chosen but never started by the sky, so the child is not killed.
    assert lines[0] == "layer none", done.stdout
    assert lines[1] == "child 0 same True", done.stdout + done.stderr[-3000:]
    assert "fork() called from a process already using GNU OpenMP" not in done.stderr
