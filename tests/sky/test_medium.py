"""dustoptics.sky.medium: the slant-column grids are refused before work when they cannot
interpolate (issue 29 item 7: n_radii = 1 or n_mu = 1 raised ZeroDivisionError)."""

from __future__ import annotations

import pytest

from dustoptics.atmosphere.sets import earth_atmosphere
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
