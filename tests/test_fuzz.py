"""The fuzz harness (scripts/fuzz.py) at its CI budget, and checks that it can fail.

CI runs seed 0 with 5 cases of each kind (API calls, TOML configurations,
command lines, damaged files, sweep specifications, sweep stores damaged or
contended, sets killed while written, files beyond the readers' bounds, inputs
that raised tracebacks, seed-CSV sets without checksums, retrieve command lines), each forked with an address-space limit and a timeout.  ``pytest --hypothesis-profile=explore`` runs 60 cases of each kind
from a seed taken from the clock (printed, to reproduce a failure with
``python scripts/fuzz.py --seed SEED --cases 60``).
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import settings

_SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "fuzz.py"
_SPEC = importlib.util.spec_from_file_location("dustoptics_fuzz", _SCRIPT)
assert _SPEC is not None and _SPEC.loader is not None
fuzz = importlib.util.module_from_spec(_SPEC)
sys.modules[_SPEC.name] = fuzz  # dataclasses look their module up while being defined
_SPEC.loader.exec_module(fuzz)


def _exploring() -> bool:
    return getattr(settings, "_current_profile", None) == "explore"


def test_no_input_the_harness_generates_fails():
    seed, cases = (int(time.time()), 60) if _exploring() else (0, 5)
    # The harness forks one child per case.  It runs in an interpreter of its own, as a user
    # runs it: a fork inherits the test process's threads' locks (a parallel test worker's
    # channel, the dask clients earlier tests started) and a child can block on one forever.
    done = subprocess.run(
        [sys.executable, str(_SCRIPT), "--seed", str(seed), "--cases", str(cases)],
        capture_output=True,
        text=True,
        timeout=len(fuzz.KINDS) * cases * fuzz.CASE_TIMEOUT_S,
        check=False,
    )
    assert done.returncode == 0, f"seed {seed}:\n{done.stdout}\n{done.stderr}"
    summary = re.fullmatch(
        r"(\d+) cases \(seed \d+\) in [\d.]+ s: (\d+) ok, (\d+) clean errors, 0 failures",
        done.stdout.strip().splitlines()[-1],
    )
    assert summary is not None, done.stdout
    total, ok, clean = (int(group) for group in summary.groups())
    assert total == len(fuzz.KINDS) * cases
    # The generators reach both results and clean errors (they are not all refused).
    assert ok > 0 and clean > 0


def _case(run):
    return fuzz.Case("test", "a case of the harness's own tests", run)


def test_the_harness_sees_a_hang():
    outcome = fuzz.run_case(_case(lambda workdir: time.sleep(30)), timeout_s=1.0)
    assert outcome.status == "failure" and outcome.detail.startswith("hang")
    assert outcome.seconds < 10


def test_the_harness_sees_a_memory_blow_up():
    def blow_up(workdir):
        return bytearray(8 * 1024**3)

    outcome = fuzz.run_case(_case(blow_up))
    assert outcome.status == "failure" and "MemoryError" in outcome.detail


@pytest.mark.parametrize(
    ("error", "status"),
    [
        (ValueError("r_eff_um must be > 0 um; got -1.0"), "clean"),
        (ZeroDivisionError("x"), "failure"),
    ],
)
def test_the_harness_tells_clean_errors_from_tracebacks(error, status):
    def raise_it(workdir):
        raise error

    assert fuzz.run_case(_case(raise_it)).status == status


def test_the_harness_sees_a_file_outside_out_and_a_partial_set(monkeypatch):
    from dustoptics import cli

    def escapes(argv):
        Path("escaped.csv").write_text("x\n")
        return 0

    def partial(argv):
        Path("out").mkdir(exist_ok=True)
        Path("out/a.csv").write_text("new\n")
        print("dustoptics: error: failed half way", file=sys.stderr)
        return 1

    monkeypatch.setattr(cli, "main", escapes)
    outcome = fuzz.run_case(_case(lambda workdir: fuzz.run_cli(workdir, ["build"])))
    assert outcome.status == "failure" and "outside --out" in outcome.detail
    monkeypatch.setattr(cli, "main", partial)
    outcome = fuzz.run_case(_case(lambda workdir: fuzz.run_cli(workdir, ["build"])))
    assert outcome.status == "failure" and "changed the set" in outcome.detail


def test_the_harness_sees_a_silently_wrong_number():
    class Wrong:
        qext = -5.8e11
        ssa = 1.5

    with pytest.raises(AssertionError, match="negative"):
        fuzz._check_result(Wrong())


def test_the_sweep_families_reach_every_kind_of_input():
    """The store family draws every event (damage, contention, a full disk) and the
    sweep family every route (API, [sweep] table, command line) within a few draws,
    so that a search of a few dozen cases reaches each of issue 29's sweep defects."""
    import random

    events, routes = set(), set()
    for seed in range(4):
        rng = random.Random(seed)
        events |= {c.description.split(" (seed")[0] for c in fuzz.stores_cases(rng, 10)}
        routes |= {c.description.split(" ")[0] for c in fuzz.sweeps_cases(rng, 10)}
    assert events == set(fuzz.STORE_EVENTS)
    assert routes == {"load_sweep(SMALL_CONFIG,", "load_sweep", "dustoptics"}


def test_the_file_families_reach_every_kind_of_input():
    """Within a few draws the kill family reaches every route and the early, the
    publishing and the late steps; the bounds family every input and reader; the inputs
    family every route; the digest family a sky that forks (issue 29 items 5-7, 9)."""
    import random

    routes, steps, inputs, readers, kinds, sky = set(), set(), set(), set(), set(), False
    for seed in range(4):
        rng = random.Random(seed)
        for case in fuzz.kills_cases(rng, 10):
            route, step = case.description.split(", killed at step ")
            routes.add(route)
            steps.add(int(step.split(",")[0]) // 16)
        for case in fuzz.bounds_cases(rng, 20):
            what, reader = case.description.split(" given to ")
            inputs.add(what)
            readers.add(reader)
        kinds |= {c.description.split(" ")[0] for c in fuzz.inputs_cases(rng, 20)}
        sky |= any("sky" in c.description for c in fuzz.digests_cases(rng, 10))
    assert routes == set(fuzz.KILL_ROUTES) and steps == {0, 1, 2, 3}
    assert inputs == set(fuzz.BOUND_INPUTS) and readers == set(fuzz.BOUND_READERS)
    assert {"build", "info", "export", "texture", "do.MultiModal(modes=None,"} <= kinds
    assert sky


def test_the_sizes_family_reaches_every_input_and_reader():
    """Within a few draws the sizes family gives every crafted header (issue 42 item 1) to
    ``info`` and to the library's reader."""
    import random

    inputs, readers = set(), set()
    for seed in range(4):
        for case in fuzz.sizes_cases(random.Random(seed), 20):
            what, reader = case.description.split(" given to ")
            inputs.add(what)
            readers.add(reader)
    assert inputs == set(fuzz.SIZE_INPUTS) and readers == set(fuzz.SIZE_READERS)
