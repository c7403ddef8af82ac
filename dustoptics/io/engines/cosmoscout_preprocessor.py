"""CosmoScout VR's ``bruneton-preprocessor``: every sampling option, chosen for a set.

CosmoScout VR's ``csp-atmospheres`` plugin renders precomputed textures that
its ``bruneton-preprocessor`` makes from a settings JSON and the CSV set of
:mod:`dustoptics.io.csv.cosmoscout` [1]_.  This module is one concept: the
preprocessor's quadrature, and the values of its options that keep its
errors within a tolerance for a given set.  Read at commit
e59005a3bbea2426c841f30da6cb35a4d313455e of cosmoscout/cosmoscout-vr, whose
preprocessor files are identical to release v1.10.0 (``Params.hpp``,
``Params.cpp``, ``main.cpp``, ``Preprocessor.cpp``,
``shaders/csp-atmosphere-preprocessing-functions.glsl``).

The options and how they are chosen (tolerance ``tol``, default 0.5 %):

``refraction``
    Bent rays (Runge-Kutta through the molecules' index) and, with it, fixed
    steps in metres; without it, fixed sample counts along straight rays.
    Chosen on where the bending is visible: the horizon ray from the ground is
    bent by about ``(n - 1) sqrt(pi R / (2 H))`` (Mars 0.005 deg, Earth 0.56 deg);
    refraction is on when that exceeds a tenth of the Sun's angular radius.
    Off is also cheaper (hundreds of samples per ray instead of the horizontal
    path over the step) and its in-scattering quadrature is second order.
``stepSizeOpticalDepth`` [m], ``sampleCountOpticalDepth``
    The transmittance integrals.  With steps, sample ``k`` sits at ``k dx``
    along the ray, with weight 1/2 for the first and the fraction of its
    segment below the top for the last: the trapezoid rule for a zenith ray.
    Without, the trapezoid with N + 1 points over the straight ray.  Both are
    chosen by running that quadrature here, on the density file as the
    preprocessor reads it (below), against the exact column of each profile:
    the largest step, and the smallest count from the default 500 up, that
    keep the transmittance within ``tol / 2`` of ``exp(-tau)`` at every
    wavelength of the set (the preprocessor runs one pass per three of
    them): from the ground to the top
    along the zenith for the steps, along straight rays from the zenith to the
    horizon for the counts (where ``exp(-tau) >= 1e-3``).  The other half of
    ``tol`` is left to what the simulation does not model (float32 sums on the
    GPU, its fixed-point filter weights, the bending of slant rays).  With
    refraction on, only the zenith is checked: below mu 0.2 the bent rays of
    the texture depart from the straight-ray ``exp(-tau)`` by the bending
    itself, a physical difference, not an error of the quadrature.  When no
    value tried meets ``tol / 2``, the finest is used and its reason says what
    it leaves.  The stated ``transmittance_error`` adds the error of the set's
    wavelength sampling at the wavelengths engines render, 440, 550 and 680 nm
    (:func:`wavelength_sampling_error`).
``stepSizeSingleScattering``, ``stepSizeMultiScattering`` [m]
    With steps, the in-scattering sums add a sample's own segment to the
    optical depth before using it, which darkens the result by about
    ``beta_ext dx / 2`` (first order): ``dx <= 2 tol / beta_ext`` at the
    ground (the largest over wavelengths), and ``dx <= H sqrt(12 tol)`` for the
    thinnest scattering layer (effective scale height ``H``).
``sampleCountSingleScattering``, ``sampleCountMultiScattering``
    Without steps, a trapezoid over the path to the nearest boundary:
    ``N >= L beta_ext / sqrt(12 tol)`` along the horizontal path ``L`` from the
    ground to the top, and ``N >= T / (H sqrt(12 tol))`` across the thinnest
    layer of a column of thickness ``T``.
``multiScatteringOrder``, ``scatteringTextureNuSize``, ``sampleCountScatteringDensity``, ``sampleCountIndirectIrradiance``
    :mod:`dustoptics.io.engines.precomputation` over every wavelength of the
    set (``multiScatteringOrder`` counts the orders beyond the first: ``K - 1``).
Texture sizes, ``maxSunZenithAngle``, ``groundAlbedo``
    Written with the preprocessor's own defaults (Bruneton's sizes; 120 deg;
    0.1), so that the file states everything it runs with.

How the preprocessor reads the files (beyond the CSV rules): a density file's
N values fill a linearly filtered, edge-clamped texture over the thickness
``T`` read at ``u = altitude / T``, so value ``i`` stands at altitude
``(i + 1/2) T / N`` (the texel centre), constant below the first and above
the last; a phase file's n columns fill a texture read at
``u = acos(nu) / pi``, so column ``j`` stands at ``(j + 1/2) 180 / n`` deg.
:mod:`dustoptics.io.csv.cosmoscout` writes both at those places.

Checked against CosmoScout's own code: ``scripts/cosmoscout_preprocessor.py``
compiles the preprocessor of that commit and runs it on the Mars and Earth
sets; the transmittance it writes agrees with :func:`preprocessor_transmittance`
to the float32 rounding of its sums and is within ``tol`` of ``exp(-tau)``
(``tests/io/engines/test_cosmoscout_real_preprocessor.py``, where
``COSMOSCOUT_VR_DIR`` names a checkout).

References
----------
.. [1] German Aerospace Center (DLR), CosmoScout VR, ``plugins/csp-atmospheres/
   bruneton-preprocessor``, https://github.com/cosmoscout/cosmoscout-vr (MIT and
   BSD-3-Clause), commit e59005a3bbea2426c841f30da6cb35a4d313455e (v1.10.0 for these files).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from dustoptics._validation import check_closed_interval, check_open_interval
from dustoptics.io.engines.precomputation import (
    BRUNETON_DEFAULTS,
    PrecomputationSampling,
    effective_scale_height_m,
    precomputation_sampling,
)

if TYPE_CHECKING:
    from dustoptics.atmosphere.sets import Atmosphere

__all__ = [
    "COSMOSCOUT_COMMIT",
    "COSMOSCOUT_DEFAULTS",
    "SUN_RADIUS_M",
    "CosmoScoutSampling",
    "cosmoscout_sampling",
    "horizon_refraction_rad",
    "preprocessor_transmittance",
    "wavelength_sampling_error",
]

#: The commit of cosmoscout/cosmoscout-vr read (its preprocessor files are those of v1.10.0).
COSMOSCOUT_COMMIT: Final = "e59005a3bbea2426c841f30da6cb35a4d313455e"

#: The Sun's radius CosmoScout's preprocessor uses for its angular radius. [m]
SUN_RADIUS_M: Final = 696_340_000.0

#: The preprocessor's defaults (``Params.hpp``), by JSON key.
COSMOSCOUT_DEFAULTS: Final = {
    "refraction": True,
    "groundAlbedo": 0.1,
    "multiScatteringOrder": 4,
    "sampleCountOpticalDepth": 500,
    "stepSizeOpticalDepth": 10000,
    "sampleCountSingleScattering": 50,
    "stepSizeSingleScattering": 10000,
    "sampleCountMultiScattering": 50,
    "stepSizeMultiScattering": 10000,
    "sampleCountScatteringDensity": 16,
    "sampleCountIndirectIrradiance": 32,
    "transmittanceTextureWidth": 256,
    "transmittanceTextureHeight": 64,
    "scatteringTextureRSize": 32,
    "scatteringTextureMuSize": 128,
    "scatteringTextureMuSSize": 32,
    "scatteringTextureNuSize": 8,
    "irradianceTextureWidth": 64,
    "irradianceTextureHeight": 16,
    "maxSunZenithAngle": 120.0 / 180.0 * math.pi,
}

#: Steps tried for the transmittance, largest first. [m]
_STEPS_M: Final = (
    10000, 8000, 6000, 5000, 4000, 3000, 2500, 2000, 1500, 1200, 1000, 800, 600, 500, 400, 300,
    250, 200, 150, 100, 50, 20, 10,
)  # fmt: skip
#: Sample counts tried for the transmittance, smallest first (from the preprocessor's default).
_COUNTS: Final = (500, 750, 1000, 1500, 2000, 3000, 5000, 10000, 20000)
#: Zenith cosines of the straight rays checked (refraction off).
_MUS: Final = (1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.0)
#: Share of the tolerance the simulated transmittance may use (the rest is left to what the
#: simulation does not model: float32 sums on the GPU, its fixed-point filter weights, bending).
_MARGIN: Final = 0.5
#: Transmittances below this are not checked (a ray that dims the Sun a thousandfold shows nothing).
_VISIBLE: Final = 1e-3
#: Refraction on when the horizon bending exceeds this fraction of the Sun's angular radius.
_REFRACTION_FRACTION: Final = 0.1

#: Options the caller may set, and whether a larger value is finer (True) or coarser.
_FINER_IF_LARGER: Final = {
    "multiScatteringOrder": True,
    "sampleCountOpticalDepth": True,
    "stepSizeOpticalDepth": False,
    "sampleCountSingleScattering": True,
    "stepSizeSingleScattering": False,
    "sampleCountMultiScattering": True,
    "stepSizeMultiScattering": False,
    "sampleCountScatteringDensity": True,
    "sampleCountIndirectIrradiance": True,
    "scatteringTextureNuSize": True,
}


# ------------------------------------------------------------------ the quadrature


@dataclass(frozen=True)
class _Column:
    """What the preprocessor reads of one constituent, and the truth."""

    density: np.ndarray  # float32 values of the density file
    beta_ext_per_m: np.ndarray  # float32, per wavelength, where the file's density is 1
    exact_tau: np.ndarray  # the profile's vertical optical depth, per wavelength
    profile: Any
    peak: float  # file density = profile / peak


def _columns(atmosphere: Atmosphere) -> list[_Column]:
    out = []
    written = atmosphere.cosmoscout_constituents()
    for c in atmosphere.constituents:
        table, density = written[atmosphere.file_prefix(c.role)]
        n0 = c.table.quantity("number_density_per_m3")
        assert n0 is not None and (
            table.cross_sections is not None
            and table.cross_sections.number_density_per_m3 is not None
        )
        out.append(
            _Column(
                density=np.asarray(density, dtype=np.float32),
                beta_ext_per_m=np.asarray(table.beta_ext_per_m, dtype=np.float32),
                exact_tau=np.asarray(c.table.beta_ext_per_m, dtype=np.float64)
                * c.profile.column_length_m(top_altitude_m=atmosphere.thickness_m),
                profile=c.profile,
                peak=table.cross_sections.number_density_per_m3 / n0,
            )
        )
    return out


def _lookup(values: np.ndarray, altitude_m: np.ndarray, thickness_m: float) -> np.ndarray:
    """The density texture: linear between texel centres, clamped, at u = altitude / T."""
    n = values.size
    x = np.clip(altitude_m / thickness_m, 0.0, 1.0) * n - 0.5
    i0 = np.floor(x)
    t = x - i0
    i = i0.astype(np.int64)
    a = values[np.clip(i, 0, n - 1)].astype(np.float64)
    b = values[np.clip(i + 1, 0, n - 1)].astype(np.float64)
    return a + (b - a) * t


def _zenith_steps(step_m: int, thickness_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Sample altitudes and weights [m] of the fixed-step loop along a zenith ray from the ground."""
    dx = float(step_m)
    last = max(0, math.ceil((thickness_m - dx / 2.0) / dx))  # first k with (k + 1/2) dx > T
    k = np.arange(last + 1, dtype=np.float64)
    w = np.ones(k.size)
    w[0] = 0.5
    seg_start, seg_end = (last - 0.5) * dx, (last + 0.5) * dx
    w[-1] = 1.0 - (seg_end - thickness_m) / (seg_end - seg_start)
    return k * dx, w * dx


def _straight_ray(mu: float, count: int, radius_m: float, thickness_m: float):
    """Altitudes and trapezoid weights of N + 1 points along a straight ray to the top."""
    r, top = radius_m, radius_m + thickness_m
    d = -r * mu + math.sqrt(max(0.0, r * r * (mu * mu - 1.0) + top * top))
    s = np.linspace(0.0, d, count + 1)
    alt = np.sqrt(s * s + 2.0 * r * mu * s + r * r) - r
    w = np.full(count + 1, d / count)
    w[0] = w[-1] = 0.5 * d / count
    return alt, w, d


def _transmittance(
    columns: list[_Column],
    *,
    radius_m: float,
    thickness_m: float,
    refraction: bool,
    step_m: int = 10000,
    sample_count: int = 500,
    mu: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    tau = np.zeros_like(columns[0].exact_tau)
    exact = np.zeros_like(tau)
    if refraction:
        if mu != 1.0:
            raise ValueError(f"mu must be 1 (a zenith ray) with refraction; got {mu!r}")
        ray_alt, ray_w = _zenith_steps(int(step_m), thickness_m)
    else:
        ray_alt, ray_w, _ = _straight_ray(float(mu), int(sample_count), radius_m, thickness_m)
        fine_alt, fine_w, _ = _straight_ray(float(mu), 100000, radius_m, thickness_m)
    for col in columns:
        length = float(np.sum(ray_w * _lookup(col.density, ray_alt, thickness_m)))
        tau += col.beta_ext_per_m.astype(np.float64) * length
        if mu == 1.0:
            exact += col.exact_tau
        else:
            rho = np.asarray(col.profile.relative_density(np.clip(fine_alt, 0.0, thickness_m)))
            vertical = col.profile.column_length_m(top_altitude_m=thickness_m)
            exact += col.exact_tau * float(np.sum(fine_w * rho)) / vertical
    return np.exp(-tau), np.exp(-exact)


def preprocessor_transmittance(
    atmosphere: Atmosphere,
    *,
    refraction: bool,
    step_m: int = 10000,
    sample_count: int = 500,
    mu: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Transmittance from the ground to the top as the preprocessor integrates it, and the exact one.

    Parameters
    ----------
    atmosphere : Atmosphere
        The set, as :mod:`dustoptics.io.csv.cosmoscout` writes it (density
        files at the texel centres, float32 as the reader parses them).
    refraction : bool
        Fixed steps (``stepSizeOpticalDepth``; a zenith ray, which refraction
        does not bend) or fixed counts (``sampleCountOpticalDepth``; any
        straight ray).
    step_m : int
        ``stepSizeOpticalDepth`` (the preprocessor reads an integer). [m]
    sample_count : int
        ``sampleCountOpticalDepth``.
    mu : float
        Zenith cosine of the ray (refraction off only; 1 with refraction). [-]

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        The preprocessor's transmittance and ``exp(-tau)`` of the profiles
        along the same ray, at every wavelength of the set. [-]
    """
    return _transmittance(
        _columns(atmosphere),
        radius_m=atmosphere.planet_radius_m,
        thickness_m=atmosphere.thickness_m,
        refraction=refraction,
        step_m=step_m,
        sample_count=sample_count,
        mu=mu,
    )


# ------------------------------------------------------------------ the rules


def horizon_refraction_rad(atmosphere: Atmosphere) -> float:
    """Bending of the horizontal ray from the ground to space: ``(n - 1) sqrt(pi R / (2 H))``. [rad]

    ``n - 1`` is the set's refractivity at the ground, ``H`` the molecules'
    effective scale height; the bending of a ray through an exponential
    atmosphere, to first order in ``n - 1``.
    """
    h = effective_scale_height_m(
        atmosphere.constituent("molecules").profile, top_altitude_m=atmosphere.thickness_m
    )
    return atmosphere.refractivity * math.sqrt(math.pi * atmosphere.planet_radius_m / (2.0 * h))


@dataclass(frozen=True)
class CosmoScoutSampling:
    """The preprocessor's options chosen for one set, with the errors they leave.

    Attributes
    ----------
    settings : dict
        Every sampling option by its JSON key (``refraction``,
        ``multiScatteringOrder``, step sizes [m], sample counts, texture
        sizes, ``maxSunZenithAngle`` [rad], ``groundAlbedo``).
    tolerance : float
        The error the rules keep within. [-]
    transmittance_error : float
        The set's whole stated transmittance error: :attr:`quadrature_error`
        plus :attr:`wavelength_error` (where known). [-]
    inactive_transmittance_error : float
        The quadrature error with the other quadrature's option (so that
        switching ``refraction`` keeps the transmittance right), plus
        :attr:`wavelength_error`. [-]
    horizon_refraction_rad : float
        :func:`horizon_refraction_rad`. [rad]
    precomputation : PrecomputationSampling
        Orders, NU size and scattering-density directions.
    reasons : dict
        Why each chosen value (by JSON key).
    quadrature_error : float
        Largest relative error of the ground-to-top transmittance with the
        active quadrature (steps with refraction, along the zenith; counts
        without, along straight rays from the zenith to the horizon), over the
        set's wavelengths, against ``exp(-tau)`` along straight rays (with
        refraction the texture departs from that below mu 0.2, by the bending
        itself: not an error, and not checked). [-]
    wavelength_error : float
        :func:`wavelength_sampling_error`: what the set's wavelength sampling
        adds at 440, 550 and 680 nm (``nan`` if the set carries no exact
        optics there). [-]
    wavelength_errors : dict
        The same per wavelength (``"440"``, ``"550"``, ``"680"``). [-]
    notes : tuple of str
        What the preprocessor will not do with this set (its wavelength rules,
        ``main.cpp`` and ``Preprocessor.cpp``: at least three; exactly 440,
        550, 680 nm when three; passes of three with the remainder dropped;
        luminance weights for evenly spaced wavelengths).
    """

    settings: dict[str, Any]
    tolerance: float
    transmittance_error: float
    inactive_transmittance_error: float
    horizon_refraction_rad: float
    precomputation: PrecomputationSampling
    reasons: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    quadrature_error: float = math.nan
    wavelength_error: float = math.nan
    wavelength_errors: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready record of the choices (the ``dustoptics`` entry of the settings)."""
        return {
            "cosmoscout_commit": COSMOSCOUT_COMMIT,
            "tolerance": self.tolerance,
            "transmittance_error": self.transmittance_error,
            "inactive_transmittance_error": self.inactive_transmittance_error,
            "quadrature_transmittance_error": self.quadrature_error,
            "wavelength_sampling_error": (
                None if math.isnan(self.wavelength_error) else self.wavelength_error
            ),
            "wavelength_sampling_error_by_nm": dict(self.wavelength_errors),
            "horizon_refraction_deg": math.degrees(self.horizon_refraction_rad),
            "reasons": dict(self.reasons),
            "notes": list(self.notes),
            "precomputation": self.precomputation.to_dict(),
        }


def _wavelength_notes(wavelength_nm: np.ndarray) -> tuple[str, ...]:
    """The preprocessor's wavelength rules the set breaks (``main.cpp``, ``Preprocessor.cpp``)."""
    wl = np.asarray(wavelength_nm, dtype=np.float64)
    n = wl.size
    notes = []
    if n < 3:
        notes.append(f"the preprocessor refuses fewer than three wavelengths; the set has {n}")
    elif n == 3 and not np.allclose(wl, (440.0, 550.0, 680.0), rtol=0, atol=1e-6):
        notes.append(
            f"the preprocessor refuses three wavelengths other than 440, 550, 680 nm; the set has "
            f"{wl.tolist()} nm"
        )
    elif n > 3:
        if n % 3:
            notes.append(
                f"the preprocessor runs passes of three wavelengths and drops the last {n % 3} "
                f"of the set's {n}"
            )
        if not np.allclose(np.diff(wl), wl[1] - wl[0], rtol=1e-6, atol=0):
            notes.append(
                "the preprocessor's luminance weights take the wavelengths as evenly spaced "
                "(the first step for all); the set's are not"
            )
    return tuple(notes)


def _round_down(value: float, quantum: int) -> int:
    return max(quantum, int(value // quantum) * quantum)


def _round_up(value: float, quantum: int) -> int:
    return max(quantum, math.ceil(value / quantum) * quantum)


def _check_option(key: str, value: Any, needed: Any, why: str) -> Any:
    if key == "refraction":
        if not isinstance(value, bool):
            raise TypeError(f"options['refraction'] must be True or False; got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"options[{key!r}] must be an integer >= 1; got {value!r}")
    if _FINER_IF_LARGER[key] and value < needed:
        raise ValueError(
            f"options[{key!r}] = {int(value)} is too small for this set ({why}); "
            f"the smallest that does is {needed}"
        )
    if not _FINER_IF_LARGER[key] and value > needed:
        raise ValueError(
            f"options[{key!r}] = {int(value)} m is too large for this set ({why}); "
            f"the largest that does is {needed} m"
        )
    return int(value)


def _choose_refraction(
    atmosphere: Atmosphere, refraction: bool | None, *, bend: float, reasons: dict[str, str]
) -> bool:
    """``refraction`` as given, or on where the horizon bending ``bend`` [rad] exceeds a
    tenth of the Sun's angular radius; the reason goes into ``reasons``."""
    if refraction is not None:
        reasons["refraction"] = "given"
        return bool(refraction)
    sun_radius = math.asin(SUN_RADIUS_M / atmosphere.sun_distance_m)
    chosen = bend > _REFRACTION_FRACTION * sun_radius
    reasons["refraction"] = (
        f"horizon bending {math.degrees(bend):.3g} deg "
        f"{'>' if chosen else '<='} {_REFRACTION_FRACTION:g} x the Sun's angular radius "
        f"{math.degrees(sun_radius):.3g} deg"
    )
    return chosen


def _transmittance_error_of(atmosphere: Atmosphere) -> Callable[..., float]:
    """``error(**quadrature) -> float``: the largest relative error of the preprocessor's
    transmittance with those quadrature keywords, where exp(-tau) is visible."""
    columns = _columns(atmosphere)

    def error(**kwargs: Any) -> float:
        got, want = _transmittance(
            columns,
            radius_m=atmosphere.planet_radius_m,
            thickness_m=atmosphere.thickness_m,
            **kwargs,
        )
        seen = want >= _VISIBLE
        return float(np.max(np.abs(got / want - 1.0)[seen], initial=0.0))

    return error


def wavelength_sampling_error(atmosphere: Atmosphere) -> tuple[float, dict[str, float]]:
    """Error of the transmittance an engine gets from the set's wavelength sampling.

    At each of the wavelengths engines render (:data:`~dustoptics.atmosphere.sets.RGB_WAVELENGTHS_NM`,
    440, 550 and 680 nm), the set's extinction coefficients read linearly between its
    wavelengths (a wavelength of the set is read exactly; outside the set's range, its
    nearest wavelength's, what an engine without data there has) against the same atmosphere
    computed there (:attr:`~dustoptics.atmosphere.sets.Atmosphere.rgb_optics`), along
    straight rays from the ground at the zenith cosines :data:`_MUS` (where the exact
    transmittance is at least 1e-3): ``|exp(-(tau_set - tau_exact)) - 1|``.

    Returns
    -------
    (float, dict)
        The largest relative error, and the largest per wavelength (keys ``"440"``,
        ...); ``nan`` and an empty dict when the set carries no ``rgb_optics``. [-]
    """
    exact = atmosphere.rgb_optics
    if exact is None:
        return math.nan, {}
    wl = np.asarray(atmosphere.wavelength_nm, dtype=np.float64)
    rgb = np.asarray(exact.wavelength_nm, dtype=np.float64)
    top = atmosphere.thickness_m
    worst: dict[str, float] = {}
    for mu in _MUS:
        alt, w, _ = _straight_ray(mu, 20000, atmosphere.planet_radius_m, top)
        d_tau = np.zeros(rgb.size)
        tau = np.zeros(rgb.size)
        for c, e in zip(atmosphere.constituents, exact.constituents, strict=True):
            length = float(np.sum(w * c.profile.relative_density(np.clip(alt, 0.0, top))))
            beta_set = np.interp(rgb, wl, np.asarray(c.table.beta_ext_per_m, dtype=np.float64))
            beta_exact = np.asarray(e.table.beta_ext_per_m, dtype=np.float64)
            d_tau += (beta_set - beta_exact) * length
            tau += beta_exact * length
        err = np.abs(np.expm1(-d_tau))
        for lam, e_x, t in zip(rgb, err, tau, strict=True):
            if math.exp(-t) >= _VISIBLE:
                key = f"{lam:g}"
                worst[key] = max(worst.get(key, 0.0), float(e_x))
    return max(worst.values(), default=0.0), worst


def _optical_depth_sampling(
    error: Callable[..., float], *, tol: float, reasons: dict[str, str]
) -> tuple[float, int]:
    """``stepSizeOpticalDepth`` and ``sampleCountOpticalDepth`` within ``tol``; their reasons
    go into ``reasons``."""
    bound = _MARGIN * tol

    def step_ok(i: int) -> bool:
        return all(error(refraction=True, step_m=s) <= bound for s in _STEPS_M[i : i + 3])

    def count_ok(n: int) -> bool:
        return all(error(refraction=False, sample_count=n, mu=mu) <= bound for mu in _MUS)

    step = next((dx for i, dx in enumerate(_STEPS_M) if step_ok(i)), None)
    count = next((n for n in _COUNTS if count_ok(n)), None)
    if step is not None:
        reasons["stepSizeOpticalDepth"] = (
            f"largest of {list(_STEPS_M)} m whose zenith transmittance (and the next two "
            f"smaller steps') is within {bound:g} of exp(-tau) at every wavelength"
        )
    else:
        step = _STEPS_M[-1]
        reasons["stepSizeOpticalDepth"] = (
            f"none of {list(_STEPS_M)} m keeps the zenith transmittance within {bound:g} of "
            f"exp(-tau) at every wavelength: the finest, {step} m, leaves "
            f"{error(refraction=True, step_m=step):.3g}"
        )
    if count is not None:
        reasons["sampleCountOpticalDepth"] = (
            f"smallest of {list(_COUNTS)} whose transmittance along straight rays at zenith "
            f"cosines {list(_MUS)} is within {bound:g} of exp(-tau) at every wavelength (where "
            f"exp(-tau) >= {_VISIBLE:g})"
        )
    else:
        count = _COUNTS[-1]
        worst = max(error(refraction=False, sample_count=count, mu=mu) for mu in _MUS)
        reasons["sampleCountOpticalDepth"] = (
            f"none of {list(_COUNTS)} keeps the transmittance along straight rays at zenith "
            f"cosines {list(_MUS)} within {bound:g} of exp(-tau) at every wavelength (where "
            f"exp(-tau) >= {_VISIBLE:g}): the largest, {count}, leaves {worst:.3g}"
        )
    return step, count


def _scattering_sampling(
    atmosphere: Atmosphere, *, tol: float, reasons: dict[str, str]
) -> tuple[float, int]:
    """The in-scattering step [m] and sample count (single and multiple scattering alike):
    first-order bias with steps, trapezoid without; their reasons go into ``reasons``."""
    beta_ground = sum(
        np.asarray(c.table.beta_ext_per_m, dtype=np.float64)
        * float(c.profile.relative_density(np.array([0.0]))[0])
        for c in atmosphere.constituents
    )
    beta = float(np.max(beta_ground))
    thin = min(
        effective_scale_height_m(c.profile, top_altitude_m=atmosphere.thickness_m)
        for c in atmosphere.constituents
        if c.table.cross_sections is not None and np.any(c.table.cross_sections.csca_um2 > 0)
    )
    root = math.sqrt(12.0 * tol)
    path = math.sqrt(atmosphere.atmosphere_radius_m**2 - atmosphere.planet_radius_m**2)
    scatter_step = _round_down(min(2.0 * tol / beta, thin * root), 10)
    scatter_count = _round_up(max(path * beta / root, atmosphere.thickness_m / (thin * root)), 10)
    for key in ("stepSizeSingleScattering", "stepSizeMultiScattering"):
        reasons[key] = (
            f"min(2 tol / beta_ext = {2.0 * tol / beta:.4g} m, H sqrt(12 tol) = {thin * root:.4g} m) "
            "rounded down to 10 m"
        )
    for key in ("sampleCountSingleScattering", "sampleCountMultiScattering"):
        reasons[key] = (
            f"max(L beta_ext / sqrt(12 tol) = {path * beta / root:.4g}, "
            f"T / (H sqrt(12 tol)) = {atmosphere.thickness_m / (thin * root):.4g}) rounded up to 10"
        )
    return scatter_step, scatter_count


def _why_finer(tol: float) -> dict[str, str]:
    """What a value coarser than the chosen one would cost, by option, for the refusal."""
    return {
        "multiScatteringOrder": f"more than {tol:g} of the diffuse light beyond its orders",
        "sampleCountOpticalDepth": f"transmittance error above {tol:g}",
        "stepSizeOpticalDepth": f"transmittance error above {tol:g}",
        "sampleCountSingleScattering": f"in-scattering error above {tol:g}",
        "stepSizeSingleScattering": f"in-scattering bias above {tol:g}",
        "sampleCountMultiScattering": f"in-scattering error above {tol:g}",
        "stepSizeMultiScattering": f"in-scattering bias above {tol:g}",
        "sampleCountScatteringDensity": f"phase-function integral off by more than {tol:g}",
        "sampleCountIndirectIrradiance": f"phase-function integral off by more than {tol:g}",
        "scatteringTextureNuSize": "the NU slices' interpolation error near the Sun",
    }


def cosmoscout_sampling(
    atmosphere: Atmosphere,
    *,
    tolerance: float = 0.005,
    refraction: bool | None = None,
    ground_albedo: float = 0.1,
    max_sun_zenith_angle_deg: float = 120.0,
    options: Mapping[str, Any] | None = None,
) -> CosmoScoutSampling:
    """Every sampling option of the preprocessor for a set (module docstring).

    Parameters
    ----------
    atmosphere : Atmosphere
    tolerance : float, default 0.005
        Error allowed to the transmittance, the in-scattering quadrature, the
        orders and the scattering-density rule. [-]
    refraction : bool, optional
        Default: on where the horizon bending exceeds a tenth of the Sun's
        angular radius (:func:`horizon_refraction_rad`).
    ground_albedo : float, default 0.1
        ``groundAlbedo`` (the preprocessor's default), in [0, 1]. [-]
    max_sun_zenith_angle_deg : float, default 120
        ``maxSunZenithAngle`` (the preprocessor's default), in (90, 180]. [deg]
    options : mapping, optional
        Values to use instead of the chosen ones, by JSON key
        (``"scatteringTextureNuSize"``, ``"stepSizeOpticalDepth"``, ...).  A value
        coarser than the set needs is refused, naming the finest that does.

    Returns
    -------
    CosmoScoutSampling

    Raises
    ------
    ValueError
        An unknown option, or one coarser than the set needs (the message
        names the value that does).
    """
    tol = check_open_interval("tolerance", tolerance, 0.0, 1.0)
    albedo = check_closed_interval("ground_albedo", ground_albedo, 0.0, 1.0)
    zenith = check_closed_interval(
        "max_sun_zenith_angle_deg", max_sun_zenith_angle_deg, 90.0, 180.0
    )
    given = dict(options or {})
    unknown = sorted(set(given) - set(_FINER_IF_LARGER) - {"refraction"})
    if unknown:
        raise ValueError(
            f"options {unknown} are not sampling options of the preprocessor; allowed: "
            f"{sorted([*_FINER_IF_LARGER, 'refraction'])}"
        )
    reasons: dict[str, str] = {}
    bend = horizon_refraction_rad(atmosphere)
    if "refraction" in given:
        refraction = _check_option("refraction", given.pop("refraction"), None, "")
    refraction = _choose_refraction(atmosphere, refraction, bend=bend, reasons=reasons)

    # Transmittance: simulate the preprocessor's two quadratures.
    transmittance_error = _transmittance_error_of(atmosphere)
    step, count = _optical_depth_sampling(transmittance_error, tol=tol, reasons=reasons)
    # In-scattering: first-order bias with steps, trapezoid without.
    scatter_step, scatter_count = _scattering_sampling(atmosphere, tol=tol, reasons=reasons)

    pre = precomputation_sampling(atmosphere, tolerance=tol)
    chosen: dict[str, Any] = {
        "multiScatteringOrder": pre.num_scattering_orders - 1,
        "sampleCountOpticalDepth": count,
        "stepSizeOpticalDepth": step,
        "sampleCountSingleScattering": scatter_count,
        "stepSizeSingleScattering": scatter_step,
        "sampleCountMultiScattering": scatter_count,
        "stepSizeMultiScattering": scatter_step,
        "sampleCountScatteringDensity": pre.scattering_density_sample_count,
        "sampleCountIndirectIrradiance": pre.indirect_irradiance_sample_count,
        "scatteringTextureNuSize": pre.scattering_texture_nu_size,
    }
    reasons["multiScatteringOrder"] = (
        f"K - 1 for K = {pre.num_scattering_orders} orders (path model, m = "
        f"{pre.mean_scatterings:.3g})"
    )
    for key in ("scatteringTextureNuSize", "sampleCountScatteringDensity"):
        reasons[key] = "dustoptics.io.engines.precomputation"
    reasons["sampleCountIndirectIrradiance"] = (
        "the scattering density's angular step, at least the default 32"
    )
    why = _why_finer(tol)
    for key, value in given.items():
        if key == "scatteringTextureNuSize":
            # Checked (and capped by the texture size) by the precomputation rules.
            pre = precomputation_sampling(
                atmosphere, tolerance=tol, nu_size=value,
                num_scattering_orders=pre.num_scattering_orders,
                scattering_density_sample_count=pre.scattering_density_sample_count,
            )  # fmt: skip
        chosen[key] = _check_option(key, value, chosen[key], why[key])
        reasons[key] = "given"
    error = transmittance_error(refraction=True, step_m=chosen["stepSizeOpticalDepth"])
    error_off = max(
        transmittance_error(refraction=False, sample_count=chosen["sampleCountOpticalDepth"], mu=mu)
        for mu in _MUS
    )
    settings = {
        "refraction": bool(refraction),
        "groundAlbedo": albedo,
        **chosen,
        "transmittanceTextureWidth": BRUNETON_DEFAULTS["transmittance_texture_width"],
        "transmittanceTextureHeight": BRUNETON_DEFAULTS["transmittance_texture_height"],
        "scatteringTextureRSize": BRUNETON_DEFAULTS["scattering_texture_r_size"],
        "scatteringTextureMuSize": BRUNETON_DEFAULTS["scattering_texture_mu_size"],
        "scatteringTextureMuSSize": pre.scattering_texture_mu_s_size,
        "irradianceTextureWidth": BRUNETON_DEFAULTS["irradiance_texture_width"],
        "irradianceTextureHeight": BRUNETON_DEFAULTS["irradiance_texture_height"],
        "maxSunZenithAngle": math.radians(zenith),
    }
    quadrature = error if refraction else error_off
    inactive = error_off if refraction else error
    wl_error, wl_errors = wavelength_sampling_error(atmosphere)
    notes = _wavelength_notes(atmosphere.wavelength_nm)
    if math.isnan(wl_error):
        notes += (
            "the error of the set's wavelength sampling at 440, 550 and 680 nm is not included "
            "(the set carries no optics computed there: build it with "
            "dustoptics.atmosphere.build.build_atmosphere)",
        )
    added = 0.0 if math.isnan(wl_error) else wl_error
    return CosmoScoutSampling(
        settings=settings,
        tolerance=tol,
        transmittance_error=quadrature + added,
        inactive_transmittance_error=inactive + added,
        horizon_refraction_rad=bend,
        precomputation=pre,
        reasons=reasons,
        notes=notes,
        quadrature_error=quadrature,
        wavelength_error=wl_error,
        wavelength_errors=wl_errors,
    )
