"""A Sphinx directive that writes the error table of the shipped dust phase fit by size.

``.. dustoptics-dust-phase-fit::`` reads ``dustoptics/models/data/fits/dust_phase_fit.json``
(:func:`dustoptics.models.dust_phase_fit.load_dust_phase_fit`) and writes, per preset, radius
and channel, the closed form's error against Mie, so the page shows the numbers the package
ships, regenerated with them by ``scripts/dust_phase_fit.py``.
"""

from __future__ import annotations

import math
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective

from dustoptics.models.dust_phase_fit import DUST_FIT_PRESETS, load_dust_phase_fit


def error_table_rst() -> list[str]:
    """The error tables as reStructuredText list-tables, one per preset."""
    lines: list[str] = []
    for preset in DUST_FIT_PRESETS:
        fit = load_dust_phase_fit(preset)
        low, high = fit.r_eff_range_um
        lines += [
            f".. list-table:: {preset} (v_eff {fit.v_eff:g}, r_eff {low:g} .. {high:g} um): "
            "RMS / max relative error [%] of the closed form (alone: that radius fitted on its own)",
            "   :header-rows: 1",
            "",
            "   * - r_eff [um]",
            "     - radius",
            *[f"     - {c} rms / max (alone)" for c in fit.channels],
        ]
        rows: dict[float, list[str]] = {}
        kinds: dict[float, str] = {}
        for r, fitted, _channel, rms, worst, alone in fit.error_table():
            alone_text = "" if math.isnan(alone) else f" ({100 * alone:.1f})"
            rows.setdefault(r, []).append(f"{100 * rms:.1f} / {100 * worst:.0f}{alone_text}")
            kinds[r] = "fitted" if fitted else "held out"
        for r, cells in rows.items():
            lines += [f"   * - {r:.3f}", f"     - {kinds[r]}", *[f"     - {c}" for c in cells]]
        lines.append("")
    return lines


class DustPhaseFitTable(SphinxDirective):
    """``.. dustoptics-dust-phase-fit::``: the shipped fit's error tables."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        container = nodes.container()
        lines = StringList(error_table_rst(), source="dustoptics.models.dust_phase_fit")
        self.state.nested_parse(lines, self.content_offset, container)
        return list(container.children)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("dustoptics-dust-phase-fit", DustPhaseFitTable)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
