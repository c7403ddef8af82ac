"""
The seed's table against the physical one
=========================================

The seed thesis (Meyran 2022) published a "Blue Moon's" Mars-dust table made
by averaging the phase functions of random radii without weighting them: a
number-weighted mean.  The physical phase function of the same dust weights
each radius by its scattering cross-section (:doc:`/concepts/weighting`).

The preset ``blue-moons-seed`` recomputes the seed's table deterministically
(number weighting, the seed's 1,800 angles; it matches the published file to
0.4-0.5 % in the median at 360, 550 and 680 nm).  The preset ``blue-moons`` is
the physical table of the same dust.  Here both are computed and compared.
"""

import matplotlib.pyplot as plt
import numpy as np

from dustoptics.compare import compare_tables
from dustoptics.models import presets

seed = presets.build_preset("blue-moons-seed")  # number weighting, 48 x 1,800
physical = presets.build_preset("blue-moons")  # scattering weighting, 48 x 1,801
print(seed)
print(physical)

# %%
# The two tables have different angle grids (the seed's step is 180/1799 deg),
# so :func:`~dustoptics.compare.compare_tables` reads both at whole degrees by
# linear interpolation, as a renderer reads a table.

comparison = compare_tables(seed, physical, theta_deg=np.arange(0.0, 181.0))
rows = np.isin(comparison.wavelength_nm, [360.0, 440.0, 550.0, 680.0, 830.0])
print(comparison.to_frame()[rows].round(3).to_string(index=False))

# %%
# The physical forward peak is 2.3-2.4 times higher, and the two differ by
# 20-36 % in the median over angle between 360 and 680 nm.

fig, (ax_phase, ax_ratio) = plt.subplots(1, 2, figsize=(10, 4.2), layout="constrained")
for wavelength_nm, colour in [(440.0, "tab:blue"), (550.0, "tab:green"), (680.0, "tab:red")]:
    i = int(np.flatnonzero(physical.wavelength_nm == wavelength_nm)[0])
    ax_phase.plot(
        physical.theta_deg,
        physical.phase[i],
        color=colour,
        label=f"{wavelength_nm:.0f} nm, scattering weighted",
    )
    ax_phase.plot(
        seed.theta_deg,
        seed.phase[i],
        color=colour,
        linestyle="--",
        label=f"{wavelength_nm:.0f} nm, number weighted (seed)",
    )
ax_phase.set_yscale("log")
ax_phase.set_xlim(0, 180)
ax_phase.set_xlabel("scattering angle theta [degree]")
ax_phase.set_ylabel("phase function P [sr$^{-1}$]")
ax_phase.set_title("Blue Moon's dust: phase functions")
ax_phase.legend(fontsize="x-small")

ax_ratio.plot(
    comparison.wavelength_nm,
    comparison.forward_peak_ratio,
    color="black",
    label="forward peak ratio P_phys(0) / P_seed(0)",
)
ax_ratio.set_xlabel("wavelength [nm]")
ax_ratio.set_ylabel("forward peak ratio [-]")
ax_diff = ax_ratio.twinx()
ax_diff.plot(
    comparison.wavelength_nm,
    100 * comparison.median_rel_diff,
    color="tab:purple",
    label="median |P_phys - P_seed| / P_seed",
)
ax_diff.set_ylabel("median relative difference [%]", color="tab:purple")
ax_ratio.set_title("physical against seed, per wavelength")
ax_ratio.legend(loc="upper right", fontsize="x-small")
ax_diff.legend(loc="lower left", fontsize="x-small")
plt.show()

# %%
# The same comparison from the command line, on files::
#
#     dustoptics build blue-moons-seed --out tables
#     dustoptics build blue-moons --out tables
#
# and :func:`dustoptics.compare.compare_tables` on the tables read back.
