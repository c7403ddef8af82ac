"""CDISORT with and without the DISORT file's phase-function block: the sky near the Sun.

Usage::

    python scripts/disort_phase_block.py [--optical-depth TAU] [--sun-zenith-deg SZA]
                                         [--streams N] [--json OUT.json]

A forward-peaked Mars dust layer (the seed thesis's Blue Moon's dust: 3 % hematite, r_eff
1.6 um, v_eff 0.2; g = 0.86 at 440 nm) with Mars's CO2, at vertical optical depth TAU (default
1) at 550 nm, 11.1 km scale height, on a plane-parallel planet (the validation column of
``tests/reference/disort.py``).  The dust's ``NAME_disort.txt`` is written by the ``disort``
format and read back (:func:`dustoptics.io.rt.disort.read_disort`); CDISORT (nanodisort) is
given its moments and, for the new intensity correction of Buras, Dowling and Emde (2011), its
phase block (mixed with CO2's tabulated phase function by scattering coefficient, per layer).
The radiance seen from the ground in the Sun's vertical plane, 0.5 to 20 deg from the Sun
(toward the zenith), at 440, 550 and 670 nm:

- ``reference``: CDISORT converged as in ``tests/reference/disort.py`` (NSTR = 128, 2,048
  moments, the older Nakajima-Tanaka correction);
- ``phase``: CDISORT at NSTR = 2 x ``--streams`` (default 16: NSTR 32), the file's moments
  truncated to NSTR, and the phase block (``old_intensity_correction = FALSE``);
- ``moments``: the same, the moments alone (Nakajima-Tanaka, with the same moments);
- ``moments-all``: NSTR as above, every moment of the file, Nakajima-Tanaka;
- ``sky``: the renderer of :mod:`dustoptics.sky` (its defaults) on the same column.

Prints each one's relative difference from the reference.  Needs the ``test`` extra
(nanodisort).  About two minutes on two cores.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import nanodisort  # type: ignore[import-untyped]
import numpy as np

from dustoptics.io.rt.disort import read_disort, write_disort
from dustoptics.particles.mixing import mars_dust
from dustoptics.particles.sizedist import ModifiedGamma
from dustoptics.scattering.optics import compute_optics
from dustoptics.sky.medium import Medium, legendre_moments
from dustoptics.sky.orders import _layer_amounts, _level_altitudes, solve_orders
from dustoptics.sky.render import line_of_sight_radiance
from tests.reference import disort as ref

WAVELENGTHS_NM = (440.0, 550.0, 670.0)
SUN_DISTANCES_DEG = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0)


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def layer_phase(medium: Medium, dust_index: int, mu: np.ndarray, dust_phase: np.ndarray) -> Any:
    """The layers' phase function at ``mu`` (n_wavelength, n_layers, nphase), 1/2 int P dmu = 1:
    the file's dust block and the other constituents' tables, weighted by scattering."""
    z = _level_altitudes(medium.top_altitude_m, ref.REFERENCE_LAYERS)
    amount = _layer_amounts(medium, z)  # (c, k)
    theta = np.rad2deg(np.arccos(np.clip(mu, -1.0, 1.0)))
    phases = []
    for c, t in enumerate(medium.tables):
        phases.append(dust_phase if c == dust_index else 4 * np.pi * t.phase_at(theta))
    p = np.array(phases)  # (c, x, m)
    w = np.einsum("cx,ck->cxk", medium.sigma_sca_m2, amount)
    return np.einsum("cxk,cxm->xkm", w, p) / w.sum(axis=0)[..., None]


def run_cdisort(
    optics: dict,
    phase: np.ndarray | None,
    mu_phase: np.ndarray,
    *,
    wl: int,
    n_streams: int,
    n_moments: int,
    sza: float,
    umu: np.ndarray,
) -> np.ndarray:
    """Downward radiance at the ground at ``umu`` (< 0), azimuth 0 (toward the Sun)."""
    n_layers = optics["dtau"].shape[1]
    s = nanodisort.DisortState()
    s.nstr, s.nlyr, s.nmom = 2 * n_streams, n_layers, n_moments
    s.ntau, s.numu, s.nphi = 1, umu.size, 1
    s.nphase = 0 if phase is None else mu_phase.size
    s.usrtau = s.usrang = s.lamber = s.quiet = True
    s.onlyfl = False
    s.intensity_correction = True
    s.old_intensity_correction = phase is None
    s.allocate()
    s.dtauc = optics["dtau"][wl].copy()
    s.ssalb = optics["ssa"][wl].copy()
    s.pmom = np.asfortranarray(optics["pmom"][wl, :, : n_moments + 1].T)
    if phase is not None:
        s.mu_phase = mu_phase
        s.phase = np.ascontiguousarray(phase[wl])
    s.utau = np.array([optics["dtau"][wl].sum()])
    s.umu, s.phi = umu, np.array([0.0])
    s.fbeam, s.umu0, s.phi0, s.albedo = 1.0, math.cos(math.radians(sza)), 0.0, 0.0
    s.solve()
    return np.asarray(s.uu)[:, 0, 0].copy()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--optical-depth", type=float, default=1.0)
    p.add_argument("--sun-zenith-deg", type=float, default=45.0)
    p.add_argument("--streams", type=int, default=16, help="CDISORT's NSTR / 2 (default 16)")
    p.add_argument("--json", type=Path)
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    dust = compute_optics(
        mars_dust(),
        ModifiedGamma(r_eff_um=1.6, v_eff=0.2),
        wavelength_nm=list(WAVELENGTHS_NM),
        expansion=True,
        name="mars-dust",
    )
    atm = ref.validation_atmosphere("mars-dust", args.optical_depth, table=dust)
    medium = Medium.from_atmosphere(atm)
    (dust_index,) = [i for i, c in enumerate(atm.constituents) if c.role == "aerosols"]
    with tempfile.TemporaryDirectory() as tmp:
        (path,) = write_disort(medium.tables[dust_index], tmp)
        f = read_disort(path)
    log(
        f"disort file: {f.pmom.shape[1]} moments, nphase {f.mu_phase.size} ({time.perf_counter() - t0:.0f} s)"
    )
    n_all = f.pmom.shape[1] - 1
    sza = args.sun_zenith_deg
    vz = np.array([sza - d for d in SUN_DISTANCES_DEG])
    va = np.zeros_like(vz)
    umu = -np.cos(np.deg2rad(vz))
    order = np.argsort(umu)
    optics = ref.column_optics(medium, n_moments=ref.REFERENCE_MOMENTS)
    # Our file's moments for the dust (the column's projection is the renderer's; both agree
    # to the expansion's accuracy): rebuild the layers' moments with them.
    z = _level_altitudes(medium.top_altitude_m, ref.REFERENCE_LAYERS)
    amount = _layer_amounts(medium, z)
    chi = np.zeros((len(medium.tables), f.pmom.shape[0], ref.REFERENCE_MOMENTS + 1))
    for c, t in enumerate(medium.tables):
        if c == dust_index:
            chi[c, :, : f.pmom.shape[1]] = f.pmom[:, : ref.REFERENCE_MOMENTS + 1]
        else:
            m = legendre_moments(t, ref.REFERENCE_MOMENTS + 1)
            chi[c] = m / m[:, :1]
    w = np.einsum("cx,ck->cxk", medium.sigma_sca_m2, amount)
    file_optics = dict(optics)
    file_optics["pmom"] = np.einsum("cxk,cxl->xkl", w, chi) / w.sum(axis=0)[..., None]
    phase = layer_phase(medium, dust_index, f.mu_phase, f.phase)
    results: dict[str, np.ndarray] = {}
    n_trunc = 2 * args.streams
    runs = {
        "reference": (optics, None, ref.REFERENCE_STREAMS, ref.REFERENCE_MOMENTS),
        "phase": (file_optics, phase, args.streams, n_trunc),
        "moments": (file_optics, None, args.streams, n_trunc),
        "moments-all": (file_optics, None, args.streams, min(n_all, ref.REFERENCE_MOMENTS)),
    }
    for name, (opt, ph, streams, nmom) in runs.items():
        out = np.empty((vz.size, len(WAVELENGTHS_NM)))
        for w_i in range(len(WAVELENGTHS_NM)):
            r = run_cdisort(
                opt,
                ph,
                f.mu_phase,
                wl=w_i,
                n_streams=streams,
                n_moments=nmom,
                sza=sza,
                umu=umu[order],
            )
            out[order, w_i] = r
        results[name] = out
        log(f"{name}: NSTR {2 * streams}, {nmom} moments ({time.perf_counter() - t0:.0f} s)")
    field = solve_orders(medium, sun_zenith_deg=sza, geometry="plane-parallel")
    results["sky"] = line_of_sight_radiance(
        medium, field, view_zenith_deg=vz, view_azimuth_deg=va, observer_altitude_m=0.0
    )
    log(f"sky ({time.perf_counter() - t0:.0f} s)")
    print(
        f"Mars dust tau {args.optical_depth:g} at 550 nm, Sun zenith {sza:g} deg; radiance "
        "relative to the converged reference (NSTR 128, 2048 moments), in %"
    )
    head = f"{'from Sun':>9} {'nm':>4} {'reference':>11} " + " ".join(
        f"{k:>11}" for k in ("phase", "moments", "moments-all", "sky")
    )
    print(head)
    for i, d in enumerate(SUN_DISTANCES_DEG):
        for w_i, nm in enumerate(WAVELENGTHS_NM):
            r = results["reference"][i, w_i]
            cells = " ".join(
                f"{100 * (results[k][i, w_i] / r - 1):+11.3f}"
                for k in ("phase", "moments", "moments-all", "sky")
            )
            print(f"{d:9g} {nm:4g} {r:11.5g} {cells}")
    if args.json:
        args.json.write_text(
            json.dumps(
                {
                    "sun_distance_deg": list(SUN_DISTANCES_DEG),
                    "wavelength_nm": list(WAVELENGTHS_NM),
                    **{k: v.tolist() for k, v in results.items()},
                },
                indent=1,
            )
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
