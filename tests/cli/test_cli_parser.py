"""The parser: every format in ``--help``, from the registry; an example at the end of each help."""

from __future__ import annotations

import argparse
import re
import shlex

import pytest

from dustoptics import io
from dustoptics.cli import _parser, main


def _help(capsys, *argv: str, flag: str = "--help") -> str:
    assert main([*argv, flag]) == 0
    return capsys.readouterr().out


def _has_help_all(parser: argparse.ArgumentParser) -> bool:
    return any("--help-all" in action.option_strings for action in parser._actions)


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
    # Each format's entry: its line, and the lines under its text where it wraps.
    entries = re.findall(r"^  (\S+)  +(.*(?:\n {4,}\S.*)*)", text, re.M)
    marked = [name for name, entry in entries if entry.endswith("(default)")]
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
        # A long example wraps with a shell continuation: one command still.
        block = re.sub(r" \\\n\s+", " ", "\n".join(text[start + 1 :]))
        examples = [line.strip() for line in block.splitlines()]
        assert examples, argv
        for example in examples:
            words = shlex.split(example.split(" > ")[0])
            assert words[0] == "dustoptics" and tuple(words[1 : 1 + len(argv)]) == argv
            parser.parse_args(words[1:])  # a usage error would exit 2


@pytest.mark.parametrize("columns", ["40", "200"])
def test_help_fits_80_columns_and_keeps_option_names_whole(capsys, monkeypatch, columns):
    """Whatever the terminal's width, every --help is 80 columns at most, and an option name
    is never broken at its hyphens (argparse's default breaks --allow-large)."""
    monkeypatch.setenv("COLUMNS", columns)
    parser = _parser()
    for argv, sub in [((), parser), *_commands(parser)]:
        text = _help(capsys, *argv, flag="--help-all" if _has_help_all(sub) else "--help")
        lines = text.splitlines()
        assert max(len(line) for line in lines) <= 80, (argv, max(lines, key=len))
        words = text.split()
        for action in sub._actions:
            for option in action.option_strings:
                assert option in words or f"[{option}" in text, (argv, option)
        assert not any(re.search(r"(^|\s)--?[a-z]+(-[a-z0-9]+)*-$", line) for line in lines), argv


def test_help_is_short_and_help_all_has_every_format_option(capsys):
    """``--help`` leaves each format's options out (and says where they are); ``--help-all``
    shows them; both parse the same options."""
    short = _help(capsys, "build")
    full = _help(capsys, "build", flag="--help-all")
    assert "--help-all" in short and "--n-angles" not in short and "--glsl-version" not in short
    assert "--n-angles N" in full and "--glsl-version" in full
    assert len(short.splitlines()) < len(full.splitlines()) - 40
    args = _parser().parse_args(["build", "--format", "texture", "--n-angles", "91"])
    assert args.n_angles == 91


def test_help_all_is_only_where_there_is_more_to_show(capsys):
    parser = _parser()
    with_more = {argv for argv, sub in _commands(parser) if _has_help_all(sub)}
    assert ("build",) in with_more and ("export",) in with_more
    assert ("info",) not in with_more
