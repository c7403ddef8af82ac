"""``main``, its exit status and the module entry points (``python -m dustoptics``)."""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import warnings

import pytest

import dustoptics as do
from dustoptics.cli import _interrupt, errors, main


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


@pytest.mark.parametrize("module", ["dustoptics", "dustoptics.cli"])
def test_module_entry_points_run_and_exit_with_the_status(module):
    done = subprocess.run(
        [sys.executable, "-m", module, "--version"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0
    assert done.stdout.strip() == f"dustoptics {do.__version__}"
    usage = subprocess.run(
        [sys.executable, "-m", module, "no-such-command"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert usage.returncode == 2
    assert "invalid choice: 'no-such-command'" in usage.stderr


@pytest.mark.parametrize(
    ("orig_argv", "expected"),
    [
        (["python", "-m", "dustoptics", "build"], True),
        (["python", "-m", "dustoptics.cli", "build"], True),
        (["python", "-m", "pytest", "dustoptics"], False),
        (["python", "-c", "import dustoptics"], False),
    ],
)
def test_python_m_dustoptics_is_the_command(monkeypatch, orig_argv, expected):
    monkeypatch.setattr(sys, "argv", ["/site-packages/package/__main__.py", orig_argv[-1]])
    monkeypatch.setattr(sys, "orig_argv", orig_argv)
    assert _interrupt.is_the_command() is expected


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
        "engines",
    ]


def test_main_and_the_parser_import_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        module = importlib.import_module("dustoptics.cli")
        assert callable(module.main) and callable(module._parser)
