"""
An analytic fit against its table
=================================

Renderers often replace the tabulated phase function by an analytic one.
``dustoptics.scattering.fit.fit_table`` fits a model to every wavelength of a
table and reports what it costs.  Here the double Henyey-Greenstein of Costa
et al. (2021) and the one-parameter Cornette & Shanks (1992) function are
fitted to the Blue Moon's table at the three wavelengths a renderer uses, and
drawn against it with their relative error.
"""

import matplotlib.pyplot as plt
import numpy as np

from dustoptics.models.presets import build_preset
from dustoptics.scattering.fit import fit_table
from dustoptics.scattering.phase import cornette_shanks1992, dhg_costa2021

table = build_preset("blue-moons")
channels = (440.0, 550.0, 680.0)  # [nm]
rows = [int(np.argmin(np.abs(table.wavelength_nm - w))) for w in channels]
dhg = fit_table(table, model="dhg-costa2021", colour="wavelengths", channels_nm=channels)
cs = fit_table(table, model="cornette-shanks1992", colour="wavelengths", channels_nm=channels)
for fit in (dhg, cs):
    print(fit.model)
    for label, params, err in zip(
        fit.labels, fit.parameters, fit.median_relative_error, strict=True
    ):
        values = ", ".join(f"{n} {v:.4f}" for n, v in zip(fit.parameter_names, params, strict=True))
        print(f"  {label}: {values}; median relative error {err:.3f}")

# %%
# The table (solid), the double Henyey-Greenstein (dashed) and Cornette-Shanks
# (dotted), and their relative errors.
mu = np.cos(np.radians(table.theta_deg))
fig, (ax, ax_err) = plt.subplots(2, 1, figsize=(7, 7), sharex=True, layout="constrained")
for i, (row, colour) in enumerate(zip(rows, ("tab:blue", "tab:green", "tab:red"), strict=True)):
    g1, g2, alpha = dhg.parameters[i]
    p_dhg = dhg_costa2021(mu, g1=g1, g2=g2, alpha=alpha)
    p_cs = cornette_shanks1992(mu, g=cs.parameters[i, 0])
    ax.semilogy(table.theta_deg, table.phase[row], color=colour, label=dhg.labels[i])
    ax.semilogy(table.theta_deg, p_dhg, color=colour, ls="--")
    ax.semilogy(table.theta_deg, p_cs, color=colour, ls=":")
    ax_err.plot(table.theta_deg, p_dhg / table.phase[row] - 1.0, color=colour, ls="--")
    ax_err.plot(table.theta_deg, p_cs / table.phase[row] - 1.0, color=colour, ls=":")
ax.set_ylabel("phase function [sr$^{-1}$]")
ax.legend(title="table (solid), DHG (dashed), CS (dotted)", fontsize=8)
ax_err.axhline(0.0, color="0.5", lw=0.5)
ax_err.set_ylabel("model / table - 1 [-]")
ax_err.set_xlabel("scattering angle [deg]")
ax_err.set_xlim(0, 180)
plt.show()
