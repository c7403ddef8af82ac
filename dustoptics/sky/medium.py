"""The atmosphere as a scattering medium: per-constituent optics and columns.

A :class:`Medium` is what the radiative transfer needs from an
:class:`~dustoptics.atmosphere.sets.Atmosphere`, once, at its wavelengths:

- per constituent c, the cross-sections per particle ``sigma_ext[c, lambda]``
  and ``sigma_sca[c, lambda]`` [m^2], the number density ``N0[c]`` [m^-3] where
  its relative density is 1, and the relative density ``rho_c(z)`` tabulated
  on a fine altitude grid;
- the Legendre moments ``chi[c, lambda, l]`` of each phase function,
  ``P(mu) = (1 / 4 pi) sum_l (2 l + 1) chi_l P_l(mu)`` with ``chi_0 = 1``
  (``chi_1 = g``), projected from the table by Gauss-Legendre quadrature;
- the delta-M truncation (Wiscombe 1977) of each phase function to the
  ``2 n_streams`` moments that the discrete-ordinate multiple-scattering
  solver resolves: ``f = chi_{2N}``, ``sigma'_sca = (1 - f) sigma_sca``,
  ``sigma'_ext = sigma_ext - f sigma_sca``, ``chi'_l = (chi_l - f) / (1 - f)``.
  Because each constituent is truncated on its own, the scaled extinction of
  any path is again a sum of cross-sections times column amounts, so one
  table of slant columns (:class:`SlantColumns`) gives both the true and the
  scaled transmittance of every path.

References
----------
.. [1] W. J. Wiscombe, "The delta-M method: rapid yet accurate radiative flux
   calculations for strongly asymmetric phase functions," J. Atmos. Sci. 34,
   1408-1422 (1977), doi:10.1175/1520-0469(1977)034<1408:TDMRYA>2.0.CO;2.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, fields
from typing import Final, Generic, TypeVar

import numba
import numpy as np
from numpy.polynomial import legendre
from scipy.special import roots_legendre

from dustoptics._numba_cache import F8, F8_1D, F8_2D, I8, kernel
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky._shared import in_threads
from dustoptics.table import Table

__all__ = [
    "AUREOLE_MOMENTS",
    "N_STREAMS",
    "Medium",
    "MediumOptics",
    "SlantColumns",
    "legendre_moments",
]

#: numba types of the sky's kernels' arguments (:func:`dustoptics._numba_cache.kernel`).
_F8_3D, _F8_4D = "float64[:, :, ::1]", "float64[:, :, :, ::1]"
_I8_2D, _B1_1D = "int64[:, ::1]", "boolean[::1]"

_T = TypeVar("_T")

_UM2_TO_M2: Final = 1e-12
#: Gauss-Legendre nodes used to project a tabulated phase function on P_l.
_PROJECTION_NODES: Final = 4096
#: Altitude samples of the relative densities (linear interpolation between).
_N_DENSITY_SAMPLES: Final = 4001
#: Discrete ordinates per hemisphere unless given: with the fine first orders
#: and the aureole correction, the radiance is within 0.3 % of converged
#: CDISORT for Mars dust up to optical depth 2, 3 deg or more from the Sun
#: (16 streams: 1.1 % there; docs/concepts/sky.rst).
N_STREAMS: Final = 20
#: Legendre moments of each phase function kept for the aureole correction
#: (:func:`dustoptics.sky.render.aureole_correction`): the correction at 3 deg
#: from the Sun changes by less than 1e-4 of the radiance beyond them.
AUREOLE_MOMENTS: Final = 512


def _compute_projection_rule() -> tuple[np.ndarray, np.ndarray]:
    mu, w = roots_legendre(_PROJECTION_NODES)
    mu.setflags(write=False)
    w.setflags(write=False)
    return mu, w


class _Once(Generic[_T]):
    """A value computed once in the process: by the first caller of :meth:`get`, or by a
    thread of its own from :meth:`start` on, so that it is ready when first asked for."""

    def __init__(self, compute: Callable[[], _T]) -> None:
        self._compute = compute
        self._lock = threading.Lock()
        self._future: Future[_T] | None = None

    def _claim(self) -> Future[_T] | None:
        """A new future if nobody computes the value yet (the caller computes it)."""
        with self._lock:
            if self._future is not None:
                return None
            self._future = Future()
            return self._future

    def _run(self, future: Future[_T]) -> None:
        try:
            future.set_result(self._compute())
        except BaseException as exc:  # handed to whoever asks (get)
            future.set_exception(exc)

    def start(self) -> None:
        """Compute the value in a thread of its own, unless it is (being) computed."""
        future = self._claim()
        if future is not None:
            threading.Thread(target=self._run, args=(future,), daemon=True).start()

    def get(self) -> _T:
        """The value (computed now if nobody has started it; else waited for)."""
        future = self._claim()
        if future is not None:
            self._run(future)
        assert self._future is not None
        return self._future.result()


#: The Gauss-Legendre rule of the projections: ``roots_legendre(4096)``, 0.35 s of CPU,
#: computed once per process and shared.
_PROJECTION_RULE: Final = _Once(_compute_projection_rule)


def _projection_rule() -> tuple[np.ndarray, np.ndarray]:
    return _PROJECTION_RULE.get()


def prefetch_projection_rule() -> None:
    """Start computing the projection rule of :func:`legendre_moments` in a thread of its own.

    It depends on nothing: a job that will build a medium starts it before the atmosphere's
    tables, whose first wavelength leaves a core free (it loads the kernels alone), and
    finds it ready.  Its scipy routines release the GIL for most of their work; the values
    are the same whoever computes them.
    """
    _PROJECTION_RULE.start()


def legendre_moments(table: Table, n_moments: int) -> np.ndarray:
    """Legendre moments ``chi_l = 2 pi int P(mu) P_l(mu) dmu`` of a table.

    The table's phase function is read as a renderer reads it (linear in
    angle between its samples, :meth:`~dustoptics.table.Table.phase_at`) and
    projected with a 4,096-node Gauss-Legendre rule in ``mu``.

    Parameters
    ----------
    table : Table
        Phase function normalized to 1 over the sphere. [sr^-1]
    n_moments : int
        Number of moments ``l = 0 .. n_moments - 1``.

    Returns
    -------
    numpy.ndarray, shape (n_wavelength, n_moments)
        ``chi_l``; ``chi_0`` is the table's normalization (1 to its accuracy),
        ``chi_1`` its asymmetry parameter g. [-]
    """
    return _moments(table, _projection_vander(n_moments))


def _projection_vander(n_moments: int) -> np.ndarray:
    """``P_l(mu_i)`` at the projection rule's nodes, l < ``n_moments``: (4096, n_moments)."""
    mu, _ = _projection_rule()
    return legendre.legvander(mu, n_moments - 1)


def _moments(table: Table, vander: np.ndarray) -> np.ndarray:
    """:func:`legendre_moments` with the nodes' Legendre polynomials given (shared by the
    tables of a medium)."""
    mu, w = _projection_rule()
    theta = np.rad2deg(np.arccos(mu))
    p = table.phase_at(theta)
    return 2.0 * np.pi * (p * w) @ vander


@dataclass(frozen=True)
class SlantColumns:
    """Column amounts ``int rho_c ds`` along straight rays, tabulated.

    Rays start at radius ``r`` with cosine ``mu`` of their zenith angle and run
    to the top of the atmosphere; a ray that meets the ground has an infinite
    column (no light gets through).  Radii are tabulated on ``radius_m`` and
    cosines on a grid that is dense near the horizon; lookups interpolate
    linearly (:meth:`columns`).

    Attributes
    ----------
    radius_m : numpy.ndarray, shape (n_r,)
        Radii from the ground to the top. [m]
    mu : numpy.ndarray, shape (n_mu,)
        Increasing cosines of the ray's zenith angle, -1 .. 1. [-]
    column_m : numpy.ndarray, shape (n_constituent, n_r, n_mu)
        ``int rho_c ds`` [m], ``inf`` where the ray meets the ground.
    """

    radius_m: np.ndarray
    mu: np.ndarray
    column_m: np.ndarray

    def columns(self, radius_m: np.ndarray, mu: np.ndarray) -> np.ndarray:
        """Columns [m] of rays from ``radius_m`` with zenith cosine ``mu``.

        Returns an array of shape ``(n_constituent,) + radius_m.shape``.
        """
        r, m = np.broadcast_arrays(np.asarray(radius_m, float), np.asarray(mu, float))
        flat = _columns_many(r.ravel(), m.ravel(), self.radius_m, self.mu, self.column_m)
        return flat.reshape((self.column_m.shape[0],) + r.shape)


@kernel(F8_1D, F8_1D, F8_1D, F8_1D, _F8_3D, group="sky")
def _columns_many(
    r: np.ndarray, mu: np.ndarray, radius_grid: np.ndarray, mu_grid: np.ndarray, columns: np.ndarray
) -> np.ndarray:
    out = np.empty((columns.shape[0], r.size))
    col = np.empty(columns.shape[0])
    for i in range(r.size):
        found = _interp_columns(r[i], mu[i], radius_grid, mu_grid, columns, col)
        for c in range(columns.shape[0]):
            out[c, i] = col[c] if found else np.inf
    return out


@numba.njit(cache=True, nogil=True)
def _search_left(a: np.ndarray, v: float) -> int:
    """``numpy.searchsorted(a, v)`` (side "left") for a sorted ``a``: the first index whose
    value is not below ``v`` (``a.size`` for NaN, which sorts last).  A plain bisection,
    which numba compiles several times faster than its generic ``searchsorted``."""
    lo, hi = 0, a.size
    if v != v:
        return hi
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(cache=True, nogil=True)
def _sort_small(a: np.ndarray) -> None:
    """Sort ``a`` in place, ascending (insertion sort: the few numbers of a path's cuts,
    or samples already sorted but for a few edge crossings)."""
    for i in range(1, a.size):
        v = a[i]
        j = i - 1
        while j >= 0 and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


@numba.njit(cache=True, nogil=True)
def _interp_columns(
    r: float,
    mu: float,
    radius_grid: np.ndarray,
    mu_grid: np.ndarray,
    columns: np.ndarray,
    out: np.ndarray,
) -> bool:
    """Slant columns from (r, mu) to the top; False if the ray meets the ground.

    Bilinear in radius and cosine over the finite corners only: next to the
    rays that meet the ground (infinite columns) a grazing ray takes the
    columns of its grazing neighbours.
    """
    r_ground = radius_grid[0]
    if mu < 0.0 and r * math.sqrt(max(0.0, 1.0 - mu * mu)) < r_ground:
        return False
    nr = radius_grid.shape[0]
    nm = mu_grid.shape[0]
    rr = min(max(r, radius_grid[0]), radius_grid[nr - 1])
    ir = _search_left(radius_grid, rr) - 1
    ir = min(max(ir, 0), nr - 2)
    fr = (rr - radius_grid[ir]) / (radius_grid[ir + 1] - radius_grid[ir])
    mm = min(max(mu, -1.0), 1.0)
    im = _search_left(mu_grid, mm) - 1
    im = min(max(im, 0), nm - 2)
    fm = (mm - mu_grid[im]) / (mu_grid[im + 1] - mu_grid[im])
    den = 0.0
    for c in range(columns.shape[0]):
        out[c] = 0.0
    for corner in range(4):
        di = corner & 1
        dj = corner >> 1
        wgt = (fr if di else 1.0 - fr) * (fm if dj else 1.0 - fm)
        v0 = columns[0, ir + di, im + dj]
        if math.isinf(v0):
            continue
        den += wgt
        for c in range(columns.shape[0]):
            out[c] += wgt * columns[c, ir + di, im + dj]
    if den <= 0.0:
        return False
    for c in range(columns.shape[0]):
        out[c] /= den
    return True


@dataclass(frozen=True)
class _ColumnOptics:
    """What :class:`Medium` and :class:`MediumOptics` hold alike (their attributes but
    the slant columns), and what is derived from it."""

    name: str
    wavelength_nm: np.ndarray
    planet_radius_m: float
    top_altitude_m: float
    roles: tuple[str, ...]
    tables: tuple[Table, ...]
    number_density_per_m3: np.ndarray
    sigma_ext_m2: np.ndarray
    sigma_sca_m2: np.ndarray
    chi: np.ndarray
    truncation: np.ndarray
    altitude_m: np.ndarray
    relative_density: np.ndarray
    edges_m: np.ndarray
    n_streams: int

    @property
    def scaled_sigma_ext_m2(self) -> np.ndarray:
        """Delta-M extinction cross-sections ``sigma_ext - f sigma_sca``. [m^2]"""
        return self.sigma_ext_m2 - self.truncation * self.sigma_sca_m2

    @property
    def scaled_sigma_sca_m2(self) -> np.ndarray:
        """Delta-M scattering cross-sections ``(1 - f) sigma_sca``. [m^2]"""
        return (1.0 - self.truncation) * self.sigma_sca_m2

    @property
    def scaled_chi(self) -> np.ndarray:
        """Delta-M moments ``(chi_l - f) / (1 - f)``, l < 2 n_streams. [-]"""
        f = self.truncation[:, :, None]
        return (self.chi[:, :, : 2 * self.n_streams] - f) / (1.0 - f)

    def density(self, altitude_m: np.ndarray) -> np.ndarray:
        """Number densities ``N0 rho_c(z)``, shape (n_constituent,) + z.shape. [m^-3]"""
        z = np.asarray(altitude_m, dtype=float)
        rho = np.array(
            [np.interp(z, self.altitude_m, r, left=r[0], right=0.0) for r in self.relative_density]
        )
        return rho * self.number_density_per_m3.reshape((-1,) + (1,) * z.ndim)

    def vertical_optical_depth(self) -> np.ndarray:
        """Vertical optical depth of each constituent, shape (n_constituent, n_wavelength). [-]"""
        col = np.trapezoid(self.relative_density, self.altitude_m, axis=1)
        return self.sigma_ext_m2 * (self.number_density_per_m3 * col)[:, None]


@dataclass(frozen=True)
class MediumOptics(_ColumnOptics):
    """A medium's optics without its slant columns: what the budgets read, before any work.

    The estimates of :func:`~dustoptics.sky.orders.estimate_orders_cost` and
    :func:`~dustoptics.sky.render.estimate_render_cost` read the sizes, the
    cross-sections, the vertical optical depths and the delta-M truncation;
    :meth:`from_atmosphere` computes them as :meth:`Medium.from_atmosphere` does
    (the same code) without tabulating the slant columns, the bulk of a medium's
    work, and for a budget without the moments beyond the truncation's, so that a
    request can be refused before the medium is built
    (:func:`dustoptics.sky.space.check_limb_cost`).  The attributes are
    :class:`Medium`'s of the same names (``chi`` to ``2 n_streams`` for a budget).
    """

    @classmethod
    def from_atmosphere(
        cls, atmosphere: Atmosphere, *, n_streams: int = N_STREAMS, budget_only: bool = False
    ) -> MediumOptics:
        """The optics of :meth:`Medium.from_atmosphere` (its parameters checked there).

        With ``budget_only`` the moments stop at ``2 n_streams`` (the truncation's),
        a tenth of the work, and the truncation is the medium's to rounding.
        """
        top = float(atmosphere.thickness_m)
        radius = float(atmosphere.planet_radius_m)
        n_mom = 2 * n_streams + 1 if budget_only else max(2 * n_streams + 1, AUREOLE_MOMENTS)
        roles, tables, n0, ext, sca, chi = [], [], [], [], [], []
        vander = _projection_vander(n_mom)  # one for all the constituents
        for c in atmosphere.constituents:
            t = c.table
            assert t.cross_sections is not None
            assert (
                t.cross_sections is not None and t.cross_sections.number_density_per_m3 is not None
            )
            roles.append(c.role)
            tables.append(t)
            n0.append(t.cross_sections.number_density_per_m3)
            ext.append(t.cross_sections.cext_um2 * _UM2_TO_M2)
            sca.append(t.cross_sections.csca_um2 * _UM2_TO_M2)
            chi.append(
                _moments(t, vander)
                if np.any(t.cross_sections.csca_um2 > 0)
                else np.zeros((t.wavelength_nm.size, n_mom))
            )
        chi_arr = np.array(chi)
        # The projected chi_0 is 1 to the table's accuracy; make it exact so
        # that scattering conserves energy in the solver.
        scatters = np.array([_scatters(t) for t in tables])
        chi_arr[scatters] /= chi_arr[scatters, :, :1]
        f = np.clip(chi_arr[:, :, 2 * n_streams], 0.0, 1.0 - 1e-9)
        edges = _edges(atmosphere, top)
        altitude = _with_edges(_altitude_grid(top, _N_DENSITY_SAMPLES), edges)
        rho = np.array([c.profile.relative_density(altitude) for c in atmosphere.constituents])
        return cls(
            name=atmosphere.name,
            wavelength_nm=np.array(atmosphere.wavelength_nm, dtype=float),
            planet_radius_m=radius,
            top_altitude_m=top,
            roles=tuple(roles),
            tables=tuple(tables),
            number_density_per_m3=np.array(n0, dtype=float),
            sigma_ext_m2=np.array(ext),
            sigma_sca_m2=np.array(sca),
            chi=chi_arr,
            truncation=f,
            altitude_m=altitude,
            relative_density=rho,
            edges_m=edges,
            n_streams=n_streams,
        )


@dataclass(frozen=True)
class Medium(_ColumnOptics):
    """Optics and geometry of an atmosphere at its wavelengths.

    Build it with :meth:`from_atmosphere`.

    Attributes
    ----------
    name : str
        The atmosphere's name.
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Wavelengths. [nm]
    planet_radius_m, top_altitude_m : float
        Ground radius and atmosphere thickness. [m]
    roles : tuple of str
        Constituent roles (``molecules``, ``aerosols``, ``ozone``).
    tables : tuple of Table
        The constituents' tables (phase functions for single scattering).
    number_density_per_m3 : numpy.ndarray, shape (n_constituent,)
        N0 of each constituent. [m^-3]
    sigma_ext_m2, sigma_sca_m2 : numpy.ndarray, shape (n_constituent, n_wavelength)
        Cross-sections per particle. [m^2]
    chi : numpy.ndarray, shape (n_constituent, n_wavelength, n_moments)
        Legendre moments of the phase functions (zeros for ozone),
        ``n_moments = max(2 n_streams + 1, AUREOLE_MOMENTS)``. [-]
    truncation : numpy.ndarray, shape (n_constituent, n_wavelength)
        Delta-M forward-peak fraction f. [-]
    altitude_m : numpy.ndarray, shape (n_z,)
        Fine altitude grid of the relative densities (the edges among its
        nodes). [m]
    relative_density : numpy.ndarray, shape (n_constituent, n_z)
        rho_c on ``altitude_m``. [-]
    edges_m : numpy.ndarray, shape (n_edge,)
        Altitudes strictly inside the atmosphere where some constituent's
        density or its slope jumps (its profile's
        :meth:`~dustoptics.atmosphere.column.DensityProfile.edges_m`),
        increasing: nodes of every grid in altitude (the densities, the slant
        columns' radii, the levels of :func:`~dustoptics.sky.orders.solve_orders`)
        and samples of every line of sight that crosses them, so that a sharp
        layer is integrated as exactly as a smooth one. [m]
    slant : SlantColumns
        Column amounts along rays.
    n_streams : int
        Discrete ordinates per hemisphere of the multiple-scattering solver.
    """

    slant: SlantColumns

    @classmethod
    def from_atmosphere(
        cls,
        atmosphere: Atmosphere,
        *,
        n_streams: int = N_STREAMS,
        n_radii: int = 96,
        n_mu: int = 512,
    ) -> Medium:
        """The medium of an atmosphere set.

        Parameters
        ----------
        atmosphere : Atmosphere
            Constituents with cross-sections, number densities and profiles.
        n_streams : int
            Discrete ordinates per hemisphere (moments resolved by the
            multiple scattering: ``2 n_streams``); default :data:`N_STREAMS`.
        n_radii, n_mu : int
            Grid of the slant-column table (radius, zenith cosine), each in [2, 2048].
        """
        if not isinstance(atmosphere, Atmosphere):
            raise TypeError(f"atmosphere must be an Atmosphere; got {type(atmosphere).__name__}")
        if not (isinstance(n_streams, int) and 2 <= n_streams <= 32):
            raise ValueError(f"n_streams must be an integer in [2, 32]; got {n_streams!r}")
        for key, n in (("n_radii", n_radii), ("n_mu", n_mu)):  # interpolated: 2 at least
            if not (type(n) is int and 2 <= n <= 2048):
                raise ValueError(f"{key} must be an integer in [2, 2048]; got {n!r}")
        o = MediumOptics.from_atmosphere(atmosphere, n_streams=n_streams)
        slant = _slant_columns(
            o.altitude_m, o.relative_density, o.planet_radius_m, o.top_altitude_m,
            n_radii=n_radii, n_mu=n_mu, edges=o.edges_m,
        )  # fmt: skip
        return cls(**{f.name: getattr(o, f.name) for f in fields(o)}, slant=slant)

    def transmittance(
        self, radius_m: np.ndarray, mu: np.ndarray, *, scaled: bool = False
    ) -> np.ndarray:
        """Transmittance to the top of the atmosphere along rays.

        Returns shape ``(n_wavelength,) + radius_m.shape``; 0 for rays that
        meet the ground.
        """
        col = self.slant.columns(np.asarray(radius_m, float), np.asarray(mu, float))
        sigma = self.scaled_sigma_ext_m2 if scaled else self.sigma_ext_m2
        amount = col * self.number_density_per_m3.reshape((-1,) + (1,) * (col.ndim - 1))
        finite = np.isfinite(amount).all(axis=0)
        tau = np.einsum("cl,c...->l...", sigma, np.where(np.isfinite(amount), amount, 0.0))
        return np.where(finite, np.exp(-tau), 0.0)


def _scatters(table: Table) -> bool:
    return table.cross_sections is not None and bool(np.any(table.cross_sections.csca_um2 > 0))


def _edges(atmosphere: Atmosphere, top: float) -> np.ndarray:
    """The constituents' edges strictly between the ground and ``top`` [m], increasing."""
    found = {float(e) for c in atmosphere.constituents for e in c.profile.edges_m()}
    return np.array(sorted(e for e in found if 0.0 < e < top), dtype=float)


def _with_edges(grid: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """``grid`` with ``edges`` among its nodes (the same array when there are none)."""
    return np.union1d(grid, edges) if edges.size else grid


def _altitude_grid(top: float, n: int) -> np.ndarray:
    # Dense near the ground, where the densities change fastest.
    u = np.linspace(0.0, 1.0, n)
    a = 5.0
    return top * np.expm1(a * u) / np.expm1(a)


def _slant_columns(
    altitude: np.ndarray,
    rho: np.ndarray,
    radius: float,
    top: float,
    *,
    n_radii: int,
    n_mu: int,
    edges: np.ndarray,
) -> SlantColumns:
    """Tabulate ``int rho ds`` along rays (compiled Gauss-Legendre sums).

    The radii include the ``edges`` [m] (the columns have a kink there) and
    each ray's path is split where it crosses one (the density jumps or bends
    there), so that every Gauss-Legendre rule integrates a smooth density.
    """
    r_grid = radius + _with_edges(_altitude_grid(top, n_radii), edges)
    # Cosines dense near the horizon (where columns change fastest).
    u = np.linspace(-1.0, 1.0, n_mu)
    mu_grid = np.sign(u) * np.abs(u) ** 3
    x, w = legendre.leggauss(_SLANT_NODES)
    out = np.zeros((rho.shape[0], r_grid.size, mu_grid.size))
    in_threads(
        _slant_kernel, r_grid.size,
        r_grid, mu_grid, 0.5 * (x + 1.0), 0.5 * w, altitude, np.ascontiguousarray(rho), radius,
        top, np.ascontiguousarray(edges, dtype=float), out,
    )  # fmt: skip
    return SlantColumns(radius_m=r_grid, mu=mu_grid, column_m=out)


#: Gauss-Legendre nodes on each part of a slant path.
_SLANT_NODES: Final = 160


@numba.njit(cache=True, nogil=True)
def _path_breaks(
    r: float, mu: float, length: float, radius: float, edges: np.ndarray
) -> np.ndarray:
    """Distances along a ray from radius ``r`` [m] with zenith cosine ``mu`` where it
    crosses the altitudes ``edges`` [m] above ``radius`` [m], within ``(0, length)``,
    unsorted. [m]

    Roots of ``s^2 + 2 r mu s + r^2 - R_e^2 = 0``, with ``r^2 - R_e^2`` formed as
    ``(r - R_e)(r + R_e)`` so that a planet of any size keeps the crossing's
    altitude to rounding.
    """
    out = np.empty(2 * edges.size)
    n = 0
    b = r * mu
    for e in range(edges.size):
        r_e = radius + edges[e]
        disc = b * b - (r - r_e) * (r + r_e)
        if disc < 0.0:
            continue
        q = math.sqrt(disc)
        for s in (-b - q, -b + q):
            if 0.0 < s < length:
                out[n] = s
                n += 1
    return out[:n]


@kernel(I8, I8, F8_1D, F8_1D, F8_1D, F8_1D, F8_1D, F8_2D, F8, F8, F8_1D, _F8_3D, group="sky")
def _slant_kernel(
    lo: int,
    hi: int,
    r_grid: np.ndarray,
    mu_grid: np.ndarray,
    t: np.ndarray,
    w: np.ndarray,
    altitude: np.ndarray,
    rho: np.ndarray,
    radius: float,
    top: float,
    edges: np.ndarray,
    out: np.ndarray,
) -> None:
    # Columns ``out`` (zeros on entry) of the radii ``r_grid[lo:hi]``.  The path is split at the perigee of a downward ray and where it crosses
    # an edge; on each part the substitution s = s0 + span t^2 puts the nodes
    # densely at the end nearer the perigee, where the ray is lowest (the
    # densities fall off with altitude).
    n_c = rho.shape[0]
    r_top = radius + top
    nz = altitude.size
    for i in range(lo, hi):
        r = r_grid[i]
        for j in range(mu_grid.size):
            m = mu_grid[j]
            if m < 0.0 and r * math.sqrt(max(0.0, 1.0 - m * m)) < radius:
                for c in range(n_c):
                    out[c, i, j] = np.inf
                continue
            length = -r * m + math.sqrt(max(r * r * (m * m - 1.0) + r_top * r_top, 0.0))
            s_p = max(-r * m, 0.0)
            breaks = _path_breaks(r, m, length, radius, edges)
            cuts = np.empty(3 + breaks.size)
            cuts[0], cuts[1], cuts[2] = 0.0, s_p, length
            for b in range(breaks.size):
                cuts[3 + b] = breaks[b]
            _sort_small(cuts)
            for part in range(cuts.size - 1):
                lo, hi = cuts[part], cuts[part + 1]
                span = hi - lo
                if span <= 0.0:
                    continue
                for q in range(t.size):
                    if hi <= s_p:
                        s = hi - span * t[q] * t[q]
                    else:
                        s = lo + span * t[q] * t[q]
                    ds = span * 2.0 * t[q] * w[q]
                    h = math.sqrt(max(r * r + s * s + 2.0 * r * m * s, 0.0)) - radius
                    k = _search_left(altitude, h) - 1
                    k = min(max(k, 0), nz - 2)
                    f = (h - altitude[k]) / (altitude[k + 1] - altitude[k])
                    f = min(max(f, 0.0), 1.0)
                    for c in range(n_c):
                        out[c, i, j] += (rho[c, k] * (1.0 - f) + rho[c, k + 1] * f) * ds
