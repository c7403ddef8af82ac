"""The package as a newcomer meets it: quick start, dependencies, install, citation.

- The README's quick start is what CI runs (``.ci/quickstart_lines.sh``).
- The runtime dependencies are exactly the packages dustoptics imports at run
  time, and it imports without any optional package (miepython, pandas,
  matplotlib, ...).
- numba's cache of an installed package lives outside ``site-packages``, so
  ``pip install .`` followed by ``pip install -e .`` in one environment
  imports cleanly (the folder numba used to leave behind made ``dustoptics``
  a namespace package).
- LICENSE, CITATION.cff and CHANGELOG.md say what pyproject.toml says.
"""

from __future__ import annotations

import ast
import os
import re
import shutil
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "dustoptics"

#: Import name -> distribution name, where they differ.
DISTRIBUTION = {"yaml": "pyyaml", "OpenEXR": "openexr"}


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def _requirement_name(requirement: str) -> str:
    return re.split(r"[<>=!~\[; ]", requirement, maxsplit=1)[0].lower()


# ----------------------------------------------------------------------------- quick start


def _readme_quickstart() -> list[str]:
    """The quick start's command lines, read independently of the CI script."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Quick start\n", 1)[1].split("\n## ", 1)[0]
    block = section.split("```bash\n", 1)[1].split("\n```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


def test_ci_runs_the_readme_quick_start_lines_as_written():
    done = subprocess.run(
        ["bash", str(ROOT / ".ci" / "quickstart_lines.sh"), str(ROOT / "README.md")],
        capture_output=True,
        text=True,
        check=True,
    )
    lines = done.stdout.splitlines()
    assert lines == _readme_quickstart()
    assert len(lines) == 2
    assert lines[0].startswith("python3 -m pip install . && dustoptics build")
    assert lines[1].endswith("&& pytest")
    # .ci/run takes its commands from that script, before any other step installs anything.
    run = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "bash .ci/quickstart_lines.sh README.md" in run
    assert run.index("quickstart_lines.sh") < run.index("ruff check")


# ----------------------------------------------------------------------------- dependencies


def _third_party_imports() -> tuple[set[str], set[str]]:
    """Top-level third-party modules the package imports: (at module level, anywhere)."""
    stdlib = set(sys.stdlib_module_names) | {"__future__"}
    module_level: set[str] = set()
    anywhere: set[str] = set()
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        typing_only = {
            id(child)
            for node in ast.walk(tree)
            if isinstance(node, ast.If) and ast.unparse(node.test).endswith("TYPE_CHECKING")
            for child in ast.walk(node)
        }
        top = {id(node) for node in tree.body}
        top |= {
            id(child)
            for node in tree.body
            if isinstance(node, ast.Try | ast.If)
            for child in ast.walk(node)
        }
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            if id(node) in typing_only:
                continue
            for name in names:
                root = name.split(".")[0]
                if root in stdlib or root == "dustoptics":
                    continue
                module = DISTRIBUTION.get(root, root)
                anywhere.add(module)
                if id(node) in top:
                    module_level.add(module)
    return module_level, anywhere


def test_runtime_dependencies_are_what_the_package_imports():
    project = _pyproject()["project"]
    runtime = {_requirement_name(r) for r in project["dependencies"]}
    extras = {
        _requirement_name(r)
        for reqs in project["optional-dependencies"].values()
        for r in reqs
        if not r.startswith("dustoptics[")
    }
    module_level, anywhere = _third_party_imports()
    # Everything imported when the package loads is a runtime dependency ...
    assert module_level <= runtime, module_level - runtime
    # ... every runtime dependency is imported by the package ...
    assert runtime <= anywhere, runtime - anywhere
    # ... and what is imported lazily, on demand, is a runtime dependency or an extra.
    assert anywhere <= runtime | extras, anywhere - runtime - extras
    # miepython is a test reference and benchmark baseline, not part of the product.
    assert "miepython" not in runtime and "miepython" not in anywhere


BLOCKER = textwrap.dedent(
    """
    import importlib.abc, sys

    BLOCKED = {"miepython", "pandas", "matplotlib", "moderngl", "xarray", "hypothesis", "pytest"}

    class Block(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in BLOCKED:
                raise ImportError(f"{name} is blocked for this test")
            return None

    sys.meta_path.insert(0, Block())
    """
)


def test_package_imports_and_runs_without_optional_packages(tmp_path):
    """Every module imports, and the command line answers, with the extras blocked."""
    code = BLOCKER + textwrap.dedent(
        """
        import importlib, pkgutil
        import dustoptics
        for info in pkgutil.walk_packages(dustoptics.__path__, "dustoptics."):
            if info.name == "dustoptics.refractive_indices" or ".tests" in info.name:
                continue
            importlib.import_module(info.name)
        assert "miepython" not in sys.modules and "pandas" not in sys.modules
        from dustoptics import cli
        sys.exit(cli.main(["presets"]))
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert "blue-moons" in done.stdout


def test_optional_import_fails_with_a_message_naming_the_extra(tmp_path):
    code = BLOCKER + textwrap.dedent(
        """
        import dustoptics as do
        from dustoptics.compare import TableComparison
        try:
            TableComparison.to_frame(None)
        except ImportError as exc:
            print(exc)
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert "pip install 'dustoptics[pandas]'" in done.stdout, done.stderr


# ----------------------------------------------------------------------------- numba's cache


def _venv_python(venv: Path) -> Path:
    return venv / ("Scripts" if os.name == "nt" else "bin") / "python"


@pytest.mark.slow
def test_install_then_editable_install_imports_cleanly(tmp_path):
    """pip install . (a kernel compiled into numba's cache), then pip install -e . in the same
    environment: both import cleanly, and numba never writes into site-packages.  Needs
    network access for the build backend (setuptools-scm).  .ci/run runs the README's
    quick start in both orders on top of this."""
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = _venv_python(venv)
    site = Path(
        subprocess.run(
            [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    )
    # The runtime dependencies come from this environment (appended after the venv's own
    # site-packages, as a plain path: its .pth files, e.g. an editable dustoptics, are not run).
    ours = [p for p in sys.path if Path(p).name in ("site-packages", "dist-packages")]
    (site / "deps-from-test-environment.pth").write_text(
        "".join(f"{p}\n" for p in ours), encoding="utf-8"
    )
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "PYTHON"))}
    env["XDG_CACHE_HOME"] = str(tmp_path / "user-cache")
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"

    pip = [sys.executable, "-m", "pip", "--python", str(python)]  # this environment's pip
    # The build backend once, then builds without isolation (no new build environment each).
    build_requires = _pyproject()["build-system"]["requires"]
    subprocess.run(
        [*pip, "install", "--quiet", *build_requires],
        check=True,
        env=env,
        timeout=600,
    )

    def pip_install(*args: str) -> None:
        done = subprocess.run(
            [*pip, "install", "--quiet", "--no-deps", "--no-build-isolation"] + list(args),
            capture_output=True,
            text=True,
            env=env,
            cwd=tmp_path,
            timeout=600,
        )
        assert done.returncode == 0, done.stderr

    def run(code: str) -> list[str]:
        done = subprocess.run(
            [str(python), "-c", textwrap.dedent(code)],
            capture_output=True,
            text=True,
            env=env,
            cwd=tmp_path,
            timeout=300,
        )
        assert done.returncode == 0, done.stderr
        return done.stdout.splitlines()

    compile_one_kernel = """
        import os, numpy as np, dustoptics
        from dustoptics.scattering import quadrature
        w = quadrature._unstretch(np.array([1.0]), 2.0)[0]
        assert abs(w / 2.0 + np.log(w / 2.0) - 1.0) < 1e-15   # omega + ln omega = s
        print(dustoptics.__file__)
        print(os.environ.get("NUMBA_CACHE_DIR", ""))
        print(dustoptics.__version__)
    """
    pip_install(str(ROOT))
    installed_file, cache, version = run(compile_one_kernel)
    installed = Path(installed_file).parent
    assert installed.is_relative_to(site)
    assert Path(cache) == tmp_path / "user-cache" / "dustoptics" / f"numba-{version}"
    assert list(Path(cache).rglob("quadrature._unstretch-*.nbi"))
    assert not list(installed.rglob("*.nb[ic]")), "numba wrote into site-packages"

    pip_install("-e", str(ROOT))
    check = """
        import dustoptics
        from dustoptics import cli
        print(dustoptics.__file__)
        assert cli.main(["--version"]) == 0
    """
    editable_file, version_line = run(check)
    assert Path(editable_file) == PACKAGE / "__init__.py"
    assert version_line.startswith("dustoptics ") and version_line != "dustoptics 0.0.0+unknown"
    assert not installed.exists() or not any(installed.iterdir())


# ----------------------------------------------------------------------------- citation


def test_license_citation_and_changelog_agree_with_pyproject():
    project = _pyproject()["project"]
    assert project["license"] == "MIT"
    license_text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert license_text.startswith("MIT License\n")
    assert "Permission is hereby granted, free of charge" in license_text

    cff = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    assert re.search(r"^cff-version: 1\.2\.0$", cff, re.M)
    assert re.search(r"^license: MIT$", cff, re.M)
    assert re.search(r"^title: .*dustoptics", cff, re.M)
    assert re.search(r"^type: software$", cff, re.M)

    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert "[Keep a Changelog](https://keepachangelog.com/" in changelog
    assert "\n## [Unreleased]\n" in changelog


CFFCONVERT = shutil.which(
    "cffconvert", path=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"
)


@pytest.mark.skipif(CFFCONVERT is None, reason="cffconvert not installed (.ci/run runs it)")
def test_citation_cff_is_valid():
    """cffconvert validates against the CFF 1.2.0 schema (.ci/run always runs it)."""
    done = subprocess.run(
        [str(CFFCONVERT), "--validate", "--infile", str(ROOT / "CITATION.cff")],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stdout + done.stderr


def test_version_says_where_it_came_from():
    """setuptools-scm: X.Y.Z at a tag vX.Y.Z, else X.Y.Z.devN+gHASH, the commit's hash."""
    import dustoptics

    pyproject = _pyproject()
    assert "version" in pyproject["project"]["dynamic"]
    assert pyproject["tool"]["setuptools_scm"]["fallback_version"]
    if not (ROOT / ".git").exists() or shutil.which("git") is None:
        pytest.skip("not a git checkout: the version is the fallback")
    tagged = subprocess.run(
        ["git", "-C", str(ROOT), "describe", "--tags", "--exact-match"], capture_output=True
    )
    pattern = (
        r"\d+\.\d+\.\d+"
        if tagged.returncode == 0
        else r"\d+\.\d+\.\d+\.dev\d+\+g[0-9a-f]{7,}(\.d\d{8})?"
    )
    assert re.fullmatch(pattern, dustoptics.__version__), dustoptics.__version__


def test_numba_cache_directory_choice(tmp_path, monkeypatch):
    """The user's NUMBA_CACHE_DIR is kept; an install in site-packages caches per user and
    version; a source checkout keeps numba's default (None)."""
    from dustoptics import _numba_cache

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert _numba_cache.configure("1.2.3") == tmp_path / "mine"

    monkeypatch.delenv("NUMBA_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(_numba_cache.sys, "platform", "linux")
    monkeypatch.setattr(_numba_cache, "_PACKAGE_DIR", tmp_path / "src" / "dustoptics")
    assert _numba_cache.configure("1.2.3") is None
    assert "NUMBA_CACHE_DIR" not in os.environ

    site = tmp_path / "venv" / "lib" / "python3.11" / "site-packages" / "dustoptics"
    monkeypatch.setattr(_numba_cache, "_PACKAGE_DIR", site)
    chosen = _numba_cache.configure("1.2.3")
    assert chosen == tmp_path / "xdg" / "dustoptics" / "numba-1.2.3"
    assert chosen.is_dir() and os.environ["NUMBA_CACHE_DIR"] == str(chosen)
    monkeypatch.delenv("NUMBA_CACHE_DIR")  # and back to this process's numba setting
    from numba.core import config

    config.reload_config()
