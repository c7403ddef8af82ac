"""Views of the Mie kernel (:mod:`dustoptics.scattering.mie`) for its own tests.

The product calls the kernel's compiled functions directly; these plain-Python
wrappers give the tests the pieces one at a time: the Mie coefficients of a
workspace, the interpolation maps between two symmetric Gauss grids in new arrays,
and the tiered angular sums with a homogeneous sphere's or a coated one's index.
"""

from __future__ import annotations

import numpy as np

from dustoptics.scattering.mie import (
    _AI,
    _AR,
    _BI,
    _BLK,
    _BR,
    _LANE,
    _N_PLANES,
    LANES,
    _accumulate_grids,
    _core_index,
    _interpolation_maps_into,
)


def coefficients(ws: np.ndarray, n_top: int, n_sph: int) -> tuple[np.ndarray, np.ndarray]:
    """a_n, b_n of the spheres of a workspace.

    Parameters
    ----------
    ws : numpy.ndarray
        The workspace after :func:`dustoptics.scattering.mie._mie_coefficients`.
    n_top : int
        The orders to read (n = 1..n_top).
    n_sph : int
        The spheres to read (at most ``LANES``).

    Returns
    -------
    a, b : numpy.ndarray
        Complex, of shape (n_top, n_sph).
    """
    blocks = ws[_LANE : _LANE + n_top * _BLK].reshape(n_top, _N_PLANES, LANES)[:, :, :n_sph]
    a = blocks[:, _AR // LANES] + 1j * blocks[:, _AI // LANES]
    b = blocks[:, _BR // LANES] + 1j * blocks[:, _BI // LANES]
    return a, b


def interpolation_maps(
    mu_half: np.ndarray, w_half: np.ndarray, mu_half_out: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(R_even, R_odd) of :func:`dustoptics.scattering.mie._interpolation_maps_into`.

    Parameters
    ----------
    mu_half, w_half : numpy.ndarray
        The positive half of a symmetric Gauss-Legendre grid and its weights.
    mu_half_out : numpy.ndarray
        The positive half of the grid to map to.

    Returns
    -------
    r_even, r_odd : numpy.ndarray
        New arrays of shape (len(mu_half), len(mu_half_out)).
    """
    r_even = np.empty((mu_half.shape[0], mu_half_out.shape[0]))
    r_odd = np.empty((mu_half.shape[0], mu_half_out.shape[0]))
    _interpolation_maps_into(mu_half, w_half, mu_half_out, r_even, r_odd)
    return r_even, r_odd


def accumulate_tiers(
    m: complex,
    x_nodes: np.ndarray,
    w_nodes: np.ndarray,
    node_panel: np.ndarray,
    node_tier: np.ndarray,
    n_panels: int,
    per_particle: bool,
    tier_size: np.ndarray,
    tables: np.ndarray,
    table_start: np.ndarray,
    maps: np.ndarray,
    map_start: np.ndarray,
    n_stokes: int,
    m_core: complex,
    core_fraction: float,
) -> np.ndarray:
    """:func:`dustoptics.scattering.mie._accumulate` on tiers of symmetric Gauss grids.

    Node j is summed on tier ``node_tier[j]``: the grid of tier_size[t]
    half-grid angles, whose :func:`~dustoptics.scattering.mie.angular_table` is
    ``tables[table_start[t]:table_start[t + 1]]`` (flattened).  Each panel's nodes must
    share one tier, and the nodes come sorted by tier, then by x.  Rows of tiers below
    the last are moved to the last tier's grid by the maps of :func:`interpolation_maps`
    (R_even then R_odd, flattened, at ``maps[map_start[t]:]``).  Returns rows of shape
    (n_panels, 2 n_stokes tier_size[-1] + N_SUMS), as ``_accumulate`` would on the
    largest grid (to the rounding of the interpolation; every block I, Q, U, V of the
    scattering matrix is a polynomial in mu of degree 2 n_max, as the intensity is).
    ``_accumulate_grids`` with ``symmetric`` true; ``m_core`` counts only if
    ``core_fraction`` > 0.
    """
    return _accumulate_grids(
        m,
        x_nodes,
        w_nodes,
        node_panel,
        node_tier,
        n_panels,
        per_particle,
        tier_size,
        tables,
        table_start,
        maps,
        map_start,
        True,
        n_stokes,
        _core_index(m_core, core_fraction),
        core_fraction,
    )
