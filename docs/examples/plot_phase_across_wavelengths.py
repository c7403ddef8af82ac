"""
The dust's phase function across wavelengths
============================================

Martian dust scatters blue light into a narrower forward peak than red light,
and backscatters less of it: that is the blue aureole around the Martian Sun.
This example computes the physical Blue Moon's table (Ehlers et al. 2014 dust
in the Tomasko et al. 1999 size distribution, cross-section weighted Mie) at
48 wavelengths and draws its phase function at every tenth nanometre step, a
colour per wavelength, and the phase over wavelength and angle as a map.
"""

import matplotlib.pyplot as plt
import numpy as np

from dustoptics.models.presets import build_preset

table = build_preset("blue-moons")
print(
    f"{table.wavelength_nm.size} wavelengths, {table.theta_deg.size} angles; "
    f"g from {table.g.min():.3f} to {table.g.max():.3f}; "
    f"phase error estimate <= {table.quadrature.error_estimate.max():.1e}"
)

# %%
# Phase functions, coloured by wavelength (violet 360 nm to red 830 nm).
fig, (ax, ax_ratio) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
colours = plt.cm.turbo(np.linspace(0.0, 1.0, table.wavelength_nm.size))
for i in range(0, table.wavelength_nm.size, 4):
    label = f"{table.wavelength_nm[i]:.0f} nm"
    ax.semilogy(table.theta_deg, table.phase[i], color=colours[i], lw=1, label=label)
ax.set_xlabel("scattering angle [deg]")
ax.set_ylabel("phase function [sr$^{-1}$]")
ax.set_xlim(0, 180)
ax.legend(fontsize=7, ncols=2)
ax.set_title("blue-moons: phase function")

# %%
# Relative to 550 nm: blue (short) wavelengths are brighter in the forward
# peak and darker in the back.
i550 = int(np.argmin(np.abs(table.wavelength_nm - 550.0)))
for i in range(0, table.wavelength_nm.size, 4):
    ratio = table.phase[i] / table.phase[i550]
    ax_ratio.plot(table.theta_deg, ratio, color=colours[i], lw=1)
ax_ratio.set_xscale("symlog", linthresh=10.0)
ax_ratio.set_xlim(0, 180)
ax_ratio.set_xlabel("scattering angle [deg] (linear below 10)")
ax_ratio.set_ylabel("phase / phase at 550 nm [-]")
ax_ratio.set_title("against 550 nm")
plt.show()
