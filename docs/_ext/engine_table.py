"""Sphinx directives for the engines' page: the engines and the error table.

``.. dustoptics-engines::`` lists :data:`dustoptics.sky.engines.ENGINES` (engine, format name,
source read); ``.. dustoptics-engine-errors::`` prints the table the package ships
(:func:`dustoptics.sky.engines.report.shipped_report`, computed by ``dustoptics engines
report``) and the rows where the fitted parameters do not beat the community's.  Nothing is
computed at build time: the fits take minutes.
"""

from __future__ import annotations

from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective

from dustoptics.sky.engines import ENGINES
from dustoptics.sky.engines.report import shipped_report


def _engines_rst() -> list[str]:
    lines = [
        ".. list-table::",
        "   :header-rows: 1",
        "",
        "   * - engine",
        "     - ``--format``",
        "     - fitted parameters",
        "     - model read from",
    ]
    for name, engine in ENGINES.items():
        lines += [
            f"   * - {engine.title}",
            f"     - ``{name}``",
            "     - " + ", ".join(f"``{p.name}``" for p in engine.parameters),
            f"     - {engine.source}",
        ]
    return lines


def _errors_rst() -> list[str]:
    report = shipped_report()
    lines = report.table_rst().splitlines()
    rows = report.row_losses()
    lines += [
        "",
        "Engines and planets where the fitted parameters do not beat the community's",
        "(Delta E 2000 over the dome, averaged over the Sun elevations):",
        "",
    ]
    lines += [f"- {line}" for line in rows] if rows else ["- none"]
    losses = report.losses()
    lines += ["", "Single Sun elevations where they do not (mean or 95th percentile):", ""]
    lines += [f"- {line}" for line in losses] if losses else ["- none"]
    return lines


class _Generated(SphinxDirective):
    has_content = False
    make: Any = None

    def run(self) -> list[nodes.Node]:
        container = nodes.container()
        lines = StringList(type(self).make(), source="dustoptics.sky.engines")
        self.state.nested_parse(lines, self.content_offset, container)
        return list(container.children)


class EngineList(_Generated):
    """``.. dustoptics-engines::``."""

    make = staticmethod(_engines_rst)


class EngineErrors(_Generated):
    """``.. dustoptics-engine-errors::``."""

    make = staticmethod(_errors_rst)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("dustoptics-engines", EngineList)
    app.add_directive("dustoptics-engine-errors", EngineErrors)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
