"""Per-panel sums of the derivatives' refinement probe (``table_derivatives``).

Each panel of the derivatives' own radius quadrature is summed on its own at
a few output angles, on each half of its fine rule (one Gauss-Legendre rule
on each half of the panel) and with its coarse rule (one on the whole
panel); :mod:`dustoptics.scattering.table_derivatives` compares the two to
find each panel's share of a derivative's error.  A split panel's halves are
its children's coarse rules (the same nodes and weights: the children are
cut at the same midpoint, :func:`_halves`), so its rows carry over.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__: list[str] = []


@dataclass(frozen=True)
class _PanelSums:
    """Sums per panel (leading axis) at the probe angles, as ``table_derivatives._Sums``."""

    ang: np.ndarray
    dang: np.ndarray
    sums: np.ndarray
    dsums: np.ndarray

    def fields(self) -> tuple[np.ndarray, ...]:
        return self.ang, self.dang, self.sums, self.dsums

    def take(self, keep: np.ndarray) -> _PanelSums:
        return _PanelSums(*(a[keep] for a in self.fields()))

    def joined(self, other: _PanelSums) -> _PanelSums:
        return _PanelSums(
            *(np.concatenate([a, b]) for a, b in zip(self.fields(), other.fields(), strict=True))
        )

    def plus(self, other: _PanelSums) -> _PanelSums:
        return _PanelSums(*(a + b for a, b in zip(self.fields(), other.fields(), strict=True)))


@dataclass(frozen=True)
class _Probe:
    """The probe rows of panels (leading axis): each half's rule (the fine
    rule is the two together) and the coarse rule.  A panel's halves are its
    children's coarse rules when it is split (the same nodes and weights),
    so a split sums only the children's halves."""

    left: _PanelSums
    right: _PanelSums
    coarse: _PanelSums
    fine: _PanelSums  # left plus right, added once per panel

    @classmethod
    def of(cls, left: _PanelSums, right: _PanelSums, coarse: _PanelSums) -> _Probe:
        return cls(left, right, coarse, left.plus(right))

    def parts(self) -> tuple[_PanelSums, ...]:
        return self.left, self.right, self.coarse, self.fine

    def take(self, keep: np.ndarray) -> _Probe:
        return _Probe(*(p.take(keep) for p in self.parts()))

    def joined(self, other: _Probe) -> _Probe:
        return _Probe(*(a.joined(b) for a, b in zip(self.parts(), other.parts(), strict=True)))


def _halves(panels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The left and right halves of panels, as the fine rule cuts them."""
    mid = 0.5 * (panels[:, 0] + panels[:, 1])
    return np.column_stack([panels[:, 0], mid]), np.column_stack([mid, panels[:, 1]])
