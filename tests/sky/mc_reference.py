"""An independent Monte Carlo sky for the tests (shares no code with dustoptics.sky).

Backward Monte Carlo in a plane-parallel atmosphere: photons leave the
observer on the ground in the viewing direction, fly free paths sampled
from the extinction (the column's optical depth tabulated from the
constituents' profiles by the trapezoid rule on 20,001 altitudes), lose the
single-scattering albedo as weight at each collision, and at every
collision add the Sun's contribution by next-event estimation,
``W * P_mix(Theta) * exp(-tau_up / mu_sun)``; the new direction is drawn
from the phase function of a constituent chosen by its share of
scattering (inverse CDF of the tabulated phase function).  The ground is
black.  The estimate is the mean over photons and its standard error the
standard deviation over photons divided by sqrt(n).
"""

from __future__ import annotations

import numpy as np


def _phase_sampler(theta_deg: np.ndarray, phase: np.ndarray):
    # CDF in mu of the tabulated phase function, piecewise linear in angle
    # (integrated on a 20x finer angle grid).
    fine = np.linspace(0.0, 180.0, 20 * (theta_deg.size - 1) + 1)
    p = np.interp(fine, theta_deg, phase)
    mu = np.cos(np.deg2rad(fine))
    seg = 0.5 * (p[1:] + p[:-1]) * (mu[:-1] - mu[1:]) * 2.0 * np.pi
    cdf = np.concatenate([[0.0], np.cumsum(seg)])
    cdf /= cdf[-1]
    return lambda u: np.deg2rad(np.interp(u, cdf, fine))


def mc_sky_radiance(
    *,
    altitude_m: np.ndarray,
    beta_ext_per_m: np.ndarray,
    beta_sca_per_m: np.ndarray,
    theta_deg: list[np.ndarray],
    phase: list[np.ndarray],
    sun_zenith_deg: float,
    view_zenith_deg: float,
    view_azimuth_deg: float,
    n_photons: int,
    seed: int,
) -> tuple[float, float]:
    """Radiance per unit solar irradiance [sr^-1] and its standard error.

    ``beta_*`` have shape (n_constituent, n_altitude) at one wavelength;
    ``phase[c]`` is constituent c's phase function on ``theta_deg[c]``.
    """
    rng = np.random.default_rng(seed)
    z_grid = altitude_m
    b_ext = beta_ext_per_m.sum(axis=0)
    b_sca_c = beta_sca_per_m
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (b_ext[1:] + b_ext[:-1]) * np.diff(z_grid))])
    tau_top = cum[-1]
    samplers = [_phase_sampler(t, p) for t, p in zip(theta_deg, phase)]
    mus = np.cos(np.deg2rad(sun_zenith_deg))
    sun = np.array([np.sin(np.deg2rad(sun_zenith_deg)), 0.0, mus])
    tv, pv = np.deg2rad(view_zenith_deg), np.deg2rad(view_azimuth_deg)
    d = np.tile([np.sin(tv) * np.cos(pv), np.sin(tv) * np.sin(pv), np.cos(tv)], (n_photons, 1))
    z = np.zeros(n_photons)
    w = np.ones(n_photons)
    total = np.zeros(n_photons)
    alive = np.ones(n_photons, dtype=bool)
    for _ in range(400):
        idx = np.flatnonzero(alive)
        if idx.size == 0:
            break
        dz = d[idx, 2]
        c_here = np.interp(z[idx], z_grid, cum)
        step = -np.log(rng.random(idx.size))
        with np.errstate(divide="ignore", invalid="ignore"):
            c_new = c_here + step * dz
        leaves = (c_new >= tau_top) | (c_new <= 0.0) | (dz == 0.0)
        alive[idx[leaves]] = False  # out of the top, or onto the black ground
        keep = ~leaves
        idx, c_new = idx[keep], c_new[keep]
        z[idx] = np.interp(c_new, cum, z_grid)
        ext_z = np.interp(z[idx], z_grid, b_ext)
        sca_c = np.array([np.interp(z[idx], z_grid, b) for b in b_sca_c])
        sca_z = sca_c.sum(axis=0)
        # Next-event estimate toward the Sun.
        cos_t = d[idx] @ sun
        theta = np.rad2deg(np.arccos(np.clip(cos_t, -1.0, 1.0)))
        p_mix = sum(sca_c[c] * np.interp(theta, theta_deg[c], phase[c]) for c in range(len(phase)))
        t_sun = np.exp(-(tau_top - np.interp(z[idx], z_grid, cum)) / mus)
        with np.errstate(invalid="ignore", divide="ignore"):
            total[idx] += w[idx] * np.where(ext_z > 0, p_mix / ext_z, 0.0) * t_sun
            w[idx] *= np.where(ext_z > 0, sca_z / ext_z, 0.0)
        # New direction: constituent by its share of scattering, angle by its CDF.
        u = rng.random(idx.size) * sca_z
        choice = (u[:, None] > np.cumsum(sca_c, axis=0).T).sum(axis=1)
        choice = np.minimum(choice, len(phase) - 1)
        angle = np.empty(idx.size)
        for c in range(len(phase)):
            sel = choice == c
            angle[sel] = samplers[c](rng.random(int(sel.sum())))
        azim = 2.0 * np.pi * rng.random(idx.size)
        d[idx] = _rotate(d[idx], angle, azim)
        # Russian roulette on small weights (unbiased).
        small = w[idx] < 1e-3
        survive = rng.random(idx.size) < 0.1
        w[idx[small & survive]] *= 10.0
        alive[idx[small & ~survive]] = False
    return float(total.mean()), float(total.std(ddof=1) / np.sqrt(n_photons))


def _rotate(d: np.ndarray, theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    # New unit vectors at polar angle theta and azimuth phi about d.
    ux, uy, uz = d[:, 0], d[:, 1], d[:, 2]
    st, ct = np.sin(theta), np.cos(theta)
    sp, cp = np.sin(phi), np.cos(phi)
    out = np.empty_like(d)
    near_pole = np.abs(uz) > 0.99999
    den = np.sqrt(np.maximum(1.0 - uz * uz, 1e-300))
    out[:, 0] = st * (ux * uz * cp - uy * sp) / den + ux * ct
    out[:, 1] = st * (uy * uz * cp + ux * sp) / den + uy * ct
    out[:, 2] = -st * cp * den + uz * ct
    pole = np.stack([st * cp, st * sp, np.sign(uz) * ct], axis=1)
    out[near_pole] = pole[near_pole]
    return out
