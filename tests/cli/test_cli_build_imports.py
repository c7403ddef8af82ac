"""What a ``dustoptics build`` of a table imports: only what it uses (issue 40, warm build).

Each check runs in a fresh interpreter (a module imported by another test would hide
an import).  The modules named here cost a warm build of the default preset CPU time it
did not need (``python -X importtime``): xarray with pandas and dask.array 0.5-0.7 s
(the netCDF writer built an xarray Dataset), scipy.integrate 0.03 s beyond scipy.optimize,
itself 0.2 s (a tabulated density's and a truncated distribution's integrals, and the
bounds of the families without closed-form quantiles, and the engines' fits, whose
module the build's parser loads for their format names), scipy.io 0.04 s (libRadtran's
netCDF files, one format of many).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from _cli import SMALL

import dustoptics

#: Where the dustoptics under test is (the checkout, or the installed wheel the release check
#: tests: the checkout's folder has no data package, the wheel maps it in).
WHERE = Path(dustoptics.__file__).resolve().parents[1]


def _imported(code: str, modules: tuple[str, ...]) -> list[str]:
    """Which of ``modules`` are in sys.modules after ``code`` ran in a new interpreter."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(WHERE), env.get("PYTHONPATH")) if p)
    script = f"{code}\nimport sys\nprint(sorted(m for m in {modules!r} if m in sys.modules))"
    done = subprocess.run(
        [sys.executable, "-c", script],
        env=env,
        cwd=WHERE,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return eval(done.stdout.strip().splitlines()[-1])  # a list of str, printed above


def test_a_table_build_imports_no_xarray_pandas_or_dask(tmp_path):
    config = tmp_path / "small.toml"
    config.write_text(SMALL, encoding="utf-8")
    out = tmp_path / "out"
    code = (
        "from dustoptics.cli import main\n"
        f"assert main(['build', {str(config)!r}, '--out', {str(out)!r}, '--quiet']) == 0"
    )
    unused = ("xarray", "pandas", "dask", "dask.array", "scipy.io", "scipy.optimize")
    assert _imported(code, unused) == []
    assert sorted(p.name for p in (out / "small-dust").iterdir()) == [
        "MieExtinctionSpectrum.csv",
        "MiePhaseFunctionSpectrum.csv",
        "small-dust.nc",
        "table_summary.json",
    ]


def test_a_modified_gamma_table_imports_no_scipy_integrate_or_optimize():
    code = (
        "import dustoptics as do\n"
        "t = do.compute_optics(do.mars_dust(), do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2),\n"
        "    wavelength_nm=[550.0], theta_deg=[0.0, 90.0, 180.0], rtol=1e-3, workers=1)\n"
        "assert t.phase.shape == (1, 3)"
    )
    assert _imported(code, ("scipy.integrate", "scipy.optimize", "xarray")) == []
