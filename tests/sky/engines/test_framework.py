"""The engines' framework: colour differences, the registry, the format's refusal of a table."""

from __future__ import annotations

import numpy as np
import pytest

from dustoptics import colour
from dustoptics.io import FORMATS
from dustoptics.sky.engines import ENGINES

# Sharma, Wu and Dalal (2005), Table 1: pairs 1, 7, 13 and 17 with their Delta E 2000.
SHARMA_PAIRS = [
    ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
    ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
    ((50.0, 2.49, -0.001), (50.0, -2.49, 0.0009), 7.1792),
    ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492),
]


@pytest.mark.parametrize(("lab1", "lab2", "expected"), SHARMA_PAIRS)
def test_delta_e_2000_matches_sharma_2005(lab1, lab2, expected):
    assert colour.delta_e_ciede2000(lab1, lab2) == pytest.approx(expected, abs=5e-5)
    # Symmetric in its two colours (their Eq. 1-22 are).
    assert colour.delta_e_ciede2000(lab2, lab1) == pytest.approx(expected, abs=5e-5)


def test_delta_e_2000_broadcasts():
    a = np.array([p[0] for p in SHARMA_PAIRS])
    b = np.array([p[1] for p in SHARMA_PAIRS])
    np.testing.assert_allclose(
        colour.delta_e_ciede2000(a, b), [p[2] for p in SHARMA_PAIRS], atol=5e-5
    )


def test_lab_of_the_white_is_100_0_0_and_of_18_percent_grey_is_about_49():
    white = np.array([0.95047, 1.0, 1.08883])
    np.testing.assert_allclose(colour.xyz_to_lab(white, white), [100.0, 0.0, 0.0], atol=1e-12)
    # L* = 116 * 0.18^(1/3) - 16 = 49.496 (CIE 15:2004 Eq. 8.1).
    assert colour.xyz_to_lab(0.18 * white, white)[0] == pytest.approx(49.4961, abs=1e-4)


def test_lab_refuses_a_non_positive_white():
    with pytest.raises(ValueError, match="white_xyz"):
        colour.xyz_to_lab([0.5, 0.5, 0.5], [1.0, 0.0, 1.0])


def test_every_engine_is_a_format_that_refuses_one_table(tmp_path):
    assert ENGINES
    for name in ENGINES:
        assert name in FORMATS
        with pytest.raises(ValueError, match="planet's sky"):
            FORMATS[name].write(object(), tmp_path)
