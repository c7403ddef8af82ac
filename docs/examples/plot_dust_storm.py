"""
A dust-storm table
==================

During a dust storm the Martian atmosphere carries larger grains.  This
example computes a storm table, effective radius 4 um and effective variance
0.3 (modified gamma, Hansen & Travis 1974), for the same dust material as the
Blue Moon's model, and compares it with the clear-season dust (r_eff 1.6 um,
v_eff 0.2).  Larger grains need more radius nodes (their Mie series are
longer and their resonances denser); the quadrature finds them by itself.
"""

import matplotlib.pyplot as plt
import numpy as np

import dustoptics as do

dust = do.mars_dust(hematite_fraction=0.03, host_index=1.5, hematite="querry-extraordinary")
theta_deg = np.linspace(0.0, 180.0, 721)  # 0.25 degree steps, the seed shader's
storm = do.compute_optics(dust, do.ModifiedGamma(r_eff_um=4.0, v_eff=0.3), theta_deg=theta_deg)
clear = do.compute_optics(dust, do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2), theta_deg=theta_deg)
for name, t in (("storm", storm), ("clear", clear)):
    print(
        f"{name}: {t.quadrature.n_nodes.min()}-{t.quadrature.n_nodes.max()} radius nodes, "
        f"error estimate <= {t.quadrature.error_estimate.max():.1e}"
    )

# %%
# Phase functions at three wavelengths, and the spectra of the
# single-scattering albedo, the asymmetry parameter and the extinction
# efficiency.  The storm's larger grains scatter more strongly forward, absorb
# more (lower albedo) and depend less on wavelength.

fig, axes = plt.subplots(2, 2, figsize=(10, 7), layout="constrained")
ax = axes[0, 0]
for wavelength_nm, colour in [(440.0, "tab:blue"), (550.0, "tab:green"), (680.0, "tab:red")]:
    i = int(np.flatnonzero(storm.wavelength_nm == wavelength_nm)[0])
    ax.plot(theta_deg, storm.phase[i], color=colour, label=f"storm {wavelength_nm:.0f} nm")
    ax.plot(
        theta_deg,
        clear.phase[i],
        color=colour,
        linestyle=":",
        label=f"clear {wavelength_nm:.0f} nm",
    )
ax.set_yscale("log")
ax.set_xlim(0, 180)
ax.set_xlabel("scattering angle theta [degree]")
ax.set_ylabel("phase function P [sr$^{-1}$]")
ax.legend(fontsize="x-small", ncol=2)
for ax, key, label in [
    (axes[0, 1], "ssa", "single-scattering albedo [-]"),
    (axes[1, 0], "g", "asymmetry parameter g [-]"),
    (axes[1, 1], "qext", "extinction efficiency Q_ext [-]"),
]:
    ax.plot(
        storm.wavelength_nm,
        storm.quantity(key),
        color="tab:brown",
        label="storm, r_eff 4 um, v_eff 0.3",
    )
    ax.plot(
        clear.wavelength_nm,
        clear.quantity(key),
        color="tab:gray",
        label="clear, r_eff 1.6 um, v_eff 0.2",
    )
    ax.set_xlabel("wavelength [nm]")
    ax.set_ylabel(label)
    ax.legend(fontsize="x-small")
fig.suptitle("Mars dust: storm against clear season")
plt.show()

# %%
# The same table from the command line: write a configuration file with its
# own name, description and sources, the same material and the storm's size
# distribution (:doc:`/howto/scientist` shows one), and build it::
#
#     dustoptics build storm.toml --out tables
