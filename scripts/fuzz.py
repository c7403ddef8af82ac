"""Fuzz dustoptics: API calls, TOML configurations, command lines, damaged files, sweeps.

Usage::

    python scripts/fuzz.py                      # the CI budget: seed 0, 5 cases per kind
    python scripts/fuzz.py --cases 200 --seed 7 # a longer search
    python scripts/fuzz.py --kinds api,files    # some kinds only
    python scripts/fuzz.py --kinds sweeps,stores --cases 25 --seed 1   # the sweep families
    python scripts/fuzz.py --kinds kills,bounds,inputs,digests --cases 50 # the files' families
    python scripts/fuzz.py --kinds sizes --cases 60 --seed 1   # headers declaring huge sizes

Kinds: ``api``, ``config``, ``cli``, ``files``, ``sweeps`` (sweep specifications: axes
spelled several ways, huge and refused sizes, by the API and the command line),
``stores`` (a tiny sweep store damaged, held by another run, written by two runs at once or
on a full disk, then checked and resumed), ``kills`` (a table's set killed with SIGKILL at
any step of the writer, then ``info`` and a later write), ``bounds`` (crafted table files,
devices, FIFOs and oversized files given to every reader), ``inputs`` (arguments, TOML,
provenance and texture sidecars that raised tracebacks), ``digests`` (seed-CSV sets
without their checksums, and a process that forks after rendering a sky) and ``retrieve``
(``dustoptics retrieve`` with bounds, priors and options at and beyond their edges, on
observation files good, incomplete, damaged or of another kind) and ``sizes`` (headers
and metadata declaring more than their files hold: Zarr ``.zarray``/``.zmetadata``, a
sweep's netCDF-4 bomb or missing chunks, a sky's and an observation file's netCDF classic
header, KTX2 and EXR headers, and a link to a store, given to ``info`` and to the library's
reader).

Every case runs in a forked process with an address-space limit
(``resource.setrlimit(RLIMIT_AS)``) and a timeout, and with the package's
budgets lowered (memory :data:`CASE_MEMORY_BUDGET`, work
:data:`CASE_WORK_BUDGET`), so that any accepted request is small and fast:
a case that runs past the timeout or out of memory means the cost estimate
let through a request it should have refused.  Outcomes:

- ``ok``: a result (exit status 0 for a command line);
- ``clean``: ValueError, TypeError or FormatError from the API, exit status 1
  or 2 with exactly one line on stderr from the command line;
- anything else is a failure: another exception or a traceback, a hang
  (timeout), a memory blow-up (MemoryError or death by signal), a file
  written outside ``--out``, or a set of files that changed partially when
  the command failed.

The cases are drawn from a seeded :class:`random.Random`, so a seed gives the
same cases on every run; ``tests/test_fuzz.py`` runs the CI budget and
extends it under ``pytest --hypothesis-profile=explore`` (more cases, a seed
from the clock).  It exits 1 if any case failed and prints each failure with
the code that reproduces it.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import random
import resource
import select
import shutil
import signal
import sys
import tempfile
import time
import traceback
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: Memory budget of the package inside a case (instead of 2 GiB). [bytes]
CASE_MEMORY_BUDGET = 256 * 1024**2

#: Work budget inside a case (instead of 1e12: about a second).
CASE_WORK_BUDGET = 2e9

#: Address space a case may add to what the warmed-up parent already maps. [bytes]
CASE_ADDRESS_SPACE = 1536 * 1024**2

#: Seconds before a case counts as a hang.
CASE_TIMEOUT_S = 60.0

KINDS = (
    "api",
    "config",
    "cli",
    "files",
    "sweeps",
    "stores",
    "kills",
    "bounds",
    "inputs",
    "digests",
    "retrieve",
    "sizes",
)


@dataclass(frozen=True)
class Case:
    """One input: a kind, a description that reproduces it, and the call."""

    kind: str
    description: str
    run: Callable[[Path], Any]


@dataclass(frozen=True)
class Outcome:
    case: Case
    status: str  # "ok", "clean" or "failure"
    detail: str
    seconds: float


# ------------------------------------------------------------------ running one case


def _address_space_now() -> int:
    with open("/proc/self/statm") as handle:
        return int(handle.read().split()[0]) * resource.getpagesize()


def _child(case: Case, workdir: Path, write_fd: int) -> None:  # pragma: no cover - runs forked
    import dustoptics._validation as validation
    import dustoptics.io.describe_formats as describe_formats
    import dustoptics.scattering.optics as optics

    validation.MEMORY_BUDGET_BYTES = CASE_MEMORY_BUDGET
    describe_formats.MAX_READ_BYTES = CASE_MEMORY_BUDGET
    optics.WORK_BUDGET = CASE_WORK_BUDGET
    limit = _address_space_now() + CASE_ADDRESS_SPACE
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    os.chdir(workdir)
    from dustoptics.io import FormatError

    try:
        result = case.run(workdir)
        message = {"status": "ok", "detail": repr(result)[:300]}
    except (FormatError, ValueError, TypeError) as exc:
        text = str(exc)
        status = "clean" if text and "Traceback" not in text else "failure"
        message = {"status": status, "detail": f"{type(exc).__name__}: {text[:300]}"}
    except MemoryError:
        message = {"status": "failure", "detail": "MemoryError (beyond the address-space limit)"}
    except BaseException:
        message = {"status": "failure", "detail": traceback.format_exc()[-2000:]}
    with os.fdopen(write_fd, "w") as pipe:
        pipe.write(json.dumps(message))
    os._exit(0)


def run_case(case: Case, *, timeout_s: float = CASE_TIMEOUT_S) -> Outcome:
    """Run ``case`` in a forked process with limits; classify what happened."""
    workdir = Path(tempfile.mkdtemp(prefix="dustoptics-fuzz-"))
    read_fd, write_fd = os.pipe()
    start = time.perf_counter()
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        os.close(read_fd)
        try:
            _child(case, workdir, write_fd)
        finally:
            os._exit(3)
    os.close(write_fd)
    chunks = []
    status, detail = "failure", ""
    deadline = start + timeout_s
    with os.fdopen(read_fd, "r") as pipe:
        while True:
            left = deadline - time.perf_counter()
            if left <= 0:
                os.kill(pid, signal.SIGKILL)
                detail = f"hang: no result within {timeout_s:g} s"
                break
            ready, _, _ = select.select([pipe], [], [], left)
            if ready:
                chunk = pipe.read()
                chunks.append(chunk)
                break
    _, wait_status = os.waitpid(pid, 0)
    seconds = time.perf_counter() - start
    text = "".join(chunks)
    if text:
        message = json.loads(text)
        status, detail = message["status"], message["detail"]
    elif not detail:
        if os.WIFSIGNALED(wait_status):
            detail = f"killed by signal {os.WTERMSIG(wait_status)} (memory blow-up or crash)"
        else:
            detail = f"exited with status {os.waitstatus_to_exitcode(wait_status)} without a result"
    shutil.rmtree(workdir, ignore_errors=True)
    return Outcome(case, status, detail, seconds)


# ------------------------------------------------------------------ command lines


def _snapshot(root: Path) -> dict[str, bytes]:
    out = {}
    for path in sorted(root.rglob("*")):
        if path.is_file() and not path.is_symlink():
            out[str(path.relative_to(root))] = path.read_bytes()
    return out


def run_cli(workdir: Path, argv: list[str], out: str = "out") -> str:
    """Run the command line in ``workdir`` and check the rules a command must keep.

    Raises AssertionError (a failure) on a traceback, an exit status other
    than 0, 1, 2, a failure with other than one stderr line, a file written
    outside ``out``, or an output set changed by a failing command.
    """
    from dustoptics import cli

    before_all = _snapshot(workdir)
    out_dir = workdir / out
    before_out = _snapshot(out_dir) if out_dir.exists() else {}
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        status = cli.main(argv)
    err = stderr.getvalue()
    assert status in (0, 1, 2), f"exit status {status}"
    assert "Traceback" not in err, err
    if status != 0:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("dustoptics: error: "), f"stderr: {err!r}"
    after_all = _snapshot(workdir)
    outside = [
        name
        for name, data in after_all.items()
        if not name.startswith(f"{out}/") and before_all.get(name) != data
    ]
    assert not outside, f"files written outside --out: {outside}"
    if status != 0:
        after_out = _snapshot(out_dir) if out_dir.exists() else {}
        changed = {
            k for k in set(before_out) | set(after_out) if before_out.get(k) != after_out.get(k)
        }
        assert not changed, f"a failing command changed the set: {sorted(changed)}"
        return f"exit {status}: {err.strip()[:200]}"
    return "exit 0"


# ------------------------------------------------------------------ generators

#: Values that have broken numerical code before: edges of the float range,
#: zero, signs, NaN, strings and booleans that Python would take as numbers.
EDGE_NUMBERS: tuple[Any, ...] = (
    0.0,
    -1.0,
    1e-300,
    1e-100,
    1e-30,
    1e-15,
    1e-9,
    1e-4,
    0.3,
    0.4999999,
    0.5,
    1.0,
    2.0,
    10.0,
    1e4,
    1e12,
    1e308,
    float("nan"),
    float("inf"),
    "1.5",
    True,
    None,
    [1.0],
)


def _pick(rng: random.Random, valid: tuple[str, ...], invalid: tuple[str, ...]) -> str:
    return rng.choice(valid) if rng.random() < 0.5 else rng.choice(invalid)


def _number(rng: random.Random, typical: float) -> Any:
    return rng.choice(EDGE_NUMBERS) if rng.random() < 0.5 else typical * rng.uniform(0.5, 2.0)


def api_cases(rng: random.Random, n: int) -> list[Case]:
    """compute_optics, single_sphere and the size distributions with edge values."""
    cases = []
    for _ in range(n):
        choice = rng.randrange(6)
        if choice == 0:
            a, b = _number(rng, 1.0), _number(rng, 0.2)
            code = f"do.ModifiedGamma(r_eff_um={a!r}, v_eff={b!r})"
        elif choice == 1:
            a, b = _number(rng, 1.0), _number(rng, 0.3)
            code = f"do.ModifiedLogNormal(r_eff_um={a!r}, v_eff={b!r})"
        elif choice == 2:
            code = f"do.Monodisperse(radius_um={_number(rng, 0.5)!r})"
        elif choice == 3:
            code = (
                f"do.LogNormal(median_radius_um={_number(rng, 0.5)!r}, sigma={_number(rng, 0.4)!r})"
            )
        elif choice == 4:
            m = complex(
                rng.choice((1.0, 1.5, 2.0, 1e300, 1.0 + 1e-9)), rng.choice((0.0, 1e-300, 0.01, 1.0))
            )
            code = f"mie.single_sphere(m={m!r}, x={_number(rng, 1.0)!r})"
        else:
            code = (
                "do.MultiModal(modes=(do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2), "
                "do.ModifiedGamma(r_eff_um=0.1, v_eff=0.1)), "
                f"relative_number_densities=({_number(rng, 1.0)!r}, {_number(rng, 1.0)!r}))"
            )
        if choice != 4 and rng.random() < 0.8:
            # Each argument valid half of the time, so that some calls compute.
            wl = _pick(
                rng,
                ("[550.0]", "[440.0, 680.0]"),
                ("[0.44, 0.55]", "[1e-3]", "[True]", "[1e9]", "[-1.0]"),
            )
            theta = _pick(
                rng, ("[0.0, 90.0, 180.0]", "[0.0, 180.0]"), ("None", "[180.0, 0.0]", "[]")
            )
            m = _pick(
                rng,
                ("1.5 + 0.01j", "1.5", "2 + 1j"),
                ("1 + 1e-300j", "1e300", "'1.5'", "lambda w: None"),
            )
            weighting = _pick(rng, ("'scattering'", "'number'"), ("['number']", "1", "'Number'"))
            code = f"do.compute_optics({m}, {code}, {wl}, {theta}, rtol=1e-2, weighting={weighting}, workers=1)"
        cases.append(Case("api", code, _evaluator(code)))
    return cases


def _evaluator(code: str) -> Callable[[Path], Any]:
    def run(workdir: Path) -> Any:
        import numpy as np

        import dustoptics as do
        from dustoptics.scattering import mie

        result = eval(
            code, {"do": do, "mie": mie, "np": np, "nan": float("nan"), "inf": float("inf")}
        )
        _check_result(result)
        return result

    return run


def _check_result(result: Any) -> None:
    """A returned table or sphere must hold physical numbers (no silent wrong values)."""
    import numpy as np

    for name in ("qext", "qsca", "cext_um2", "csca_um2", "cabs_um2", "phase"):
        value = getattr(result, name, None)
        if value is not None:
            arr = np.asarray(value)
            assert np.all(np.isfinite(arr)), f"{name} not finite: {arr}"
            assert np.all(arr >= 0), f"{name} negative: {arr}"
    ssa = getattr(result, "ssa", None)
    if ssa is not None:
        assert np.all((np.asarray(ssa) >= 0) & (np.asarray(ssa) <= 1)), f"ssa outside [0, 1]: {ssa}"
    g = getattr(result, "g", None)
    if g is not None:
        assert np.all(np.abs(np.asarray(g)) <= 1), f"|g| > 1: {g}"


SMALL_CONFIG = """\
name = "fuzz"
description = "a small table for the fuzz harness"

[material]
model = "constant"
n = 1.5
k = 0.001

[size_distribution]
model = "modified_gamma"
r_eff_um = 0.5
v_eff = 0.1

[optics]
rtol = 1e-2
wavelengths_nm = [440.0, 550.0, 680.0]
n_theta = 19

[phase]
model = "mie"
"""

#: Keys of :data:`SMALL_CONFIG` and TOML values to put there.
CONFIG_EDITS: tuple[tuple[str, tuple[str, ...]], ...] = (
    (
        'name = "fuzz"',
        (
            'name = "../escaped"',
            'name = "/tmp/abs"',
            'name = "a\\u001b[31m"',
            'name = ""',
            'name = ".."',
        ),
    ),
    (
        "r_eff_um = 0.5",
        (
            "r_eff_um = 1e-300",
            "r_eff_um = 1e308",
            'r_eff_um = "1.5"',
            "r_eff_um = true",
            "r_eff_um = 1000.0",
            "r_eff_um = -1.0",
        ),
    ),
    (
        "v_eff = 0.1",
        ("v_eff = 1e-15", "v_eff = 0.5", "v_eff = 0.0", "v_eff = nan", "v_eff = 0.4999"),
    ),
    (
        "n_theta = 19",
        ("n_theta = 9223372036854775807", "n_theta = 1", "n_theta = 1.5", "n_theta = 100000000"),
    ),
    (
        "wavelengths_nm = [440.0, 550.0, 680.0]",
        (
            "wavelengths_nm = [0.44, 0.55]",
            "wavelengths_nm = []",
            "wavelengths_nm = [true]",
            "wavelengths_nm = { start = 1.0, stop = 1e12, step = 1.0 }",
            "wavelengths_nm = [550.0, 440.0]",
        ),
    ),
    ("k = 0.001", ("k = -1.0", "k = 1e300", "k = inf")),
    ("rtol = 1e-2", ("rtol = 0.0", "rtol = 1e-300", 'rtol = "x"')),
)


def config_cases(rng: random.Random, n: int) -> list[Case]:
    """TOML configurations with one or two values replaced, built by ``dustoptics build``."""
    cases = []
    for _ in range(n):
        text = SMALL_CONFIG
        for key, values in rng.sample(CONFIG_EDITS, rng.choice((1, 2))):
            text = text.replace(key, rng.choice(values))
        formats = rng.choice(("hdf5,csv", "csv", "hdf5,csv,cosmoscout", "texture,glsl"))

        def run(workdir: Path, text: str = text, formats: str = formats) -> str:
            (workdir / "fuzz.toml").write_text(text, encoding="utf-8")
            return run_cli(
                workdir, ["build", "fuzz.toml", "--out", "out", "--quiet", "--format", formats]
            )

        cases.append(Case("config", f"build --format {formats} of:\n{text}", run))
    return cases


CLI_ARGUMENTS: tuple[tuple[str, ...], ...] = (
    ("--resolution-deg", "1e-9"),
    ("--resolution-deg", "0"),
    ("--n-angles", "100000000000"),
    ("--n-angles", "-3"),
    ("--channels-nm", "1e9,2,3"),
    ("--channels-nm", "nan"),
    ("--number-density-per-m3", "1e308"),
    ("--n-altitudes", "9223372036854775807"),
    ("--scale-height-m", "1e-300"),
    ("--format", "nope"),
    ("--format", ""),
    ("--force",),
    ("--sampling", "cos"),
    ("--colour", "cie1931-xyz"),
)


def cli_cases(rng: random.Random, n: int) -> list[Case]:
    """Command lines: export and build with edge option values, over an existing set."""
    cases = []
    for _ in range(n):
        extra = [a for option in rng.sample(CLI_ARGUMENTS, rng.choice((1, 2, 3))) for a in option]
        command = rng.choice(("export", "build"))
        formats = rng.choice(("glsl", "texture", "csv,glsl", "hdf5,csv,texture", "cosmoscout"))

        def run(
            workdir: Path, extra: list[str] = extra, command: str = command, formats: str = formats
        ) -> str:
            table = _small_table()
            from dustoptics.io import write_hdf5

            write_hdf5(table, workdir / "in.h5")
            (workdir / "fuzz.toml").write_text(SMALL_CONFIG, encoding="utf-8")
            # An existing set the command may replace: it must stay whole if the command fails.
            run_cli(workdir, ["export", "in.h5", "--out", "out", "--format", "hdf5,csv", "--quiet"])
            source = "in.h5" if command == "export" else "fuzz.toml"
            argv = [command, source, "--out", "out", "--format", formats, "--quiet", *extra]
            if "--format" in extra:
                argv = [command, source, "--out", "out", "--quiet", *extra]
            return run_cli(workdir, argv)

        cases.append(Case("cli", f"{command} --format {formats} {' '.join(extra)}", run))
    return cases


def _small_table() -> Any:
    import dustoptics as do

    return do.compute_optics(
        1.5 + 0.01j,
        do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1),
        [440.0, 550.0, 680.0],
        [0.0, 45.0, 90.0, 135.0, 180.0],
        rtol=1e-2,
        workers=1,
        name="fuzz",
    )


def _damage(rng: random.Random, data: bytes) -> tuple[bytes, str]:
    kind = rng.randrange(7)
    if kind == 0 and data:
        i = rng.randrange(len(data))
        return data[:i] + bytes([data[i] ^ (1 << rng.randrange(8))]) + data[
            i + 1 :
        ], f"bit flip at {i}"
    if kind == 1:
        i = rng.randrange(len(data) + 1)
        return data[:i], f"truncated to {i} bytes"
    if kind == 2:
        return b"\n" * rng.choice((1, 5, 1000)), "blank lines"
    if kind == 3:
        return b"a," + b"9" * (200 * 1024) + b"\n", "a 200 KiB cell"
    if kind == 4:
        depth = rng.choice((100, 10_000, 100_000))
        return b"[" * depth + b"]" * depth, f"JSON nested {depth} deep"
    if kind == 5:
        return data.replace(b"fuzz", b"\x1b]0;pwned\x07\x1b[2J"), "escape sequences in the name"
    return data + data, "doubled"


def files_cases(rng: random.Random, n: int) -> list[Case]:
    """Damaged or crafted files given to every reader, and to ``info`` and ``export``."""
    cases = []
    for _ in range(n):
        target = rng.choice(
            (
                "MiePhaseFunctionSpectrum.csv",
                "MieExtinctionSpectrum.csv",
                "table_summary.json",
                "fuzz_phase_theta.json",
                "fuzz_phase_theta.raw",
                "ozone.csv",
                "fuzz.h5",
                "FIFO",
                "/dev/zero",
            )
        )
        seed = rng.randrange(2**32)

        def run(workdir: Path, target: str = target, seed: int = seed) -> str:
            from dustoptics.atmosphere.gases import read_ozone_csv
            from dustoptics.io import (
                read_seed_csv,
                read_texture,
                write_hdf5,
                write_seed_csv,
                write_texture,
            )

            table = _small_table()
            d = workdir / "set"
            write_seed_csv(table, d)
            write_texture(table, d)
            write_hdf5(table, d / "fuzz.h5")
            (d / "ozone.csv").write_text(
                "# a citation\nwavelength_nm,sigma_m2\n500,1e-25\n600,2e-25\n"
            )
            local = random.Random(seed)
            if target == "FIFO":
                os.mkfifo(d / "ozone.csv.fifo")
                path = d / "ozone.csv.fifo"
            elif target == "/dev/zero":
                path = Path("/dev/zero")
            else:
                matches = sorted(d.glob(target if "*" in target else f"*{target}")) or [d / target]
                path = matches[0]
                data, _ = _damage(local, path.read_bytes() if path.exists() else b"")
                path.write_bytes(data)
            results = []
            for reader in (read_seed_csv, read_texture, read_ozone_csv):
                arg = (
                    d
                    if reader is read_seed_csv
                    else (
                        path
                        if reader is read_ozone_csv or path.suffix == ".json"
                        else d / "fuzz_phase_theta.json"
                    )
                )
                try:
                    reader(arg)
                    results.append(f"{reader.__name__}: read")
                except (ValueError, TypeError, FileNotFoundError) as exc:
                    assert str(exc), f"{reader.__name__}: an empty message"
                    results.append(f"{reader.__name__}: {type(exc).__name__}")
            results.append(
                run_cli(workdir, ["info", str(path if path.suffix in (".h5", ".json") else d)])
            )
            results.append(
                run_cli(workdir, ["export", str(d / "fuzz.h5"), "--out", "out", "--format", "csv"])
            )
            return "; ".join(results)

        cases.append(Case("files", f"damaged {target} (seed {seed})", run))
    return cases


# ------------------------------------------------------------------ sweeps and their stores

#: Sweep axes over :data:`SMALL_CONFIG`: how each is spelled (canonical, with
#: whitespace or a newline, with a leading zero in an index) and what it takes.
SWEEP_SPELLINGS: tuple[str, ...] = (
    "size_distribution.r_eff_um",
    "size_distribution.r_eff_um\n",
    " size_distribution . r_eff_um ",
    "size_distribution.v_eff",
    "size_distribution.v_eff\t",
    "material.n",
    "material.k",
    "optics.rtol",
)
SWEEP_VALUES: tuple[Any, ...] = (
    [0.4, 0.6],
    [0.5],
    {"start": 0.3, "stop": 0.6, "num": 2},
    {"start": 0.3, "stop": 0.6, "num": 10**9},
    {"start": 0.3, "stop": 0.6, "num": 10**30},
    {"start": 0.3, "stop": 0.6, "num": 0},
    {"start": 0.3, "stop": 0.6, "num": 2.5},
    {"start": 0.3, "stop": 0.6, "num": True},
    {"start": 0.3, "stop": 0.6},
    [2000.0],
    [0.5, 0.5],
    [10**400],
    [],
    "0.5",
    [True],
    [float("nan")],
)

#: ``[sweep]`` tables for :data:`SMALL_CONFIG` (TOML), and whether each is refused.
SWEEP_TABLES: tuple[tuple[str, bool], ...] = (
    ('"size_distribution.r_eff_um" = [0.4, 0.6]\nsize_distribution.r_eff_um = [0.5, 0.7]\n', True),
    ('"size_distribution.modes[01].r_eff_um" = [0.4]\n', True),
    ("size_distribution.r_eff_um = { start = 0.3, stop = 0.6, num = 1000000000 }\n", True),
    ('size_distribution.r_eff_um = [2000.0]\n"size_distribution.v_eff" = [0.1]\n', True),
    ("material = [1.5]\n", True),
    ("x = " + "[" * 3000 + "]" * 3000 + "\n", True),
    ("size_distribution = { r_eff_um = [0.4, 0.5], v_eff = [0.1, 0.2] }\n", False),
    ('"size_distribution.r_eff_um" = [0.4, 0.6]\n', False),
)


def _canonical_axes_checked(spec: Any) -> str:
    """A spec that loaded: its axes are canonical and each names one input."""
    from dustoptics.sweep.spec import canonical_key

    keys = [a.key for a in spec.axes]
    assert len(set(keys)) == len(keys), f"two axes name one input: {keys}"
    assert all(canonical_key(k) == k for k in keys), f"axis names not canonical: {keys}"
    return f"{len(keys)} axes, {spec.n_points} points"


def _threads_client() -> Any:
    """A cluster of threads in this (forked) process and its client, to close."""
    from distributed import Client

    from dustoptics.sweep import local_cluster

    cluster = local_cluster(1, threads=2, processes=False)
    return cluster, Client(cluster)


def _timed_refusal(call: Callable[[], Any], limit_s: float = 20.0) -> Any:
    """``call()``, which must return or refuse within ``limit_s`` (before any work; a
    million points took minutes to validate, a loaded 2-core machine takes seconds)."""
    start = time.perf_counter()
    try:
        return call()
    finally:
        seconds = time.perf_counter() - start
        assert seconds < limit_s, f"took {seconds:.1f} s to validate"


def sweeps_cases(rng: random.Random, n: int) -> list[Case]:
    """Sweep specifications (issue 29 items 3, 4): axes spelled several ways, sizes up
    to 10**30 points, values a single build refuses, ``[sweep]`` tables with a quoted
    and a bare key for one input; by the API (``load_sweep``, a tiny ``sweep`` when it
    loads) and the command line.  An accepted sweep must have canonical, distinct axes,
    and every refusal must come before any work, within seconds."""
    cases = []
    for _ in range(n):
        route = rng.choice(("api", "api", "table", "cli"))
        if route == "api":
            over = {
                rng.choice(SWEEP_SPELLINGS): rng.choice(SWEEP_VALUES)
                for _ in range(rng.choice((1, 2, 2, 3)))
            }
            compute = rng.random() < 0.3

            def run(workdir: Path, over: dict = over, compute: bool = compute) -> str:
                from dustoptics.sweep import load_sweep, sweep

                spec = _timed_refusal(lambda: load_sweep(SMALL_CONFIG, over))
                result = _canonical_axes_checked(spec)
                if compute and spec.n_points <= 4:
                    cluster, client = _threads_client()
                    with cluster, client:
                        ds = sweep(SMALL_CONFIG, over, out="s.zarr", client=client, progress=None)
                        assert list(ds.phase.dims[:-2]) == [a.key for a in spec.axes]
                        _check_result(ds.load())
                    result += ", computed"
                return result

            cases.append(Case("sweeps", f"load_sweep(SMALL_CONFIG, {over!r})", run))
        else:
            table, refused = rng.choice(SWEEP_TABLES)
            text = SMALL_CONFIG + "\n[sweep]\n" + table
            if route == "table" or not refused:  # the command line only where it refuses

                def run(workdir: Path, text: str = text) -> str:
                    from dustoptics.sweep import load_sweep

                    return _canonical_axes_checked(_timed_refusal(lambda: load_sweep(text)))

                cases.append(Case("sweeps", f"load_sweep of [sweep]:\n{table[:200]}", run))
            else:

                def run(workdir: Path, text: str = text) -> str:
                    (workdir / "fuzz.toml").write_text(text, encoding="utf-8")
                    argv = ["sweep", "fuzz.toml", "--out", "out/s.zarr"]
                    return _timed_refusal(lambda: run_cli(workdir, argv))

                cases.append(Case("sweeps", f"dustoptics sweep of [sweep]:\n{table[:200]}", run))
    return cases


#: What happens to a finished store before a run resumes it (issue 29 items 1, 2, 7).
STORE_EVENTS = (
    "flip a byte",
    "delete a file",
    "truncate a file",
    "garbage in a marker",
    "a marker replaced by a folder",
    "garbage in .zmetadata",
    "another run holds the store",
    "two runs start at once",
    "a full disk while writing a chunk",
)


def stores_cases(rng: random.Random, n: int) -> list[Case]:
    """A tiny store (2 points x 3 wavelengths), then damage or a concurrent run, then
    ``verify_store`` and a resume: each must give the undamaged values or a one-line
    error (FormatError, StoreBusyError), never a traceback or a wrong value."""
    cases = []
    for _ in range(n):
        event = rng.choice(STORE_EVENTS)
        seed = rng.randrange(2**32)

        def run(workdir: Path, event: str = event, seed: int = seed) -> str:
            return _store_case(workdir, event, random.Random(seed))

        cases.append(Case("stores", f"{event} (seed {seed})", run))
    return cases


def _store_case(workdir: Path, event: str, local: random.Random) -> str:
    import errno
    import threading

    import numpy as np
    import xarray as xr

    from dustoptics.io._atomic import held_lock
    from dustoptics.sweep import run as sweep_run
    from dustoptics.sweep import sweep, verify_store
    from dustoptics.sweep.store import StoreBusyError

    over = {"size_distribution.r_eff_um": [0.4, 0.6]}
    cluster, client = _threads_client()
    with cluster, client:

        def go(out: Path, axes: dict = over) -> Any:
            return sweep(
                SMALL_CONFIG, axes, out=out, client=client, chunk_wavelengths=1, progress=None
            )

        reference = go(workdir / "reference.zarr").load()
        store = workdir / "s.zarr"
        shutil.copytree(workdir / "reference.zarr", store)
        files = sorted(p for p in store.rglob("*") if p.is_file())
        path = local.choice(files)
        outcome = event
        if event == "flip a byte" and path.stat().st_size:
            data = bytearray(path.read_bytes())
            data[local.randrange(len(data))] ^= 1 << local.randrange(8)
            path.write_bytes(bytes(data))
            outcome += f" in {path.relative_to(store)}"
        elif event == "delete a file":
            path.unlink()
            outcome += f" {path.relative_to(store)}"
        elif event == "truncate a file":
            path.write_bytes(path.read_bytes()[: local.randrange(path.stat().st_size + 1)])
            outcome += f" {path.relative_to(store)}"
        elif event == "garbage in a marker":
            marker = local.choice(sorted((store / "sweep-done").iterdir()))
            marker.write_bytes(
                local.choice((b"", b"\xff\xfe", b"[" * 100_000, b'{"chunk": [0, 0]}'))
            )
        elif event == "a marker replaced by a folder":
            marker = local.choice(sorted((store / "sweep-done").iterdir()))
            marker.unlink()
            marker.mkdir()
        elif event == "garbage in .zmetadata":
            (store / ".zmetadata").write_bytes(b"{not json")
        elif event == "another run holds the store":
            before = {p: p.read_bytes() for p in files}
            with held_lock(store) as fd:
                assert fd is not None
                try:
                    go(store)
                except StoreBusyError:
                    pass
                else:
                    raise AssertionError("a held store was not refused")
            assert {p: p.read_bytes() for p in files} == before, "the refused run changed it"
            return outcome + ": refused, the store untouched"
        elif event == "two runs start at once":
            fresh = workdir / "two.zarr"
            other = {"size_distribution.r_eff_um": [0.45, 0.65]}
            errors: list[BaseException] = []

            def second() -> None:
                try:
                    go(fresh, other)
                except (StoreBusyError, ValueError) as exc:
                    errors.append(exc)

            thread = threading.Thread(target=second)
            thread.start()
            try:
                go(fresh)
            except (StoreBusyError, ValueError) as exc:
                errors.append(exc)
            thread.join()
            assert len(errors) <= 1, f"both runs failed: {errors}"
            verify_store(fresh)
            return outcome + f": {len(errors)} refused, the store whole"
        elif event == "a full disk while writing a chunk":
            fresh = workdir / "full.zarr"
            write = sweep_run._write_chunk
            calls: list[str] = []

            def full(store: Path, region: Any, name: str, result: Any) -> None:
                calls.append(name)
                if len(calls) > local.randrange(3):
                    raise OSError(errno.ENOSPC, "No space left on device", str(store))
                write(store, region, name, result)

            sweep_run._write_chunk = full
            try:
                go(fresh)
            except OSError as exc:
                assert exc.errno == errno.ENOSPC and "\n" not in str(exc), repr(exc)
            finally:
                sweep_run._write_chunk = write
            store = fresh
            outcome += f" after {len(calls) - 1} chunks"
        try:
            verify_store(store)
            outcome += ": verified"
        except ValueError as exc:
            assert "\n" not in str(exc) and str(store) in str(exc), str(exc)
            outcome += ": verify refused"
        ds = go(store).load()  # a FormatError here (damage at creation) is a clean refusal
        verify_store(store)
        for name in ("phase", "cext_um2", "g"):
            assert np.array_equal(ds[name].values, reference[name].values), f"{name} differs"
        assert isinstance(ds, xr.Dataset)
        return outcome + ", resumed to the undamaged values"


def _warm_up_sweeps() -> None:
    """Load the shared solver's kernels, Dask and the command line once, before the
    cases fork."""
    try:
        import distributed  # noqa: F401
        import xarray  # noqa: F401
        import zarr  # noqa: F401

        import dustoptics.cli
        from dustoptics.sweep.shared import solve_shared
    except ImportError:
        return
    import numpy as np

    import dustoptics as do
    from dustoptics.scattering.quadrature import QuadratureSettings

    solve_shared(
        m=1.5 + 0.001j,
        wavelength_nm=550.0,
        mu_out=np.cos(np.deg2rad(np.linspace(0.0, 180.0, 19))),
        distributions=[do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1)],
        per_particle=False,
        settings=QuadratureSettings(),
        rtol=1e-2,
        cross_rtol=1e-4,
    )


# ------------------------------------------------------------------ kill -9, bounds, inputs, digests


#: How a set is written when the writer is killed (issue 29 item 5).
KILL_ROUTES = ("replace a set", "a new set", "another run after the killed one")


def kills_cases(rng: random.Random, n: int) -> list[Case]:
    """A table's files (``place_table``, as ``dustoptics build`` writes them) killed with
    SIGKILL at a random step of the writer; then ``info`` must refuse the set or describe
    it whole (the old or the new files, never a mix), and after a later write into the
    folder (an unrelated file, or another run with ``force``) the set must be one run's,
    whole: the killed run's if it had begun to publish, else the old one."""
    cases = []
    for _ in range(n):
        route = rng.choice(KILL_ROUTES)
        step = rng.randrange(64)
        formats = rng.choice((("hdf5", "csv"), ("hdf5", "csv", "texture", "glsl"), ("csv",)))

        def run(
            workdir: Path, route: str = route, step: int = step, formats: tuple = formats
        ) -> str:
            return _kill_case(workdir, route, step, formats)

        cases.append(Case("kills", f"{route}, killed at step {step}, formats {formats}", run))
    return cases


def _kill_case(workdir: Path, route: str, step: int, formats: tuple[str, ...]) -> str:
    from dustoptics.io import _atomic
    from dustoptics.io._atomic import whole_set, write_files
    from dustoptics.io.outputs import place_table, with_inputs

    base = _small_table()
    old, new, third = (with_inputs(base, run=k) for k in ("old", "new", "third"))

    def files(table: Any, where: Path) -> dict[str, bytes]:
        place_table(table, where, formats, force=True)
        return _snapshot(where / "fuzz")

    expect = {k: files(t, workdir / f"ref-{k}") for k, t in (("old", old), ("new", new))}
    out, scratch = workdir / "out", workdir / "scratch"
    if route != "a new set":
        place_table(old, out, formats)
        shutil.copytree(out, scratch)
    # The steps of the same write on a copy (files that are already the same are not moved).
    seen: list[str] = []
    _atomic._STEP_HOOK = seen.append
    try:
        place_table(new, scratch, formats, force=True)
    finally:
        _atomic._STEP_HOOK = None
    k = step % len(seen)
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the killed writer
        count = iter(range(10**6))

        def hook(name: str) -> None:
            if next(count) == k:
                os.kill(os.getpid(), signal.SIGKILL)

        _atomic._STEP_HOOK = hook
        try:
            place_table(new, out, formats, force=True)
        finally:
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert os.WIFSIGNALED(status), f"the writer was not killed at step {k} ({seen[k]})"
    folder = out / "fuzz"
    whole = (
        {"old": expect["old"], "new": expect["new"]}
        if route != "a new set"
        else {"new": expect["new"]}
    )

    def state() -> str:
        present = _snapshot(folder) if folder.exists() else {}
        present = {n: d for n, d in present.items() if not n.startswith(".") and n != "notes.txt"}
        if not present:
            return ""
        for label, wanted in whole.items():
            if present == wanted:
                return label
        raise AssertionError(f"a mixed or partial set after a kill at {seen[k]!r}")

    try:
        with whole_set(folder if folder.exists() else out):
            before = state()
        assert run_cli(workdir, ["info", str(folder)]) == "exit 0" or not before
    except ValueError as exc:
        assert "interrupted write" in str(exc), str(exc)
        assert run_cli(workdir, ["info", str(folder)]).startswith("exit 1")
        before = "refused"
    # The last journal is the placement's (the formats are rendered by a write of their own).
    publishing = len(seen) - 1 - seen[::-1].index("journal")
    killed_run = "new" if k >= publishing else ("old" if route != "a new set" else "")
    if route == "another run after the killed one":
        place_table(third, out, formats, force=True)
        assert _snapshot(folder) == files(third, workdir / "ref-third"), "not the last run's set"
        return f"killed at {seen[k]!r}: {before or 'nothing'}; the next run's set whole"
    write_files({folder / "notes.txt": b"an unrelated write\n"})
    after = state()
    assert after == killed_run, f"killed at {seen[k]!r}: {after!r}, expected {killed_run!r}"
    if after:
        assert run_cli(workdir, ["info", str(folder)]) == "exit 0"
    return f"killed at {seen[k]!r}: {before or 'nothing'}, then {after or 'nothing'}"


#: Files that must be refused within bounds (issue 29 item 6): what, and how it is made.
BOUND_INPUTS = (
    "a table declaring chunks never written",
    "a table with an unknown filter",
    "a table of zeros compressed at deflate's limit",
    "/dev/zero",
    "a FIFO",
    "a sparse 100 MiB file",
    "a 200 KiB CSV cell",
)
#: The readers each input is given to.
BOUND_READERS = ("open_table", "info", "size table", "index table", "ozone table", "seed CSV")


def bounds_cases(rng: random.Random, n: int) -> list[Case]:
    """Crafted or special files given to the readers: each must answer (a clean error)
    within the case's memory limit and timeout, never read a FIFO or a device."""
    cases = []
    for _ in range(n):
        what, reader = rng.choice(BOUND_INPUTS), rng.choice(BOUND_READERS)

        def run(workdir: Path, what: str = what, reader: str = reader) -> str:
            return _bounds_case(workdir, what, reader)

        cases.append(Case("bounds", f"{what} given to {reader}", run))
    return cases


def _bounds_case(workdir: Path, what: str, reader: str) -> str:
    import h5py
    import numpy as np

    from dustoptics.atmosphere.gases import read_ozone_csv
    from dustoptics.io import open_table, read_seed_csv, write_hdf5
    from dustoptics.particles.custom_sizedist import TabulatedDistribution
    from dustoptics.particles.materials import read_index_csv

    path = workdir / "input.h5"
    if what.startswith("a table"):
        write_hdf5(_small_table(), path)
        with h5py.File(path, "r+") as f:
            if what == "a table with an unknown filter":
                values = f["g"][()]
                del f["g"]
                f.create_dataset("g", data=values, chunks=(3,), compression="lzf")
            else:
                n = 1 << 23
                for key in ("theta_deg", "phase"):
                    del f[key]
                f.create_dataset(
                    "theta_deg", shape=(n,), dtype="<f8", chunks=(1 << 16,), compression="gzip"
                )
                f["theta_deg"].attrs["units"] = "degree"
                phase = f.create_dataset(
                    "phase", shape=(3, n), dtype="<f8", chunks=(1, 1 << 16), compression="gzip"
                )
                phase.attrs["units"] = "sr-1"
                if what.startswith("a table of zeros"):
                    f["theta_deg"][...] = np.arange(n, dtype="<f8") * (180.0 / n)
                    phase[...] = 0.0
    elif what == "/dev/zero":
        path = Path("/dev/zero")
    elif what == "a FIFO":
        path = workdir / "input.csv"
        os.mkfifo(path)
    elif what == "a sparse 100 MiB file":
        path = workdir / "input.csv"
        with open(path, "wb") as handle:
            handle.truncate(100 * 1024**2)
    else:
        path = workdir / "input.csv"
        path.write_bytes(b"a," + b"9" * (200 * 1024) + b"\n")
    if reader == "info":
        return run_cli(workdir, ["info", str(path)])
    if reader == "seed CSV":
        d = workdir / "seed"
        d.mkdir()
        (d / "table_summary.json").write_text("{}")
        target = d / "MiePhaseFunctionSpectrum.csv"
        target.symlink_to(path)
        call: Callable[[], Any] = lambda: read_seed_csv(d)  # noqa: E731
    else:
        call = {
            "open_table": lambda: open_table(path),
            "size table": lambda: TabulatedDistribution.from_csv(path),
            "index table": lambda: read_index_csv(path),
            "ozone table": lambda: read_ozone_csv(path),
        }[reader]
    start = time.perf_counter()
    try:
        call()
    except (ValueError, TypeError, FileNotFoundError) as exc:
        assert str(exc) and "\n" not in str(exc), repr(exc)
        return f"{type(exc).__name__} in {time.perf_counter() - start:.2f} s: {str(exc)[:120]}"
    raise AssertionError(f"{reader} read {what}")


#: Inputs that raised a traceback before issue 29 (item 7): API calls and command lines.
INPUT_CALLS: tuple[str, ...] = (
    "do.MultiModal(modes=None, relative_number_densities=(1.0,))",
    "do.MultiModal(modes=3, relative_number_densities=(1.0,))",
    "do.MultiModal(modes='abc', relative_number_densities=(1.0,))",
    "do.compute_optics(1.5, do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2).truncated(r_min_um=0.5),"
    " [550.0], [0.0, 90.0, 180.0], rtol=1e-2, workers=1)",
    "do.compute_optics(1.5, do.ModifiedGamma(r_eff_um=1.0, v_eff=0.2).truncated(r_min_um=0.5,"
    " r_max_um=None), [550.0], [0.0, 180.0], rtol=1e-2, workers=1).save('t.nc')",
    "Medium.from_atmosphere(earth, n_radii=1)",
    "Medium.from_atmosphere(earth, n_mu=1)",
    "Medium.from_atmosphere(earth, n_mu=10**9)",
    "small().replace(name='a\\x00b').save('t.nc')",
    "small().replace(name='a\\ud800b').save('t.nc')",
    "small().replace(provenance=Provenance(sources=(Source('s', 'r', 'c\\x00'),))).save('t.nc')",
    "small().replace(provenance=Provenance(sources=(Source('s', 'r', '\\udfff'),))).save('t.h5')",
)
#: TOML edits of :data:`SMALL_CONFIG` built by ``dustoptics build``.
INPUT_TOML: tuple[tuple[str, str], ...] = (
    ("r_eff_um = 0.5", "r_eff_um = 1" + "0" * 400),
    ("r_eff_um = 0.5", "r_eff_um = 1" + "0" * 5000),
    ("n_theta = 19", "n_theta = 19\nx = " + "[" * 3000 + "]" * 3000),
    ("k = 0.001", "k = -1" + "0" * 400),
    ("wavelengths_nm = [440.0, 550.0, 680.0]", "wavelengths_nm = [440.0, 1" + "0" * 400 + "]"),
)
#: Entries of a texture sidecar replaced by values of another type (then info, read_texture).
SIDECAR_DAMAGE: tuple[tuple[str, Any], ...] = (
    ("shape", [1e400]),
    ("shape", ["3", 721]),
    ("shape", [10**30, 10**30]),
    ("file", 7),
    ("file", "a\x00b.raw"),
    ("axes", "values"),
    ("axes", [{"values": [[1.0]] * 3}, {"values": []}]),
    ("provenance", None),
    ("provenance", {"inputs": "x"}),
    ("table", ["a"]),
    ("sphere_integral_of_samples", ["one"]),
    ("sampling", ["theta"]),
    ("dtype", {"a": 1}),
    ("format", "dustoptics-phase-texture/2"),
)


def inputs_cases(rng: random.Random, n: int) -> list[Case]:
    """What raised a traceback before issue 29: odd API arguments, TOML deep or huge, a
    table file whose provenance is nested 100,000 deep (info, export), a damaged texture
    sidecar (info, read_texture).  Every one must be a result or a one-line error."""
    cases = []
    for _ in range(n):
        route = rng.choice(("api", "toml", "provenance", "sidecar"))
        if route == "api":
            code = rng.choice(INPUT_CALLS)
            cases.append(Case("inputs", code, _inputs_evaluator(code)))
        elif route == "toml":
            key, value = rng.choice(INPUT_TOML)
            text = SMALL_CONFIG.replace(key, value)

            def run_toml(workdir: Path, text: str = text) -> str:
                (workdir / "fuzz.toml").write_text(text, encoding="utf-8")
                return run_cli(workdir, ["build", "fuzz.toml", "--out", "out", "--quiet"])

            cases.append(Case("inputs", f"build with {value[:60]!r}", run_toml))
        elif route == "provenance":
            depth = rng.choice((33, 1000, 100_000))
            command = rng.choice(("info", "export"))

            def run_deep(workdir: Path, depth: int = depth, command: str = command) -> str:
                import h5py

                from dustoptics.io import write_hdf5
                from dustoptics.io.tables.netcdf import DIGEST_ATTRIBUTE, dataset_digest

                path = write_hdf5(_small_table(), workdir / "deep.h5")
                with h5py.File(path, "r+") as f:
                    f.attrs["provenance"] = "[" * depth + "]" * depth
                    skip = {"CLASS", "NAME", "DIMENSION_LIST", "REFERENCE_LIST", "_Netcdf4Dimid"}
                    variables = {
                        k: (f[k][()], {a: _text(v) for a, v in f[k].attrs.items() if a not in skip})
                        for k in f
                    }
                    attrs = {a: _text(v) for a, v in f.attrs.items()}
                    f.attrs[DIGEST_ATTRIBUTE] = dataset_digest(variables, attrs)
                argv = (
                    ["info", str(path)]
                    if command == "info"
                    else ["export", str(path), "--out", "out", "--format", "csv"]
                )
                return run_cli(workdir, argv)

            cases.append(
                Case("inputs", f"{command} of a table with provenance {depth} deep", run_deep)
            )
        else:
            key, value = rng.choice(SIDECAR_DAMAGE)

            def run_sidecar(workdir: Path, key: str = key, value: Any = value) -> str:
                from dustoptics.io import read_texture, write_texture

                _, side = write_texture(_small_table(), workdir / "tex")
                meta = json.loads(side.read_text())
                meta[key] = value
                side.write_text(json.dumps(meta))
                result = run_cli(workdir, ["info", str(side)])
                try:
                    read_texture(side)
                except ValueError as exc:
                    assert "\n" not in str(exc), repr(exc)
                    return result + f"; read_texture: {str(exc)[:100]}"
                return result + "; read_texture: read"

            cases.append(Case("inputs", f"texture sidecar with {key} = {value!r:.60}", run_sidecar))
    return cases


def _text(value: Any) -> Any:
    return value.decode() if isinstance(value, bytes) else value


def _inputs_evaluator(code: str) -> Callable[[Path], Any]:
    def run(workdir: Path) -> Any:
        import numpy as np

        import dustoptics as do
        from dustoptics.atmosphere.sets import earth_atmosphere
        from dustoptics.sky.medium import Medium
        from dustoptics.table import Provenance, Source

        def small() -> Any:
            return do.Table(
                wavelength_nm=np.array([550.0]),
                theta_deg=np.array([0.0, 180.0]),
                phase=np.full((1, 2), 1 / (4 * np.pi)),
                g=np.array([0.0]),
            )

        names = {"do": do, "Medium": Medium, "Provenance": Provenance, "Source": Source}
        names.update(small=small, earth=earth_atmosphere(wavelength_nm=[440.0, 550.0]))
        result = eval(code, names)
        _check_result(result)
        return result

    return run


def digests_cases(rng: random.Random, n: int) -> list[Case]:
    """Seed-CSV sets whose ``sha256`` entries were deleted and whose phase file may be cut
    (issue 29 item 9): refused unless ``verify=False``, and then a cut file still refused;
    and a process that has rendered a sky forks, the child renders again (the harness
    selects numba's fork-safe threading layer, as a program that forks must)."""
    cases = []
    for _ in range(n):
        if rng.random() < 0.2:
            cases.append(Case("digests", "a sky rendered, then a fork renders again", _sky_fork))
            continue
        deleted = rng.choice(((), ("phase",), ("extinction",), ("phase", "extinction")))
        cut = rng.choice((None, 2, 3, 5))  # the phase file has 6 lines

        def run(workdir: Path, deleted: tuple = deleted, cut: int | None = cut) -> str:
            return _digest_case(workdir, deleted, cut)

        cases.append(Case("digests", f"sha256 of {deleted or 'none'} deleted, cut at {cut}", run))
    return cases


def _digest_case(workdir: Path, deleted: tuple[str, ...], cut: int | None) -> str:
    from dustoptics.io import read_seed_csv, write_seed_csv
    from dustoptics.io.csv.seed import EXTINCTION_FILENAME, PHASE_FILENAME, SUMMARY_FILENAME

    d = workdir / "set"
    write_seed_csv(_small_table(), d)
    summary = json.loads((d / SUMMARY_FILENAME).read_text())
    for name in deleted:
        del summary["files"][PHASE_FILENAME if name == "phase" else EXTINCTION_FILENAME]["sha256"]
    (d / SUMMARY_FILENAME).write_text(json.dumps(summary))
    if cut is not None:
        path = d / PHASE_FILENAME
        path.write_text("".join(path.read_text().splitlines(keepends=True)[:cut]))
    info = run_cli(workdir, ["info", str(d)])
    try:
        read_seed_csv(d)
        assert not deleted and cut is None, "read as valid"
        return info
    except ValueError as exc:
        assert deleted or cut is not None, repr(exc)
    if cut is not None:
        try:
            read_seed_csv(d, verify=False)
        except ValueError:
            return info + "; refused, also unchecked"
        raise AssertionError(f"a phase file cut at line {cut} read as a table with verify=False")
    return info + "; refused"


def _sky_fork(workdir: Path) -> str:
    import numpy as np

    from dustoptics.atmosphere.sets import earth_atmosphere
    from dustoptics.sky.scene import sky_radiance

    atmosphere = earth_atmosphere(wavelength_nm=[440.0, 550.0, 680.0])

    def render() -> float:
        sky = sky_radiance(
            atmosphere,
            sun_elevation_deg=60.0,
            view_zenith_deg=np.array([0.0, 45.0]),
            azimuth_step_deg=45.0,
        )
        return float(sky.at(0.0, 0.0)[0])

    first = render()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the forked child
        try:
            os._exit(0 if render() == first else 5)
        finally:
            os._exit(4)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0, f"the forked child: status {status}"
    return "the forked child rendered the same sky"


#: Options of ``dustoptics retrieve``: the fitted parameter first (one is always given).
RETRIEVE_FITS: tuple[str, ...] = (
    "r_eff_um=0.1:3",
    "r_eff_um=0.1:3",
    "k=0:0.05",
    "r_eff_um=-1:3",
    "r_eff_um=0.1:inf",
    "r_eff_um=nan:3",
    "r_eff_um=0.1:3000",
    "v_eff=0.01:0.9",
    "k=-1:0.05",
    "bogus=0:1",
    "r_eff_um",
    "r_eff_um=3:0.1",
)
RETRIEVE_ARGUMENTS: tuple[tuple[str, ...], ...] = (
    ("--fit", "v_eff=0.02:0.4"),
    ("--fit", "r_eff_um=0.2:2"),
    ("--prior", "r_eff_um=0.5,0.1"),
    ("--prior", "r_eff_um=0.5,-1"),
    ("--prior", "k=nan,1"),
    ("--prior", "v_eff=0.1,0.05"),
    ("--max-iterations", "0"),
    ("--max-iterations", "3"),
    ("--max-iterations", "99999999999999999999"),
    ("--sky-streams", "1"),
    ("--sky-tol", "0"),
    ("--allow-large",),
    ("--force",),
    ("--max-observation-bytes", "100"),
    ("--max-observation-bytes", "0"),
    ("--max-observation-bytes", "1e9"),
)
#: Observation files: what each holds.
RETRIEVE_FILES: tuple[str, ...] = (
    "ssa",
    "ssa",
    "ratio",
    "phase",
    "ssa_nan",
    "ssa_without_uncertainty",
    "empty",
    "sky_bad_scene",
    "wrong_dimension",
    "text",
    "damaged",
    "missing",
    "phase_nan_theta",
    "phase_inf_theta",
    "ratio_nan_reference",
    "ratio_zero_reference",
    "ratio_text_reference",
    "zero_wavelength",
    "text_wavelength",
    "wavelength_in_um",
    "text_values",
    "huge_uncertainty",
    "declared_huge",
    "many_wavelengths",
)
#: The ``--model`` of a case: the small dust's TOML mostly, a device or a FIFO sometimes.
RETRIEVE_MODELS: tuple[str, ...] = ("fuzz.toml",) * 6 + ("/dev/zero", "fifo.toml", "missing.toml")
#: Where ``--out`` goes: the usual place mostly, over an input sometimes (with --force).
RETRIEVE_OUTS: tuple[tuple[str, ...], ...] = (("out/fit.json",),) * 6 + (
    ("obs.nc", "--force"),
    ("fuzz.toml", "--force"),
)
#: Bounds given to the library's retrieve: what a caller may pass by mistake.
RETRIEVE_API_BOUNDS: tuple[Any, ...] = (
    (0.1, 3.0),
    (0.1,),
    (),
    (0.1, 3.0, 5.0),
    "0.1:3",
    None,
    ("0.1", 3.0),
    (True, 3.0),
    (float("nan"), 3.0),
    [0.1, 3.0],
    {"lower": 0.1},
)


def _observation_file(path: Path, kind: str) -> None:
    """Write an observations file of ``kind`` (:data:`RETRIEVE_FILES`) for the small dust."""
    import numpy as np
    import xarray as xr

    wl = np.array([440.0, 550.0, 680.0])
    if kind in ("text", "damaged"):
        path.write_bytes(b"not netCDF\n" if kind == "text" else b"\x89HDF\r\n\x1a\n" + bytes(64))
        return
    if kind == "missing":
        return
    if kind == "declared_huge":  # 4e8 values declared, a few KiB written
        import h5netcdf

        with h5netcdf.File(path, "w") as f:
            f.dimensions = {"wavelength_nm": 400_000_000}
            var = f.create_variable("ssa", ("wavelength_nm",), "f8", chunks=(1_000_000,))
            var.attrs["uncertainty"] = 0.01
        return
    unc: dict[str, Any] = {"uncertainty": 1e308 if kind == "huge_uncertainty" else 0.01}
    theta = np.array([10.0, 90.0, 170.0])
    if kind in ("phase_nan_theta", "phase_inf_theta"):
        theta[1] = float("nan") if kind == "phase_nan_theta" else float("inf")
        kind = "phase"
    if kind.startswith("ratio_"):
        reference = {"ratio_nan_reference": float("nan"), "ratio_zero_reference": 0.0}
        ratio = xr.DataArray([1.1, 1.0, 0.9], coords={"wavelength_nm": wl}, dims="wavelength_nm")
        ratio.attrs = {**unc, "reference_wavelength_nm": reference.get(kind, "550 nm")}
        xr.Dataset({"extinction_ratio": ratio}).to_netcdf(path)
        return
    if kind in ("zero_wavelength", "text_wavelength", "wavelength_in_um", "many_wavelengths"):
        coord: Any = {
            "zero_wavelength": ("wavelength_nm", [0.0, 550.0, 680.0]),
            "text_wavelength": ("wavelength_nm", ["440", "550", "680"]),
            "wavelength_in_um": ("wavelength_nm", wl / 1e3, {"units": "um"}),
            "many_wavelengths": ("wavelength_nm", np.linspace(400.0, 900.0, 100_000)),
        }[kind]
        n = len(coord[1])
        xr.Dataset(
            {"ssa": ("wavelength_nm", np.full(n, 0.93), unc)}, coords={"wavelength_nm": coord}
        ).to_netcdf(path)
        return
    if kind == "text_values":
        ssa = xr.DataArray(["a", "b", "c"], coords={"wavelength_nm": wl}, dims="wavelength_nm")
        ssa.attrs = unc
        xr.Dataset({"ssa": ssa}).to_netcdf(path)
        return
    if kind == "empty":
        ds = xr.Dataset()
    elif kind == "ratio":
        ratio = xr.DataArray([1.1, 1.0, 0.9], coords={"wavelength_nm": wl}, dims="wavelength_nm")
        ds = xr.Dataset({"extinction_ratio": ratio, "extinction_ratio_uncertainty": ratio * 0.01})
        ds["extinction_ratio"].attrs["reference_wavelength_nm"] = 550.0
    elif kind == "phase":
        phase = xr.DataArray(
            np.full((3, 3), 0.1), coords={"wavelength_nm": wl, "theta_deg": theta},
            dims=("wavelength_nm", "theta_deg"), attrs={"uncertainty": 0.01},
        )  # fmt: skip
        ds = xr.Dataset({"phase": phase})
    elif kind == "sky_bad_scene":
        xy = xr.DataArray(
            [[0.4, 0.38]], coords={"sun_elevation_deg": [30.0], "chromaticity": ["x", "y"]},
            dims=("sun_elevation_deg", "chromaticity"),
            attrs={"optical_depth": -1.0, "uncertainty": 0.003},
        )  # fmt: skip
        ds = xr.Dataset({"sky_chromaticity": xy})
    elif kind == "wrong_dimension":
        ssa = xr.DataArray([0.9, 0.95], dims="x", attrs={"uncertainty": 0.01})
        ds = xr.Dataset({"ssa": ssa})
    else:
        values = [0.93, float("nan") if kind in ("ssa_nan",) else 0.95, 0.96]
        attrs = {} if kind == "ssa_without_uncertainty" else unc
        ssa = xr.DataArray(values, coords={"wavelength_nm": wl}, dims="wavelength_nm", attrs=attrs)
        ds = xr.Dataset({"ssa": ssa})
    ds.to_netcdf(path)


def retrieve_cases(rng: random.Random, n: int) -> list[Case]:
    """``dustoptics retrieve``: bounds, priors and options at and beyond their edges, on
    observation files good, incomplete, damaged, of another kind or crafted (NaN angles
    and references, a declared size of 3 GiB, 100,000 wavelengths, an uncertainty of
    1e308); the small dust's TOML as the model, or a device or a FIFO; ``--out`` over
    an input; and a quarter of the cases the library's retrieve with bounds of every
    shape.  An uninformative fit must not say converged; no input may change."""
    cases = []
    for _ in range(n):
        fit = rng.choice(RETRIEVE_FITS)
        extra = [
            a for option in rng.sample(RETRIEVE_ARGUMENTS, rng.choice((0, 1, 2))) for a in option
        ]
        kind = rng.choice(RETRIEVE_FILES)
        if rng.random() < 0.25:
            bound = rng.choice(RETRIEVE_API_BOUNDS)

            def api(workdir: Path, kind: str = kind, bound: Any = bound) -> str:
                return _retrieve_api(workdir, kind, bound)

            cases.append(Case("retrieve", f"retrieve() {kind} bounds={bound!r}", api))
            continue
        model = rng.choice(RETRIEVE_MODELS)
        out = rng.choice(RETRIEVE_OUTS)

        def run(
            workdir: Path,
            fit: str = fit,
            extra: list[str] = extra,
            kind: str = kind,
            model: str = model,
            out: tuple[str, ...] = out,
        ) -> str:
            (workdir / "fuzz.toml").write_text(SMALL_CONFIG, encoding="utf-8")
            os.mkfifo(workdir / "fifo.toml")  # run_cli's snapshots skip it (not a file)
            _observation_file(workdir / "obs.nc", kind)
            inputs = {p: p.read_bytes() for p in (workdir / "obs.nc", workdir / "fuzz.toml")
                      if p.exists()}  # fmt: skip
            argv = ["retrieve", "obs.nc", "--model", model, "--fit", fit, *extra]
            said = run_cli(workdir, [*argv, "--out", *out])
            for path, data in inputs.items():
                assert path.read_bytes() == data, f"{path.name} changed"
            record = workdir / "out" / "fit.json"
            if kind == "huge_uncertainty" and said == "exit 0" and record.exists():
                assert not json.loads(record.read_text())["converged"], "called converged"
            return said

        words = f"{kind} --model {model} --fit {fit} {' '.join(extra)} --out {' '.join(out)}"
        cases.append(Case("retrieve", f"retrieve {words}", run))
    return cases


def _retrieve_api(workdir: Path, kind: str, bound: Any) -> str:
    """The library's retrieve on an observation file of ``kind`` with ``bound`` on r_eff_um:
    a clear ValueError/TypeError (raised on), or a result that does not call an
    uninformative fit converged."""
    import numpy as np
    import xarray as xr

    from dustoptics.models.config import parse_config
    from dustoptics.retrieve import retrieve

    path = workdir / "obs.nc"
    _observation_file(path, kind)
    if kind in ("text", "damaged", "missing", "declared_huge"):
        return "a file the command line refuses (see the CLI cases)"
    with xr.open_dataset(path) as ds:
        observations = ds.load()
    result = retrieve(
        observations,
        model=parse_config(SMALL_CONFIG),
        parameters=["r_eff_um"],
        bounds={"r_eff_um": bound},
        max_iterations=3,
    )
    if kind == "huge_uncertainty":
        assert not result.converged, "an uninformative fit called converged"
        assert np.isinf(result.standard_errors).all(), "its standard error reported finite"
    return f"converged={result.converged}"


#: Crafted headers and metadata that declare more than their file holds (issue 42 item 1):
#: what, and how it is made (:func:`_crafted`).
SIZE_INPUTS = (
    "a Zarr store whose .zarray and .zmetadata declare 2**40 angles",
    "a Zarr store whose .zarray alone declares 2**40 angles",
    "a Zarr store whose phase declares one chunk of 2**34 values",
    "a sweep netCDF-4 whose error estimate declares 512 MiB compressed",
    "a sweep netCDF-4 declaring chunks never written",
    "a sky netCDF declaring 2**31 values",
    "a sky netCDF whose attribute declares 2**31 bytes",
    "a KTX2 declaring 65535 x 65535 texels",
    "a KTX2 whose level lies beyond the file",
    "an EXR whose data window declares 2**30 x 2**30 pixels",
    "an observation file whose ssa declares 4e8 values",
    "a symbolic link to a sweep store",
)
#: The readers each input is given to: the command line, and the library's own reader of it
#: (describe_sweep, describe_sky, read_ktx2_metadata, read_exr_metadata, read_observations).
SIZE_READERS = ("info", "library")

_TEMPLATE_STORE: list[Path] = []


def _template_store() -> Path:
    """A small sweep store, computed once in the parent (copied by every case)."""
    if not _TEMPLATE_STORE:
        from dustoptics.sweep import sweep

        root = Path(tempfile.mkdtemp(prefix="dustoptics-fuzz-template-"))
        cluster, client = _threads_client()
        with cluster, client:
            sweep(
                SMALL_CONFIG,
                {"size_distribution.r_eff_um": [0.4, 0.6]},
                out=root / "s.zarr",
                client=client,
                chunk_wavelengths=1,
                progress=None,
            )
        _TEMPLATE_STORE.append(root / "s.zarr")
    return _TEMPLATE_STORE[0]


def sizes_cases(rng: random.Random, n: int) -> list[Case]:
    """Files whose headers or metadata declare sizes they cannot hold, given to ``info`` and
    to the library's reader: each must be refused (one clean line) before it is read, within
    the case's memory limit; the link to a store must be described."""
    cases = []
    for _ in range(n):
        what, reader = rng.choice(SIZE_INPUTS), rng.choice(SIZE_READERS)

        def run(workdir: Path, what: str = what, reader: str = reader) -> str:
            return _sizes_case(workdir, what, reader)

        cases.append(Case("sizes", f"{what} given to {reader}", run))
    return cases


def _edit_json(path: Path, edit: Callable[[Any], None]) -> None:
    data = json.loads(path.read_text(encoding="utf-8"))
    edit(data)
    path.write_text(json.dumps(data), encoding="utf-8")


def _crafted_store(workdir: Path, what: str) -> Path:
    store = workdir / "s.zarr"
    shutil.copytree(_template_store(), store)
    if "symbolic link" in what:
        link = workdir / "link.zarr"
        link.symlink_to(store.name)
        return link
    array, key, value = (
        ("phase", "chunks", [1 << 11, 1 << 11, 1 << 12])
        if "chunk of" in what
        else ("theta_deg", "shape", [1 << 40])
    )

    def edit(meta: Any) -> None:
        meta[key] = value

    _edit_json(store / array / ".zarray", edit)
    if ".zmetadata" in what or "chunk of" in what:
        _edit_json(store / ".zmetadata", lambda m: edit(m["metadata"][f"{array}/.zarray"]))
    return store


def _crafted_sweep_nc(path: Path, what: str) -> None:
    import h5py
    import numpy as np

    with h5py.File(path, "w") as f:
        f.attrs["title"] = "dustoptics sweep of fuzz"
        f.attrs["sweep"] = "{}"
        f.create_dataset("wavelength_nm", data=np.array([550.0]))
        f.create_dataset("theta_deg", data=np.linspace(0.0, 180.0, 5))
        f.create_dataset("phase", data=np.ones((1, 5)))
        shape, chunk = (2, 4096, 8192), (1, 512, 8192)
        err = f.create_dataset(
            "error_estimate", shape=shape, dtype="<f8", chunks=chunk, compression="gzip"
        )
        if "compressed" in what:  # the same deflated chunk of zeros, written raw 16 times
            block = zlib.compress(bytes(8 * chunk[1] * chunk[2]), 9)
            for i in range(shape[0]):
                for j in range(0, shape[1], chunk[1]):
                    err.id.write_direct_chunk((i, j, 0), block)


def _crafted_netcdf3(path: Path, what: str) -> None:
    import struct

    from scipy.io import netcdf_file

    with netcdf_file(path, "w", version=2) as f:
        f.title = "crafted"
        f.createDimension("wavelength_nm", 4)
        wl = f.createVariable("wavelength_nm", "f8", ("wavelength_nm",))
        wl[:] = [440.0, 550.0, 680.0, 800.0]
        name = "ssa" if "observation" in what else "radiance"
        var = f.createVariable(name, "f8", ("wavelength_nm",))
        var[:] = 0.9
        f.createVariable(f"{name}_sigma", "f8", ("wavelength_nm",))[:] = 0.01
        var.units = "1"
    data = bytearray(path.read_bytes())
    if "attribute" in what:
        at = data.find(b"title") + 8 + 4  # the padded name, then nc_type: the value count
        data[at : at + 4] = struct.pack(">i", 0x7FFFFFFF)
    else:
        at = data.find(b"wavelength_nm") + 16  # the padded name: the dimension's length
        count = 400_000_000 if "observation" in what else 0x7FFFFFFF
        data[at : at + 4] = struct.pack(">i", count)
    path.write_bytes(bytes(data))


def _crafted_texture(workdir: Path, what: str) -> Path:
    import struct

    from dustoptics.io import write

    suffix = "ktx2" if "KTX2" in what else "exr"
    (path,) = write(_small_table(), workdir / "tex", format=suffix)
    data = bytearray(path.read_bytes())
    if "65535" in what:
        data[20:28] = struct.pack("<2I", 65535, 65535)
    elif "beyond" in what:
        width, height, length = 1 << 20, 1 << 10, (1 << 30) * 16
        data[20:28] = struct.pack("<2I", width, height)
        data[88:104] = struct.pack("<2Q", length, length)
    else:
        at = data.find(b"dataWindow\0box2i\0") + len("dataWindow\0box2i\0") + 4
        data[at + 8 : at + 16] = struct.pack("<2i", (1 << 30) - 1, (1 << 30) - 1)
    path.write_bytes(bytes(data))
    return path


def _sizes_case(workdir: Path, what: str, reader: str) -> str:
    from dustoptics.cli._retrieve_files import read_observations
    from dustoptics.io.describe_formats import describe_sky, describe_sweep
    from dustoptics.io.textures.exr import read_exr_metadata
    from dustoptics.io.textures.ktx2 import read_ktx2_metadata

    if "Zarr" in what or "symbolic" in what:
        path = _crafted_store(workdir, what)
        library: Callable[[Path], Any] = describe_sweep
    elif "sweep netCDF-4" in what:
        path = workdir / "sweep.nc"
        _crafted_sweep_nc(path, what)
        library = describe_sweep
    elif "netCDF" in what or "observation" in what:
        path = workdir / ("obs.nc" if "observation" in what else "crafted_sky.nc")
        _crafted_netcdf3(path, what)
        library = read_observations if "observation" in what else describe_sky
    else:
        path = _crafted_texture(workdir, what)
        library = read_ktx2_metadata if "KTX2" in what else read_exr_metadata
    accepted = "symbolic" in what
    if reader == "info":
        said = run_cli(workdir, ["info", str(path)])
        assert (said == "exit 0") == accepted, f"info: {said}"
        assert accepted or path.name in said, f"the refusal does not name the file: {said}"
        if not accepted:  # counted as a clean error: the one line info printed
            raise ValueError(said)
        return said
    try:
        result = library(path)
    except (ValueError, TypeError, FileNotFoundError) as exc:
        assert not accepted, f"{library.__name__} refused {what}: {exc}"
        assert str(exc) and "\n" not in str(exc), repr(exc)
        assert str(path.name) in str(exc), f"the refusal does not name the file: {exc}"
        raise
    assert accepted, f"{library.__name__} read {what}: {str(result)[:200]}"
    return f"described: {str(result).splitlines()[0]}"


GENERATORS = {
    "api": api_cases,
    "config": config_cases,
    "cli": cli_cases,
    "files": files_cases,
    "sweeps": sweeps_cases,
    "stores": stores_cases,
    "kills": kills_cases,
    "bounds": bounds_cases,
    "inputs": inputs_cases,
    "digests": digests_cases,
    "retrieve": retrieve_cases,
    "sizes": sizes_cases,
}


def warm_up(kinds: tuple[str, ...] = KINDS) -> None:
    """Compile (or load) the kernels once, so that forked cases inherit them.

    Every case is a forked process: the package itself keeps that safe (numba's
    fork-safe threading layer for the sky's parallel kernels, ``_numba_cache``; Dask's
    thread pools renewed in a forked child, ``dustoptics.sweep._fork``), so the harness
    changes nothing there (issue 29 item 9).
    """
    _small_table()
    if {"sweeps", "stores", "sizes"} & set(kinds):
        _warm_up_sweeps()
    if "sizes" in kinds:
        _template_store()


def fuzz(
    seed: int,
    cases_per_kind: int,
    kinds: tuple[str, ...] = KINDS,
    *,
    timeout_s: float = CASE_TIMEOUT_S,
    report: Callable[[Outcome], None] | None = None,
) -> list[Outcome]:
    """Run ``cases_per_kind`` cases of each kind from ``seed``; return every outcome."""
    warm_up(kinds)
    rng = random.Random(seed)
    outcomes = []
    for kind in kinds:
        for case in GENERATORS[kind](rng, cases_per_kind):
            outcome = run_case(case, timeout_s=timeout_s)
            outcomes.append(outcome)
            if report is not None:
                report(outcome)
    return outcomes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0, the CI seed)")
    parser.add_argument(
        "--cases", type=int, default=5, help="cases per kind (default 5, the CI budget)"
    )
    parser.add_argument(
        "--kinds", default=",".join(KINDS), help=f"comma-separated, from {', '.join(KINDS)}"
    )
    parser.add_argument("--timeout", type=float, default=CASE_TIMEOUT_S, help="seconds per case")
    parser.add_argument("--verbose", action="store_true", help="print every case")
    args = parser.parse_args(argv)
    kinds = tuple(k for k in args.kinds.split(",") if k)

    def report(outcome: Outcome) -> None:
        if args.verbose or outcome.status == "failure":
            print(
                f"[{outcome.status}] {outcome.case.kind} {outcome.seconds:.2f} s: "
                f"{outcome.case.description}\n    {outcome.detail}",
                flush=True,
            )

    start = time.perf_counter()
    outcomes = fuzz(args.seed, args.cases, kinds, timeout_s=args.timeout, report=report)
    failures = [o for o in outcomes if o.status == "failure"]
    counts = {s: sum(o.status == s for o in outcomes) for s in ("ok", "clean", "failure")}
    print(
        f"{len(outcomes)} cases (seed {args.seed}) in {time.perf_counter() - start:.1f} s: "
        f"{counts['ok']} ok, {counts['clean']} clean errors, {counts['failure']} failures"
    )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
