"""The same column solved by CDISORT: the reference the sky is held against.

:func:`disort_radiance` gives the radiance an observer on the ground sees in
a plane-parallel atmosphere made of a :class:`~dustoptics.sky.medium.Medium`'s
constituents, computed by CDISORT (Buras, Dowling and Emde's C version of
DISORT, Stamnes et al. 1988) through its Python bindings ``nanodisort`` (the
``test`` extra).  The optics are the medium's, unscaled: each layer's optical
depth, single-scattering albedo and Legendre moments of the mixed phase
function (projected from the tables as for the renderer,
:func:`~dustoptics.sky.medium.legendre_moments`, to ``n_moments``); CDISORT
does its own delta-M scaling and its Nakajima-Tanaka intensity correction
(TMS and IMS) from these moments.  Its layers are the renderer's
(:func:`~dustoptics.sky.orders._level_altitudes`), ``n_layers`` of them
and one more at each edge of a sharp layer (the medium's
:attr:`~dustoptics.sky.medium.Medium.edges_m` are levels), homogeneous.

Converged settings for a reference (measured): with ``n_streams=64`` (``NSTR
= 128``) and 40 layers CDISORT agrees with itself at ``NSTR = 192`` and 120
layers to about 1e-4 for Mars dust (r_eff 1.6 um) at optical depth 2; 40
layers are within 1e-4 of 120 for an Earth aerosol 1.2 km high under 8 km of
air.  Near the user angle equal to the Sun's zenith angle CDISORT's
radiance is ill-conditioned (``NSTR = 96``: 5 % off 0.001 deg from it; ``NSTR =
128``: 0.07 %): :func:`validation_directions` keeps 0.25 deg away from it.

:func:`compare_with_disort` holds the renderer (its defaults, a planet so
large that the column is plane-parallel) against this reference for the
validation cases (:data:`VALIDATION_CASES`): Rayleigh scattering, an Earth
aerosol and Mars dust, at :data:`VALIDATION_WAVELENGTHS_NM`, in the
directions a plane-parallel model can judge (Sun elevation >= 20 deg, view
zenith <= 75 deg, 3 deg or more from the Sun).  ``scripts/sky_vs_disort.py``
prints the table of its maximum errors; ``tests/sky/test_sky_vs_cdisort.py`` runs a
subset; both import it from here (with the tests, not in the
package: it checks the product and is no part of it).

References
----------
.. [1] K. Stamnes, S.-C. Tsay, W. Wiscombe and K. Jayaweera, Appl. Opt. 27,
   2502-2509 (1988), doi:10.1364/AO.27.002502.
.. [2] T. E. Dowling, cdisort (C DISORT), as bound by nanodisort
   (https://github.com/rayference/nanodisort).
"""

from __future__ import annotations

import math
from typing import Any, Final

import numpy as np

from dustoptics.atmosphere import sets
from dustoptics.atmosphere.column import ExponentialProfile, PiecewiseLinearProfile
from dustoptics.sky.medium import Medium, _scatters, legendre_moments
from dustoptics.sky.orders import _layer_amounts, _level_altitudes
from dustoptics.table import Table

__all__ = [
    "JUDGED_MAX_VIEW_ZENITH_DEG",
    "JUDGED_MIN_SUN_DISTANCE_DEG",
    "JUDGED_MIN_SUN_ELEVATION_DEG",
    "REFERENCE_LAYERS",
    "REFERENCE_MOMENTS",
    "REFERENCE_STREAMS",
    "SHARP_LAYER",
    "VALIDATION_CASES",
    "VALIDATION_SUN_ELEVATIONS_DEG",
    "VALIDATION_WAVELENGTHS_NM",
    "column_optics",
    "compare_with_disort",
    "disort_radiance",
    "validation_atmosphere",
    "validation_directions",
    "validation_table",
]

#: Discrete ordinates per hemisphere of a converged reference (``NSTR = 128``).
REFERENCE_STREAMS: Final = 64
#: Homogeneous layers of the reference column.
REFERENCE_LAYERS: Final = 40
#: Legendre moments given to CDISORT (its intensity correction uses them all).
REFERENCE_MOMENTS: Final = 2048


def _nanodisort() -> Any:
    try:
        import nanodisort  # type: ignore[import-untyped]
    except ImportError as exc:  # pragma: no cover - depends on the extra
        raise ImportError(
            "the CDISORT reference needs nanodisort: pip install 'dustoptics[test]'"
        ) from exc
    return nanodisort


def column_optics(
    medium: Medium, *, n_layers: int = REFERENCE_LAYERS, n_moments: int = REFERENCE_MOMENTS
) -> dict[str, np.ndarray]:
    """The layers CDISORT is given: optical depth, albedo and moments per wavelength.

    Returns
    -------
    dict
        ``dtau`` (n_wavelength, n_layers), ``ssa`` (n_wavelength, n_layers) and
        ``pmom`` (n_wavelength, n_layers, n_moments + 1); layers from the top.
    """
    z = _level_altitudes(medium.top_altitude_m, n_layers, medium.edges_m)
    amount = _layer_amounts(medium, z)  # (c, k) [m^-2]
    nwl = medium.wavelength_nm.size
    chi = np.array(
        [
            legendre_moments(t, n_moments + 1) if _scatters(t) else np.zeros((nwl, n_moments + 1))
            for t in medium.tables
        ]
    )
    scatters = np.array([_scatters(t) for t in medium.tables])
    chi[scatters] /= chi[scatters, :, :1]
    ext = np.einsum("cx,ck->xk", medium.sigma_ext_m2, amount)
    sca = np.einsum("cx,ck->xk", medium.sigma_sca_m2, amount)
    with np.errstate(invalid="ignore", divide="ignore"):
        pmom = (
            np.einsum("cx,ck,cxl->xkl", medium.sigma_sca_m2, amount, chi)
            / np.where(sca > 0, sca, 1.0)[..., None]
        )
        ssa = np.where(ext > 0, sca / np.where(ext > 0, ext, 1.0), 0.0)
    pmom[sca <= 0] = 0.0
    pmom[..., 0] = 1.0
    return {"dtau": ext, "ssa": ssa, "pmom": pmom}


def disort_radiance(
    medium: Medium,
    *,
    sun_zenith_deg: float,
    view_zenith_deg: Any,
    view_azimuth_deg: Any,
    ground_albedo: float = 0.0,
    n_streams: int = REFERENCE_STREAMS,
    n_layers: int = REFERENCE_LAYERS,
    n_moments: int = REFERENCE_MOMENTS,
    threads: int = 1,
) -> np.ndarray:
    """Radiance seen from the ground of the plane-parallel column, by CDISORT.

    Parameters
    ----------
    medium : Medium
        The atmosphere's optics (its planet radius is not used).
    sun_zenith_deg : float
        Sun's zenith angle, below 90. [deg]
    view_zenith_deg, view_azimuth_deg : array_like
        Viewing directions (upward, zenith angle below 90) and their azimuths
        from the Sun's (0: toward the Sun); same shape. [deg]
    ground_albedo : float
        Lambertian ground albedo. [-]
    n_streams : int
        Discrete ordinates per hemisphere (CDISORT's ``NSTR`` is twice this).
    n_layers : int
        Homogeneous layers.
    n_moments : int
        Legendre moments of the phase functions given to CDISORT.
    threads : int
        Threads of CDISORT's batch solver over the wavelengths.

    Returns
    -------
    numpy.ndarray, shape view_zenith_deg.shape + (n_wavelength,)
        Radiance per unit solar irradiance normal to the beam. [sr^-1]
    """
    nd = _nanodisort()
    vz = np.asarray(view_zenith_deg, dtype=float)
    va = np.asarray(view_azimuth_deg, dtype=float)
    if vz.shape != va.shape:
        raise ValueError("view_zenith_deg and view_azimuth_deg must have the same shape")
    if not (np.all(vz >= 0.0) and np.all(vz < 90.0)):
        raise ValueError("view_zenith_deg must be within [0, 90) deg (upward views)")
    if not 0.0 <= sun_zenith_deg < 90.0:
        raise ValueError(f"sun_zenith_deg must be within [0, 90) deg; got {sun_zenith_deg!r}")
    optics = column_optics(medium, n_layers=n_layers, n_moments=n_moments)
    nwl = medium.wavelength_nm.size
    # Downward radiance (mu < 0) at the bottom, increasing cosines; phi - phi0
    # is the view's azimuth from the Sun (the light travels away from the Sun).
    umu_all = np.round(-np.cos(np.deg2rad(vz.ravel())), 12)
    phi_all = np.round(np.mod(va.ravel(), 360.0), 10)
    umu = np.unique(umu_all)
    phi = np.unique(phi_all)
    s = nd.BatchSolver(nthreads=int(threads))
    s.nstr, s.nlyr, s.nmom = 2 * int(n_streams), optics["dtau"].shape[1], int(n_moments)
    s.ntau, s.numu, s.nphi = 1, umu.size, phi.size
    s.usrtau = s.usrang = s.lamber = s.quiet = True
    s.onlyfl = False
    s.intensity_correction = s.old_intensity_correction = True
    s.umu0, s.phi0 = math.cos(math.radians(sun_zenith_deg)), 0.0
    s.set_umu(umu)
    s.set_phi(phi)
    s.allocate(nwl)
    s.set_dtauc(np.ascontiguousarray(optics["dtau"]))
    s.set_ssalb(np.ascontiguousarray(optics["ssa"]))
    s.set_pmom(np.asfortranarray(optics["pmom"].transpose(2, 1, 0)))
    s.set_fbeam(np.ones(nwl))
    s.set_albedo(np.full(nwl, float(ground_albedo)))
    s.set_utau_batched(optics["dtau"].sum(axis=1)[:, None].copy())
    s.solve()
    uu = np.asarray(s.uu)  # (batch, numu, ntau, nphi)
    iu = np.searchsorted(umu, umu_all)
    ip = np.searchsorted(phi, phi_all)
    out = uu[:, iu, 0, ip].T  # (view, wavelength)
    return out.reshape(vz.shape + (nwl,))


# ---------------------------------------------------------------- validation

#: Wavelengths of the validation. [nm]
VALIDATION_WAVELENGTHS_NM: Final = (440.0, 550.0, 670.0)
#: The validation cases: (kind, vertical optical depth of the particles at 550 nm).
VALIDATION_CASES: Final = (
    ("rayleigh", 0.0),
    ("earth-aerosol", 0.1),
    ("earth-aerosol", 0.4),
    ("mars-dust", 0.5),
    ("mars-dust", 1.0),
    ("mars-dust", 2.0),
    ("mars-dust-layer", 0.5),
)
#: A uniform layer from the ground to 1 km, nothing above (its top 1 mm thick).
SHARP_LAYER: Final = PiecewiseLinearProfile(
    altitude_m=(0.0, 1000.0, 1000.001), density=(1.0, 1.0, 0.0)
)
#: Sun elevations of the validation. [deg]
VALIDATION_SUN_ELEVATIONS_DEG: Final = (20.0, 45.0, 70.0)
#: What a plane-parallel reference can judge: the Sun at least this high, [deg]
JUDGED_MIN_SUN_ELEVATION_DEG: Final = 20.0
#: views at most this far from the zenith, [deg]
JUDGED_MAX_VIEW_ZENITH_DEG: Final = 75.0
#: and at least this far from the Sun. [deg]
JUDGED_MIN_SUN_DISTANCE_DEG: Final = 3.0
#: A planet so large that its atmosphere is plane-parallel (path curvature
#: over 1,000 km: 5e-6 rad). [m]
FLAT_RADIUS_M: Final = 1e11


def validation_table(kind: str, wavelength_nm: Any = VALIDATION_WAVELENGTHS_NM) -> Table:
    """The particles of a validation case, by Mie theory (:func:`dustoptics.compute_optics`).

    ``"earth-aerosol"``: a continental-like Mie aerosol chosen for this check
    (modified gamma, r_eff 0.5 um, v_eff 0.3, m = 1.45 + 0.005i; g = 0.73);
    ``"mars-dust"``: the seed thesis's Blue Moon's dust (3 % hematite by
    Maxwell-Garnett in a host of index 1.5, r_eff 1.6 um, v_eff 0.2; g =
    0.86 at 440 nm).
    """
    from dustoptics.particles.mixing import mars_dust
    from dustoptics.particles.sizedist import ModifiedGamma
    from dustoptics.scattering.optics import compute_optics

    wl = [float(w) for w in np.atleast_1d(wavelength_nm)]
    if kind == "earth-aerosol":
        return compute_optics(
            1.45 + 0.005j, ModifiedGamma(r_eff_um=0.5, v_eff=0.3), wavelength_nm=wl
        )
    if kind == "mars-dust":
        return compute_optics(mars_dust(), ModifiedGamma(r_eff_um=1.6, v_eff=0.2), wavelength_nm=wl)
    raise ValueError(f"kind must be 'earth-aerosol' or 'mars-dust'; got {kind!r}")


def validation_atmosphere(
    kind: str,
    optical_depth: float,
    *,
    wavelength_nm: Any = VALIDATION_WAVELENGTHS_NM,
    table: Table | None = None,
) -> sets.Atmosphere:
    """A validation case's atmosphere on a plane-parallel planet.

    ``"rayleigh"``: Earth's air alone (no ozone, aerosols of zero density);
    ``"earth-aerosol"``: the air and :func:`validation_table`'s aerosol, 1.2
    km scale height, at ``optical_depth`` at 550 nm; ``"mars-dust"``: Mars's
    CO2 and the dust, 11.1 km scale height, at ``optical_depth`` at 550 nm;
    ``"mars-dust-layer"``: the same dust uniform from the ground to 1 km and
    none above (:data:`SHARP_LAYER`, the layer of the ``libradtran`` and
    ``disort`` formats' files).
    ``table`` replaces the Mie computation (the particles at the
    wavelengths).
    """
    wl = [float(w) for w in np.atleast_1d(wavelength_nm)]
    if kind in ("mars-dust", "mars-dust-layer"):
        dust = validation_table("mars-dust", wl) if table is None else table
        return sets.mars_atmosphere(
            dust_table=dust,
            optical_depth=optical_depth,
            dust_profile=SHARP_LAYER if kind == "mars-dust-layer" else None,
            planet_radius_m=FLAT_RADIUS_M,
            atmosphere_radius_m=FLAT_RADIUS_M + 120e3,
            name=kind,
        )
    if kind not in ("rayleigh", "earth-aerosol"):
        raise ValueError(
            "kind must be one of 'rayleigh', 'earth-aerosol', 'mars-dust', 'mars-dust-layer'; "
            f"got {kind!r}"
        )
    profile = ExponentialProfile(scale_height_m=1200.0)
    aerosol = validation_table("earth-aerosol", wl) if table is None else table
    if kind == "rayleigh":
        aerosol = aerosol.replace(cross_sections={"number_density_per_m3": 1e-30})
    else:
        aerosol = sets.with_optical_depth(
            aerosol,
            optical_depth=optical_depth,
            reference_wavelength_nm=550.0,
            profile=profile,
            top_altitude_m=80e3,
        )
    return sets.earth_atmosphere(
        wavelength_nm=wl,
        planet_radius_m=FLAT_RADIUS_M,
        atmosphere_radius_m=FLAT_RADIUS_M + 80e3,
        ozone=None,
        aerosol_table=aerosol,
        aerosol_profile=profile,
        name=kind,
    )


def _scattering_angle(vz: np.ndarray, va: np.ndarray, sza: float) -> np.ndarray:
    mu, mu0 = np.cos(np.deg2rad(vz)), math.cos(math.radians(sza))
    c = mu * mu0 + np.sqrt(1 - mu**2) * math.sqrt(1 - mu0**2) * np.cos(np.deg2rad(va))
    return np.rad2deg(np.arccos(np.clip(c, -1.0, 1.0)))


def validation_directions(
    sun_elevation_deg: float, *, zenith_step_deg: float = 5.0, azimuth_step_deg: float = 15.0
) -> tuple[np.ndarray, np.ndarray]:
    """Viewing directions of the validation: a grid and a ring around the Sun.

    View zenith 0-10 deg in 1 deg steps, then from 12.5 deg in
    ``zenith_step_deg`` steps, and 75 deg, at azimuths 0-180 deg in
    ``azimuth_step_deg`` steps; and directions 3, 4, 5, 7, 10 and 15 deg from
    the Sun in eight directions around it.  Kept: the judged ones (view
    zenith <= 75 deg, >= 3 deg from the Sun), at least 0.25 deg in zenith
    angle from the Sun (CDISORT's ill-conditioned user angle).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        View zenith angles and azimuths from the Sun, 1-D. [deg]
    """
    sza = 90.0 - float(sun_elevation_deg)
    zen = np.concatenate(
        [
            np.arange(0.0, 10.5, 1.0),
            np.arange(12.5, JUDGED_MAX_VIEW_ZENITH_DEG, zenith_step_deg),
            [JUDGED_MAX_VIEW_ZENITH_DEG],
        ]
    )
    azi = np.arange(0.0, 180.0 + 1e-9, azimuth_step_deg)
    zz, aa = (g.ravel() for g in np.meshgrid(zen, azi, indexing="ij"))
    # The ring: rotate the Sun's direction by theta toward eight headings.
    sun = np.array([math.sin(math.radians(sza)), 0.0, math.cos(math.radians(sza))])
    east = np.array([0.0, 1.0, 0.0])
    north = np.cross(east, sun)
    rz, ra = [], []
    for ring in (3.0, 4.0, 5.0, 7.0, 10.0, 15.0):
        t = math.radians(ring)
        for heading in np.deg2rad(np.arange(0.0, 360.0, 45.0)):
            vec = math.cos(t) * sun + math.sin(t) * (
                math.cos(heading) * north + math.sin(heading) * east
            )
            rz.append(math.degrees(math.acos(min(max(vec[2], -1.0), 1.0))))
            ra.append(abs(math.degrees(math.atan2(vec[1], vec[0]))))
    vz = np.concatenate([zz, rz])
    va = np.concatenate([aa, ra])
    theta = _scattering_angle(vz, va, sza)
    keep = (
        (vz <= JUDGED_MAX_VIEW_ZENITH_DEG + 1e-9)
        & (theta >= JUDGED_MIN_SUN_DISTANCE_DEG - 1e-9)
        & (np.abs(vz - sza) >= 0.25)
    )
    return vz[keep], va[keep]


def compare_with_disort(
    atmosphere: sets.Atmosphere,
    *,
    sun_elevation_deg: float,
    view_zenith_deg: np.ndarray | None = None,
    view_azimuth_deg: np.ndarray | None = None,
    reference_streams: int = REFERENCE_STREAMS,
    reference_layers: int = REFERENCE_LAYERS,
    reference_moments: int = REFERENCE_MOMENTS,
    threads: int = 1,
    n_streams: int | None = None,
) -> dict[str, Any]:
    """The renderer's radiance (its defaults) against CDISORT's, from the ground.

    Parameters
    ----------
    atmosphere : Atmosphere
        A plane-parallel atmosphere (:func:`validation_atmosphere`).
    sun_elevation_deg : float
        The Sun's elevation. [deg]
    view_zenith_deg, view_azimuth_deg : array_like, optional
        Directions (default :func:`validation_directions`). [deg]
    reference_streams, reference_layers, reference_moments : int
        CDISORT's ordinates per hemisphere, layers and Legendre moments
        (:func:`disort_radiance`).
    threads : int
        CDISORT's threads.
    n_streams : int, optional
        The renderer's streams (default its own,
        :data:`~dustoptics.sky.medium.N_STREAMS`).

    Returns
    -------
    dict
        ``view_zenith_deg``, ``view_azimuth_deg``, ``theta_deg`` (from the
        Sun), ``radiance`` and ``reference`` (n_view, n_wavelength),
        ``relative_error`` (radiance / reference - 1), ``max_error`` (the
        largest absolute relative error) and ``radiance_error_estimate``
        (:func:`dustoptics.sky.accuracy.radiance_error_estimate` of this run).
    """
    from dustoptics.sky.accuracy import radiance_error_estimate
    from dustoptics.sky.orders import solve_orders
    from dustoptics.sky.render import line_of_sight_radiance

    if view_zenith_deg is None or view_azimuth_deg is None:
        view_zenith_deg, view_azimuth_deg = validation_directions(sun_elevation_deg)
    vz = np.asarray(view_zenith_deg, dtype=float)
    va = np.asarray(view_azimuth_deg, dtype=float)
    sza = 90.0 - float(sun_elevation_deg)
    medium = (
        Medium.from_atmosphere(atmosphere)
        if n_streams is None
        else Medium.from_atmosphere(atmosphere, n_streams=n_streams)
    )
    field = solve_orders(medium, sun_zenith_deg=sza, geometry="plane-parallel")
    ours = line_of_sight_radiance(
        medium, field, view_zenith_deg=vz, view_azimuth_deg=va, observer_altitude_m=0.0
    )
    ref = disort_radiance(
        medium,
        sun_zenith_deg=sza,
        view_zenith_deg=vz,
        view_azimuth_deg=va,
        n_streams=reference_streams,
        n_layers=reference_layers,
        n_moments=reference_moments,
        threads=threads,
    )
    err = ours / ref - 1.0
    return {
        "view_zenith_deg": vz,
        "view_azimuth_deg": va,
        "theta_deg": _scattering_angle(vz, va, sza),
        "radiance": ours,
        "reference": ref,
        "relative_error": err,
        "max_error": float(np.max(np.abs(err))),
        "radiance_error_estimate": radiance_error_estimate(medium, field),
    }
