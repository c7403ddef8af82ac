"""Calibrate the error estimates a table states, for its values and its derivatives.

Over a seeded random set of dust models of every size-distribution family
(refractive index, distribution parameters), at 450 and 750 nm, each table at
the tolerance under test (default ``rtol`` 1e-4) is compared with a reference
computed independently at a tight tolerance (``rtol`` 1e-8 for the angular
values, 1e-10 for the cross-sections and g, tail fraction 1e-14): the
reference's own derivatives, summed on its own far finer radius nodes over a
wider radius range.  For every case (model x quantity x parameter x
wavelength) the measured error is set against the estimate the table reports:

- derivatives: ``Table.derivative_error_estimate`` (largest over angle or
  order), against the largest difference over angle or order;
- values: the phase function's and the matrix's relative estimate
  (``error_estimate``, ``matrix_error_estimate``: relative to the phase
  function at each angle), the cross-sections' (``cross_section_error_estimate``:
  relative for C_ext, C_sca, absolute for g; C_back = 4 pi C_sca P(180 deg)
  adds the phase function's ``error_estimate``), propagated to the single
  scattering albedo and the lidar ratio, and the expansion coefficients'
  (``expansion_error_estimate`` times 2 l + 1).

Reported per quantity: the cases whose estimate is above round-off (1e-11 of
the quantity's scale), the fraction of them whose error exceeds the estimate
(the error less the reference's own stated estimate, for derivatives), the
worst error / estimate, and, for derivatives that are not near zero
(|p dY/dp| >= 1e-3 |Y| over the wavelength's angles), the worst relative
error in units of rtol.

Usage::

    python scripts/calibrate_estimates.py --per-family 20          # the full set
    python scripts/calibrate_estimates.py --per-family 2 --seed 7  # a quick look
    python scripts/calibrate_estimates.py --per-family 1 --seed 3 --wavelengths 750 \
        --reference-rtol 1e-7                                       # the suite's subset

The suite runs a small seeded subset (``tests/scattering/test_calibration.py``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

import dustoptics as do
from dustoptics.particles.custom_sizedist import MultiModal
from dustoptics.particles.sizedist import (
    SIZE_DISTRIBUTIONS,
    DeirmendjianGamma,
    Gamma,
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    Monodisperse,
    PowerLaw,
)
from dustoptics.particles.sizedist_derivatives import parameter_names, parameter_value
from dustoptics.scattering.quadrature import QuadratureSettings

WAVELENGTHS_NM = (450.0, 750.0)
THETA_DEG = np.linspace(0.0, 180.0, 37)
#: Orders of the expansion coefficients compared (the table's first ones).
EXPANSION_ORDER = 16
REFERENCE_RTOL = 1e-8
REFERENCE_CROSS_RTOL = 1e-10
REFERENCE_TAIL = 1e-14
#: Below this fraction of a quantity's scale an estimate is round-off.
ROUNDOFF = 1e-11
#: A derivative is near zero where |p dY/dp| < NEAR_ZERO |Y|.
NEAR_ZERO = 1e-3

#: Families with no sampler below: a measured table and a density function have no shape
#: parameters to draw.
_NOT_SAMPLED = ("tabulated", "density_function")
#: The registry's other families (a new one needs a sampler in :func:`_distribution`), in
#: the order the seeded draws take them: the registry's, monodisperse last.
FAMILIES = tuple(
    sorted(
        (n for n in SIZE_DISTRIBUTIONS if n not in _NOT_SAMPLED), key=lambda n: n == "monodisperse"
    )
)


def _distribution(family: str, rng: np.random.Generator) -> do.SizeDistribution:
    """A random distribution of the family, of dust-like sizes (r_eff 0.15-1.6 um)."""
    u = rng.uniform
    if family == "modified_gamma":
        return ModifiedGamma(r_eff_um=u(0.2, 1.6), v_eff=u(0.05, 0.35))
    if family == "gamma":
        shape = u(3.0, 15.0)
        return Gamma(shape=shape, scale_um=u(0.1, 0.8) / shape)
    if family == "log_normal":
        return LogNormal(median_radius_um=u(0.08, 0.6), sigma=u(0.2, 0.6))
    if family == "modified_log_normal":
        return ModifiedLogNormal(r_eff_um=u(0.2, 1.6), v_eff=u(0.05, 0.35))
    if family == "deirmendjian_gamma":
        alpha, gamma, r_c = u(1.0, 6.0), u(0.6, 1.5), u(0.1, 0.6)
        return DeirmendjianGamma(alpha=alpha, b=alpha / (gamma * r_c**gamma), gamma=gamma)
    if family == "power_law":
        return PowerLaw(exponent=u(2.5, 4.5), r_min_um=u(0.05, 0.2), r_max_um=u(0.8, 2.0))
    if family == "truncated":
        r_eff = u(0.3, 1.2)
        parent = ModifiedGamma(r_eff_um=r_eff, v_eff=u(0.1, 0.3))
        return parent.truncated(r_min_um=u(0.1, 0.4) * r_eff, r_max_um=u(1.2, 2.0) * r_eff)
    if family == "multimodal":
        fine = ModifiedLogNormal(r_eff_um=u(0.08, 0.2), v_eff=u(0.1, 0.3))
        coarse = ModifiedLogNormal(r_eff_um=u(0.6, 1.5), v_eff=u(0.1, 0.35))
        return MultiModal(modes=(fine, coarse), relative_number_densities=(u(10.0, 300.0), 1.0))
    if family == "monodisperse":
        return Monodisperse(radius_um=u(0.1, 1.6))
    raise ValueError(f"family must be one of {FAMILIES}; got {family!r}")


@dataclass(frozen=True)
class Model:
    family: str
    m: complex
    distribution: do.SizeDistribution

    @property
    def parameters(self) -> tuple[str, ...]:
        own = (
            ("radius_um",)
            if self.distribution.is_monodisperse
            else parameter_names(self.distribution)
        )
        return (*own, "n", "k")

    def value(self, p: str) -> float:
        if p == "n":
            return self.m.real
        if p == "k":
            return self.m.imag
        if p == "radius_um":
            return float(self.distribution.mean_radius_um)
        return abs(parameter_value(self.distribution, p))


def models(*, seed: int, per_family: int, families: Sequence[str] = FAMILIES) -> list[Model]:
    """``per_family`` random models of each family, reproducible from ``seed``.

    The models of a family do not depend on ``families``: all are drawn, in
    the order of :data:`FAMILIES`, and those of ``families`` kept (a subset
    run checks the same models as the full set)."""
    unknown = sorted(set(families) - set(FAMILIES))
    if unknown:
        raise ValueError(f"families must be among {FAMILIES}; got {unknown}")
    rng = np.random.default_rng(seed)
    out = []
    for family in FAMILIES:
        for _ in range(per_family):
            m = complex(rng.uniform(1.35, 1.7), 10.0 ** rng.uniform(-4.0, -1.5))
            model = Model(family, m, _distribution(family, rng))
            if family in families:
                out.append(model)
    return out


def _table(
    model: Model,
    *,
    rtol: float,
    reference: bool,
    wavelengths_nm: Sequence[float] = WAVELENGTHS_NM,
    reference_rtol: float = REFERENCE_RTOL,
) -> do.Table:
    kw: dict[str, Any] = {}
    if reference:
        kw = {
            "cross_section_rtol": reference_rtol * REFERENCE_CROSS_RTOL / REFERENCE_RTOL,
            "quadrature": QuadratureSettings(tail_fraction=REFERENCE_TAIL, max_level=14),
        }
    return do.compute_optics(
        model.m,
        model.distribution,
        list(wavelengths_nm),
        THETA_DEG,
        rtol=reference_rtol if reference else rtol,
        polarization=True,
        expansion=EXPANSION_ORDER,
        derivatives=model.parameters,
        workers=1,
        **kw,
    )


@dataclass
class Case:
    kind: str  # "value" or "derivative"
    family: str
    quantity: str
    parameter: str
    wavelength_nm: float
    error: float
    estimate: float
    scale: float
    relative_error: float = math.nan  # |error| / |derivative|, where not near zero
    reference_estimate: float = 0.0  # the reference's own stated error
    model: str = ""  # the model's index among the run's and its parameters

    @property
    def ratio(self) -> float:
        """The error (less the reference's own estimate) over the estimate."""
        if self.estimate <= ROUNDOFF * self.scale:
            return math.nan
        return max(self.error - self.reference_estimate, 0.0) / self.estimate


ANGULAR = ("phase", "f12", "f33", "f34")
EXPANSION = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")
DERIVATIVE_QUANTITIES = (
    *ANGULAR,
    *EXPANSION,
    "g",
    "cext_um2",
    "csca_um2",
    "cback_um2",
    "ssa",
    "cabs_um2",
    "lidar_ratio_sr",
)


def derivative_cases(model: Model, table: do.Table, ref: do.Table) -> Iterator[Case]:
    """Each derivative's error against the reference's, with its estimate."""
    for q in table.derivative_quantities:
        if q not in DERIVATIVE_QUANTITIES:
            continue
        values = np.asarray(table.quantity(q))
        for p in model.parameters:
            d = table.derivative(q, p)
            d_ref = ref.derivative(q, p)
            est = table.derivative_error_estimate(q, p)
            est_ref = ref.derivative_error_estimate(q, p)
            for i, wl in enumerate(table.wavelength_nm):
                di, ri = np.atleast_1d(d[i]), np.atleast_1d(d_ref[i])
                if q in EXPANSION:
                    n = min(di.size, ri.size)
                    di, ri = di[:n], ri[:n]
                err = float(np.max(np.abs(di - ri)))
                scale = float(np.max(np.abs(ri)))
                y = float(np.max(np.abs(np.atleast_1d(values[i])))) if values.ndim else 0.0
                near_zero = model.value(p) * scale < NEAR_ZERO * y
                yield Case(
                    "derivative",
                    model.family,
                    q,
                    p,
                    float(wl),
                    err,
                    float(est[i]),
                    scale,
                    math.nan if near_zero or scale == 0.0 else err / scale,
                    float(est_ref[i]),
                )


def value_cases(model: Model, table: do.Table, ref: do.Table) -> Iterator[Case]:
    """Each value's error against the reference, with the estimate the table states."""
    rq, rc = table.quadrature, table.cross_sections
    assert rq is not None and rc is not None and table.matrix is not None
    rel_phase = np.asarray(rq.error_estimate)
    rel_matrix = np.maximum(rel_phase, np.asarray(table.matrix.matrix_error_estimate))
    rel_cross = np.asarray(rq.cross_section_error_estimate)
    phase, phase_ref = table.phase, ref.phase
    for i, wl in enumerate(table.wavelength_nm):
        wl = float(wl)
        # Angular values: relative to the phase function at each angle.
        for q, rel in (("phase", rel_phase), ("f12", rel_matrix), ("f33", rel_matrix)):
            a, b = np.asarray(table.quantity(q))[i], np.asarray(ref.quantity(q))[i]
            ratio = np.abs(a - b) / (rel[i] * phase_ref[i])
            j = int(np.argmax(ratio))
            yield Case(
                "value", model.family, q, "", wl, abs(a[j] - b[j]), rel[i] * phase[i, j], 1.0
            )
        for q in ("cext_um2", "csca_um2", "cback_um2"):
            a, b = float(table.quantity(q)[i]), float(ref.quantity(q)[i])
            # <C_back> = 4 pi <C_sca> P(180 deg): the phase function's error adds.
            rel = rel_cross[i] + (rel_phase[i] if q == "cback_um2" else 0.0)
            yield Case("value", model.family, q, "", wl, abs(a - b), rel * abs(a), abs(b))
        g, g_ref = float(table.g[i]), float(ref.g[i])
        yield Case("value", model.family, "g", "", wl, abs(g - g_ref), float(rel_cross[i]), 1.0)
        ssa, ssa_ref = float(table.ssa[i]), float(ref.ssa[i])
        yield Case(
            "value", model.family, "ssa", "", wl, abs(ssa - ssa_ref), 2 * rel_cross[i] * ssa, 1.0
        )
        lr, lr_ref = float(table.lidar_ratio_sr[i]), float(ref.lidar_ratio_sr[i])
        yield Case(
            "value",
            model.family,
            "lidar_ratio_sr",
            "",
            wl,
            abs(lr - lr_ref),
            (2 * rel_cross[i] + rel_phase[i]) * lr,
            abs(lr_ref),
        )
        if table.expansion is not None and ref.expansion is not None:
            e = table.expansion.expansion_error_estimate
            assert e is not None
            orders = 2.0 * np.arange(EXPANSION_ORDER + 1) + 1.0
            for q in EXPANSION:
                a = np.asarray(getattr(table.expansion, q))[i, : orders.size]
                b = np.asarray(getattr(ref.expansion, q))[i, : orders.size]
                ratio = np.abs(a - b) / (e[i] * orders)
                j = int(np.argmax(ratio))
                yield Case(
                    "value", model.family, q, "", wl, abs(a[j] - b[j]), e[i] * orders[j], 1.0
                )


@dataclass
class Summary:
    kind: str
    quantity: str
    cases: int = 0
    decisive: int = 0  # estimate above round-off
    over: int = 0
    worst_ratio: float = 0.0
    worst_case: str = ""
    worst_relative: float = 0.0
    worst_relative_case: str = ""
    by_family: dict[str, int] = field(default_factory=dict)


def summarize(cases: Sequence[Case], *, rtol: float) -> dict[tuple[str, str], Summary]:
    """Per (kind, quantity): counts over estimate, worst ratio, worst relative error / rtol."""
    out: dict[tuple[str, str], Summary] = {}
    for c in cases:
        s = out.setdefault((c.kind, c.quantity), Summary(c.kind, c.quantity))
        s.cases += 1
        floor = ROUNDOFF * c.scale
        label = f"{c.family} {c.parameter} {c.wavelength_nm:g} nm"
        if math.isfinite(c.relative_error) and c.relative_error / rtol > s.worst_relative:
            s.worst_relative = c.relative_error / rtol
            s.worst_relative_case = label
        if c.estimate <= floor:
            continue
        s.decisive += 1
        # The error measured against the reference holds the reference's own.
        ratio = max(c.error - c.reference_estimate, 0.0) / c.estimate
        if ratio > 1.0 and c.error > floor:
            s.over += 1
            s.by_family[c.family] = s.by_family.get(c.family, 0) + 1
        if ratio > s.worst_ratio:
            s.worst_ratio = ratio
            s.worst_case = label
    return out


def totals(summaries: dict[tuple[str, str], Summary], kind: str) -> tuple[int, int, float, float]:
    """Decisive cases, those over estimate, worst ratio, worst relative error / rtol of a kind."""
    rows = [s for (k, _), s in summaries.items() if k == kind]
    return (
        sum(s.decisive for s in rows),
        sum(s.over for s in rows),
        max((s.worst_ratio for s in rows), default=0.0),
        max((s.worst_relative for s in rows), default=0.0),
    )


def run(
    *,
    seed: int,
    per_family: int,
    rtol: float,
    families: Sequence[str] = FAMILIES,
    wavelengths_nm: Sequence[float] = WAVELENGTHS_NM,
    reference_rtol: float = REFERENCE_RTOL,
) -> list[Case]:
    """Every case of the seeded models."""
    cases: list[Case] = []
    kw = {"wavelengths_nm": wavelengths_nm, "reference_rtol": reference_rtol}
    for i, model in enumerate(models(seed=seed, per_family=per_family, families=families)):
        table = _table(model, rtol=rtol, reference=False, **kw)
        ref = _table(model, rtol=rtol, reference=True, **kw)
        label = f"#{i} m={model.m:.5g} {model.distribution!r}"
        for c in (*derivative_cases(model, table, ref), *value_cases(model, table, ref)):
            c.model = label
            cases.append(c)
    return cases


def worst(cases: Sequence[Case], n: int, *, rtol: float) -> str:
    """The ``n`` cases of largest error / estimate and of largest relative error."""
    lines = [f"the {n} largest error / estimate:"]
    by_ratio = sorted((c for c in cases if c.ratio > 0), key=lambda c: -c.ratio)
    for c in by_ratio[:n]:
        lines.append(
            f"  {c.ratio:7.3g}  {c.kind} {c.quantity} {c.parameter} {c.wavelength_nm:g} nm "
            f"err {c.error:.3g} est {c.estimate:.3g} ref est {c.reference_estimate:.3g}  {c.model}"
        )
    lines.append(f"the {n} largest relative derivative errors / rtol:")
    by_rel = sorted(
        (c for c in cases if math.isfinite(c.relative_error)), key=lambda c: -c.relative_error
    )
    for c in by_rel[:n]:
        lines.append(
            f"  {c.relative_error / rtol:7.3g}  {c.quantity} {c.parameter} {c.wavelength_nm:g} nm "
            f"err {c.error:.3g} est {c.estimate:.3g} |d| {c.scale:.3g}  {c.model}"
        )
    return "\n".join(lines)


def report(summaries: dict[tuple[str, str], Summary], *, rtol: float) -> str:
    lines = [
        f"{'kind':10} {'quantity':16} {'cases':>6} {'decisive':>8} {'over':>5} "
        f"{'worst err/est':>13} {'worst rel/rtol':>14}  worst case (ratio; rel)"
    ]
    for (kind, q), s in sorted(summaries.items()):
        rel = f"{s.worst_relative:14.3g}" if kind == "derivative" else f"{'':14}"
        lines.append(
            f"{kind:10} {q:16} {s.cases:6d} {s.decisive:8d} {s.over:5d} {s.worst_ratio:13.3g} "
            f"{rel}  {s.worst_case}; {s.worst_relative_case if kind == 'derivative' else ''}"
        )
    for kind in ("value", "derivative"):
        n, over, worst, rel = totals(summaries, kind)
        frac = over / n if n else 0.0
        lines.append(
            f"{kind}s: {over} of {n} decisive cases over their estimate ({100 * frac:.2f} %), "
            f"worst error/estimate {worst:.3g}"
            + (f", worst relative error {rel:.3g} x rtol={rtol:g}" if kind == "derivative" else "")
        )
    return "\n".join(lines)


def main(args: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-family", type=int, default=20, help="models per family")
    parser.add_argument("--seed", type=int, default=20261206)
    parser.add_argument("--rtol", type=float, default=1e-4, help="the tolerance under test")
    parser.add_argument("--families", nargs="*", default=list(FAMILIES), choices=FAMILIES)
    parser.add_argument(
        "--wavelengths", nargs="*", type=float, default=list(WAVELENGTHS_NM), help="[nm]"
    )
    parser.add_argument("--reference-rtol", type=float, default=REFERENCE_RTOL)
    parser.add_argument(
        "--worst", type=int, default=0, help="also list this many worst cases, with their models"
    )
    opts = parser.parse_args(args)
    start = time.perf_counter()
    cases = run(
        seed=opts.seed,
        per_family=opts.per_family,
        rtol=opts.rtol,
        families=opts.families,
        wavelengths_nm=opts.wavelengths,
        reference_rtol=opts.reference_rtol,
    )
    print(report(summarize(cases, rtol=opts.rtol), rtol=opts.rtol))
    if opts.worst:
        print(worst(cases, opts.worst, rtol=opts.rtol))
    print(
        f"{opts.per_family} models per family, seed {opts.seed}, rtol {opts.rtol:g}, "
        f"{len(cases)} cases in {time.perf_counter() - start:.0f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
