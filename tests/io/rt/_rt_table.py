"""The table the radiative-transfer file tests write: Mars dust with expansion coefficients.

Imported by the test modules beside it (pytest puts this directory on ``sys.path``).
"""

from __future__ import annotations

from functools import cache

import numpy as np

import dustoptics as do

N_M3 = 2.0e6  # number density [m-3], a typical Mars dust value (Smith 2004 order of magnitude)


@cache
def rt_table() -> do.Table:
    """Mars dust at 500 and 900 nm, 19 angles, expansion coefficients, N = 2e6 m-3 (computed once)."""
    return do.compute_optics(
        do.mars_dust(),
        do.ModifiedGamma(r_eff_um=1.5, v_eff=0.3),
        [500.0, 900.0],
        np.linspace(0.0, 180.0, 19),
        rtol=1e-3,
        expansion=True,
        name="mars rt",
    ).replace(cross_sections={"number_density_per_m3": N_M3})
