"""dustoptics.sky.scene: the Sun's disc in the images and the exposure chosen from the scene."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from dustoptics import colour
from dustoptics.sky.scene import (
    EXPOSURE_SUN_EXCLUSION_DEG,
    SkyRadiance,
    sun_angular_radius_deg_of,
    sun_disc_xyz,
    sunlit_xyz,
)

WL = np.linspace(360.0, 830.0, 48)  # the colour-matching functions' whole range
T_SUN = np.linspace(0.5, 0.8, WL.size)  # redder through the air
AU_M = 1.495978707e11  # IAU 2012 Resolution B2


def _sky(
    sun_zenith_deg: float, alpha_deg: float, radiance: np.ndarray | None = None
) -> SkyRadiance:
    zen = np.linspace(0.0, 90.0, 91)
    azi = np.linspace(0.0, 180.0, 91)
    if radiance is None:
        # A smooth sky brightening toward the horizon, bluer than the Sun.
        shape = (1.0 + 2.0 * (zen / 90.0) ** 2)[:, None, None] * np.ones((1, azi.size, 1))
        radiance = 0.02 * shape * np.linspace(1.5, 0.7, WL.size)
    return SkyRadiance(
        name="test",
        wavelength_nm=WL,
        view_zenith_deg=zen,
        view_azimuth_deg=azi,
        radiance=radiance,
        sun_zenith_deg=sun_zenith_deg,
        observer_altitude_m=2.0,
        ground_albedo=np.full(WL.size, 0.2),
        sun_transmittance=T_SUN,
        n_orders=10,
        error_estimate=1e-5,
        tol=1e-4,
        sun_angular_radius_deg=alpha_deg,
    )


def test_the_suns_angular_radius_seen_from_one_astronomical_unit() -> None:
    # The Sun's mean angular radius at 1 au: 959.63 arcsec (Allen's Astrophysical Quantities,
    # 4th ed., 2000, Table 14.1, with the 6.96e8 m radius; the IAU nominal 6.957e8 m gives
    # 0.04 % less).
    assert sun_angular_radius_deg_of(AU_M) * 3600.0 == pytest.approx(959.63, rel=1e-3)


def test_the_disc_integrates_to_the_transmitted_beam() -> None:
    alpha = 0.27
    # The irradiance normal to the beam: 2 pi int I(psi) cos(psi) sin(psi) dpsi.
    total = [
        quad(
            lambda psi, k=k: (
                2.0
                * math.pi
                * sun_disc_xyz(WL, T_SUN, math.degrees(psi), sun_angular_radius_deg=alpha)[k]
                * math.sin(psi)
                * math.cos(psi)
            ),
            0.0,
            math.radians(alpha),
            limit=200,
        )[0]
        for k in range(3)
    ]
    np.testing.assert_allclose(total, sunlit_xyz(WL, T_SUN), rtol=1e-6)
    # Limb darkening: the edge is 2/5 of the centre (Eddington's grey law).
    centre = sun_disc_xyz(WL, T_SUN, 0.0, sun_angular_radius_deg=alpha)[1]
    edge = sun_disc_xyz(WL, T_SUN, alpha * (1.0 - 1e-9), sun_angular_radius_deg=alpha)[1]
    assert edge / centre == pytest.approx(0.4, abs=1e-3)
    assert sun_disc_xyz(WL, T_SUN, alpha * 1.001, sun_angular_radius_deg=alpha)[1] == 0.0


@pytest.mark.parametrize("alpha_deg", [0.17, 0.27, 1.0])
def test_the_antialiased_disc_in_the_panorama_keeps_the_beam(alpha_deg: float) -> None:
    """Summed over the panorama's pixels times their solid angles, the disc gives back the
    transmitted beam: the sub-pixel sampling neither loses nor adds light."""
    sky = _sky(50.0, alpha_deg)
    width, height = 1440, 360  # 0.25 deg pixels
    azi = (np.arange(width) + 0.5) / width * 360.0 - 180.0
    elev = 90.0 - (np.arange(height) + 0.5) / height * 90.0
    aa, ee = np.meshgrid(azi, elev)

    def direction(z, a, du, dv):
        return np.clip(z + dv * 90.0 / height, 0.0, 90.0), a + du * 360.0 / width

    sun = sky._sun_in_pixels(90.0 - ee, aa, 0.25, direction)
    d_omega = np.radians(0.25) ** 2 * np.cos(np.radians(ee))
    got = np.sum(sun * d_omega[..., None], axis=(0, 1))
    np.testing.assert_allclose(got, sunlit_xyz(WL, T_SUN), rtol=0.01)


def test_the_fisheye_shows_the_disc_where_the_sun_is() -> None:
    sky = _sky(40.0, 0.5)
    size = 360  # 0.5 deg of zenith per pixel
    image = sky.fisheye(size=size)
    # The Sun's azimuth points up: 40 deg from the centre toward the top.
    row = round(size / 2 - 40.0 / 90.0 * size / 2)
    assert np.all(image[row - 1 : row + 1, size // 2 - 1 : size // 2 + 1] == 255)
    plain = _sky(40.0, 0.0).fisheye(size=size)
    assert np.array_equal(
        np.delete(image, np.s_[row - 4 : row + 4], axis=0),
        np.delete(plain, np.s_[row - 4 : row + 4], axis=0),
    )


def test_the_default_exposure_clips_nothing_away_from_the_sun() -> None:
    sky = _sky(30.0, 0.27)
    e = sky.default_exposure()
    zz, aa = np.meshgrid(sky.view_zenith_deg, sky.view_azimuth_deg, indexing="ij")
    cos_psi = np.cos(np.radians(zz)) * math.cos(math.radians(30.0)) + np.sin(
        np.radians(zz)
    ) * math.sin(math.radians(30.0)) * np.cos(np.radians(aa))
    away = np.degrees(np.arccos(np.clip(cos_psi, -1, 1))) > EXPOSURE_SUN_EXCLUSION_DEG
    linear = e * colour.xyz_to_linear_srgb(sky.xyz()[away])
    assert np.max(linear) == pytest.approx(1.0, rel=1e-12)  # the brightest just reaches white
    # The horizon (the brightest here) is not clipped in the image either.
    pano = sky.panorama(exposure=e)
    assert pano[-1].max() <= 255 and np.all(pano[-1, :, 0] < 255)
