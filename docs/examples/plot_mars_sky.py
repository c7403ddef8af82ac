"""
A Mars sky at noon and at sunset
================================

The sky a dust table makes, computed by ``dustoptics.sky``: the seed thesis's
"hybrid" dust at optical depth 0.5 (550 nm) over a rover's camera 2 m above the
ground, with the Sun high and setting.  Each fisheye has the zenith at its
centre and the horizon at its rim, the Sun's azimuth up; its exposure is
chosen from the sky (the brightest sky farther than 10 degrees from the Sun is
white) and the Sun's disc is drawn at its angular size seen from Mars.  The
butterscotch day sky and the blue sunset aureole come from the same dust.
"""

import matplotlib.pyplot as plt

from dustoptics.sky import Medium
from dustoptics.sky.compare import mars_sky_atmosphere
from dustoptics.sky.scene import sky_radiance, sun_angular_radius_deg_of

atmosphere = mars_sky_atmosphere("hybrid", optical_depth=0.5)
medium = Medium.from_atmosphere(atmosphere)  # the optics, once for both Suns
alpha = sun_angular_radius_deg_of(atmosphere.sun_distance_m)
skies = {
    elevation: sky_radiance(
        medium, sun_elevation_deg=elevation, ground_albedo=0.2, sun_angular_radius_deg=alpha
    )
    for elevation in (60.0, 5.0)
}
for elevation, sky in skies.items():
    x, y = sky.chromaticity()[0, 0]
    print(
        f"Sun at {elevation:g} deg: zenith chromaticity x {x:.4f}, y {y:.4f}; "
        f"{sky.n_orders} orders of scattering; radiance error <= {sky.radiance_error.max():.1e}"
    )

# %%
# The two skies, each at its own exposure.
fig, axes = plt.subplots(1, 2, figsize=(9, 4.8), layout="constrained")
for ax, (elevation, sky) in zip(axes, skies.items(), strict=True):
    ax.imshow(sky.fisheye(size=384))
    ax.set_title(f"Mars, Sun {elevation:g} deg above the horizon")
    ax.set_axis_off()
plt.show()
