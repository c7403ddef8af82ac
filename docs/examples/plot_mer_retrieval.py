"""
A Mars dust fitted to the rovers' sky colour
============================================

The Mars Exploration Rovers saw the sky's chromaticity within CIE 1931
x 0.396-0.408, y 0.377-0.383 (Bell, Savransky & Wolff 2006).  Starting from
Wolff et al. (2009)'s dust (their CRISM index, modified gamma sizes r_eff
1.5 um, v_eff 0.3), whose sky with the Sun 30 degree high is bluer than the
range, ``dustoptics.retrieve`` fits the effective radius (v_eff held) so that
the sky seen as the rovers saw it (away from the Sun, 30 degree above the
horizon; dust optical depth 0.5 at 550 nm, ground albedo 0.2) is the centre
of the range.  The result is the preset ``mer-sky-fit``.

The fit takes minutes of sky solves, so this page plots the run that
``python scripts/mer_retrieval.py --write`` recorded when it wrote the preset
(``docs/examples/mer_retrieval.json``): the path of the fit, its one sigma,
and both dusts' chromaticity against the Sun's elevation.
"""

import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Rectangle

from dustoptics.models import presets
from dustoptics.sky.compare import MER_SKY_CHROMATICITY

try:
    here = Path(__file__).resolve().parent
except NameError:  # run by sphinx-gallery in the examples' directory
    here = Path.cwd()
run = json.loads((here / "mer_retrieval.json").read_text(encoding="utf-8"))
sizes = presets.load_preset("mer-sky-fit").size_distribution.build()
for name, value, error in zip(run["parameters"], run["values"], run["standard_errors"]):
    print(f"{name} = {value:.4f} +- {error:.4f}")
print(f"preset mer-sky-fit: {sizes} ({run['written_by']})")

# %%
# Left: the fit's path in the chromaticity plane (Sun 30 degree) and both dusts'
# sky as the Sun rises (labels: its elevation).  Right: the path in r_eff, with
# the fit's one sigma (how far r_eff may move before the sky leaves one
# half-width of the range's centre).
path_xy = np.array(run["path_xy"])
start_xy = np.array(run["curve_start_xy"])
fitted_xy = np.array(run["curve_fitted_xy"])
elevations = run["curve_sun_elevation_deg"]
(x0, x1), (y0, y1) = MER_SKY_CHROMATICITY["x"], MER_SKY_CHROMATICITY["y"]

fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4.5), layout="constrained")
ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, color="0.85", label="MER range"))
ax.plot(*start_xy.T, "o-", color="tab:blue", label="start: Wolff et al. 2009")
ax.plot(*fitted_xy.T, "o-", color="tab:red", label="fitted: mer-sky-fit")
for xy, elevation in zip(fitted_xy, elevations):
    ax.annotate(f"{elevation:g}", xy, textcoords="offset points", xytext=(4, -10), fontsize=8)
ax.plot(*path_xy.T, "k.--", lw=0.8, label="fit path (Sun 30 deg)")
ax.set_xlabel("CIE 1931 x")
ax.set_ylabel("CIE 1931 y")
ax.set_title("sky away from the Sun, 30 deg up; labels: Sun elevation [deg]")
ax.legend(fontsize=8)

values = np.array(run["path_values"])[:, 0]
value, error = run["values"][0], run["standard_errors"][0]
steps = np.arange(1, values.size + 1)
bx.axhspan(value - error, value + error, color="tab:red", alpha=0.15, label="fitted +- one sigma")
bx.plot(steps, values, "k.--", lw=0.8, label="fit path")
bx.plot(1, values[0], "o", color="tab:blue", label="start")
bx.axhline(value, color="tab:red")
bx.set_xlabel("evaluation of the residuals")
bx.set_ylabel("r_eff [um]")
bx.set_title("the fit in r_eff (v_eff 0.3 held)")
bx.legend(fontsize=8)
plt.show()
