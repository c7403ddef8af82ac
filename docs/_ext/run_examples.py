"""Run every example of the pages while Sphinx reads them.

Each page's ``>>>`` blocks (doctest syntax, run by the standard library's
:mod:`doctest` with ELLIPSIS and NORMALIZE_WHITESPACE) run in page order with
one namespace per page, and each
``.. dustoptics-command:: ARGS`` runs ``dustoptics ARGS`` through
:func:`dustoptics.cli.main` and shows the command with its real output.  A page
runs in a fresh temporary directory, so files that its examples write
(``tables/...``) land there and never in the source tree.  A failing example,
an output that differs from the one shown, or a command with an unexpected
exit status is a Sphinx warning: with ``-W`` the build fails.
"""

from __future__ import annotations

import contextlib
import doctest
import io
import os
import shlex
import tempfile
import time
from typing import Any, ClassVar

from docutils import nodes
from docutils.parsers.rst import Directive, directives
from sphinx.application import Sphinx
from sphinx.util import logging

logger = logging.getLogger(__name__)

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


class command_block(nodes.literal_block):
    """A literal block whose text is filled in when its command has run."""


class DustopticsCommand(Directive):
    """``.. dustoptics-command:: build --out tables`` (``:status:`` the expected exit status)."""

    required_arguments = 1
    final_argument_whitespace = True
    option_spec: ClassVar[dict[str, Any]] = {
        "status": directives.nonnegative_int,
        "hide-output": directives.flag,
    }

    def run(self) -> list[nodes.Node]:
        node = command_block("", "")
        node["argv"] = shlex.split(self.arguments[0])
        node["status"] = self.options.get("status", 0)
        node["hide_output"] = "hide-output" in self.options
        self.state.document.settings.env.note_dependency(__file__)
        node.source, node.line = self.state_machine.get_source_and_line(self.lineno)
        return [node]


def _run_command(node: command_block) -> None:
    from dustoptics.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(list(node["argv"]))
    shown = "$ dustoptics " + " ".join(shlex.quote(a) for a in node["argv"])
    if not node["hide_output"]:
        text = (err.getvalue() + out.getvalue()).rstrip()
        shown += ("\n" + text) if text else ""
    block = nodes.literal_block(shown, shown, language="console")
    block.source, block.line = node.source, node.line
    node.replace_self(block)
    if status != node["status"]:
        logger.warning(
            "dustoptics %s exited %s (expected %s): %s",
            " ".join(node["argv"]),
            status,
            node["status"],
            err.getvalue().strip(),
            location=node,
        )


def _run_doctest(node: nodes.doctest_block, globs: dict[str, Any], docname: str) -> None:
    text = node.astext()
    test = doctest.DocTestParser().get_doctest(text, globs, docname, node.source, node.line or 0)
    report = io.StringIO()
    runner = doctest.DocTestRunner(optionflags=FLAGS, verbose=False)
    runner.run(test, out=report.write, clear_globs=False)
    globs.update(test.globs)  # DocTest runs on a copy; later blocks see these names
    if runner.failures:
        logger.warning("example failed:\n%s", report.getvalue(), location=node)


def run_examples(app: Sphinx, doctree: nodes.document) -> None:
    # Only the page's own examples: docstrings' examples (autodoc) are run by the
    # test suite (pytest --doctest-modules).
    docname = app.env.docname
    own = str(app.env.doc2path(docname))
    blocks = [
        n
        for n in doctree.findall()
        if isinstance(n, (nodes.doctest_block, command_block)) and n.source == own
    ]
    if not blocks:
        return
    start = time.perf_counter()
    globs: dict[str, Any] = {"__name__": f"docs.{docname.replace('/', '.')}"}
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="dustoptics-docs-") as tmp:
        os.chdir(tmp)
        try:
            for node in blocks:
                if isinstance(node, command_block):
                    _run_command(node)
                else:
                    _run_doctest(node, globs, docname)
        finally:
            os.chdir(cwd)
            try:
                import matplotlib.pyplot as plt

                plt.close("all")
            except ImportError:
                pass
    logger.info(
        "ran %d examples of %s in %.1f s", len(blocks), docname, time.perf_counter() - start
    )


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("dustoptics-command", DustopticsCommand)
    app.connect("doctree-read", run_examples)
    return {"version": "1", "parallel_read_safe": False, "parallel_write_safe": True}
