"""A Sphinx directive that documents a command line from its argparse parser.

``.. argparse-reference:: package.module:function`` imports the module, calls
the function (it must return an :class:`argparse.ArgumentParser`) and writes
the program's usage, then one section per subcommand with its usage, its
arguments grouped as the parser groups them, their help text, choices and
defaults.  The page is generated from the parser that the program runs, so it
cannot drift from it.
"""

from __future__ import annotations

import argparse
import importlib
from typing import Any

from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx


def _load(spec: str) -> argparse.ArgumentParser:
    module_name, _, attr = spec.partition(":")
    if not attr:
        raise ValueError(f"expected 'module:function'; got {spec!r}")
    parser = getattr(importlib.import_module(module_name), attr)()
    if not isinstance(parser, argparse.ArgumentParser):
        raise TypeError(f"{spec} returned {type(parser).__name__}, not an ArgumentParser")
    return parser


def _subcommands(parser: argparse.ArgumentParser) -> list[tuple[str, str, argparse.ArgumentParser]]:
    """(name, one-line help, parser) of each subcommand, in the parser's order."""
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help or "" for choice in action._choices_actions}
            out += [(name, helps.get(name, ""), sub) for name, sub in action.choices.items()]
    return out


#: Width of the usage text: the page's column, whatever the terminal of the build.
USAGE_WIDTH = 72


def _usage(parser: argparse.ArgumentParser) -> nodes.literal_block:
    formatter = argparse.HelpFormatter(parser.prog, width=USAGE_WIDTH)
    formatter.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    text = formatter.format_help().strip()
    return nodes.literal_block(text, text, language="text")


def _invocation(action: argparse.Action, formatter: argparse.HelpFormatter) -> str:
    if not action.option_strings:
        return formatter._metavar_formatter(action, action.dest)(1)[0]
    if action.nargs == 0:
        return ", ".join(action.option_strings)
    metavar = formatter._format_args(action, action.dest.upper())
    return ", ".join(f"{opt} {metavar}" for opt in action.option_strings)


def _describe(action: argparse.Action, formatter: argparse.HelpFormatter) -> str:
    text = formatter._expand_help(action) if action.help else ""
    extras = []
    if action.choices is not None and not isinstance(action, argparse._SubParsersAction):
        extras.append("choices: " + ", ".join(map(str, action.choices)))
    if action.required and action.option_strings:
        extras.append("required")
    if extras:
        text = f"{text} ({'; '.join(extras)})" if text else "; ".join(extras)
    return text


class ArgparseReference(Directive):
    required_arguments = 1
    has_content = False

    def _section(self, title: str, ident: str) -> nodes.section:
        section = nodes.section(
            ids=[nodes.make_id(ident)], names=[nodes.fully_normalize_name(ident)]
        )
        section += nodes.title(text=title)
        return section

    def _arguments(self, parser: argparse.ArgumentParser) -> list[nodes.Node]:
        formatter = parser._get_formatter()
        out: list[nodes.Node] = []
        for group in parser._action_groups:
            actions = [
                a
                for a in group._group_actions
                if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))
                and a.help != argparse.SUPPRESS
            ]
            if not actions:
                continue
            title = group.title or ""
            if title in ("options", "positional arguments"):  # argparse's own titles
                title = title.capitalize()
            out.append(nodes.rubric(text=title))
            items = nodes.definition_list()
            for action in actions:
                item = nodes.definition_list_item()
                term = nodes.term()
                term += nodes.literal(text=_invocation(action, formatter))
                item += term
                definition = nodes.definition()
                definition += nodes.paragraph(text=_describe(action, formatter))
                item += definition
                items += item
            out.append(items)
        return out

    def run(self) -> list[nodes.Node]:
        parser = _load(self.arguments[0])
        prog = parser.prog
        result: list[nodes.Node] = []
        result.append(_usage(parser))
        if parser.description:
            result.append(nodes.paragraph(text=parser.description))
        result += self._arguments(parser)
        for name, help_text, sub in _subcommands(parser):
            section = self._section(f"{prog} {name}", f"{prog}-{name}")
            if help_text:
                section += nodes.paragraph(text=help_text[:1].upper() + help_text[1:] + ".")
            section += _usage(sub)
            for node in self._arguments(sub):
                section += node
            result.append(section)
        return result


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("argparse-reference", ArgparseReference)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
