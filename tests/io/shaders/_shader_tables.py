"""Tables shared by the shader tests of every language, and the float64 reference.

Imported by the test modules beside it (pytest puts this directory on ``sys.path``).
"""

from __future__ import annotations

import numpy as np

from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.table import CrossSections, Provenance, Table

# lavapipe's compile time grows faster than linearly with the constant array's
# length (measured: 1 s for 181 samples, 80 s for 361 on a loaded 2-core
# machine), so the run uses the table's own 1 deg grid (181 samples); the
# default 721 samples differ only in N and are compiled and validated below.
RUN_RESOLUTION_DEG = 1.0


def hg_table(g: tuple[float, ...] = (0.8, 0.7, 0.6)) -> Table:
    """Henyey-Greenstein phase functions at 440, 550, 680 nm on a 1 deg grid, with cross-sections."""
    theta = np.linspace(0.0, 180.0, 181)
    mu = np.cos(np.deg2rad(theta))
    return Table(
        name="hg",
        wavelength_nm=np.array([440.0, 550.0, 680.0]),
        theta_deg=theta,
        phase=np.array([henyey_greenstein(mu, g=x) for x in g]),
        g=np.array(g),
        cross_sections=CrossSections(
            cext_um2=np.array([2.0, 1.5, 1.0]),
            csca_um2=np.array([1.8, 1.4, 0.95]),
            number_density_per_m3=1e6,
        ),
        provenance=Provenance(inputs={"model": "hg", "g": list(g)}),
    )


#: The table every language's snippet is proved with.
TABLE = hg_table()

#: A second table, for two snippets in one shader.
OTHER_TABLE = hg_table(g=(0.5, 0.4, 0.3))


def exact(table: Table, nu: np.ndarray) -> np.ndarray:
    """The float64 table read by linear interpolation in angle, channels 680, 550, 440 nm."""
    theta = np.degrees(np.arccos(np.clip(nu.astype(np.float64), -1.0, 1.0)))
    return table.phase_at(np.minimum(theta, 180.0))[[2, 1, 0]].T
