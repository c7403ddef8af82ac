"""The limb seen from space: radiance of the atmosphere against black space.

A distant observer looks along parallel lines of sight past the planet.  A
line of sight is fixed by its tangent point ``T``: the tangent altitude
``h`` above the ground and the limb angle ``psi`` around the planet's disc
(0 where the limb is closest to the Sun's direction).  The Sun's direction
makes the angle ``sun_view_angle_deg`` (``beta``) with the lines of sight, so
every line of sight has the scattering angle ``beta`` (90 deg: the Sun
beside the observer's line of sight, a quadrature view).

Each line of sight is integrated from where it enters the atmosphere to where
it leaves it (or meets the ground) with the ground observer's machinery of
:mod:`dustoptics.sky.render`: exact single scattering in the spherical shell
(the Sun's path to every point), every beam attenuated with the delta-M
scaled extinction.  The multiple-scattering source changes along the limb
with the local Sun: the diffuse field is solved
(:func:`~dustoptics.sky.orders.solve_orders`) at Sun zenith angles every
``field_step_deg`` over the range of the tangent points' local Sun zenith
angles, and each line of sight takes the source of the two fields that
bracket its tangent point's, linearly interpolated (the radiance is linear
in the source, so interpolating the two radiances is interpolating the
sources).  As for the ground observer, the multiple-scattering source takes
the column at each tangent point as laterally uniform; near the terminator,
where the local Sun changes fastest along a line of sight, this is the
approximation's weakest place.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from typing import Any, Final, TextIO

import numpy as np

from dustoptics import colour
from dustoptics._validation import BudgetError, check_closed_interval, check_positive
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky._progress import Reporter, reporter
from dustoptics.sky.medium import Medium, MediumOptics
from dustoptics.sky.orders import N_LAYERS, WORK_BUDGET, estimate_orders_cost, solve_orders
from dustoptics.sky.render import _radiance, check_render_cost
from dustoptics.sky.scene import check_image_size, check_png_support, display_rgb, sunlit_xyz

__all__ = ["LimbRadiance", "check_limb_cost", "limb_radiance"]

#: Largest local Sun zenith angle at a tangent point (that of solve_orders). [deg]
MAX_SUN_ZENITH_DEG: Final = 100.0
#: Samples along a line of sight through the limb (nearly uniform: the
#: tangent point, where the densities are largest, is mid-way).
N_LIMB_PATH: Final = 600
_LIMB_STRETCH: Final = 1e-6


@dataclass(frozen=True, eq=False)
class LimbRadiance:
    """Spectral radiance of the limb seen from space.

    Attributes
    ----------
    name : str
        The atmosphere's name.
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Wavelengths. [nm]
    tangent_altitude_m : numpy.ndarray, shape (n_altitude,)
        Tangent altitudes of the lines of sight. [m]
    limb_angle_deg : numpy.ndarray, shape (n_limb,)
        Limb angles (0: closest to the Sun's direction). [deg]
    radiance : numpy.ndarray, shape (n_altitude, n_limb, n_wavelength)
        Radiance per unit solar irradiance normal to the beam. [sr^-1]
    sun_view_angle_deg : float
        Angle between the Sun's direction and the lines of sight (the
        scattering angle). [deg]
    field_sun_zenith_deg : numpy.ndarray
        Sun zenith angles at which the diffuse field was solved. [deg]
    n_orders : int
        Largest number of orders of scattering summed.
    error_estimate : float
        Largest estimated relative remainder of the series of orders. [-]
    tol : float
        Requested tolerance of the series. [-]
    planet_radius_m : float
        The planet's radius, for :meth:`view` (0: unknown). [m]
    """

    name: str
    wavelength_nm: np.ndarray
    tangent_altitude_m: np.ndarray
    limb_angle_deg: np.ndarray
    radiance: np.ndarray
    sun_view_angle_deg: float
    field_sun_zenith_deg: np.ndarray
    n_orders: int
    error_estimate: float
    tol: float
    planet_radius_m: float = 0.0

    def xyz(self) -> np.ndarray:
        """CIE 1931 XYZ under sunlight, per unit solar illuminance. [sr^-1]"""
        return sunlit_xyz(self.wavelength_nm, self.radiance)

    def default_exposure(self) -> float:
        """Exposure at which the brightest of the limb just reaches display white.

        The largest linear sRGB channel of the computed lines of sight is put
        at 1: no part of the limb clips (the dense low layers keep their colour).
        """
        brightest = float(np.max(colour.xyz_to_linear_srgb(self.xyz()), initial=0.0))
        return 1.0 / brightest if brightest > 0.0 else 1.0

    def image(self, *, exposure: float | None = None) -> np.ndarray:
        """Display sRGB image: tangent altitude upward (rows), limb angle across.

        Returns
        -------
        numpy.ndarray, shape (n_altitude, n_limb, 3), dtype uint8
            The top row is the highest tangent altitude.
        """
        e = self.default_exposure() if exposure is None else check_positive("exposure", exposure)
        return display_rgb(self.xyz()[::-1], e)

    def view_xyz(
        self, *, width: int = 1200, height: int = 400, half_angle_deg: float = 15.0
    ) -> tuple[np.ndarray, tuple[float, float, float, float]]:
        """The limb as a distant camera sees it: the planet's curved edge at true scale.

        The image plane is perpendicular to the lines of sight.  Its centre
        column passes through the limb point at limb angle 0; a pixel at
        ``(u, v)`` km (u along the limb, v up from the ground there) lies at
        ``rho = hypot(R + v, u)`` from the planet's centre and limb angle
        ``psi = atan2(u, R + v)``, so its tangent altitude is ``rho - R``: the
        sky's XYZ is interpolated bilinearly in (altitude, limb angle).
        Pixels below the ground (the surface is not rendered) and above the
        atmosphere are 0.

        Parameters
        ----------
        width, height : int
            Image size, 16 .. 8192 each. [pixels]
        half_angle_deg : float
            Limb angles shown either side of the centre, within the computed
            ones. [deg]

        Returns
        -------
        xyz : numpy.ndarray, shape (height, width, 3)
            CIE XYZ per unit solar illuminance, top row highest. [sr^-1]
        extent_km : tuple of float
            (left, right, bottom, top) of the image in km, for a plot's axes.
        """
        width = check_image_size("width", width)
        height = check_image_size("height", height)
        if not self.planet_radius_m > 0.0:
            raise ValueError("view_xyz needs planet_radius_m (a LimbRadiance from limb_radiance)")
        psi_grid, h_grid = self.limb_angle_deg, self.tangent_altitude_m
        half = check_closed_interval(
            "half_angle_deg", half_angle_deg, 0.5, float(min(-psi_grid[0], psi_grid[-1]))
        )
        r_km = self.planet_radius_m / 1e3
        top_km = float(h_grid[-1]) / 1e3
        u_max = r_km * math.sin(math.radians(half))
        sagitta = r_km * (1.0 - math.cos(math.radians(half)))
        # Room for the atmosphere over the whole arc, and as much planet below it.
        v_top = 1.3 * top_km
        v_bottom = -sagitta - 0.5 * top_km
        u = (np.arange(width) + 0.5) / width * 2.0 * u_max - u_max
        v = v_top - (np.arange(height) + 0.5) / height * (v_top - v_bottom)
        uu, vv = np.meshgrid(u, v)
        rho = np.hypot(r_km + vv, uu)
        h_m = (rho - r_km) * 1e3
        psi = np.degrees(np.arctan2(uu, r_km + vv))
        inside = (h_m >= h_grid[0]) & (h_m <= h_grid[-1])
        xyz = self.xyz()
        ih = np.clip(np.searchsorted(h_grid, h_m) - 1, 0, h_grid.size - 2)
        fh = np.clip((h_m - h_grid[ih]) / (h_grid[ih + 1] - h_grid[ih]), 0.0, 1.0)[..., None]
        ip = np.clip(np.searchsorted(psi_grid, psi) - 1, 0, psi_grid.size - 2)
        fp = np.clip((psi - psi_grid[ip]) / (psi_grid[ip + 1] - psi_grid[ip]), 0.0, 1.0)[..., None]
        out = (
            xyz[ih, ip] * (1 - fh) * (1 - fp)
            + xyz[ih + 1, ip] * fh * (1 - fp)
            + xyz[ih, ip + 1] * (1 - fh) * fp
            + xyz[ih + 1, ip + 1] * fh * fp
        )
        out[~inside] = 0.0
        return out, (-u_max, u_max, v_bottom, v_top)

    def view_png(
        self,
        *,
        width: int = 1200,
        height: int = 400,
        half_angle_deg: float = 15.0,
        exposure: float | None = None,
    ) -> bytes:
        """PNG of :meth:`view_xyz` as a labelled figure: axes in km (the scale), title.

        The exposure puts the brightest of the limb at white
        (:meth:`default_exposure`).  Needs matplotlib (the ``plot`` extra).
        """

        check_png_support()
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        e = self.default_exposure() if exposure is None else check_positive("exposure", exposure)
        xyz, extent = self.view_xyz(width=width, height=height, half_angle_deg=half_angle_deg)
        # The axes hold the view pixel for pixel (no resampling): margins for the labels.
        left, bottom, right, top = 90, 60, 20, 40  # [pixels]
        fig_w, fig_h = width + left + right, height + bottom + top
        fig = plt.figure(figsize=(fig_w / 100.0, fig_h / 100.0), dpi=100)
        ax = fig.add_axes((left / fig_w, bottom / fig_h, width / fig_w, height / fig_h))
        ax.imshow(display_rgb(xyz, e), extent=extent, interpolation="nearest", aspect="auto")
        ax.set_xlabel("along the limb [km]")
        ax.set_ylabel("above the ground at the centre [km]")
        stretch = ((extent[3] - extent[2]) / height) and (
            (extent[1] - extent[0]) / width / ((extent[3] - extent[2]) / height)
        )
        ax.set_title(
            f"{self.name}: the limb from space, Sun {self.sun_view_angle_deg:g} deg from the "
            f"line of sight; heights drawn {stretch:.2g}x; the surface is not rendered"
        )
        buf = io.BytesIO()
        fig.savefig(buf, format="png", metadata={"Software": None})
        plt.close(fig)
        return buf.getvalue()


def limb_geometry(
    *,
    planet_radius_m: float,
    top_radius_m: float,
    tangent_altitude_m: np.ndarray,
    limb_angle_deg: np.ndarray,
    sun_view_angle_deg: float,
) -> dict[str, np.ndarray]:
    """Where each line of sight enters the atmosphere, in the local frame there.

    Lines of sight run along +x; the tangent point is
    ``r_t (0, cos psi, sin psi)``; the Sun is in the direction
    ``(cos beta, sin beta, 0)``.  Returns, per (altitude, limb angle): the
    view cosine ``mu_view`` and the Sun cosine ``mu_sun`` at the entry point,
    the azimuth ``phi_view`` [rad] between them there, and the local Sun zenith
    cosine at the tangent point ``mu_sun_tangent``.
    """
    h, psi = np.meshgrid(tangent_altitude_m, np.deg2rad(limb_angle_deg), indexing="ij")
    beta = math.radians(sun_view_angle_deg)
    r_t = planet_radius_m + h
    half = np.sqrt(np.maximum(top_radius_m**2 - r_t**2, 0.0))
    mu_view = -half / top_radius_m
    s_dot_t = math.sin(beta) * np.cos(psi)  # Sun . (tangent point direction)
    mu_sun = (r_t * s_dot_t - half * math.cos(beta)) / top_radius_m
    sv = np.sqrt(np.maximum(0.0, 1.0 - mu_view**2))
    ss = np.sqrt(np.maximum(0.0, 1.0 - mu_sun**2))
    with np.errstate(invalid="ignore", divide="ignore"):
        cphi = np.where(sv * ss > 1e-12, (math.cos(beta) - mu_view * mu_sun) / (sv * ss), 1.0)
    return {
        "mu_view": mu_view,
        "mu_sun": mu_sun,
        "phi_view": np.arccos(np.clip(cphi, -1.0, 1.0)),
        "mu_sun_tangent": s_dot_t,
    }


def limb_radiance(
    atmosphere: Atmosphere | Medium,
    *,
    sun_view_angle_deg: float = 90.0,
    tangent_altitude_m: Any = None,
    limb_angle_deg: Any = None,
    ground_albedo: float | np.ndarray = 0.2,
    tol: float = 1e-4,
    field_step_deg: float = 10.0,
    n_path: int = N_LIMB_PATH,
    progress: TextIO | Reporter | None = None,
    allow_large: bool = False,
) -> LimbRadiance:
    """The limb of an atmosphere seen from far away in space.

    Parameters
    ----------
    atmosphere : Atmosphere or Medium
        An atmosphere set or its medium.
    sun_view_angle_deg : float
        Angle between the Sun's direction and the lines of sight, 1 .. 179
        (the scattering angle; 90: quadrature). [deg]
    tangent_altitude_m : array_like, optional
        Tangent altitudes, within [0, top); default 120 from the ground to the
        top. [m]
    limb_angle_deg : array_like, optional
        Limb angles; default -60 .. 60 deg in 2 deg steps. [deg]
    ground_albedo : float or array_like
        Lambertian ground albedo. [-]
    tol : float
        Tolerance of the series of orders of scattering. [-]
    field_step_deg : float
        Step of the Sun zenith angles at which the diffuse field is solved. [deg]
    n_path : int
        Samples along each line of sight (nearly uniform).
    progress : text stream, optional
        Where to report the diffuse fields and lines of sight done after the
        first two seconds; None is silent.
    allow_large : bool
        Go ahead beyond the memory and work budget (checked before any work:
        every diffuse field and every line of sight).

    Returns
    -------
    LimbRadiance

    Raises
    ------
    dustoptics._validation.BudgetError
        Beyond the budget and ``allow_large`` is False.
    """
    # Checked before any work: an atmosphere's budget from its optics, before its medium.
    h, psi, geo, sza_t, nodes, k, weight_hi = _limb_plan(
        _optics(atmosphere),
        sun_view_angle_deg=sun_view_angle_deg,
        tangent_altitude_m=tangent_altitude_m,
        limb_angle_deg=limb_angle_deg,
        tol=tol,
        field_step_deg=field_step_deg,
        n_path=n_path,
        allow_large=allow_large,
    )
    medium = atmosphere if isinstance(atmosphere, Medium) else Medium.from_atmosphere(atmosphere)
    beta = float(sun_view_angle_deg)
    top = medium.top_altitude_m
    nwl = medium.wavelength_nm.size
    report = reporter(progress)
    radiance = np.zeros(sza_t.shape + (nwl,))
    n_orders, err = 0, 0.0
    for j, sza in enumerate(nodes):
        share = np.where(k == j, 1.0 - weight_hi, 0.0) + np.where(k + 1 == j, weight_hi, 0.0)
        if nodes.size == 1:
            share = np.ones_like(sza_t)
        rays = share > 0
        if not np.any(rays):
            continue
        report(f"limb: diffuse field {j + 1} of {nodes.size} (Sun at {float(sza):g} deg)")
        field = solve_orders(
            medium,
            sun_zenith_deg=float(sza),
            ground_albedo=ground_albedo,
            tol=tol,
            progress=report,
            allow_large=allow_large,
        )
        n_orders = max(n_orders, field.n_orders)
        err = max(err, float(np.max(field.error_estimate)))
        part = _radiance(
            medium,
            field,
            mu_view=geo["mu_view"][rays],
            phi_view=geo["phi_view"][rays],
            mu_sun=geo["mu_sun"][rays],
            radius_m=medium.planet_radius_m + top,
            n_path=n_path,
            stretch=_LIMB_STRETCH,
            report=report,
            allow_large=allow_large,
        )
        radiance[rays] += share[rays, None] * part
    return LimbRadiance(
        name=medium.name,
        wavelength_nm=medium.wavelength_nm,
        tangent_altitude_m=h,
        limb_angle_deg=psi,
        radiance=radiance,
        sun_view_angle_deg=beta,
        field_sun_zenith_deg=nodes,
        n_orders=n_orders,
        error_estimate=err,
        tol=float(tol),
        planet_radius_m=float(medium.planet_radius_m),
    )


def _optics(atmosphere: Atmosphere | Medium) -> Medium | MediumOptics:
    # What the budget reads: a medium as it is, an atmosphere's optics without the medium's work.
    if isinstance(atmosphere, Medium):
        return atmosphere
    if not isinstance(atmosphere, Atmosphere):
        raise TypeError(
            f"atmosphere must be an Atmosphere or a Medium; got {type(atmosphere).__name__}"
        )
    return MediumOptics.from_atmosphere(atmosphere, budget_only=True)


def _limb_plan(
    medium: Medium | MediumOptics,
    *,
    sun_view_angle_deg: float,
    tangent_altitude_m: Any,
    limb_angle_deg: Any,
    tol: float,
    field_step_deg: float,
    n_path: int,
    allow_large: bool,
) -> tuple[Any, ...]:
    """The limb's checked parameters, geometry and field nodes; its budget checked (no work)."""
    beta = check_closed_interval("sun_view_angle_deg", sun_view_angle_deg, 1.0, 179.0)
    step = check_closed_interval("field_step_deg", field_step_deg, 1.0, 50.0)
    top = medium.top_altitude_m
    h = (
        (np.arange(120) + 0.5) / 120 * top
        if tangent_altitude_m is None
        else np.asarray(tangent_altitude_m, dtype=float)
    )
    psi = (
        np.arange(-60.0, 60.01, 2.0)
        if limb_angle_deg is None
        else np.asarray(limb_angle_deg, dtype=float)
    )
    if h.ndim != 1 or h.size < 1 or not np.all(np.isfinite(h)) or np.any((h < 0) | (h >= top)):
        raise ValueError(
            f"tangent_altitude_m must be a 1-D array within [0, {top:g}) m (inside the atmosphere)"
        )
    if psi.ndim != 1 or psi.size < 1 or not np.all(np.isfinite(psi)):
        raise ValueError("limb_angle_deg must be a finite 1-D array [deg]")
    if not (isinstance(n_path, int) and 16 <= n_path <= 100_000):
        raise ValueError(f"n_path must be an integer in [16, 100000]; got {n_path!r}")
    geo = limb_geometry(
        planet_radius_m=medium.planet_radius_m,
        top_radius_m=medium.planet_radius_m + top,
        tangent_altitude_m=h,
        limb_angle_deg=psi,
        sun_view_angle_deg=beta,
    )
    sza_t = np.rad2deg(np.arccos(np.clip(geo["mu_sun_tangent"], -1.0, 1.0)))
    if sza_t.max() > MAX_SUN_ZENITH_DEG:
        raise ValueError(
            f"limb_angle_deg reaches tangent points with the Sun {sza_t.max():.1f} deg from the "
            f"zenith (sun_view_angle_deg {beta:g}); at most {MAX_SUN_ZENITH_DEG:g} deg is allowed"
        )
    lo = math.floor(sza_t.min() / step) * step
    hi = min(math.ceil(sza_t.max() / step) * step, MAX_SUN_ZENITH_DEG)
    nodes = np.unique(np.append(np.arange(lo, hi, step), hi))
    k = np.clip(np.searchsorted(nodes, sza_t, side="right") - 1, 0, max(nodes.size - 2, 0))
    if nodes.size == 1:
        weight_hi = np.zeros_like(sza_t)
    else:
        weight_hi = (sza_t - nodes[k]) / (nodes[k + 1] - nodes[k])
    # The budget of every field and every line of sight, before any work.
    check_render_cost(
        medium,
        n_rays=2 * sza_t.size,
        n_rows=2 * h.size,
        n_path=n_path,
        allow_large=allow_large,
        what="tangent_altitude_m x limb_angle_deg",
    )
    orders = estimate_orders_cost(medium, n_layers=N_LAYERS, tol=tol)
    if not allow_large and orders.work * nodes.size > WORK_BUDGET:
        largest = max(int(WORK_BUDGET / orders.work), 1)
        raise BudgetError(
            f"limb_radiance would solve {nodes.size} diffuse fields of about {orders.work:.3g} "
            f"multiply-adds each, beyond the budget of {WORK_BUDGET:g}; field_step_deg must give "
            f"at most {largest} fields (a larger step, or fewer wavelengths), or pass "
            "allow_large=True (--allow-large on the command line) to go ahead"
        )
    return h, psi, geo, sza_t, nodes, k, weight_hi


def check_limb_cost(
    atmosphere: Atmosphere | Medium,
    *,
    sun_view_angle_deg: float = 90.0,
    tangent_altitude_m: Any = None,
    limb_angle_deg: Any = None,
    tol: float = 1e-4,
    field_step_deg: float = 10.0,
    n_path: int = N_LIMB_PATH,
    allow_large: bool = False,
) -> None:
    """Check :func:`limb_radiance`'s parameters and budget without computing anything.

    The parameters are :func:`limb_radiance`'s; a caller that computes
    other skies first (``dustoptics sky --space``) calls this before them.
    An atmosphere's budget is estimated from its optics
    (:class:`~dustoptics.sky.medium.MediumOptics`: its cross-sections, optical
    depths and delta-M truncation) without building its medium.

    Raises
    ------
    ValueError
        A parameter out of range (as :func:`limb_radiance` raises it).
    dustoptics._validation.BudgetError
        Beyond the budget and ``allow_large`` is False.
    """
    _limb_plan(
        _optics(atmosphere),
        sun_view_angle_deg=sun_view_angle_deg,
        tangent_altitude_m=tangent_altitude_m,
        limb_angle_deg=limb_angle_deg,
        tol=tol,
        field_step_deg=field_step_deg,
        n_path=n_path,
        allow_large=allow_large,
    )
