"""Running a sweep on Dask, stored chunk by chunk, resumable.

The points of a sweep are cut into chunks: one value of every axis that
changes more than the size distribution (so that a chunk's points share one
refractive index and their spheres, :mod:`dustoptics.sweep.shared`), up to
``max_points`` points along the size axes, and a block of wavelengths.  A
chunk is one Dask task and one chunk of every array in the Zarr store.  The
client submits the chunks that the store does not hold yet, and each is
written as it finishes, by its worker where the worker sees the store (a
local cluster, or workers on a shared filesystem), otherwise by the client:
its arrays first, then a completion marker with their digests (a small
file written to a temporary name and renamed; :mod:`dustoptics.sweep.store`).
A chunk without a marker that its files match is computed again, so a
stopped or crashed sweep resumes where it stopped, no half-written or damaged
chunk is ever counted, and one run at a time writes a store; a worker that
dies is replaced and its tasks run elsewhere (Dask's scheduler).

Before any work the whole sweep is estimated (each point as a single build
estimates it, a chunk's memory, the result and the store) and refused beyond
the budgets unless ``allow_large``.  A chunk that fails on its worker (a full
disk) comes back to the client as a value and is raised there, without the
worker's traceback; a Ctrl-C closes the cluster that the sweep started, whose
workers ignore it, and raises KeyboardInterrupt.

Values depend only on the sweep and its chunks along the size axes, never on
the number of workers, the scheduler, the order in which chunks finish or
the wavelength blocks (each wavelength is computed independently): the same
sweep gives the same bytes.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import math
import os
import pickle
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from dustoptics._validation import BudgetError, check_budget
from dustoptics.io._atomic import write_files
from dustoptics.models.config import BuildConfig
from dustoptics.scattering import optics
from dustoptics.sweep import _fork  # noqa: F401  (Dask's pools renewed in forked children)
from dustoptics.sweep.chunk import (
    EXPANSION,
    MATRIX,
    PER_WAVELENGTH,
    ChunkResult,
    compute_chunk,
    outputs,
    shareable,
)
from dustoptics.sweep.run_token import RunToken as _RunToken
from dustoptics.sweep.spec import SweepSpec, _load_points, expansion_orders
from dustoptics.sweep.store import (
    MARKERS,
    StoreLayout,
    done_chunks,
    held_store,
    read_layout,
    write_marker,
)
from dustoptics.table import Provenance, canonical_json, software_versions

__all__ = ["local_cluster", "sweep"]

#: Blocks of wavelengths by default.  Chunks of the benchmark sweep take
#: 0.5-3 s; the last to finish leaves the other workers idle, about half a
#: chunk on average, while each chunk costs about 25 ms beside its work (its
#: points parsed, its arrays written): 24 blocks (2 of 48 wavelengths) keep
#: both near 2 % on 2 workers.
_WAVELENGTH_BLOCKS = 24


def _require_extra() -> tuple[Any, Any, Any]:
    """xarray, zarr and dask.distributed, or an ImportError naming the extra."""
    # Imported here, not at module level: they are the optional 'sweep' extra, and
    # they add 1.2 s to importing dustoptics.sweep (measured: 1.34 s without them).
    try:
        import distributed
        import xarray
        import zarr
    except ImportError as exc:
        raise ImportError(
            f"sweeps need the 'sweep' extra (dask[distributed], xarray, zarr): "
            f"pip install 'dustoptics[sweep]' ({exc})"
        ) from None
    return xarray, zarr, distributed


# ---------------------------------------------------------------------- layout


@dataclass(frozen=True)
class _Layout:
    """Chunks of the sweep: per axis the chunk length, and wavelengths per chunk."""

    spec: SweepSpec
    axis_chunks: tuple[int, ...]
    wl_chunk: int
    n_wl: int

    @property
    def grid(self) -> tuple[int, ...]:
        """Chunks along each axis, then along wavelength."""
        return tuple(-(-n // c) for n, c in zip(self.spec.shape, self.axis_chunks)) + (
            -(-self.n_wl // self.wl_chunk),
        )

    def chunks(self) -> list[tuple[int, ...]]:
        return list(np.ndindex(*self.grid))

    def region(self, chunk: Sequence[int]) -> tuple[slice, ...]:
        """The chunk's slices: one per axis, then wavelength."""
        out = [
            slice(i * c, min((i + 1) * c, n))
            for i, c, n in zip(chunk, self.axis_chunks, self.spec.shape)
        ]
        w = chunk[-1]
        out.append(slice(w * self.wl_chunk, min((w + 1) * self.wl_chunk, self.n_wl)))
        return tuple(out)

    def name(self, chunk: Sequence[int]) -> str:
        return ".".join(str(i) for i in chunk)

    def size(self, chunk: Sequence[int]) -> int:
        """Point-wavelengths of the chunk."""
        return int(np.prod([s.stop - s.start for s in self.region(chunk)]))


def _layout(spec: SweepSpec, n_wl: int, chunk_wavelengths: int | None, max_points: int) -> _Layout:
    chunks = []
    budget = max_points
    for axis in spec.axes:
        if not axis.size_only:
            chunks.append(1)
    size_axes = [i for i, a in enumerate(spec.axes) if a.size_only]
    sizes = {i: len(spec.axes[i].values) for i in size_axes}
    # Full size axes from the last (fastest) one, the first that does not fit cut into blocks.
    per_axis = {}
    for i in reversed(size_axes):
        if sizes[i] <= budget:
            per_axis[i] = sizes[i]
            budget //= sizes[i]
        else:
            per_axis[i] = max(1, budget)
            budget = 1
    chunks = [per_axis.get(i, 1) for i in range(len(spec.axes))]
    wl = (
        chunk_wavelengths
        if chunk_wavelengths is not None
        else max(1, math.ceil(n_wl / _WAVELENGTH_BLOCKS))
    )
    return _Layout(spec, tuple(chunks), min(wl, n_wl), n_wl)


# ---------------------------------------------------------------------- store


def _computed_variables(
    first: BuildConfig,
    dims: tuple[str, ...],
    shape: tuple[int, ...],
    layout: _Layout,
    coords: dict[str, Any],
) -> dict[str, Any]:
    """Lazy (unwritten) placeholders of the arrays the chunks compute
    (:func:`~dustoptics.sweep.chunk.outputs`); adds the ``order`` coordinate to
    ``coords`` where the expansion coefficients have one."""
    import dask.array as da  # the optional 'sweep' extra (see _require_extra)

    wl, theta = first.wavelengths_nm, first.theta_deg
    sizes = {"theta_deg": theta.size, "order": expansion_orders(first)}
    if sizes["order"]:
        coords["order"] = (
            "order",
            np.arange(sizes["order"]),
            {"units": "1", "long_name": "order l of the generalized spherical functions"},
        )
    meanings = {
        "phase": ("sr-1", "phase function, 2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian)"),
        **PER_WAVELENGTH,
        **MATRIX,
        **EXPANSION,
    }
    data: dict[str, Any] = {}
    for name, extra in outputs(first).items():
        units, meaning = meanings[name]
        n_extra = tuple(sizes[d] for d in extra)
        data[name] = (
            dims + ("wavelength_nm",) + extra,
            da.full(
                shape + (wl.size,) + n_extra,
                np.nan,
                chunks=layout.axis_chunks + (layout.wl_chunk,) + n_extra,
            ),
            {"units": units, "long_name": meaning},
        )
    return data


def _template(spec: SweepSpec, configs: list[BuildConfig], layout: _Layout, method: str) -> Any:
    """The Dataset's coordinates, per-point variables and attributes, with
    lazy (unwritten) placeholders for the computed arrays."""
    import xarray as xr  # the optional 'sweep' extra (see _require_extra)

    first = configs[0]
    dims = tuple(a.key for a in spec.axes)
    shape = spec.shape
    wl = first.wavelengths_nm
    theta = first.theta_deg
    coords: dict[str, Any] = {
        a.key: (a.key, np.array(a.values), {"long_name": f"swept input {a.key}"}) for a in spec.axes
    }
    coords["wavelength_nm"] = (
        "wavelength_nm",
        wl,
        {"units": "nm", "long_name": "vacuum wavelength"},
    )
    coords["theta_deg"] = (
        "theta_deg",
        theta,
        {"units": "degree", "long_name": "scattering angle, 0 = forward"},
    )
    data = _computed_variables(first, dims, shape, layout, coords)
    geometric = np.full(shape, np.nan)
    provenance = np.empty(shape, dtype=object)
    sources: dict[str, Any] = {}
    for index, config in zip(spec.indices(), configs):
        inputs = config.to_inputs()
        record = Provenance(inputs=inputs)
        provenance[index] = canonical_json({"inputs": inputs, "input_hash": record.input_hash})
        if config.size_distribution is not None:
            geometric[index] = config.size_distribution.build().mean_cross_section_um2
        for s in config.sources:
            sources[s.citation] = {"name": s.name, "role": s.role, "citation": s.citation}
    data["mean_geometric_cross_section_um2"] = (
        dims,
        geometric,
        {"units": "um2", "long_name": "pi <r^2> of the size distribution"},
    )
    data["provenance"] = (
        dims,
        provenance.astype(str),
        {
            "long_name": "inputs of the point (canonical JSON) and their SHA-256, as a single build records them"
        },
    )
    attrs = {
        "title": f"dustoptics sweep of {first.name}",
        "source": f"dustoptics {software_versions().get('dustoptics', '?')}",
        "sweep": spec.identity(),
        "method": method,
        "software": json.dumps(software_versions(), sort_keys=True),
        "sources": json.dumps(list(sources.values())),
        "accuracy": (
            "each point's error_estimate (phase function, relative, max over angle) and "
            "cross_section_error_estimate (cext, csca relative, g absolute) are its own quadrature's; "
            + (
                "shared radius nodes (dustoptics.sweep.shared): a point differs from a single build "
                "of the same configuration by at most the sum of the two error estimates"
                if method == "shared"
                else "independent builds: every point equals a single build of its configuration to the bit"
            )
            + _records_accuracy(first)
        ),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _records_accuracy(config: BuildConfig) -> str:
    """The accuracy statement's words on the matrix and the expansion coefficients
    (nothing for a sweep without them, whose attributes stay as they were)."""
    words = ""
    if config.optics.polarization:
        words += (
            "; matrix_error_estimate (F12, F33, F34 relative to F11 at the same angle) is "
            "each point's own, and error_estimate includes it"
        )
    if config.optics.expansion is not None:
        words += (
            "; expansion_error_estimate bounds every expansion coefficient divided by (2 l + 1), "
            f"orders 0..{config.optics.expansion} (zero beyond the orders the spheres need)"
        )
    return words


def _store_layout(layout: _Layout, config: BuildConfig) -> StoreLayout:
    """Which files the chunks of ``layout`` write (arrays over angles or orders keep
    them whole)."""
    return StoreLayout(layout.grid, {k: len(extra) for k, extra in outputs(config).items()})


@contextmanager
def _writing_for(store: Path, run_token: str) -> Iterator[bool]:
    """Whether this worker writes the chunk into the store for the run ``run_token``
    (it sees the run's token, and the run has not ended): the token's shared lock is
    held for the block (see :class:`_RunToken`)."""
    if not _sees(store, run_token):
        yield False
        return
    path = store / MARKERS / run_token
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # the run ended meanwhile
        yield False
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_SH)
        try:
            live = os.stat(path).st_ino == os.fstat(fd).st_ino
        except OSError:
            live = False
        yield live
    finally:
        os.close(fd)  # releases the lock


def _write_chunk(store: Path, region: tuple[slice, ...], name: str, result: ChunkResult) -> None:
    """The chunk's arrays, then its completion marker with their digests (written
    last, atomically)."""
    import zarr  # the optional 'sweep' extra (see _require_extra)

    group = zarr.open_group(str(store), mode="r+", zarr_format=2)
    shape = tuple(s.stop - s.start for s in region[:-1])
    n_w = region[-1].stop - region[-1].start
    for key, values in result.arrays.items():
        array: Any = group[key]
        array[region] = values.reshape(shape + (n_w,) + values.shape[2:])
    record = {
        "seconds": result.seconds,
        "cpu_seconds": result.cpu_seconds,
        "spheres_computed": result.spheres_computed,
        "spheres_weighted": result.spheres_weighted,
    }
    write_marker(store, read_layout(store), name, record)


@dataclass(frozen=True)
class _Failed:
    """A chunk's task that raised: the exception, returned as a value (so that
    Dask does not log the worker's traceback) and raised by the client."""

    error: BaseException


def _run_chunk(
    points: bytes,
    wl_start: int,
    wl_stop: int,
    shared: bool,
    store: str,
    run_token: str,
    region: tuple[slice, ...],
    name: str,
    allow_large: bool = False,
) -> tuple[ChunkResult | _Failed | None, float]:
    """The Dask task: compute a chunk and, where this worker sees the
    client's store, write it there (None); otherwise return it to the client.
    With the seconds it took (for :class:`_Order`).  An error (a full disk, a
    request beyond the budget) comes back as :class:`_Failed`.

    The points come pickled, one opaque argument: Dask would otherwise walk
    every value of every point's TOML data looking for dependencies (0.75 s
    of the client's time for the benchmark's 12 chunks of 100 points).  A
    worker sees the store when it sees the file ``run_token`` that this run
    of the client made in it (a worker of a local cluster always does; one
    on another machine does on a shared filesystem), so that a store at the
    same path on another machine is never written by mistake.  Writing on
    the workers keeps the client's process, which shares the cores of a
    local cluster, from receiving and writing every array.
    """
    start = time.perf_counter()
    try:
        result = compute_chunk(
            pickle.loads(points), wl_start, wl_stop, shared=shared, allow_large=allow_large
        )
        with _writing_for(Path(store), run_token) as writes:
            if writes:
                _write_chunk(Path(store), region, name, result)
                return None, result.seconds
        return result, result.seconds
    except Exception as exc:
        try:
            pickle.dumps(exc)
        except Exception:
            exc = RuntimeError(f"{type(exc).__name__}: {exc}")
        return _Failed(exc), time.perf_counter() - start


def _sees(store: Path, run_token: str) -> bool:
    """Whether this process sees the store of the client's run ``run_token``."""
    return (store / MARKERS / run_token).is_file()


class _Order:
    """Which chunk goes to Dask next: the longest still to run, as far as
    the chunks that finished tell (longest processing time first: the last
    chunks to run are then short, and leave the other workers idle the
    least; R. L. Graham, SIAM J. Appl. Math. 17, 416-429 (1969),
    doi:10.1137/0117039).

    A chunk's time varies with its wavelengths, smoothly but not in one
    direction (in the benchmark sweep, 0.5 s at 400 nm, 1.5 s at 800 nm:
    Mars dust absorbs less in the red, and its resonances need more nodes).
    Chunks that nothing is known of go in an order that spreads over the
    wavelengths (first, last, middle, then the quarters, ...); once chunks
    have finished, each waiting chunk's time is interpolated from the
    nearest finished ones of its block (the same values of the other axes)
    along the wavelength axis, or is the mean of all finished chunks for a
    block with none yet.  Each block keeps its best candidate, so a choice
    costs a pass over the blocks, not over every waiting chunk.
    """

    def __init__(self, chunks: Sequence[tuple[int, ...]]):
        last = max((c[-1] for c in chunks), default=0)
        self.rank = {w: i for i, w in enumerate(_spread(last + 1))}
        self.pending: dict[tuple[int, ...], list[int]] = {}  # block -> w, by rank
        for c in chunks:
            self.pending.setdefault(c[:-1], []).append(c[-1])
        for ws in self.pending.values():
            ws.sort(key=self.rank.__getitem__)
        self.known: dict[tuple[int, ...], dict[int, float]] = {}
        self.best: dict[tuple[int, ...], tuple[float, int, int]] = {}  # (time, -rank, w)
        self.total = 0.0
        self.count = 0

    def finished(self, chunk: tuple[int, ...], seconds: float) -> None:
        block = chunk[:-1]
        self.known.setdefault(block, {})[chunk[-1]] = seconds
        self.total += seconds
        self.count += 1
        self._update(block)

    def _update(self, block: tuple[int, ...]) -> None:
        """The best waiting chunk of a block with finished chunks."""
        known = self.known.get(block)
        ws = self.pending.get(block)
        if not known or not ws:
            self.best.pop(block, None)
            return
        done = sorted(known)
        times = [known[k] for k in done]
        # np.interp holds the end values beyond the finished range.
        estimates = np.interp(ws, done, times)
        self.best[block] = max(
            (float(t), -self.rank[w], w) for t, w in zip(estimates, ws, strict=True)
        )

    def next(self) -> tuple[int, ...] | None:
        """The chunk to submit next (removed from the waiting ones), or None."""
        mean = self.total / self.count if self.count else 0.0
        choice: tuple[float, int, int] | None = None
        block_of_choice: tuple[int, ...] = ()
        for block, ws in self.pending.items():
            if not ws:
                continue
            # A block with finished chunks: its best; without: its first by
            # rank, at the mean time of all finished chunks.
            candidate = self.best.get(block) or (mean, -self.rank[ws[0]], ws[0])
            if choice is None or candidate > choice:
                choice, block_of_choice = candidate, block
        if choice is None:
            return None
        w = choice[2]
        self.pending[block_of_choice].remove(w)
        self._update(block_of_choice)
        return block_of_choice + (w,)


def _spread(n: int) -> list[int]:
    """0 .. n-1 in an order that spreads over the range: 0, n-1, then the
    middle of the widest gap, and so on (for 5: 0, 4, 2, 1, 3)."""
    if n <= 2:
        return list(range(n))
    order = [0, n - 1]
    gaps = [(0, n - 1)]
    while gaps:
        gaps.sort(key=lambda g: (g[0] - g[1], g[0]))  # the widest first, then the lowest
        lo, hi = gaps.pop(0)
        if hi - lo < 2:
            continue
        mid = (lo + hi) // 2
        order.append(mid)
        gaps += [(lo, mid), (mid, hi)]
    return order


# ---------------------------------------------------------------------- progress


class _Progress:
    """``sweep [####....] N/M point-wavelengths, elapsed, ETA`` on a stream, within 80 columns
    for sweeps of up to a million point-wavelengths and a day's work."""

    def __init__(
        self,
        stream: TextIO | None,
        callback: Callable[[int, int], None] | None,
        total: int,
        done: int,
    ):
        self.stream = stream
        self.callback = callback
        self.total = total
        self.done = done
        self.start_done = done
        self.start = time.perf_counter()
        self.tty = stream is not None and hasattr(stream, "isatty") and stream.isatty()
        self.report()

    def add(self, n: int) -> None:
        self.done += n
        self.report()

    def report(self) -> None:
        if self.callback is not None:
            self.callback(self.done, self.total)
        if self.stream is None:
            return
        elapsed = time.perf_counter() - self.start
        rate = (self.done - self.start_done) / elapsed if elapsed > 0 else 0.0
        if self.done == self.total:
            eta = "0 s"
        else:
            eta = f"{(self.total - self.done) / rate:.0f} s" if rate > 0 else "?"
        width = 16
        filled = int(width * self.done / max(1, self.total))
        bar = "#" * filled + "." * (width - filled)
        end = "\n" if (self.done == self.total or not self.tty) else "\r"
        print(
            f"sweep [{bar}] {self.done}/{self.total} point-wavelengths, {elapsed:.0f} s, ETA {eta}",
            end=end,
            file=self.stream,
        )
        self.stream.flush()


# ---------------------------------------------------------------------- the sweep


#: Dask settings for the local clusters that sweeps start.  Dask's defaults
#: wake every worker and the scheduler 50 times a second (the event-loop
#: tick), sample every task's stack 100 times a second (the profiler) and
#: read each process's memory 10 times a second; on the benchmark sweep's 2
#: cores these took 6.4 s of CPU time in 29 s, beside the tasks, and
#: 1.3 s with these.  The tasks themselves are minutes of compiled code
#: whose profile Dask cannot show.  Memory is still watched, once a second.
_LOCAL_CLUSTER_CONFIG = {
    "distributed.admin.tick.interval": "500ms",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.worker.profile.enabled": False,
}


@contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in this thread for the block, and so in the threads and
    processes started meanwhile (they inherit the mask, across ``exec`` too);
    a Ctrl-C meanwhile waits and is delivered when the block ends."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(
        signal, "pthread_sigmask"
    ):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def local_cluster(workers: int | None = None, *, threads: int = 1, processes: bool = True) -> Any:
    """The Dask ``LocalCluster`` that a sweep starts when given no client.

    Parameters
    ----------
    workers : int, optional
        Worker processes (default: all cores).
    threads : int
        Threads per worker.
    processes : bool
        Workers in their own processes (the default, and the faster with
        numba's kernels: the sweep benchmark) or threads of this process.

    Returns
    -------
    distributed.LocalCluster
        With :data:`_LOCAL_CLUSTER_CONFIG`'s settings, the dashboard on a
        free port, and Dask's logs below critical silenced.  Its worker processes
        ignore SIGINT (:mod:`dustoptics.sweep._worker`): a Ctrl-C stops the
        process that started it, which closes the cluster (a sweep does),
        rather than printing every worker's traceback.  Close it (or use it
        as a context manager) when done.
    """
    import dask  # the optional 'sweep' extra (see _require_extra)

    _, _, distributed = _require_extra()
    with dask.config.set(_LOCAL_CLUSTER_CONFIG), _sigint_blocked():
        return distributed.LocalCluster(
            n_workers=workers or os.cpu_count() or 1,
            threads_per_worker=threads,
            processes=processes,
            dashboard_address=":0",
            # Only critical logs: a chunk's own errors come back as values (ChunkResult), and
            # the errors Dask logs while a cluster closes under it (a worker's heartbeat to a
            # scheduler already gone, after a Ctrl-C on a loaded machine) are not the user's.
            silence_logs=50,
            preload=["dustoptics.sweep._worker"],
        )


def _client(client: Any, workers: int | None, distributed: Any, to_close: list[Any]) -> Any:
    """A Client for ``client``: None (a local cluster of worker processes,
    :func:`local_cluster`), an address, or a Client.  What the sweep must
    close afterwards is appended to ``to_close`` as soon as it exists."""
    if client is None:
        with _sigint_blocked():  # a Ctrl-C comes after the cluster is in to_close
            cluster = local_cluster(workers)
            to_close.append(cluster)
            c = distributed.Client(cluster)
            to_close.insert(0, c)
        return c
    if isinstance(client, str):
        c = distributed.Client(client)
        to_close.append(c)
        return c
    if isinstance(client, distributed.Client):
        return client
    raise TypeError(
        f"client must be None, a scheduler address 'tcp://HOST:PORT' or a dask.distributed.Client; got {client!r}"
    )


def _close(objects: Sequence[Any]) -> None:
    """Close the client, then the cluster, each whatever the other did."""
    for obj in objects:
        with contextlib.suppress(Exception):
            obj.close()


def _values_per_point_wavelength(template: Any) -> int:
    """Values per point and wavelength of every computed array: the angles of
    ``phase`` (and of F12, F33, F34), the orders of the expansion coefficients,
    one of each other."""
    return sum(
        math.prod(template.sizes[d] for d in v.dims[v.dims.index("wavelength_nm") + 1 :])
        for v in template.data_vars.values()
        if "wavelength_nm" in v.dims
    )


def _check_cost(
    spec: SweepSpec,
    costs: Sequence[Any],
    layout: _Layout,
    template: Any,
    *,
    store: Path,
    in_memory: bool,
    allow_large: bool,
) -> None:
    """Refuse a sweep beyond the budgets before any work: its work (each point
    as :func:`~dustoptics.scattering.optics.estimate_cost` estimates a single
    build of it, an upper estimate for points that share their spheres), a
    chunk's memory, the result in memory, and the store on its disk.

    Raises
    ------
    dustoptics._validation.BudgetError
        Beyond a budget, and ``allow_large`` is False; the message says what
        drives the estimate and what to change.
    """
    if allow_large:
        return
    n_theta = template.sizes["theta_deg"]
    mie = [(i, c) for i, c in enumerate(costs) if c is not None]
    work = float(sum(c.work for _, c in mie))
    budget = optics.WORK_BUDGET
    if work > budget:
        i, costliest = max(mie, key=lambda ic: ic[1].work)
        raise BudgetError(
            f"the sweep would need about {work:.3g} sphere-order-angle terms over its "
            f"{spec.n_points} points of {layout.n_wl} wavelengths x {n_theta} angles (the "
            f"costliest, {_where(spec, i)}, {costliest.work:.3g}), beyond the budget of "
            f"{budget:g} (about ten minutes on this machine): use fewer points, wavelengths or "
            "angles, or smaller particles, or pass allow_large=True (--allow-large on the "
            "command line) to go ahead"
        )
    per_chunk = int(np.prod(layout.axis_chunks)) * layout.wl_chunk
    per_value = _values_per_point_wavelength(template)
    arrays = 2.0 * 8.0 * per_chunk * per_value
    solver = max((c.memory_bytes for _, c in mie), default=0.0)
    check_budget(
        "a chunk of the sweep",
        solver + arrays,
        allow_large=False,
        change=(
            f"a chunk holds up to {per_chunk} point-wavelengths x {per_value} values (the "
            f"phase function's {n_theta} angles, and the matrix's and expansion's where asked) "
            "beside the solver of its largest point: use a smaller max_points or "
            "chunk_wavelengths, fewer angles or orders, or smaller particles"
        ),
    )
    size = float(template.nbytes)
    if in_memory:
        check_budget(
            "the sweep's result",
            size,
            allow_large=False,
            change=(
                f"it holds {spec.n_points} points x {layout.n_wl} wavelengths x {n_theta} angles "
                "in memory: use fewer, or write a Zarr store (out='NAME.zarr'), read lazily"
            ),
        )
    held = sum(p.stat().st_size for p in store.rglob("*") if p.is_file()) if store.is_dir() else 0
    need = size - held
    directory = store
    while not directory.exists() and directory.parent != directory:
        directory = directory.parent
    try:
        free = shutil.disk_usage(directory).free
    except OSError:
        return
    if need > free:
        raise BudgetError(
            f"the sweep's store {str(store)!r} needs about {need / 1024**3:.3g} GiB more "
            f"(uncompressed), and its filesystem has {free / 1024**3:.3g} GiB free: free some "
            "space, choose another path, or use fewer points, wavelengths or angles, or pass "
            "allow_large=True (--allow-large on the command line) to go ahead (compression "
            "may make it fit)"
        )


def _where(spec: SweepSpec, flat: int) -> str:
    """``axis = value, ...`` of the point at flat (C order) index ``flat``."""
    index = np.unravel_index(flat, spec.shape)
    return ", ".join(f"{a.key} = {a.values[int(i)]!r}" for a, i in zip(spec.axes, index))


def sweep(
    config: Any,
    over: Mapping[str, Any] | None = None,
    *,
    out: str | os.PathLike[str] | None = None,
    client: Any = None,
    workers: int | None = None,
    shared: bool = True,
    chunk_wavelengths: int | None = None,
    max_points: int = 400,
    progress: TextIO | Callable[[int, int], None] | None = sys.stderr,
    allow_large: bool = False,
) -> Any:
    """Compute a configuration over axes of its inputs: one labelled dataset.

    Parameters
    ----------
    config : str, os.PathLike or BuildConfig
        A preset name, a TOML file (whose ``[sweep]`` table gives axes), TOML
        text, or a configuration object (:mod:`dustoptics.models.config`).
    over : Mapping, optional
        Axes: dotted TOML keys -> values (a list, or ``{"start", "stop",
        "num"}``), e.g. ``{"size_distribution.r_eff_um": [0.5, 1, 2, 4],
        "size_distribution.v_eff": [0.1, 0.2]}``; see :mod:`dustoptics.sweep.spec`.
    out : str or os.PathLike, optional
        Store: a Zarr directory, written chunk by chunk and resumed when it
        exists, or a ``.nc`` file (netCDF-4, written at the end from a Zarr
        working store ``OUT.zarr-partial`` that makes it resumable too).
        None: nothing is written; the result is returned in memory.  One run
        at a time writes a store (:mod:`dustoptics.sweep.store`); every chunk
        carries its digest, checked on resume.
    client : None, str or dask.distributed.Client, optional
        Where to compute: None starts a local cluster of ``workers`` worker
        processes (one thread each, :func:`local_cluster`) and closes it at
        the end; a ``tcp://HOST:PORT`` address connects to that scheduler; or
        a Client.  Workers that see the store's filesystem write their
        chunks themselves; others return them to the client.
    workers : int, optional
        Worker processes of the local cluster (default: all cores).
    shared : bool
        Share radius nodes across points that differ only in their size
        distribution (:mod:`dustoptics.sweep.shared`).  False builds every
        point independently: each then equals a single build to the bit.
    chunk_wavelengths : int, optional
        Wavelengths per chunk (default: the wavelengths in 24 blocks).
    max_points : int
        Most points of a chunk along the size-distribution axes.
    progress : stream or callable, optional
        Progress bar (points x wavelengths done, elapsed time, remaining time)
        on a stream (default stderr), a callable ``progress(done, total)``, or
        None.
    allow_large : bool
        Go ahead beyond the budgets (default False): before any work, the
        sweep is refused if its points, as a single build estimates each
        (:func:`~dustoptics.scattering.optics.check_cost`), need more than
        :data:`~dustoptics.scattering.optics.WORK_BUDGET` together, if a
        point or a chunk needs more memory than a single call may, if the
        result held in memory (``out`` None or ``.nc``) would, or if the
        store would not fit on its disk.

    Returns
    -------
    xarray.Dataset
        Dimensions: the axes (named by their keys), ``wavelength_nm``,
        ``theta_deg``.  ``phase`` [sr^-1], ``cext_um2``, ``csca_um2``
        [um^2], ``g``, ``error_estimate``, ``cross_section_error_estimate``,
        ``n_nodes``, per point ``mean_geometric_cross_section_um2`` [um^2]
        and ``provenance`` (its inputs and their hash), attributes with the
        sweep, software versions, sources and the accuracy statement.  With
        ``optics.polarization = true`` also ``f12``, ``f33``, ``f34``
        [sr^-1] and ``matrix_error_estimate``; with ``optics.expansion = N``
        also ``alpha1`` .. ``alpha4``, ``beta1``, ``beta2`` over an ``order``
        dimension (0..N) and ``expansion_error_estimate``
        (:func:`~dustoptics.sweep.point_table` reads a point as a table).  For a
        Zarr ``out``, the dataset opened from the store, every chunk checked.

    Raises
    ------
    ValueError
        An invalid axis or value (before any work: the message names the
        axis, the value and its range), ``optics.expansion = true`` (every
        order the spheres need differs by point: give an order N), a request beyond the budget
        (:class:`~dustoptics._validation.BudgetError`), a store holding
        another sweep or damaged where a chunk cannot be recomputed
        (:class:`~dustoptics.io.FormatError`), or a store that another run is
        writing (:class:`~dustoptics.sweep.store.StoreBusyError`).
    OSError
        Writing the store failed (e.g. a full disk); what was written stays,
        and a new run resumes it.
    KeyboardInterrupt
        After the cluster that the sweep started has been closed; the
        finished chunks stay in the store.
    ImportError
        Without the ``sweep`` extra.
    """
    xr, _, distributed = _require_extra()
    _check_options(max_points, chunk_wavelengths, workers, allow_large)
    spec, data, configs, costs = _load(config, over, allow_large)
    layout = _layout(spec, configs[0].wavelengths_nm.size, chunk_wavelengths, max_points)
    method = "shared" if shared and all(shareable(c) for c in configs) else "independent"
    template = _template(spec, configs, layout, method)
    identity = canonical_json(
        {
            "sweep": spec.identity(),
            "method": method,
            "chunks": list(layout.axis_chunks),
            "wavelengths_per_chunk": layout.wl_chunk,
        }
    )
    netcdf = out is not None and str(out).endswith(".nc")
    temporary: str | None = None
    if out is None:
        temporary = tempfile.mkdtemp(prefix="dustoptics-sweep-")
        store = Path(temporary) / "sweep.zarr"
    else:
        store = Path(str(out) + ".zarr-partial") if netcdf else Path(out)
    try:
        _check_cost(
            spec,
            costs,
            layout,
            template,
            store=store,
            in_memory=out is None or netcdf,
            allow_large=allow_large,
        )

        def create(folder: Path) -> None:
            # "w-" writes into the (empty, locked) folder; "w" would replace it.
            template.to_zarr(folder, compute=False, mode="w-", zarr_format=2, consolidated=True)

        with held_store(
            store, identity=identity, layout=_store_layout(layout, configs[0]), create=create
        ) as new:
            todo = _todo(store, layout, new=new)
            total = spec.n_points * layout.n_wl
            bar = _progress_bar(progress, total, total - sum(layout.size(c) for c in todo))
            if todo:
                _compute(
                    data,
                    layout,
                    todo,
                    store,
                    bar,
                    client=client,
                    workers=workers,
                    shared=shared,
                    allow_large=allow_large,
                    distributed=distributed,
                )
            return _result(xr, store, out=out, netcdf=netcdf, in_memory=temporary is not None)
    finally:
        if temporary is not None:
            shutil.rmtree(temporary, ignore_errors=True)


#: Most worker processes per core a local cluster starts without ``allow_large``.
_MAX_WORKERS_PER_CORE = 4


def _check_options(max_points: Any, chunk_wavelengths: Any, workers: Any, allow_large: Any) -> None:
    """Refuse :func:`sweep`'s options outside their ranges, before any work."""
    for key, value in (
        ("max_points", max_points),
        ("chunk_wavelengths", chunk_wavelengths),
        ("workers", workers),
    ):
        if key != "max_points" and value is None:
            continue
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise ValueError(f"{key} must be a positive integer; got {value!r}")
    if not isinstance(allow_large, bool):
        raise TypeError(f"allow_large must be True or False; got {allow_large!r}")
    most = _MAX_WORKERS_PER_CORE * (os.cpu_count() or 1)
    if workers is not None and workers > most and not allow_large:
        raise ValueError(
            f"workers={workers}: a local cluster of at most {most} worker processes "
            f"({_MAX_WORKERS_PER_CORE} per core of this machine's {os.cpu_count() or 1}; each "
            "one a Python process with its own compiled kernels); pass allow_large=True "
            "(--allow-large) to start more"
        )


def _todo(store: Path, layout: _Layout, *, new: bool) -> list[tuple[int, ...]]:
    """The chunks a held store does not hold yet (all of a new one)."""
    done: set[str] = set() if new else done_chunks(store, read_layout(store), repair=True)
    return [c for c in layout.chunks() if layout.name(c) not in done]


def _progress_bar(
    progress: TextIO | Callable[[int, int], None] | None, total: int, done: int
) -> _Progress:
    """A progress bar on a stream, a callback, or neither."""
    stream: Any = progress if progress is not None and hasattr(progress, "write") else None
    callback: Any = progress if callable(progress) and stream is None else None
    return _Progress(stream, callback, total, done)


def _result(
    xr: Any,
    store: Path,
    *,
    out: str | os.PathLike[str] | None,
    netcdf: bool,
    in_memory: bool,
) -> Any:
    """The finished sweep: from a netCDF file written from the store (which is
    removed), loaded from a temporary store, or opened lazily from the store."""
    if netcdf:
        assert out is not None
        ds = xr.open_zarr(store, consolidated=True).load()
        write_files(
            {Path(out): lambda path: ds.to_netcdf(path, engine="h5netcdf")},
            overwrite=True,
        )
        shutil.rmtree(store)  # still held: no other run is using it
        return xr.open_dataset(out, engine="h5netcdf")
    if in_memory:
        return xr.open_zarr(store, consolidated=True).load()
    return xr.open_zarr(store, consolidated=True)


def _compute(
    data: Sequence[Mapping[str, Any]],
    layout: _Layout,
    todo: Sequence[tuple[int, ...]],
    store: Path,
    bar: _Progress,
    *,
    client: Any,
    workers: int | None,
    shared: bool,
    allow_large: bool,
    distributed: Any,
) -> None:
    """Compute the chunks ``todo`` on Dask into the store (which this run holds)."""
    token = _RunToken(store)
    to_close: list[Any] = []
    futures: dict[Any, tuple[int, ...]] = {}
    try:
        c = _client(client, workers, distributed, to_close)
        flat = np.arange(layout.spec.n_points).reshape(layout.spec.shape)
        where = str(store.resolve())  # workers may run in another directory
        order = _Order(todo)

        def submit(chunk: tuple[int, ...]) -> Any:
            region = layout.region(chunk)
            points = pickle.dumps([data[int(i)] for i in flat[region[:-1]].ravel()], protocol=5)
            return c.submit(
                _run_chunk,
                points,
                region[-1].start,
                region[-1].stop,
                shared,
                where,
                token.name,
                region,
                layout.name(chunk),
                allow_large,
                pure=False,
                key=f"dustoptics-sweep-{layout.name(chunk)}-{os.getpid()}-{time.time_ns()}",
            )

        def slots() -> int:
            # One chunk running and one waiting per worker thread: the
            # rest wait here, so that each goes out in _Order's order.
            return max(2, 2 * sum(c.nthreads().values()))

        running = distributed.as_completed()

        def fill() -> None:
            limit = slots()  # one call to the scheduler, not one per chunk
            while len(futures) < limit and (chunk := order.next()) is not None:
                future = submit(chunk)
                futures[future] = chunk
                running.add(future)

        fill()
        for future in running:
            chunk = futures.pop(future)
            result, seconds = future.result()
            if isinstance(result, _Failed):
                raise result.error
            if result is not None:  # the worker does not see the store
                _write_chunk(store, layout.region(chunk), layout.name(chunk), result)
            future.release()
            order.finished(chunk, seconds)
            bar.add(layout.size(chunk))
            fill()
    finally:
        token.end()
        if futures and not to_close:  # a cluster that outlives the sweep: stop its work
            with contextlib.suppress(Exception):
                c.cancel(list(futures))
        _close(to_close)
    names = [layout.name(chunk) for chunk in todo]
    missing = sorted(set(names) - done_chunks(store, read_layout(store), names, repair=False))
    if missing:
        raise RuntimeError(
            f"chunks {missing} finished but their markers are not in {str(store)!r}: "
            "did their workers write to another filesystem at the same path? "
            "Running the sweep again computes them"
        )


def _load(
    config: Any, over: Mapping[str, Any] | None, allow_large: bool = False
) -> tuple[SweepSpec, list[dict[str, Any]], list[BuildConfig], list[Any]]:
    """The sweep, its points' TOML data (in C order of the axes), their
    validated configurations and their costs (None for a point without Mie
    work), each point refused as a single build would refuse it."""
    return _load_points(config, over, allow_large=allow_large)
