"""
The blue forward peak
=====================

Mars has blue sunsets: dust grains about as large as the wavelength
(r_eff ~ 1.6 um) scatter blue light more strongly than red into the directions
close to the sun.  An Earth-style renderer with one phase function for all
wavelengths cannot show it; a wavelength-dependent table can.

This example computes the physical table of the Blue Moon's dust on a grid
that is fine near the forward direction (where the peak is) and coarse
elsewhere, which the figure allows and which keeps the computation small.
"""

import matplotlib.pyplot as plt
import numpy as np

import dustoptics as do

dust = do.mars_dust(hematite_fraction=0.03, host_index=1.5, hematite="querry-extraordinary")
dist = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
theta_deg = np.concatenate([np.arange(0.0, 30.0, 0.1), np.arange(30.0, 180.5, 1.0)])
wavelengths_nm = np.arange(360.0, 831.0, 10.0)
table = do.compute_optics(dust, dist, wavelengths_nm, theta_deg)
print(
    f"{table.phase.shape[0]} wavelengths x {table.phase.shape[1]} angles, "
    f"largest error estimate {table.quadrature.error_estimate.max():.1e}"
)

# %%
# Left: within a few degrees of the forward direction the phase function is
# several times larger in the blue than in the red; beyond about 7 degrees the
# order reverses, since each wavelength's phase function integrates to 1 over
# the sphere.  Right: the peak value P(0) and the asymmetry parameter g
# against wavelength.

fig, (ax_theta, ax_peak) = plt.subplots(1, 2, figsize=(10, 4.2), layout="constrained")
cmap = plt.get_cmap("turbo")
for i in range(0, wavelengths_nm.size, 4):
    wl = wavelengths_nm[i]
    colour = cmap((wl - 360.0) / (830.0 - 360.0))
    ax_theta.plot(table.theta_deg, table.phase[i], color=colour, label=f"{wl:.0f} nm")
ax_theta.set_xlim(0, 30)
ax_theta.set_yscale("log")
ax_theta.set_xlabel("scattering angle theta [degree]")
ax_theta.set_ylabel("phase function P [sr$^{-1}$]")
ax_theta.set_title("forward peak, 0-30 degree")
ax_theta.set_ylim(0.1, 100)
ax_theta.legend(ncol=2, fontsize="x-small")

ax_peak.plot(table.wavelength_nm, table.phase[:, 0], color="black", label="P(0 degree)")
ax_peak.set_xlabel("wavelength [nm]")
ax_peak.set_ylabel("forward peak P(0) [sr$^{-1}$]")
ax_g = ax_peak.twinx()
ax_g.plot(table.wavelength_nm, table.g, color="tab:orange", label="g")
ax_g.set_ylabel("asymmetry parameter g [-]", color="tab:orange")
ax_peak.set_title("forward peak and g across wavelength")
ax_peak.legend(loc="upper center", fontsize="x-small")
ax_g.legend(loc="upper right", fontsize="x-small")
plt.show()

# %%
# The ratio of the blue (440 nm) and red (680 nm) phase functions: above 1
# within about 5-7 degrees of the forward direction, which is why the glow
# around the setting sun is blue on Mars.

blue = int(np.flatnonzero(wavelengths_nm == 440.0)[0])
red = int(np.flatnonzero(wavelengths_nm == 680.0)[0])
for angle in (0.0, 2.0, 5.0, 10.0, 20.0, 40.0, 90.0):
    j = int(np.flatnonzero(np.isclose(table.theta_deg, angle))[0])
    print(
        f"theta {angle:4.0f} degree: P(440 nm) / P(680 nm) = {table.phase[blue, j] / table.phase[red, j]:.2f}"
    )
