"""One chunk of a sweep: its points at a block of wavelengths, as one task computes it.

:func:`compute_chunk` parses the chunk's points (TOML data) and fills its
arrays, either with points that share their spheres (a polydisperse Mie
model whose points differ only in their size distribution: the first
point's :class:`~dustoptics.scattering.optics.OpticsRequest` at the chunk's
wavelengths, :func:`dustoptics.sweep.shared.solve_shared`) or with each point
built on its own (:func:`dustoptics.models.compute.build_table`, equal to
the bit to the same wavelengths of a single build).  :mod:`dustoptics.sweep.run`
submits the chunks to Dask and stores them.
"""

from __future__ import annotations

import ctypes
import os
import platform
import sys
import threading
import time
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from dustoptics.models.compute import build_table, mie_request
from dustoptics.models.config import BuildConfig
from dustoptics.sweep.shared import solve_shared
from dustoptics.sweep.spec import expansion_orders, parse_points
from dustoptics.table import Table

__all__ = [
    "EXPANSION",
    "MATRIX",
    "PER_WAVELENGTH",
    "ChunkResult",
    "compute_chunk",
    "outputs",
    "shareable",
]

#: Variables per point and wavelength (besides ``phase``), with units and meaning.
PER_WAVELENGTH = {
    "cext_um2": ("um2", "mean extinction cross-section per particle"),
    "csca_um2": ("um2", "mean scattering cross-section per particle"),
    "g": ("1", "asymmetry parameter 2 pi int P mu dmu"),
    "error_estimate": ("1", "estimated largest relative error of the phase function at any angle"),
    "cross_section_error_estimate": (
        "1",
        "estimated error of cext, csca (relative) and g (absolute)",
    ),
    "n_nodes": ("1", "radius nodes of the quadrature of the phase function"),
}

#: The scattering matrix (``optics.polarization = true``): per point, wavelength and
#: angle, then its error estimate per point and wavelength.
MATRIX = {
    "f12": ("sr-1", "scattering matrix element F12, normalized as the phase function (F11)"),
    "f33": ("sr-1", "scattering matrix element F33, normalized as the phase function (F11)"),
    "f34": ("sr-1", "scattering matrix element F34, normalized as the phase function (F11)"),
    "matrix_error_estimate": (
        "1",
        "estimated largest error of F12, F33, F34 relative to F11 at the same angle",
    ),
}

#: The expansion coefficients in generalized spherical functions (``optics.expansion
#: = N``): per point, wavelength and order l = 0..N, then their error estimate.
EXPANSION = {
    **{
        name: ("1", f"expansion coefficient {name}_l in generalized spherical functions")
        for name in ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")
    },
    "expansion_error_estimate": (
        "1",
        "bound on the error of every expansion coefficient divided by (2 l + 1)",
    ),
}


def outputs(config: BuildConfig) -> dict[str, tuple[str, ...]]:
    """The arrays a sweep of ``config`` computes -> their dimensions after the point's
    and the wavelength's: ``phase`` and :data:`PER_WAVELENGTH` always, :data:`MATRIX`
    with ``optics.polarization``, :data:`EXPANSION` with ``optics.expansion = N`` (on
    an ``order`` dimension of N + 1)."""
    out: dict[str, tuple[str, ...]] = {"phase": ("theta_deg",)}
    out.update(dict.fromkeys(PER_WAVELENGTH, ()))
    if config.optics.polarization:
        out.update({k: () if k.endswith("_estimate") else ("theta_deg",) for k in MATRIX})
    if config.optics.expansion is not None:
        out.update({k: () if k.endswith("_estimate") else ("order",) for k in EXPANSION})
    return out


@dataclass(frozen=True)
class ChunkResult:
    """What a task returns: its arrays and the work it did.

    Attributes
    ----------
    arrays : Mapping
        ``phase`` (points, wavelengths, angles), the variables of
        :data:`PER_WAVELENGTH` (points, wavelengths), and those of
        :data:`MATRIX` and :data:`EXPANSION` where the configuration asks for
        them (:func:`outputs`), points in C order of the chunk.
    spheres_computed, spheres_weighted : int
        Spheres whose Mie sums were computed, and sphere-distribution pairs
        weighted (equal without sharing). [-]
    seconds : float
        Time the task took on its worker. [s]
    cpu_seconds : float
        CPU time of the thread that ran it: below ``seconds`` by the time it
        waited (for a core, or for the GIL). [s]
    """

    arrays: Mapping[str, np.ndarray]
    spheres_computed: int
    spheres_weighted: int
    seconds: float
    cpu_seconds: float


def shareable(config: BuildConfig) -> bool:
    """Whether a point's spheres can be shared with others (:mod:`dustoptics.sweep.shared`):
    a polydisperse Mie phase function without the matrix or expansion coefficients, which
    the shared solver does not compute."""
    return (
        config.phase.model == "mie"
        and not config.optics.polarization
        and config.optics.expansion is None
        and config.size_distribution is not None
        and config.size_distribution.build().has_density
    )


# glibc's mallopt parameters (malloc.h).
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_GLIBC_MMAP_THRESHOLD = 128 * 1024  # glibc's default, before any adjustment
_allocator_lock = threading.Lock()
_allocator_users = 0


@contextmanager
def _allocations_reused() -> Iterator[None]:
    """Let glibc reuse freed memory for the duration of a task, in processes
    whose allocator thresholds were fixed by the environment.

    Dask starts its worker processes with ``MALLOC_TRIM_THRESHOLD_=65536``
    (``distributed.nanny.pre-spawn-environ``), so that they return memory to
    the operating system.  Fixing a threshold also stops glibc from raising
    its mmap threshold, so every array above 128 KiB is a fresh mapping
    whose pages fault in and are zeroed again: a chunk ran 35-40 % slower in
    a worker than in a plain process (the same four wavelengths of the
    benchmark sweep, 1.3-1.4 s against 1.8-2.0 s).  While any chunk runs,
    arrays up to 64 MiB come from the heap and stay there; when the last one
    ends, the thresholds the environment set (or glibc's defaults) are back
    and ``malloc_trim`` returns the free memory, as Dask intends.  Elsewhere
    (other C libraries, or no threshold in the environment) nothing changes.
    """
    global _allocator_users
    fixed = "MALLOC_TRIM_THRESHOLD_" in os.environ or "MALLOC_MMAP_THRESHOLD_" in os.environ
    libc = None
    if fixed and sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc":
        try:
            libc = ctypes.CDLL("libc.so.6")
        except OSError:
            libc = None
    if libc is None:
        yield
        return
    with _allocator_lock:
        _allocator_users += 1
        if _allocator_users == 1:
            libc.mallopt(_M_MMAP_THRESHOLD, 64 << 20)
            libc.mallopt(_M_TRIM_THRESHOLD, 256 << 20)
    try:
        yield
    finally:
        with _allocator_lock:
            _allocator_users -= 1
            if _allocator_users == 0:
                for name, param, default in (
                    ("MALLOC_MMAP_THRESHOLD_", _M_MMAP_THRESHOLD, _GLIBC_MMAP_THRESHOLD),
                    ("MALLOC_TRIM_THRESHOLD_", _M_TRIM_THRESHOLD, 2 * _GLIBC_MMAP_THRESHOLD),
                ):
                    try:
                        value = int(os.environ.get(name, default))
                    except ValueError:
                        value = default
                    libc.mallopt(param, value)
                libc.malloc_trim(0)


def compute_chunk(
    points: Sequence[Mapping[str, Any]],
    wavelength_start: int,
    wavelength_stop: int,
    *,
    shared: bool = True,
    allow_large: bool = False,
) -> ChunkResult:
    """Compute one chunk: its points at a block of their wavelengths.

    With ``shared`` (and a polydisperse Mie model), the points, which differ
    only in their size distribution, share their spheres
    (:func:`dustoptics.sweep.shared.solve_shared`); otherwise each point is
    :func:`dustoptics.models.compute.build_table` at those wavelengths, equal
    to the bit to the same wavelengths of a single build, which refuses a
    point beyond its budget unless ``allow_large``.

    Parameters
    ----------
    points : sequence of mapping
        The points' TOML data (:func:`dustoptics.sweep.spec.parse_points`).
    wavelength_start, wavelength_stop : int
        The block ``[wavelength_start, wavelength_stop)`` of indices into the
        points' wavelengths. [-]
    shared : bool
        Share the spheres where the model allows it.
    allow_large : bool
        Go ahead beyond a single build's budget.

    Returns
    -------
    ChunkResult
    """
    start, cpu = time.perf_counter(), time.thread_time()
    with _allocations_reused():
        arrays, computed, weighted = _compute_arrays(
            points, wavelength_start, wavelength_stop, shared, allow_large
        )
    return ChunkResult(
        arrays, computed, weighted, time.perf_counter() - start, time.thread_time() - cpu
    )


def _compute_arrays(
    points: Sequence[Mapping[str, Any]],
    wavelength_start: int,
    wavelength_stop: int,
    shared: bool,
    allow_large: bool = False,
) -> tuple[dict[str, np.ndarray], int, int]:
    """The arrays of :func:`compute_chunk`, and the spheres computed and weighted."""
    configs = parse_points(points)
    wl = configs[0].wavelengths_nm[wavelength_start:wavelength_stop]
    theta = configs[0].theta_deg
    n_p, n_w = len(configs), wl.size
    sizes = {"theta_deg": theta.size, "order": expansion_orders(configs[0])}
    arrays = {"phase": np.empty((n_p, n_w, theta.size))}
    for name, dims in outputs(configs[0]).items():
        if name != "phase":
            arrays[name] = np.full((n_p, n_w, *(sizes[d] for d in dims)), np.nan)
    if shared and all(shareable(c) for c in configs):
        computed, weighted = _shared_arrays(configs, wl, arrays)
    else:
        computed, weighted = _independent_arrays(configs, wl, arrays, allow_large)
    return arrays, computed, weighted


def _shared_arrays(
    configs: Sequence[BuildConfig], wavelength_nm: np.ndarray, arrays: dict[str, np.ndarray]
) -> tuple[int, int]:
    """Fill ``arrays`` with points that share their spheres (one request's index,
    grids and tolerances: the first point's at these wavelengths); returns the
    spheres computed and weighted."""
    request = mie_request(configs[0], wavelength_nm=wavelength_nm)
    mu = request.mu_out
    dists = [c.size_distribution.build() for c in configs]  # type: ignore[union-attr]
    buffers: dict[bool, np.ndarray] = {}
    computed = weighted = 0
    for w in range(wavelength_nm.size):
        results, stats = solve_shared(
            m=complex(request.m[w]),
            wavelength_nm=float(wavelength_nm[w]),
            mu_out=mu,
            distributions=dists,
            per_particle=request.per_particle,
            settings=request.quadrature,
            rtol=request.rtol,
            cross_rtol=request.cross_section_rtol,
            buffers=buffers,
        )
        computed += stats.spheres_computed
        weighted += stats.spheres_weighted
        for p, r in enumerate(results):
            if not (np.all(np.isfinite(r.phase)) and np.all(r.phase > 0)):
                raise FloatingPointError(
                    "phase function is not finite and positive; please report this input"
                )
            arrays["phase"][p, w] = r.phase
            arrays["cext_um2"][p, w] = r.cext
            arrays["csca_um2"][p, w] = r.csca
            arrays["g"][p, w] = r.g
            arrays["error_estimate"][p, w] = r.err_phase
            arrays["cross_section_error_estimate"][p, w] = r.err_cross
            arrays["n_nodes"][p, w] = r.n_nodes
    return computed, weighted


def _independent_arrays(
    configs: Sequence[BuildConfig],
    wavelength_nm: np.ndarray,
    arrays: dict[str, np.ndarray],
    allow_large: bool,
) -> tuple[int, int]:
    """Fill ``arrays`` with each point built on its own at these wavelengths
    (:func:`~dustoptics.models.compute.build_table`); returns the spheres computed
    and weighted."""
    computed = weighted = 0
    for p, config in enumerate(configs):
        part = replace(
            config,
            optics=replace(config.optics, wavelengths_nm=tuple(float(x) for x in wavelength_nm)),
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            table = build_table(part, workers=1, allow_large=allow_large)
        arrays["phase"][p] = table.phase
        arrays["g"][p] = table.g
        for name in ("cext_um2", "csca_um2", "error_estimate", "cross_section_error_estimate"):
            value = table.quantity(name)
            if value is not None:
                arrays[name][p] = value
        if table.quadrature is not None and table.quadrature.n_nodes is not None:
            arrays["n_nodes"][p] = table.quadrature.n_nodes
            computed += int(np.sum(table.quadrature.n_nodes))
            weighted += int(np.sum(table.quadrature.n_nodes))
        _fill_records(arrays, p, table)
    return computed, weighted


def _fill_records(arrays: dict[str, np.ndarray], p: int, table: Table) -> None:
    """Point ``p``'s matrix and expansion coefficients where ``arrays`` hold them.

    A sweep asks for them in every point's configuration (one base), so a table
    without a record that ``arrays`` hold is a bug, not an input to skip.
    """
    for record, names in ((table.matrix, MATRIX), (table.expansion, EXPANSION)):
        if next(iter(names)) not in arrays:
            continue
        if record is None:
            raise RuntimeError(f"the point's table has no {', '.join(names)}; please report this")
        for name in names:
            arrays[name][p] = getattr(record, name)
