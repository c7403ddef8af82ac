"""The compiled kernels: one signature each, compiled in advance in parallel and with
progress, loaded silently once cached; ``import dustoptics`` compiles nothing and stays lazy.

The tests that compile from an empty cache run ``dustoptics`` in a subprocess with its own
temporary ``NUMBA_CACHE_DIR``; the scheduler's tests replace numba by a stand-in.
"""

from __future__ import annotations

import importlib
import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import dustoptics
from dustoptics import _numba_cache
from dustoptics._numba_cache import _dependencies, compile_kernels, kernels

ROOT = Path(dustoptics.__file__).resolve().parents[1]

SMALL = """\
name = "cache-test"
description = "three wavelengths, for the tests of numba's cache"

[material]
model = "mars_dust"

[size_distribution]
model = "modified_gamma"
r_eff_um = 1.0
v_eff = 0.2

[optics]
rtol = 1e-3
wavelengths_nm = [440.0, 550.0, 680.0]
n_theta = 361

[phase]
model = "mie"
"""


def _run(code: str, cache: Path | None, *, timeout: float = 600) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
    )


# ----------------------------------------------------------------------------- signatures


def test_the_package_calls_each_kernel_with_its_declared_signature_only(tmp_path):
    """Every configuration of the optics (phase function and few angles, number weighting,
    matrix and expansion, coated spheres, one size), single and coated spheres: each kernel
    is compiled for a declared signature and no other, and no inlined helper on its own."""
    code = """
        import json, warnings
        import numpy as np
        import dustoptics as do
        from dustoptics import _numba_cache
        from dustoptics.scattering import expansion, mie

        wl = np.array([450.0, 680.0])
        dist = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
        core = do.CoatedSphere(
            core=do.ConstantIndex(value=2.0 + 0.5j), shell=do.mars_dust(), core_radius_fraction=0.5
        )
        runs = [
            dict(),
            dict(theta_deg=np.linspace(0.0, 180.0, 19), weighting="number"),
            dict(polarization=True, expansion=True),
            dict(refractive_index=core, polarization=True),
            dict(distribution=do.Monodisperse(radius_um=1.3)),
        ]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for kw in runs:
                index = kw.pop("refractive_index", do.mars_dust())
                do.compute_optics(index, kw.pop("distribution", dist), wavelength_nm=wl, **kw)
        mie.single_sphere(m=1.5 + 0.01j, x=3.0, mu=np.linspace(-1.0, 1.0, 9)[::2])
        mie.coated_sphere(m_core=2.0 + 0.1j, m_shell=1.5, x_core=1.0, x=3.0, mu=0.5)
        expansion.evaluate_matrix(np.ones((6, 4)), np.array([0.0, 90.0]))

        declared, compiled = {}, {}
        for k in _numba_cache.kernels():
            declared.setdefault(k.name.split("[")[0], set()).add(str(k.signature))
            compiled[k.name.split("[")[0]] = {str(s) for s in k.dispatcher.signatures}
        helpers = {}
        for module in (mie, expansion, do.scattering.refinement, do.scattering.quadrature):
            for name, value in vars(module).items():
                if getattr(value, "targetoptions", {}).get("inline") == "always":
                    helpers[name] = len(value.signatures)
        print(json.dumps({
            "declared": {k: sorted(v) for k, v in declared.items()},
            "compiled": {k: sorted(v) for k, v in compiled.items()},
            "helpers": helpers,
        }))
    """
    # An empty cache: every kernel is compiled in that process.  From a warm cache a kernel
    # that only other kernels call is never compiled there (its callers' machine code is
    # loaded whole), and its dispatcher lists no signature although it ran.
    done = _run(code, tmp_path / "cache")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.splitlines()[-1])
    extra = {
        name: sorted(set(sigs) - set(report["declared"][name]))
        for name, sigs in report["compiled"].items()
        if set(sigs) - set(report["declared"][name])
    }
    assert extra == {}, f"kernels compiled for undeclared signatures: {extra}"
    assert all(report["compiled"].values()), "every kernel is called by these computations"
    assert report["helpers"] and not any(report["helpers"].values())


def test_a_second_signature_is_a_declared_variant_of_its_own_group():
    names = {k.name: k for k in kernels()}
    assert "mie._accumulate_grids[coated]" in names
    coated = names["mie._accumulate_grids[coated]"]
    assert (
        coated.group == "coated" and coated.dispatcher is names["mie._accumulate_grids"].dispatcher
    )
    assert [k.name for k in kernels(["optics"]) if "[" in k.name] == []
    with pytest.raises(ValueError, match="group must be one of"):
        _numba_cache.kernel("float64", group="nope")
    with pytest.raises(ValueError, match="groups must be among"):
        kernels(["nope"])


def test_dependencies_follow_the_calls_through_inlined_helpers():
    """A kernel waits for the kernels it calls: directly, through a module
    (``mie._accumulate_grids``) or through helpers numba inlines, only among those asked for."""
    deps = _dependencies(kernels(["optics"]))
    assert {"mie._mie_coefficients", "mie._add_sphere", "mie._legendre_regrid"} <= deps[
        "mie._accumulate_grids"
    ]
    assert "mie.wiscombe_nmax" in deps["mie._accumulate_grids"]
    assert "mie._coat" not in deps["mie._accumulate_grids"]  # another group
    assert deps["refinement._phase_refinement_errors"] == {"refinement._halves_total"}
    assert "quadrature._wright_omega" in deps["refinement._panel_cost"]  # through _n_max, inlined
    assert deps["mie._mie_coefficients"] == set()
    both = _dependencies(kernels(["optics", "coated"]))
    assert {"mie._accumulate_grids", "mie._coat"} <= both["mie._accumulate_grids[coated]"]


# ----------------------------------------------------------------------------- the scheduler


_FAKE_CHILD = """\
import sys
print("ready", flush=True)
for n, line in enumerate(sys.stdin):
    if {stop_after} is not None and n >= {stop_after}:
        sys.exit(1)
    print("done", line.split()[0], 0.5, 0.5, flush=True)
"""


def _fake_compile(monkeypatch, stop_after: int | None = None) -> list[str]:
    """numba replaced: nothing is cached, this process 'compiles' by recording the name,
    a child answers as a real one would (and stops after ``stop_after`` kernels)."""
    here: list[str] = []

    def compile_here(k):
        here.append(k.name)
        return 0.0, 0.0

    monkeypatch.setattr(_numba_cache, "_in_cache", lambda k: False)
    monkeypatch.setattr(_numba_cache, "_shares_the_cache", lambda k: True)
    monkeypatch.setattr(_numba_cache, "_compile_here", compile_here)
    monkeypatch.setattr(
        _numba_cache,
        "_child_command",
        lambda modules: [sys.executable, "-c", _FAKE_CHILD.format(stop_after=stop_after)],
    )
    return here


def _check_order(report) -> None:
    names = [k.name for k in report.kernels]
    assert sorted(names) == sorted(k.name for k in kernels(["optics", "matrix"]))
    done_at = {name: i for i, name in enumerate(names)}
    for name, callees in _dependencies(kernels(["optics", "matrix"])).items():
        for callee in callees:
            assert done_at[callee] < done_at[name], (callee, name)


def test_compile_kernels_hands_each_kernel_out_once_callees_first(monkeypatch):
    here = _fake_compile(monkeypatch)
    report = compile_kernels(["optics", "matrix"], processes=2)
    assert report is not None and report.processes == 2
    _check_order(report)
    by_child = [k.name for k in report.kernels if k.process == 1]
    assert sorted(here + by_child) == sorted(k.name for k in report.kernels)


@pytest.mark.parametrize("stop_after", [0, 2])
def test_a_child_that_stops_leaves_its_kernels_to_this_process(monkeypatch, stop_after):
    here = _fake_compile(monkeypatch, stop_after=stop_after)
    report = compile_kernels(["optics", "matrix"], processes=2)
    assert report is not None
    _check_order(report)
    assert len(here) == len(report.kernels) - sum(k.process == 1 for k in report.kernels)
    assert sum(k.process == 1 for k in report.kernels) <= stop_after


def test_progress_names_each_kernel_k_of_n_with_the_time(monkeypatch, capsys):
    _fake_compile(monkeypatch)
    compile_kernels(["optics"], processes=1, progress=sys.stderr)
    lines = capsys.readouterr().err.splitlines()
    n = len(kernels(["optics"]))
    assert re.fullmatch(
        rf"dustoptics: compiling {n} kernels, once for this installation \(cached in .+\) \.\.\.",
        lines[0],
    )
    assert len(lines) == n + 1
    for k, line in enumerate(lines[1:], start=1):
        assert re.fullmatch(rf"dustoptics: compiled kernel {k}/{n}, \w+\.\w+ \(\d+\.\d s\)", line)


# ----------------------------------------------------------------------------- prestart


def test_optics_modules_are_those_that_declare_the_optics_kernels():
    """What a prestarted child imports, known before the kernels are declared."""
    declared = {k.dispatcher.py_func.__module__ for k in kernels(["optics"])}
    assert set(_numba_cache.OPTICS_MODULES) == declared


@pytest.mark.parametrize("user_dir", [False, True])
def test_the_index_folder_is_where_numba_puts_the_kernels(monkeypatch, tmp_path, user_dir):
    """The folder :func:`prestart` looks at is numba's own choice for the Mie kernels:
    its locator for a user's ``NUMBA_CACHE_DIR`` or for the sources' ``__pycache__``."""
    import inspect

    from numba.core import caching, config

    from dustoptics.scattering import mie

    def numbas(name: str):  # public in numba 0.68, with a leading underscore in older ones
        return getattr(caching, name, None) or getattr(caching, f"_{name}")

    func = mie._accumulate_grids.py_func
    if user_dir:
        monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
        monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))
        locator = numbas("UserProvidedCacheLocator").from_function(func, inspect.getfile(func))
    else:
        monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
        locator = numbas("InTreeCacheLocator").from_function(func, inspect.getfile(func))
    assert locator is not None
    assert Path(locator.get_cache_path()) == _numba_cache._optics_index_folder()
    assert _numba_cache._MARKER == "mie._accumulate_grids"


def test_prestart_on_an_empty_cache_hands_its_children_the_kernels(monkeypatch):
    """``dustoptics build`` on an empty cache: the children start before the package is
    imported, and compile_kernels hands them kernels instead of starting others."""
    here = _fake_compile(monkeypatch)
    monkeypatch.setattr(_numba_cache, "_cache_is_empty", lambda: True)
    monkeypatch.setattr(_numba_cache, "_prestarted", [])
    assert _numba_cache.prestart(processes=2) == 1
    assert _numba_cache.prestart(processes=2) == 0  # once

    def no_more(modules):
        raise AssertionError("a prestarted child was there to take")

    monkeypatch.setattr(_numba_cache, "_spawn", no_more)
    report = compile_kernels(["optics", "matrix"], processes=2)
    assert report is not None and report.processes == 2
    _check_order(report)
    by_child = [k.name for k in report.kernels if k.process == 1]
    assert sorted(here + by_child) == sorted(k.name for k in report.kernels)
    assert _numba_cache._prestarted == []


def test_prestart_does_nothing_on_a_cache_that_holds_kernels(monkeypatch):
    monkeypatch.setattr(_numba_cache, "_cache_is_empty", lambda: False)
    monkeypatch.setattr(_numba_cache, "_prestarted", [])
    assert _numba_cache.prestart(processes=2) == 0
    monkeypatch.setattr(_numba_cache, "_cache_is_empty", lambda: True)
    assert _numba_cache.prestart(processes=1) == 0  # no other core
    assert _numba_cache._prestarted == []


def test_prestarted_children_that_get_no_kernel_end(monkeypatch):
    """Nothing to compile after all (or fewer kernels than children): they are ended."""
    _fake_compile(monkeypatch)
    monkeypatch.setattr(_numba_cache, "_cache_is_empty", lambda: True)
    monkeypatch.setattr(_numba_cache, "_prestarted", [])
    assert _numba_cache.prestart(processes=2) == 1
    child = _numba_cache._prestarted[0]
    monkeypatch.setattr(_numba_cache, "_in_cache", lambda k: True)
    assert compile_kernels(["optics"]) is None
    assert _numba_cache._prestarted == [] and child.poll() is not None


@pytest.mark.parametrize(
    ("argv", "command"),
    [
        (["build"], "build"),
        (["build", "mars", "--out", "x"], "build"),
        (["build", "--help"], None),
        (["--version"], None),
        (["info", "f.nc"], "info"),
        ([], None),
    ],
)
def test_prestart_is_for_the_build_command(argv, command):
    from dustoptics.cli import _prestart

    assert _prestart._command(argv) == command
    assert _prestart.start(["build"]) == 0  # this process is not the command


def test_a_child_imports_the_kernels_modules_without_the_package():
    """A compiling child runs no package ``__init__`` (``import dustoptics`` would cost it
    a second and a half of a core that compiles): it imports the modules that declare the
    kernels, and gets all of them; with numba's error-message highlighting off.  The sky's
    kernels are declared too (their modules import the data model through the atmosphere
    sets), as they are when the suite has imported them before."""
    for module in ("dustoptics.sky.medium", "dustoptics.sky.orders", "dustoptics.sky.render"):
        importlib.import_module(module)
    modules = sorted({k.dispatcher.py_func.__module__ for k in kernels()})
    assert "dustoptics.sky.medium" in modules
    command = _numba_cache._child_command(modules)
    code = command[2].replace(
        "c._end(c._serve(sys.argv[2:]))",
        "c._import_bare(sys.argv[2:]); import json, os, numba.core.errors as e; "
        "print(json.dumps([sorted(c._KERNELS), hasattr(sys.modules['dustoptics'], "
        "'__version__'), sorted(m for m, v in sys.modules.items() if m.startswith('dustoptics.io') "
        "and getattr(v, '__file__', None)), "
        "os.environ['NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING'], "
        "type(e.termcolor()).__name__]))",
    )
    done = subprocess.run(
        [command[0], "-c", code, *command[3:]],
        capture_output=True,
        text=True,
        env=_numba_cache._child_env(),
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    names, has_version, io_modules, highlighting, scheme = json.loads(done.stdout)
    assert set(names) >= {k.name for k in kernels()}
    assert (has_version, io_modules, highlighting, scheme) == (False, [], "1", "NOPColorScheme")


def test_a_child_imports_the_package_whole_when_a_module_needs_it(tmp_path):
    """Should a module need what a package's ``__init__`` defines, the child imports the
    package whole and still gets the kernels."""
    (tmp_path / "needs_init.py").write_text("from dustoptics import __version__\n")
    command = _numba_cache._child_command(["dustoptics.scattering.mie"])
    code = command[2].replace(
        "c._end(c._serve(sys.argv[2:]))",
        "import importlib.util; "
        "sys.meta_path.insert(0, type('Finder', (), {'find_spec': staticmethod("
        "lambda name, path=None, target=None: importlib.util.spec_from_file_location("
        f"name, {str(tmp_path / 'needs_init.py')!r}) if name == 'dustoptics.needs_init' "
        "else None)})); "
        "c._import_bare(['dustoptics.needs_init', *sys.argv[2:]]); "
        "print(sys.modules['dustoptics'].__version__ is not None, "
        "'mie._mie_coefficients' in c._KERNELS)",
    )
    done = subprocess.run(
        [command[0], "-c", code, *command[3:]],
        capture_output=True,
        text=True,
        env=_numba_cache._child_env(),
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True"]


def test_with_numbas_jit_off_nothing_compiles(monkeypatch):
    """NUMBA_DISABLE_JIT=1 (the kernels run as Python, for debugging): nothing to compile,
    and a table still computes on threads."""
    code = """
        import dustoptics as do
        from dustoptics import _numba_cache
        assert _numba_cache.compile_kernels(["optics", "matrix"]) is None
        assert _numba_cache.kernels_cached(["optics"])
        do.compute_optics(
            do.mars_dust(), do.ModifiedGamma(r_eff_um=0.3, v_eff=0.1),
            wavelength_nm=[550.0, 600.0], theta_deg=[0.0, 90.0, 180.0], rtol=1e-2, workers=2,
        )
    """
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "1")
    done = _run(code, None)
    assert done.returncode == 0, done.stderr


def test_nothing_to_compile_is_silent(monkeypatch, capsys):
    monkeypatch.setattr(_numba_cache, "_in_cache", lambda k: True)
    assert compile_kernels(["optics", "matrix"], progress=sys.stderr) is None
    assert capsys.readouterr().err == ""


# ----------------------------------------------------------------------------- numba's cache


def test_first_build_compiles_with_progress_and_the_next_process_loads_silently(tmp_path):
    """From an empty cache, ``dustoptics build`` compiles the kernels once (in parallel where
    there are cores), each on a progress line; a second process finds them in numba's cache
    and says nothing of compiling, and :func:`kernels_cached` agrees."""
    config = tmp_path / "small.toml"
    config.write_text(SMALL, encoding="utf-8")
    cache = tmp_path / "cache"
    # As a user runs it (python -m dustoptics.cli): the children start while it imports.
    build = f"""
        import runpy, sys
        sys.argv = ["dustoptics", "build", {str(config)!r}, "--out", sys.argv[1],
                    "--format", "hdf5"]
        runpy.run_module("dustoptics.cli", run_name="__main__", alter_sys=True)
    """
    cached = """
        import dustoptics
        from dustoptics import _numba_cache
        print(_numba_cache.kernels_cached(["optics"]))
    """
    assert _run(cached, cache).stdout.split() == ["False"]
    n = len(kernels(["optics"]))

    first = _run(build.replace("sys.argv[1]", repr(str(tmp_path / "a"))), cache)
    assert first.returncode == 0, first.stderr
    err = first.stderr.splitlines()
    assert re.match(rf"dustoptics: compiling {n} kernels, once for this installation \(", err[0])
    progress = [line for line in err if line.startswith("dustoptics: compiled kernel ")]
    assert [line.split(",")[0] for line in progress] == [
        f"dustoptics: compiled kernel {k}/{n}" for k in range(1, n + 1)
    ]
    assert any(line.startswith("dustoptics: this first build took") for line in err)

    assert _run(cached, cache).stdout.split() == ["True"]
    second = _run(build.replace("sys.argv[1]", repr(str(tmp_path / "b"))), cache)
    assert second.returncode == 0, second.stderr
    assert "compil" not in second.stderr
    assert (tmp_path / "b" / "cache-test" / "cache-test.h5").is_file()


def test_import_compiles_nothing_and_imports_no_heavy_package():
    """``import dustoptics`` defines the kernels without compiling or loading any, and
    imports neither xarray, dask, distributed, zarr, matplotlib nor scipy.stats (0.4 s)."""
    code = """
        import sys
        import dustoptics
        from dustoptics import _numba_cache
        heavy = [m for m in ("xarray", "dask", "distributed", "zarr", "matplotlib",
                             "scipy.stats") if m in sys.modules]
        loaded = [k.name for k in _numba_cache.kernels() if k.dispatcher.signatures]
        print(heavy, loaded)
    """
    done = _run(code, None)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[] []"


@pytest.mark.parametrize("scheme", [None, "dark_bg"])
def test_numbas_error_highlighting_is_off_unless_the_user_chose_colours(monkeypatch, scheme):
    """``import dustoptics`` turns numba's error-message colouring off (a twentieth of the
    compile time), unless the user chose a colour scheme."""
    if scheme is not None:
        # numba colours its messages only with colorama; without it every scheme is NOP.
        pytest.importorskip("colorama")
    monkeypatch.delenv(_numba_cache.HIGHLIGHTING, raising=False)
    if scheme is None:
        monkeypatch.delenv("NUMBA_COLOR_SCHEME", raising=False)
    else:
        monkeypatch.setenv("NUMBA_COLOR_SCHEME", scheme)
    code = """
        import dustoptics
        import numba.core.errors as errors
        print(type(errors.termcolor()).__name__)
    """
    done = _run(code, None)
    assert done.returncode == 0, done.stderr
    expected = "NOPColorScheme" if scheme is None else "HighlightColorScheme"
    assert done.stdout.strip() == expected
