"""A Sphinx directive that lists the output formats from their records.

``.. dustoptics-formats::`` writes :func:`dustoptics.io.registry.format_table`: one row per
format registered in :data:`dustoptics.io.FORMATS` (name, files, what, needs, options), so
the documentation's format table is generated from the records the program runs and a new
format appears in it without an edit here.
"""

from __future__ import annotations

from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective

from dustoptics.io.registry import format_table


class FormatTable(SphinxDirective):
    """``.. dustoptics-formats::``: the registry's format table."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        container = nodes.container()
        lines = StringList(format_table().splitlines(), source="dustoptics.io.registry")
        self.state.nested_parse(lines, self.content_offset, container)
        return list(container.children)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("dustoptics-formats", FormatTable)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
