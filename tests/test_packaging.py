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
DISTRIBUTION = {"yaml": "pyyaml", "OpenEXR": "openexr", "PIL": "pillow"}


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


#: Runtime dependencies the package uses through xarray's engine names, not by import.
ENGINES = {"h5netcdf": 'engine="h5netcdf"'}


def test_engine_dependencies_are_named_by_the_package():
    runtime = {_requirement_name(r) for r in _pyproject()["project"]["dependencies"]}
    source = "".join(path.read_text(encoding="utf-8") for path in PACKAGE.rglob("*.py"))
    for name, spelling in ENGINES.items():
        assert name in runtime and spelling in source, name


def test_runtime_dependencies_are_what_the_package_imports():
    project = _pyproject()["project"]
    runtime = {_requirement_name(r) for r in project["dependencies"]} - set(ENGINES)
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
    # site-packages, as a plain path: its .pth files, e.g. an editable dustoptics, are not run),
    # through a folder of links to all of it but dustoptics (installed there from a wheel by
    # scripts/release_check.sh, it would shadow the editable install's finder).
    borrowed = tmp_path / "borrowed-site-packages"
    borrowed.mkdir()
    for path in sys.path:
        if Path(path).name not in ("site-packages", "dist-packages"):
            continue
        for entry in Path(path).iterdir():
            name = entry.name.lower()
            if name.startswith(("dustoptics", "__editable__")) or (borrowed / entry.name).exists():
                continue
            (borrowed / entry.name).symlink_to(entry)
    (site / "deps-from-test-environment.pth").write_text(f"{borrowed}\n", encoding="utf-8")
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
    """setuptools-scm: X.Y.Z at a tag vX.Y.Z, else X.Y(.Z).devN+gHASH, the commit's hash."""
    import dustoptics

    pyproject = _pyproject()
    assert "version" in pyproject["project"]["dynamic"]
    # No fallback: a tree without git metadata or .git_archival.txt does not invent a version.
    assert "fallback_version" not in pyproject["tool"]["setuptools_scm"]
    if not (ROOT / ".git").exists() or shutil.which("git") is None:
        pytest.skip("not a git checkout: the version came from .git_archival.txt or PKG-INFO")
    tagged = subprocess.run(
        ["git", "-C", str(ROOT), "describe", "--tags", "--exact-match"], capture_output=True
    )
    pattern = (
        r"\d+\.\d+\.\d+"
        if tagged.returncode == 0
        else r"\d+\.\d+(\.\d+)?\.dev\d+\+g[0-9a-f]{7,}(\.d\d{8})?"
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


# ----------------------------------------------------------------------------- release metadata


def _floor(requirement: str) -> str | None:
    match = re.search(r">=\s*([0-9][0-9a-z.]*)", requirement)
    return match.group(1) if match else None


def test_metadata_is_complete_for_an_index():
    """What an index page shows: readme, licence, keywords, Python versions, floors."""
    project = _pyproject()["project"]
    assert project["readme"] == {"file": "README.md", "content-type": "text/markdown"}
    assert project["license"] == "MIT" and project["license-files"] == ["LICENSE"]
    assert len(project["keywords"]) >= 5 and "Mie scattering" in project["keywords"]
    classifiers = project["classifiers"]
    assert len(set(classifiers)) == len(classifiers)
    # The Python versions classified are the supported ones: from requires-python's floor.
    floor = re.fullmatch(r">=3\.(\d+)", project["requires-python"])
    assert floor, project["requires-python"]
    versions = [c.rsplit(" :: ", 1)[1] for c in classifiers if re.search(r"Python :: 3\.\d+$", c)]
    assert versions and versions[0] == f"3.{floor.group(1)}", versions
    assert "Programming Language :: Python :: 3 :: Only" in classifiers
    assert "Typing :: Typed" in classifiers and (PACKAGE / "py.typed").is_file()


def test_every_dependency_has_a_floor_that_works():
    project = _pyproject()["project"]
    # Every dependency has a floor; scipy's admits no yanked release (1.11.0 was yanked), and
    # OpenEXR's has the OpenEXR.File API that dustoptics.io.textures.exr uses (3.3).
    floors = {}
    for requirement in project["dependencies"]:
        assert _floor(requirement), requirement
        floors[_requirement_name(requirement)] = tuple(map(int, _floor(requirement).split(".")))
    assert floors["scipy"] > (1, 11, 0)
    assert floors["openexr"] >= (3, 3)


def _installed_name(directory: Path) -> str:
    relative = directory.relative_to(ROOT)
    if relative.parts[0] == "refractive_indices":
        relative = Path("dustoptics", *relative.parts)
    return ".".join(relative.parts)


def _tree_packages() -> dict[str, Path]:
    """Installed package name -> folder, for every folder of the tree that holds files."""
    found = {}
    for top in (PACKAGE, ROOT / "refractive_indices"):
        for folder in [top, *sorted(p for p in top.rglob("*") if p.is_dir())]:
            if "__pycache__" in folder.parts:
                continue
            if any(
                f.is_file() and f.suffix not in (".pyc", ".nbi", ".nbc") for f in folder.iterdir()
            ):
                found[_installed_name(folder)] = folder
    return found


def test_packages_are_every_folder_of_the_tree():
    """The packages list names every folder that holds files (modules or data), and no other:
    a new subpackage or data folder missing from it would be left out of the wheel (with a
    warning from `python -m build`, which scripts/release_check.sh turns into a failure)."""
    tool = _pyproject()["tool"]["setuptools"]
    assert sorted(tool["packages"]) == sorted(_tree_packages())
    assert tool["package-dir"] == {
        "dustoptics": "dustoptics",
        "dustoptics.refractive_indices": "refractive_indices",
    }


def test_package_data_covers_every_data_file():
    """Every file of the tree that is not a module matches a package-data pattern."""
    import fnmatch

    data = _pyproject()["tool"]["setuptools"]["package-data"]
    missing = []
    for package, folder in _tree_packages().items():
        for path in folder.iterdir():
            if not path.is_file() or path.suffix in (".py", ".pyc", ".nbi", ".nbc"):
                continue
            if not any(fnmatch.fnmatch(path.name, p) for p in data.get(package, [])):
                missing.append(f"{package}: {path.name}")
    assert not missing, missing


USER_EXTRAS = {"pandas", "plot", "sweep"}
CHECKER_EXTRAS = {"gl", "shaders", "cf"}
TEST_STACK = {"pytest", "hypothesis", "miepython", "netcdf4", "scatrs", "nanodisort"}


def _extras() -> dict[str, list[str]]:
    return _pyproject()["project"]["optional-dependencies"]


def _expand(extra: str, extras: dict[str, list[str]]) -> set[str]:
    """Distribution names an extra installs, self-references followed."""
    names: set[str] = set()
    for requirement in extras[extra]:
        inner = re.fullmatch(r"dustoptics\[([a-z,]+)\]", requirement)
        if inner:
            for other in inner.group(1).split(","):
                names |= _expand(other, extras)
        else:
            names.add(_requirement_name(requirement))
    return names


def test_extras_mean_what_they_say():
    extras = _extras()
    assert set(extras) == USER_EXTRAS | CHECKER_EXTRAS | {"all", "test", "lint", "release", "docs"}
    # [all]: every user feature, nothing of the test stack or the checkers.
    assert extras["all"] == [f"dustoptics[{','.join(sorted(USER_EXTRAS))}]"]
    everything = _expand("all", extras)
    assert everything == set().union(*(_expand(e, extras) for e in USER_EXTRAS))
    assert not everything & (TEST_STACK | {"pytest", "ruff", "mypy", "sphinx", "build"})
    # [test]: what the whole suite needs, the user features and the checkers included.
    test = _expand("test", extras)
    assert TEST_STACK | everything <= test
    assert set().union(*(_expand(e, extras) for e in CHECKER_EXTRAS)) <= test
    assert {"radon", "ruff", "mypy"} <= _expand("lint", extras)
    assert {"build", "twine"} == _expand("release", extras)


def test_plain_install_reads_netcdf4_and_writes_exr():
    # The netCDF-4 reader of `retrieve` and the EXR writer come with a plain install.
    runtime = {_requirement_name(r) for r in _pyproject()["project"]["dependencies"]}
    assert {"h5netcdf", "openexr"} <= runtime


#: (blocked module, code that needs it, the install hint its ImportError gives)
OPTIONAL_IMPORTS = [
    ("matplotlib", "import dustoptics.plot as m; m._matplotlib()", "dustoptics[plot]"),
    (
        "matplotlib",
        "from dustoptics.sky.scene import check_png_support; check_png_support()",
        "dustoptics[plot]",
    ),
    (
        "PIL",
        "from dustoptics.sky.scene import check_png_support; check_png_support()",
        "dustoptics[plot]",
    ),
    (
        "pandas",
        "from dustoptics.compare import TableComparison; TableComparison.to_frame(None)",
        "dustoptics[pandas]",
    ),
    ("zarr", "from dustoptics.sweep import run; run._require_extra()", "dustoptics[sweep]"),
    ("distributed", "from dustoptics.sweep import run; run._require_extra()", "dustoptics[sweep]"),
    ("OpenEXR", "from dustoptics.io.textures import exr; exr._openexr()", "pip install 'OpenEXR"),
]


@pytest.mark.parametrize(("module", "code", "hint"), OPTIONAL_IMPORTS)
def test_every_optional_import_names_what_to_install(module, code, hint, tmp_path):
    blocker = BLOCKER.replace(
        'BLOCKED = {"miepython", "pandas", "matplotlib", "moderngl", "xarray", "hypothesis", "pytest"}',
        f"BLOCKED = {{{module!r}}}",
    )
    program = blocker + textwrap.dedent(
        f"""
        try:
            {code}
        except ImportError as exc:
            print(exc)
        else:
            print("no ImportError")
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", program], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert hint in done.stdout, done.stdout + done.stderr


def test_every_optional_import_has_a_case_above():
    """A new lazy import of an extra's package needs its row in OPTIONAL_IMPORTS."""
    runtime = {_requirement_name(r) for r in _pyproject()["project"]["dependencies"]}
    _, anywhere = _third_party_imports()
    optional = {name.lower() for name in anywhere} - runtime - {"xarray", "dask", "tbb"}
    covered = {DISTRIBUTION.get(module, module).lower() for module, _, _ in OPTIONAL_IMPORTS}
    assert optional <= covered | {"pandas"}, optional - covered


# ----------------------------------------------------------------------------- versions


GIT = shutil.which("git")


def _git(cwd: Path, *args: str) -> str:
    env = {
        **os.environ,
        "GIT_AUTHOR_DATE": "2026-01-01T00:00:00",
        "GIT_COMMITTER_DATE": "2026-01-01T00:00:00",
    }
    done = subprocess.run(
        [str(GIT), "-c", "user.name=t", "-c", "user.email=t@example.org", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        check=True,
        env=env,
    )
    return done.stdout.strip()


def _scm_version(root: Path) -> str:
    """The version setuptools-scm computes for ``root`` with dustoptics' settings."""
    setuptools_scm = pytest.importorskip("setuptools_scm")
    settings = _pyproject()["tool"]["setuptools_scm"]
    return setuptools_scm.get_version(root=str(root), **settings)


@pytest.mark.skipif(GIT is None, reason="git is not installed")
def test_versions_from_tags(tmp_path):
    """A tag vX.Y.Z is X.Y.Z, with no local label; commits after it are dev versions of the
    next patch release that name their commit; modified files at a tag make a dev version;
    a `git archive` knows its version from .git_archival.txt."""
    repo = tmp_path / "repo"
    repo.mkdir()
    for name in (".git_archival.txt", ".gitattributes"):
        shutil.copy(ROOT / name, repo / name)
    (repo / "f.txt").write_text("a\n")
    _git(repo, "init", "-q")
    _git(repo, "add", "-A")
    _git(repo, "commit", "-q", "-m", "one")
    untagged = _scm_version(repo)
    assert re.fullmatch(r"0\.1\.dev1\+g[0-9a-f]{7,}", untagged), untagged

    _git(repo, "tag", "v0.2.0")
    assert _scm_version(repo) == "0.2.0"
    (repo / "f.txt").write_text("b\n")
    dirty = _scm_version(repo)
    assert re.fullmatch(r"0\.2\.1\.dev0\+g[0-9a-f]{7,}\.d\d{8}", dirty), dirty
    _git(repo, "commit", "-q", "-am", "two")
    head = _git(repo, "rev-parse", "--short=9", "HEAD")
    after = _scm_version(repo)
    assert re.fullmatch(rf"0\.2\.1\.dev1\+g{head[:7]}[0-9a-f]*", after), after

    for ref, expected in (("v0.2.0", "0.2.0"), ("HEAD", after)):
        archive = tmp_path / f"archive-{ref}"
        archive.mkdir()
        tar = tmp_path / f"{ref}.tar"
        _git(repo, "archive", "--format=tar", "-o", str(tar), ref)
        shutil.unpack_archive(tar, archive)
        assert "$Format" not in (archive / ".git_archival.txt").read_text()
        got = _scm_version(archive)
        assert got.split("+")[0] == expected.split("+")[0], (ref, got)
        assert "+" not in got or got.split("+")[1].startswith(expected.split("+")[1][:8]), got


def test_a_tree_without_git_does_not_invent_a_version(tmp_path):
    setuptools_scm = pytest.importorskip("setuptools_scm")
    (tmp_path / ".git_archival.txt").write_text((ROOT / ".git_archival.txt").read_text())
    with pytest.raises(LookupError):
        _scm_version(tmp_path)
    assert setuptools_scm


def test_archive_metadata_is_substituted_by_git():
    attributes = (ROOT / ".gitattributes").read_text(encoding="utf-8").splitlines()
    assert ".git_archival.txt  export-subst" in attributes
    archival = (ROOT / ".git_archival.txt").read_text(encoding="utf-8")
    assert "describe-name: $Format:%(describe:tags=true,match=v[0-9]*)$" in archival
    assert "node: $Format:%H$" in archival


def test_changelog_has_a_section_per_release():
    """Each tag vX.Y.Z has its section; the next release's header is prepared."""
    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert re.search(r"^## \[0\.2\.0\]", changelog, re.M)
    if GIT is None or not (ROOT / ".git").exists():
        return
    tags = subprocess.run(
        [GIT, "-C", str(ROOT), "tag", "--list", "v[0-9]*"], capture_output=True, text=True
    ).stdout.split()
    for tag in tags:
        assert re.search(rf"^## \[{re.escape(tag[1:])}\]", changelog, re.M), tag
