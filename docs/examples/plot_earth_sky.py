"""
An Earth sky on a clear day
===========================

The default Earth of ``dustoptics.atmosphere.sets.earth_atmosphere``: standard
air, ozone and a continental aerosol at optical depth 0.1 at 550 nm (a typical
clear day), the Sun 30 degrees above the horizon.  The fisheye (zenith at the
centre, the Sun's azimuth up) and the panorama (the Sun in the middle) share
one exposure chosen from the sky; the horizon brightens without clipping.
"""

import matplotlib.pyplot as plt

from dustoptics.atmosphere import sets
from dustoptics.sky.scene import sky_radiance

atmosphere = sets.earth_atmosphere()
sky = sky_radiance(atmosphere, sun_elevation_deg=30.0, ground_albedo=0.2)
i_zenith, i_horizon = 0, -1
ratio = sky.xyz()[i_horizon, -1, 1] / sky.xyz()[i_zenith, 0, 1]
print(
    f"{atmosphere.name}: horizon opposite the Sun / zenith luminance {ratio:.2f}; "
    f"radiance error <= {sky.radiance_error.max():.1e}"
)

# %%
exposure = sky.default_exposure()
fig, (ax_fish, ax_pano) = plt.subplots(
    1, 2, figsize=(11, 4), layout="constrained", width_ratios=(1, 2.2)
)
ax_fish.imshow(sky.fisheye(size=384, exposure=exposure))
ax_fish.set_title("fisheye, Sun 30 deg high")
ax_fish.set_axis_off()
ax_pano.imshow(sky.panorama(width=1024, height=256, exposure=exposure), extent=(-180, 180, 0, 90))
ax_pano.set_xlabel("azimuth from the Sun [deg]")
ax_pano.set_ylabel("elevation [deg]")
ax_pano.set_title("panorama")
plt.show()
