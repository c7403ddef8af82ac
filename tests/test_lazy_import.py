"""``import dustoptics`` loads its public names on first use (issue 40 item 5)."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

import dustoptics

ROOT = Path(__file__).resolve().parents[1]


def _run(code: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    return subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=False
    )


def test_import_brings_no_numpy_scipy_or_numba():
    done = _run(
        "import sys, dustoptics\n"
        "print(sorted(m for m in ('numpy', 'scipy', 'numba', 'xarray') if m in sys.modules))"
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


@pytest.mark.parametrize("name", dustoptics.__all__)
def test_every_public_name_is_the_defining_modules(name):
    if name == "__version__":
        assert isinstance(dustoptics.__version__, str)
        return
    value = getattr(dustoptics, name)
    module_name = dustoptics._LAZY[name]
    module = importlib.import_module(module_name)
    assert value is (module if name in dustoptics._SUBMODULES else getattr(module, name))


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        dustoptics.no_such_name  # noqa: B018


def test_first_use_registers_the_writer_and_the_fitter(tmp_path):
    """As the eager import did: Table.save and Table.fit work after any public name."""
    path = tmp_path / "t.nc"
    done = _run(
        "import sys, dustoptics as do\n"
        "t = do.compute_optics(1.5 + 0.01j, do.Monodisperse(radius_um=0.5), [550.0], list(range(0, 181, 10)))\n"
        f"t.save({str(path)!r})\n"
        "print(type(t.fit(model='henyey-greenstein')).__name__)"
    )
    assert done.returncode == 0, done.stderr
    assert path.is_file()
    assert done.stdout.strip() == "FitResult"
