"""A command imports what it uses (issue 40 item 5): the packages' names load on first use,
the format modules on the first look at the registry, and the command line imports the
module of the command it runs only."""

from __future__ import annotations

import ast
import gc
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from dustoptics.cli import main
from dustoptics.cli.parser import COMMANDS, build_parser
from dustoptics.io import FORMAT_MODULES

ROOT = Path(__file__).resolve().parents[1]

#: The packages whose names are imported on first use (dustoptics._lazy).
LAZY_PACKAGES = (
    "dustoptics.io",
    "dustoptics.io.csv",
    "dustoptics.io.engines",
    "dustoptics.io.gcm",
    "dustoptics.io.rt",
    "dustoptics.io.tables",
    "dustoptics.io.textures",
    "dustoptics.atmosphere",
    "dustoptics.particles",
    "dustoptics.models",
    "dustoptics.sky",
)


def _modules_after(code: str) -> list[str]:
    """The ``dustoptics`` modules a fresh interpreter holds after running ``code``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            f"{code}\nimport json, sys\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.startswith('dustoptics'))))",
        ],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return list(json.loads(done.stdout.strip().splitlines()[-1]))


def test_importing_the_io_package_or_the_registry_imports_no_format_module():
    loaded = _modules_after("import dustoptics.io, dustoptics.io.registry")
    assert sorted(set(loaded) & set(FORMAT_MODULES)) == []


def test_writing_netcdf_imports_no_other_format_module():
    loaded = _modules_after("import dustoptics.io.tables.netcdf")
    assert sorted(set(loaded) & set(FORMAT_MODULES)) == ["dustoptics.io.tables.netcdf"]


def test_the_first_look_at_the_registry_imports_every_format_module():
    loaded = _modules_after("from dustoptics.io import FORMATS\nassert 'netcdf' in FORMATS")
    assert sorted(set(FORMAT_MODULES) - set(loaded)) == []


def _registering_modules() -> set[str]:
    """The modules under dustoptics/io that call ``register(...)`` at module level (AST)."""
    found = set()
    for path in (ROOT / "dustoptics" / "io").rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            value = getattr(node, "value", None)
            if isinstance(value, ast.Call) and getattr(value.func, "id", None) == "register":
                parts = path.relative_to(ROOT).with_suffix("").parts
                found.add(".".join(parts))
    return found


def test_every_module_that_registers_a_format_is_listed():
    """A format module left out of FORMAT_MODULES would never be registered."""
    assert _registering_modules() == set(FORMAT_MODULES)


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_every_public_name_is_the_defining_modules(package):
    module = importlib.import_module(package)
    lazy = {n: m for m, names in module._NAMES.items() for n in names}
    own = {"FORMAT_MODULES"} if package == "dustoptics.io" else set()
    assert set(lazy) <= set(module.__all__)
    for name in module.__all__:
        value = getattr(module, name)
        if name in lazy:
            assert value is getattr(importlib.import_module(lazy[name]), name), name
        elif name not in own:  # the others are the package's submodules
            assert value is importlib.import_module(f"{package}.{name}"), name
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        module.no_such_name  # noqa: B018
    assert set(module.__all__) <= set(dir(module))


def test_a_command_line_imports_its_commands_module_only():
    loaded = _modules_after(
        "from dustoptics.cli.parser import build_parser\nbuild_parser(['presets', '--show', 'x'])"
    )
    commands = {f"dustoptics.cli.{m}" for m, _ in COMMANDS.values()}
    assert sorted(commands & set(loaded)) == ["dustoptics.cli.catalogue"]
    loaded = _modules_after("from dustoptics.cli.parser import build_parser\nbuild_parser([])")
    assert sorted(commands & set(loaded)) == []


def _subparsers(parser):
    (action,) = [a for a in parser._actions if a.dest == "command"]
    return action


@pytest.mark.parametrize("argv", [[], ["--help"], ["no-such-command"], *[[c] for c in COMMANDS]])
def test_the_command_list_is_the_same_whatever_the_command(argv):
    """The other commands' lines (COMMANDS) are the lines their modules give."""
    full = build_parser()
    assert build_parser(argv).format_help() == full.format_help()
    if argv and argv[0] in COMMANDS:
        ours = _subparsers(build_parser(argv)).choices[argv[0]]
        assert ours.format_help() == _subparsers(full).choices[argv[0]].format_help()


def test_every_command_has_its_line_in_the_list():
    full = _subparsers(build_parser())
    assert list(full.choices) == list(COMMANDS)
    lines = {a.dest: a.help for a in full._choices_actions}
    assert lines == {name: line for name, (_, line) in COMMANDS.items()}


def test_a_program_calling_main_keeps_its_garbage_collector(capsys):
    """Only the ``dustoptics build`` process itself runs without the cyclic collector."""
    assert gc.isenabled()
    assert main(["build", "--help"]) == 0
    capsys.readouterr()
    assert gc.isenabled()


def test_the_programs_help_imports_no_scipy_or_numba():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            "import contextlib, io, sys\n"
            "from dustoptics.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    assert main(['--help']) == 0\n"
            "print(sorted(m for m in ('scipy', 'numba', 'xarray', 'h5py') if m in sys.modules))",
        ],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
