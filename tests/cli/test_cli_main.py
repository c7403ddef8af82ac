"""``main``, its exit status and the old import paths of :mod:`dustoptics.cli`."""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import warnings

import pytest

import dustoptics as do
from dustoptics.cli import errors, main


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"dustoptics {do.__version__}"


def test_no_command_is_a_usage_error(capsys):
    assert main([]) == 2
    assert "COMMAND" in capsys.readouterr().err


class _ClosedPipe:
    def write(self, text):
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self):
        raise BrokenPipeError(32, "Broken pipe")


@pytest.mark.parametrize("argv", [["materials"], ["build", "--help"], ["presets"]])
def test_broken_pipe_is_not_an_error(monkeypatch, argv):
    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    monkeypatch.setattr(errors, "_silence_stdout", lambda: None)
    assert main(argv) == 0


def test_module_entry_point_runs():
    done = subprocess.run(
        [sys.executable, "-m", "dustoptics.cli", "--version"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0
    assert done.stdout.strip() == f"dustoptics {do.__version__}"


@pytest.mark.parametrize(
    ("error", "status"),
    [
        (errors.UsageError("bad option"), 2),
        (do.config.ConfigError("must be > 0", key="optics.rtol", line=3, source="bad.toml"), 2),
        (FileExistsError("out/x.h5 already exists"), 1),
        (ValueError("the physics says no"), 1),
        (ImportError("needs the plot extra"), 1),
    ],
)
def test_exit_status_of_each_error(error, status, capsys):
    def command() -> int:
        raise error

    assert errors.exit_status(command) == status
    err = capsys.readouterr().err
    assert err == f"dustoptics: error: {error}\n"


def test_exit_status_puts_a_message_on_one_line_and_escapes_it(capsys):
    def command() -> int:
        raise OSError("first line\nsecond line \x1b[31mred")

    assert errors.exit_status(command) == 1
    assert capsys.readouterr().err == "dustoptics: error: first line second line \\x1b[31mred\n"


def test_a_command_error_outside_the_users_reach_is_not_caught():
    def command() -> int:
        raise RuntimeError("a bug")

    with pytest.raises(RuntimeError, match="a bug"):
        errors.exit_status(command)


def test_the_documented_parser_has_every_command():
    """docs/reference/cli.rst documents ``dustoptics.cli:_parser``: the parser main runs."""
    from dustoptics.cli import _parser

    parser = _parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert list(commands.choices) == [
        "build",
        "export",
        "info",
        "plot",
        "presets",
        "materials",
        "fit",
        "sweep",
        "sky",
        "retrieve",
    ]


def test_main_and_the_parser_import_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        module = importlib.import_module("dustoptics.cli")
        assert callable(module.main) and callable(module._parser)


@pytest.mark.parametrize(
    ("old", "module", "new"),
    [
        ("TableBuilder", "dustoptics.models.build", "TableBuilder"),
        ("FormatOptions", "dustoptics.io", "FormatOptions"),
        ("describe_path", "dustoptics.io.describe", "describe_path"),
        ("describe", "dustoptics.io.describe", "describe_table"),
        ("place_outputs", "dustoptics.io.outputs", "place_outputs"),
        ("read_table", "dustoptics.io.outputs", "read_table"),
        ("SkyJob", "dustoptics.sky.job", "SkyJob"),
        ("build_atmosphere", "dustoptics.atmosphere.build", "build_atmosphere"),
        ("SET_PROVENANCE_SUFFIX", "dustoptics.atmosphere.build", "SET_PROVENANCE_SUFFIX"),
        ("UsageError", "dustoptics.cli.errors", "UsageError"),
    ],
)
def test_old_import_paths_warn_and_give_the_moved_object(old, module, new):
    cli = importlib.import_module("dustoptics.cli")
    message = f"dustoptics.cli.{old} moved to {module}.{new}; the old path is removed in 0.3"
    with pytest.warns(DeprecationWarning, match=message.replace(".", r"\.")) as caught:
        moved = getattr(cli, old)
    assert moved is getattr(importlib.import_module(module), new)
    assert caught[0].filename == __file__  # the warning points at the line that asked


def test_an_unknown_name_is_an_attribute_error():
    cli = importlib.import_module("dustoptics.cli")
    with pytest.raises(AttributeError, match="has no attribute 'nope'"):
        cli.nope  # noqa: B018
