"""The solve and assemble steps of :func:`~dustoptics.scattering.optics.compute_optics`.

An :class:`~dustoptics.scattering.optics.OpticsRequest` (validated once, its
cost checked) is solved wavelength by wavelength (:func:`solve_wavelengths`:
the threads and the progress reports; each wavelength refined on its own by
:mod:`dustoptics.scattering.refinement`, so the result does not depend on
the thread count), and the wavelengths' results are assembled into a
:class:`~dustoptics.table.Table` (:func:`assemble_table`: the checks that the
numbers are physical, the warning where a tolerance was not reached, the
provenance).  The table's fields are built in one place (``_table``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

import numpy as np

from dustoptics.scattering.domain import domain_record
from dustoptics.scattering.quadrature import QuadratureDiagnostics
from dustoptics.scattering.refinement import _Result, _WavelengthSolver, kernels_loaded
from dustoptics.table import (
    CrossSections,
    Provenance,
    QuadratureRecord,
    Table,
    grouped_fields,
    plain,
)

if TYPE_CHECKING:  # the front door's module imports this one
    from dustoptics.scattering.optics import OpticsRequest, RequestCost

__all__ = ["ConvergenceWarning", "assemble_table", "request_indices", "solve_wavelengths"]


class ConvergenceWarning(UserWarning):
    """The radius quadrature reached its panel limit before the tolerance."""


# ---------------------------------------------------------------------- solve


def request_indices(request: OpticsRequest) -> np.ndarray:
    """Every refractive index the request's spheres use: the shell's (or the
    homogeneous sphere's) and, for a coated sphere, the core's. [-]"""
    if request.core_fraction > 0.0:
        return np.concatenate([request.m, request.m_core])
    return np.asarray(request.m)


def solve_wavelengths(
    request: OpticsRequest, *, workers: int, progress: Callable[[int, int], None] | None
) -> list[_Result]:
    """Every wavelength's converged result, in wavelength order.

    Each wavelength is computed by one thread, whatever the count, so the
    results are the same to the bit; ``progress(done, total)`` is called
    with 0 first and ``total`` last.
    """
    wl = request.wavelength_nm
    mu_out = request.mu_out

    def one(i: int) -> _Result:
        solver = _WavelengthSolver(
            m=complex(request.m[i]),
            wavelength_nm=float(wl[i]),
            mu_out=mu_out,
            distribution=request.distribution,
            per_particle=request.per_particle,
            settings=request.quadrature,
            n_stokes=request.n_stokes,
            expansion=request.expansion_order is not None,
            m_core=complex(request.m_core[i]),
            core_fraction=request.core_fraction,
        )
        return solver.solve(*_quadrature_tolerances(request))

    def report(done: int) -> None:
        if progress is not None:
            progress(done, wl.size)

    report(0)
    results: list[_Result] = []
    n_threads = min(workers, wl.size)
    if n_threads > 1:
        # In a process that has not computed a table yet, the first wavelength
        # alone compiles (or loads from numba's cache) the kernels before
        # threads share them; after that, it is the costliest wavelength to
        # leave to one thread.  Each wavelength's result is the same either way.
        if not kernels_loaded():
            results.append(one(0))
            report(1)
        with ThreadPoolExecutor(max_workers=n_threads) as pool:
            for result in pool.map(one, range(len(results), wl.size)):
                results.append(result)
                report(len(results))
    else:
        for i in range(wl.size):
            results.append(one(i))
            report(i + 1)
    return results


# ---------------------------------------------------------------------- assemble


def assemble_table(
    request: OpticsRequest, results: Sequence[_Result], *, cost: RequestCost, name: str
) -> Table:
    """The table of the wavelengths' results: checked, warned about, with its provenance."""
    cext, csca = _checked_cross_sections(request, results, cost)
    extra = _matrix_fields(
        results, polarization=request.polarization, n_order=request.expansion_order
    )
    err_phase = np.array([r.err_phase for r in results])
    if request.polarization:
        err_phase = np.maximum(err_phase, extra["matrix_error_estimate"])
    not_converged = _warn_not_converged(request, results, err_phase, extra)
    # The stated estimate also holds the truncated tails' share (the refinement's
    # tolerance is for the quadrature, which cannot see them).
    tail = _tail_error(request)
    err_phase = err_phase + tail
    extra = {
        k: v + tail if k in ("matrix_error_estimate", "expansion_error_estimate") else v
        for k, v in extra.items()
    }
    record = _quadrature_record(request, results, err_phase, extra, converged=not not_converged)
    record["domain"] = domain_record(
        m=request_indices(request),
        min_size_parameter=cost.min_size_parameter,
        max_size_parameter=cost.max_size_parameter,
    )
    return _table(
        request,
        results,
        name=name,
        cext=cext,
        csca=csca,
        err_phase=err_phase,
        extra=extra,
        record=record,
    )


def _checked_cross_sections(
    request: OpticsRequest, results: Sequence[_Result], cost: RequestCost
) -> tuple[np.ndarray, np.ndarray]:
    """<C_ext>, <C_sca> per wavelength [um^2], refused where not physical."""
    wl, m, m_core = request.wavelength_nm, request.m, request.m_core
    phase = np.vstack([r.phase for r in results])
    cext = np.array([r.cext for r in results])
    csca = np.array([r.csca for r in results])
    finite = np.all(np.isfinite(phase)) and np.all(np.isfinite(cext)) and np.all(np.isfinite(csca))
    if not (finite and np.all(phase > 0) and np.all(csca > 0)):
        raise ValueError(
            f"compute_optics: refractive_index {request.index_label} with distribution "
            f"{request.distribution!r} at {wl[0]:g} .. {wl[-1]:g} nm gives a phase function or "
            "cross-section that is not finite and positive: the input lies outside the kernel's "
            f"tested domain (size parameters {cost.min_size_parameter:.3g} .. "
            f"{cost.max_size_parameter:.3g})"
        )
    # Absorption: <C_abs> = <C_ext> - <C_sca> >= 0.  With k = 0 it is exactly 0
    # (no absorption, an identity of the physics); with k > 0 the difference
    # is kept unless it is negative beyond round-off (1e-12 of <C_ext>), which
    # would be a wrong number and raises.
    # (A coated sphere absorbs if its shell or its core does.)
    lossless = (m.imag == 0.0) & ((m_core.imag == 0.0) | (request.core_fraction == 0.0))
    cabs = np.where(lossless, 0.0, cext - csca)
    cext = np.where(lossless, csca, cext)
    if np.any(cabs < -1e-12 * cext):
        i = int(np.argmax(cabs < -1e-12 * cext))
        raise ValueError(
            f"compute_optics: <C_abs> = {cabs[i]!r} um^2 < 0 at {wl[i]:g} nm for refractive_index "
            f"{request.index_label} with distribution {request.distribution!r}: the input lies "
            "outside the kernel's tested domain"
        )
    return cext, np.minimum(csca, cext)


def _warn_not_converged(
    request: OpticsRequest,
    results: Sequence[_Result],
    err_phase: np.ndarray,
    extra: Mapping[str, Any],
) -> bool:
    """Warn (at the caller of the public entry) where a tolerance was not reached;
    True if one was not."""
    err_cross = np.array([r.err_cross for r in results])
    expansion_rtol = request.expansion_rtol
    not_converged = (err_phase > request.rtol) | (err_cross > request.cross_section_rtol)
    if expansion_rtol is not None:
        not_converged |= extra["expansion_error_estimate"] > expansion_rtol
    if not not_converged.any():
        return False
    bad = ", ".join(f"{w:g}" for w in request.wavelength_nm[not_converged])
    also = "" if expansion_rtol is None else f" / expansion rtol={expansion_rtol:g}"
    warnings.warn(
        f"radius quadrature did not reach rtol={request.rtol:g} / "
        f"cross_section_rtol={request.cross_section_rtol:g}{also} at wavelengths {bad} nm "
        f"within max_level={request.quadrature.max_level}; see error_estimate",
        ConvergenceWarning,
        # _warn_not_converged <- assemble_table <- optics._run <- compute_optics <- the caller
        stacklevel=5,
    )
    return True


#: The error from the truncated tails, in units of the tail fraction: each tail
#: holds at most that fraction of the moment that normalizes the average below
#: r_lo and of the fourth above r_hi (which bounds the phase function's forward
#: peak and the area), and the efficiencies of the left-out spheres are at
#: most about twice the mean's: 2 tails x 2.
TAIL_ERROR_FACTOR = 4.0


def _quadrature_tolerances(request: OpticsRequest) -> tuple[float, float, float | None]:
    """The refinement's tolerances (phase, cross-sections, expansion): each of the
    request's less the tails' share (:func:`_tail_error`), so that the stated
    estimates, which add it, meet the request; at least half of the request's
    (a tail fraction too large for it leaves the stated estimate above it)."""
    tail = _tail_error(request)

    def less(tol: float) -> float:
        return max(tol - tail, 0.5 * tol)

    expansion = request.expansion_rtol
    return (
        less(request.rtol),
        less(request.cross_section_rtol),
        None if expansion is None else less(expansion),
    )


def _tail_error(request: OpticsRequest) -> float:
    """The truncated tails' share of a stated relative error:
    :data:`TAIL_ERROR_FACTOR` times the tail fraction (none for one sphere). [-]"""
    if request.distribution.is_monodisperse:
        return 0.0
    return TAIL_ERROR_FACTOR * request.quadrature.tail_fraction


def _cross_section_estimates(request: OpticsRequest, results: Sequence[_Result]) -> np.ndarray:
    """The cross-sections' stated error per wavelength: the quadrature's estimate
    (relative for <C_ext>, <C_sca>, absolute for g) plus the tails' (:func:`_tail_error`)."""
    return np.array([r.err_cross for r in results]) + _tail_error(request)


def _quadrature_record(
    request: OpticsRequest,
    results: Sequence[_Result],
    err_phase: np.ndarray,
    extra: Mapping[str, Any],
    *,
    converged: bool,
) -> dict[str, Any]:
    """The provenance's quadrature record: method, tolerances, achieved errors, nodes."""
    record = {
        "method": "adaptive Gauss-Legendre panels over radius (dustoptics.scattering.quadrature), "
        "error = summed differences of each panel's rule and the rules on its halves",
        "weighting": request.weighting,
        "rtol": request.rtol,
        "cross_section_rtol": request.cross_section_rtol,
        "settings": request.quadrature,
        "converged": converged,
        "max_error_estimate": float(err_phase.max()),
        "max_cross_section_error_estimate": float(_cross_section_estimates(request, results).max()),
        "n_nodes_total": int(np.array([r.n_nodes for r in results], dtype=np.int64).sum()),
        "cross_section_n_nodes_total": int(
            np.array([r.cross_section_n_nodes for r in results], dtype=np.int64).sum()
        ),
    }
    if request.expansion_rtol is not None:  # recorded only when used (other provenance unchanged)
        record["expansion_rtol"] = request.expansion_rtol
        record["max_expansion_error_estimate"] = float(extra["expansion_error_estimate"].max())
    return record


def _table(
    request: OpticsRequest,
    results: Sequence[_Result],
    *,
    name: str,
    cext: np.ndarray,
    csca: np.ndarray,
    err_phase: np.ndarray,
    extra: Mapping[str, Any],
    record: Mapping[str, Any],
) -> Table:
    """The one place a computed table is built from its request and results."""
    distribution = request.distribution
    moments = np.array([r.moments for r in results])
    records = grouped_fields(extra)  # the matrix and the expansion, where computed
    return Table(
        name=name,
        wavelength_nm=request.wavelength_nm,
        theta_deg=request.theta_deg,
        phase=np.vstack([r.phase for r in results]),
        g=np.array([r.g for r in results]),
        refractive_index=request.m,
        cross_sections=CrossSections(
            cext_um2=cext,
            csca_um2=csca,
            cback_um2=np.array([r.cback for r in results]),
            mean_geometric_cross_section_um2=float(distribution.mean_cross_section_um2),
            mean_volume_um3=float(distribution.mean_volume_um3),
            particle_density_kg_m3=request.particle_density_kg_m3,
        ),
        quadrature=QuadratureRecord(
            error_estimate=err_phase,
            cross_section_error_estimate=_cross_section_estimates(request, results),
            n_nodes=np.array([r.n_nodes for r in results], dtype=np.int64),
            cross_section_n_nodes=np.array(
                [r.cross_section_n_nodes for r in results], dtype=np.int64
            ),
            r_eff_quadrature_um=moments[:, 1] / moments[:, 0],
            v_eff_quadrature=moments[:, 2] * moments[:, 0] / moments[:, 1] ** 2 - 1.0,
            mean_volume_quadrature_um3=4.0 / 3.0 * np.pi * moments[:, 1],
        ),
        matrix=records.get("matrix"),
        expansion=records.get("expansion"),
        provenance=Provenance(
            inputs=plain(request.inputs()),
            sources=request.sources(),
            quadrature=plain(dict(record)),
        ),
        diagnostics=QuadratureDiagnostics(
            settings=request.quadrature,
            distribution=distribution,
            panels=tuple(r.panels_s for r in results),
            cross_section_panels=tuple(r.cross_section_panels_s for r in results),
            expansion_panels=(
                None
                if request.expansion_rtol is None
                else tuple(
                    r.panels_s if r.expansion_panels_s is None else r.expansion_panels_s
                    for r in results
                )
            ),
        ),
    )


def _matrix_fields(
    results: Sequence[_Result], *, polarization: bool, n_order: int | None
) -> dict[str, Any]:
    """The optional matrix and expansion fields of a table from the
    wavelengths' results (coefficients zero-padded to one order count)."""
    out: dict[str, Any] = {}
    if not (polarization or n_order is not None):
        return out
    matrices = [r.matrix for r in results if r.matrix is not None]
    assert len(matrices) == len(results)
    if polarization:
        for key in ("f12", "f33", "f34"):
            out[key] = np.vstack([getattr(mx, key) for mx in matrices])
        out["matrix_error_estimate"] = np.array([mx.error for mx in matrices])
    if n_order is not None:
        greek = [mx.greek for mx in matrices if mx.greek is not None]
        assert len(greek) == len(results)
        size = max(g.shape[1] for g in greek) if n_order < 0 else n_order + 1
        coefficients = np.zeros((6, len(results), size))
        for i, g in enumerate(greek):
            k = min(size, g.shape[1])
            coefficients[:, i, :k] = g[:, :k]
        for j, key in enumerate(("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")):
            out[key] = coefficients[j]
        out["expansion_error_estimate"] = np.array([mx.greek_error for mx in matrices])
    return out
