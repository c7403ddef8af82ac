"""Sweeps over dust models: one labelled dataset over any numeric inputs, on Dask.

:func:`sweep` computes a configuration (:mod:`dustoptics.models.config`)
over axes of its inputs (:mod:`dustoptics.sweep.spec`), sharing the Mie work
of points that differ only in their size distribution
(:mod:`dustoptics.sweep.shared`), each chunk one task (:mod:`dustoptics.sweep.chunk`),
on a Dask cluster, stored chunk by chunk in
a resumable Zarr store (:mod:`dustoptics.sweep.run`) that one run writes at a
time and whose chunks carry their digests (:mod:`dustoptics.sweep.store`,
:func:`verify_store`); :func:`point_table` reads a point back as a table;
:mod:`dustoptics.sweep.lookup`
turns a sweep over effective radius into a 3-D texture for renderers.  Needs
the ``sweep`` extra (dask[distributed], xarray, zarr).
"""

from dustoptics.sweep.chunk import compute_chunk
from dustoptics.sweep.lookup import write_lookup
from dustoptics.sweep.points import point_table
from dustoptics.sweep.run import local_cluster, sweep
from dustoptics.sweep.spec import Axis, SweepSpec, load_sweep
from dustoptics.sweep.store import verify_store

__all__ = [
    "Axis",
    "SweepSpec",
    "compute_chunk",
    "load_sweep",
    "local_cluster",
    "point_table",
    "sweep",
    "verify_store",
    "write_lookup",
]
