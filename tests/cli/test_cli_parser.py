"""The parser: every format in ``--help``, from the registry; an example at the end of each help."""

from __future__ import annotations

import argparse
import re
import shlex

import pytest

from dustoptics import io
from dustoptics.cli import _parser, main


def _help(capsys, *argv: str) -> str:
    assert main([*argv, "--help"]) == 0
    return capsys.readouterr().out


def _commands(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()):
    """(argv prefix, parser) of every subcommand, nested ones (sky mars, ...) included."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*prefix, name), sub
                yield from _commands(sub, (*prefix, name))


@pytest.mark.parametrize("command", ["build", "export"])
def test_help_lists_every_format_on_a_line_of_its_own(capsys, command):
    text = _help(capsys, command)
    for name in io.FORMATS:
        lines = [line for line in text.splitlines() if line.startswith(f"  {name} ")]
        assert len(lines) == 1, (name, text)
        assert len(lines[0].split()) > 2  # the name, then what it writes


def test_build_help_marks_the_default_formats(capsys):
    text = _help(capsys, "build")
    marked = [line.split()[0] for line in text.splitlines() if line.endswith("(default)")]
    assert marked == ["csv", "netcdf"]
    assert "(default netcdf,csv)" in text


def test_the_format_list_comes_from_the_registry(capsys, monkeypatch):
    """A format registered later appears too, described by its record's summary."""
    fancy = io.Format(name="fancy", summary="NAME.fancy: a fancy file", write=lambda *a, **k: [])
    monkeypatch.setitem(io.FORMATS, "fancy", fancy)
    text = _help(capsys, "export")
    assert re.search(r"^  fancy +NAME\.fancy: a fancy file$", text, re.M)


def test_every_help_ends_with_an_example_that_parses(capsys):
    parser = _parser()
    commands = list(_commands(parser))
    assert {c[0][0] for c in commands} >= {"build", "export", "info", "fit", "sweep", "sky"}
    for argv, _ in commands:
        text = _help(capsys, *argv).rstrip().splitlines()
        start = max(i for i, line in enumerate(text) if line in ("example:", "examples:"))
        examples = [line.strip() for line in text[start + 1 :]]
        assert examples, argv
        for example in examples:
            words = shlex.split(example.split(" > ")[0])
            assert words[0] == "dustoptics" and tuple(words[1 : 1 + len(argv)]) == argv
            parser.parse_args(words[1:])  # a usage error would exit 2
