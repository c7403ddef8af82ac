"""The sky's serial kernels in threads: every part once, and the bits of one thread."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from dustoptics.atmosphere.sets import earth_atmosphere
from dustoptics.sky import _shared
from dustoptics.sky.medium import _search_left, _sort_small
from dustoptics.sky.scene import sky_radiance


@pytest.mark.parametrize("cores", [1, 2, 3])
@pytest.mark.parametrize("n", [0, 1, 2, 7, 100])
def test_in_threads_runs_every_index_once(monkeypatch, cores, n):
    monkeypatch.setattr(_shared, "cores", lambda: cores)
    seen = np.zeros(n, dtype=int)
    parts = []

    def run(lo: int, hi: int, step: int) -> None:
        parts.append((lo, hi))
        seen[lo:hi] += step

    _shared.in_threads(run, n, 1)
    assert seen.tolist() == [1] * n
    assert all(lo < hi for lo, hi in parts) or n == 0


def test_a_sky_in_one_thread_and_in_two_has_the_same_bits(monkeypatch):
    atm = earth_atmosphere(wavelength_nm=[440.0, 550.0, 680.0])

    def render() -> np.ndarray:
        sky = sky_radiance(
            atm, sun_elevation_deg=30.0, view_zenith_deg=np.array([0.0, 45.0, 80.0]),
            azimuth_step_deg=45.0,
        )  # fmt: skip
        return np.asarray(sky.radiance)

    monkeypatch.setattr(_shared, "cores", lambda: 1)
    one = render()
    monkeypatch.setattr(_shared, "cores", lambda: 2)
    two = render()
    assert one.tobytes() == two.tobytes()


def test_bisection_and_sort_are_numpys():
    rng = np.random.default_rng(7)
    for size in (1, 2, 5, 40):
        a = np.sort(rng.integers(0, 6, size).astype(float))  # ties
        for v in [*a, -1.0, 7.0, 2.5, np.nan, -np.inf, np.inf]:
            assert _search_left(a, v) == np.searchsorted(a, v), (a, v)
        b = rng.normal(size=size)
        c = b.copy()
        _sort_small(c)
        assert c.tobytes() == np.sort(b).tobytes()


def _blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_one_blas_thread_sets_one_and_the_last_out_restores():
    np.ones((2, 2)) @ np.ones((2, 2))  # numpy's BLAS loaded
    before = _blas_threads()
    if not before:
        pytest.skip("no BLAS thread pool threadpoolctl knows")
    with _shared.one_blas_thread():
        assert set(_blas_threads()) == {1}
        with _shared.one_blas_thread():
            assert set(_blas_threads()) == {1}
        assert set(_blas_threads()) == {1}
    assert _blas_threads() == before
