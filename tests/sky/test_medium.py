"""dustoptics.sky.medium: the slant-column grids are refused before work when they cannot
interpolate (issue 29 item 7: n_radii = 1 or n_mu = 1 raised ZeroDivisionError)."""

from __future__ import annotations

import threading

import pytest
from scipy.special import roots_legendre

from dustoptics.atmosphere.sets import earth_atmosphere
from dustoptics.sky import medium
from dustoptics.sky.medium import Medium


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("n_radii", 1),
        ("n_mu", 1),
        ("n_radii", 0),
        ("n_mu", 10**9),
        ("n_mu", 2.0),
        ("n_radii", True),
    ],
)
def test_grids_that_cannot_interpolate_are_refused(key, value) -> None:
    atmosphere = earth_atmosphere(wavelength_nm=[440.0, 550.0, 680.0])
    with pytest.raises(ValueError, match=rf"^{key} must be an integer in \[2, 2048\]; got "):
        Medium.from_atmosphere(atmosphere, **{key: value})


def test_a_value_computed_once_is_computed_once_whoever_asks_first() -> None:
    calls: list[int] = []
    gate = threading.Event()

    def compute() -> int:
        gate.wait(5.0)
        calls.append(1)
        return len(calls)

    once = medium._Once(compute)
    once.start()  # in a thread of its own, held at the gate
    once.start()
    getters = [threading.Thread(target=once.get) for _ in range(3)]
    for t in getters:
        t.start()
    gate.set()
    for t in getters:
        t.join()
    assert once.get() == 1 and calls == [1]
    failing = medium._Once(lambda: 1 // 0)
    failing.start()
    with pytest.raises(ZeroDivisionError):
        failing.get()


def test_the_projection_rule_is_scipys() -> None:
    medium.prefetch_projection_rule()
    mu, w = medium._projection_rule()
    ref_mu, ref_w = roots_legendre(4096)
    assert mu.tobytes() == ref_mu.tobytes() and w.tobytes() == ref_w.tobytes()
    assert not mu.flags.writeable and not w.flags.writeable
