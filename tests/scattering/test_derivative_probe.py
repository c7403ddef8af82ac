"""The derivatives' refinement probe: its batched kernel, its reuse of a split
panel's rows, and the final sums that skip the coarse rule where it cannot matter.

Sources: the batched kernel is checked against one call per group of the
kernel it batches (the same arithmetic: bit for bit); a child's coarse rule
against its parent's half of the fine rule (the same Gauss nodes and weights:
bit for bit); the final sums against the same table with both rules on every
panel (the difference is bounded by the derivatives' stated estimate).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import dustoptics as do
from dustoptics.particles.sizedist import ModifiedGamma
from dustoptics.scattering import mie, table_derivatives
from dustoptics.scattering.mie_derivatives import _series_lengths
from dustoptics.scattering.mie_derivatives_blocked import (
    _accumulate_blocked,
    _accumulate_groups,
)
from dustoptics.scattering.quadrature import QuadratureSettings

M = 1.52 + 0.004j
MU = np.cos(np.deg2rad(np.linspace(0.0, 180.0, 24)))


def _read_only(a: np.ndarray) -> np.ndarray:
    v = np.array(a, dtype=np.float64, order="C")
    v.flags.writeable = False
    return v


@pytest.mark.parametrize("per_particle", [False, True])
def test_batched_groups_equal_one_call_per_group_bit_for_bit(per_particle: bool) -> None:
    rng = np.random.default_rng(40)
    sizes = [16, 0, 5, 33, 16, 1]  # whole lanes, an empty group, ragged ones
    x = np.concatenate([np.sort(rng.uniform(0.05, 60.0, n)) for n in sizes])
    weights = rng.uniform(0.1, 2.0, (x.size, 3))
    starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    table = mie.angular_table(_read_only(MU), int(_series_lengths(x).max()))
    got = _accumulate_groups(M, x, weights, starts, table, MU.size, 4, per_particle, True)
    for g in range(len(sizes)):
        a, b = starts[g], starts[g + 1]
        one = _accumulate_blocked(
            M,
            np.ascontiguousarray(x[a:b]),
            np.ascontiguousarray(weights[a:b]),
            table,
            MU.size,
            False,
            4,
            per_particle,
            True,
        )
        for k in range(4):
            assert np.array_equal(got[k][g], one[k]), (g, k)
    assert not np.any(got[0][1])  # the empty group sums to zero


def _at() -> table_derivatives._At:
    return table_derivatives._At(
        m=M,
        wavelength_nm=550.0,
        distribution=ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        settings=QuadratureSettings(),
        mu_out=MU,
        index_directions=[1.0 + 0j, 1j],
        dist_parameters=["r_eff_um", "v_eff"],
        per_particle=False,
        n_q=1,
        n_order=0,
        angular_keys=("phase",),
    )


def test_a_split_panels_halves_are_its_childrens_coarse_rules_bit_for_bit() -> None:
    at = _at()
    panels = np.array([[-2.5, -1.0], [-1.0, 7.0], [7.0, 40.0], [40.0, 41.5]])
    left, right = table_derivatives._halves(panels)
    x_fine, w_fine = at.rule(panels, halves=True)
    x_kids, w_kids = at.rule(np.concatenate([left, right]), halves=False)
    assert np.array_equal(x_fine, x_kids) and np.array_equal(w_fine, w_kids)
    # And so the probe's rows: the children's coarse rows are the parents' halves.
    table = table_derivatives._probe_table(at, panels, MU)
    parent = table_derivatives._panel_probe(at, panels, MU, table)
    kids = table_derivatives._panel_probe(at, np.concatenate([left, right]), MU, table)
    for a, b in zip(kids.coarse.fields(), parent.left.joined(parent.right).fields(), strict=True):
        assert np.array_equal(a, b)


def test_final_sums_without_negligible_coarse_rules_within_the_estimate(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    names = ("r_eff_um", "v_eff", "n", "k")

    def table() -> do.Table:
        return do.compute_optics(
            1.5 + 0.003j,
            ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
            [450.0, 750.0],
            np.linspace(0.0, 180.0, 37),
            workers=1,
            derivatives=names,
        )

    fast = table()
    monkeypatch.setattr(table_derivatives, "NEGLIGIBLE", -math.inf)  # both rules everywhere
    full = table()
    skipped = 0
    for q in fast.derivative_quantities:
        for p in names:
            a, b = np.asarray(fast.derivative(q, p)), np.asarray(full.derivative(q, p))
            diff = np.abs(a - b).reshape(a.shape[0], -1).max(axis=1)
            est = np.asarray(fast.derivative_error_estimate(q, p))
            assert np.all(diff <= est), (q, p, diff, est)
            skipped += int(np.any(diff > 0))
    assert skipped  # the restriction changed something that the estimate bounds
