"""The validated domain: the spheres over which every Mie output's accuracy is verified.

A table is computed from homogeneous (or coated) spheres of size parameter
x = 2 pi r / lambda and relative refractive index m = n + i k.  Over the box
:data:`VALIDATED_DOMAIN` (size parameter, n, k and the index contrast abs(m - 1))
the kernel's outputs, per sphere, have been compared with an
arbitrary-precision reference (``mpmath``, 30 significant digits: Mie
coefficients from the Bessel-function ratios' downward recurrence, each started
twice at different depths and required to agree, and the Riccati-Bessel
functions' stable directions; tests/scattering/test_domain.py, which computes
the reference in the test for the cheap points and reads
tests/data/domain_reference.json, written by ``scripts/domain_reference.py``,
for the large spheres).  The points are the box's eight corners, the largest
size parameter the Mars and Earth presets reach, hematite's strongest
absorption in the ultraviolet (Querry 1985, ordinary ray, k = 1.317 at
260 nm) and seeded random interior points.  Through
:func:`~dustoptics.scattering.optics.compute_optics` (a
:class:`~dustoptics.particles.sizedist.Monodisperse` table, the polydisperse
kernel's own path) every output stays within :data:`VERIFIED_ACCURACY`:
extinction, scattering, absorption and backscattering cross-sections, the
asymmetry parameter, the phase function F11 and the matrix elements F12, F33,
F34 (relative to F11).  A polydisperse table adds its quadrature's error,
which the table estimates and reports itself.

Outside the box the kernel is not known to be wrong, but nobody has checked:
:func:`check_domain` refuses such a request before any work, unless the caller
passes ``allow_unvalidated=True`` (``--allow-unvalidated`` on the command
line), which warns with :class:`UnvalidatedWarning` and goes ahead.  Either
way the table's provenance records the size parameters and indices it used
and whether they stayed inside (:func:`domain_record`; ``dustoptics info``
prints it).

References
----------
.. [1] M. R. Querry, "Optical constants," Contractor Report CRDC-CR-85034,
   U.S. Army Chemical Research and Development Center (1985).
.. [2] W. J. Wiscombe, "Improved Mie scattering algorithms," Appl. Opt. 19,
   1505-1509 (1980). doi:10.1364/AO.19.001505
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "VALIDATED_DOMAIN",
    "VERIFIED_ACCURACY",
    "OutsideDomainError",
    "UnvalidatedWarning",
    "ValidatedDomain",
    "VerifiedAccuracy",
    "check_domain",
    "domain_record",
    "domain_summary",
    "domain_text",
]


@dataclass(frozen=True)
class ValidatedDomain:
    """A box of size parameters and refractive indices.

    Attributes
    ----------
    min_size_parameter, max_size_parameter : float
        Smallest and largest x = 2 pi r / lambda. [-]
    min_n, max_n : float
        Range of the real part n of m = n + i k (relative to the medium). [-]
    max_k : float
        Largest imaginary part k (k >= 0). [-]
    min_index_contrast : float
        Smallest abs(m - 1) (the series loses about eps / abs(m - 1) of relative
        precision). [-]
    """

    min_size_parameter: float
    max_size_parameter: float
    min_n: float
    max_n: float
    max_k: float
    min_index_contrast: float

    def contains_index(self, m: np.ndarray) -> np.ndarray:
        """Which refractive indices lie inside the box (element-wise)."""
        m = np.asarray(m, dtype=complex)
        return (
            (m.real >= self.min_n)
            & (m.real <= self.max_n)
            & (m.imag >= 0.0)
            & (m.imag <= self.max_k)
            & (np.abs(m - 1.0) >= self.min_index_contrast)
        )

    def contains_size_parameters(self, x_lo: float, x_hi: float) -> bool:
        """Whether [x_lo, x_hi] lies inside the box's size-parameter range."""
        return bool(x_lo >= self.min_size_parameter and x_hi <= self.max_size_parameter)


#: The validated domain.  The size parameters reach the largest that the
#: presets need with a margin: the Mars presets reach x = 661
#: (``cosmoscout-mars``: the tail of its size distribution at 360 nm) and the
#: Earth sets' coarse sea salt at 99 % humidity (OPAC, r_max 100 um) x = 2,513
#: at 250 nm, the shortest wavelength of its data.  The indices cover every
#: shipped material over its whole data range except hematite's
#: extraordinary ray beyond 15 um (n up to 10.6, k up to 9.4, inside too).  The
#: smallest x is the kernel's own limit
#: (:data:`dustoptics.scattering.mie.MIN_SIZE_PARAMETER`): the number-weighted
#: lower tails of broad distributions reach 1e-7 and below, where the spheres
#: are Rayleigh scatterers and the kernel keeps full precision.
VALIDATED_DOMAIN = ValidatedDomain(
    min_size_parameter=1e-30,
    max_size_parameter=3000.0,
    min_n=0.3,
    max_n=11.0,
    max_k=10.0,
    min_index_contrast=0.01,
)


@dataclass(frozen=True)
class VerifiedAccuracy:
    """The largest error of one sphere's outputs allowed (and met) over the domain.

    Attributes
    ----------
    cross_section_rtol : float
        C_ext, C_sca and C_abs (relative to C_ext). [-]
    backscatter_rtol : float
        C_back (4 pi times the differential cross-section at 180 degree), relative. [-]
    asymmetry_atol : float
        The asymmetry parameter g (absolute). [-]
    phase_rtol : float
        The phase function F11 at every angle, relative to itself. [-]
    matrix_rtol : float
        F12, F33, F34 relative to F11 at the same angle. [-]
    """

    cross_section_rtol: float
    backscatter_rtol: float
    asymmetry_atol: float
    phase_rtol: float
    matrix_rtol: float


#: What tests/scattering/test_domain.py asserts at every point.  The cross
#: sections are limited by Wiscombe's truncation of the series (the terms of
#: Re(a_n + b_n) left out are of order 1e-10 relative for an absorbing
#: sphere), the phase function by the same truncation at the angles where
#: F11 is small (near backscattering and in deep minima).
VERIFIED_ACCURACY = VerifiedAccuracy(
    cross_section_rtol=1e-8,
    backscatter_rtol=1e-5,
    asymmetry_atol=1e-10,
    phase_rtol=1e-4,
    matrix_rtol=1e-5,
)


class OutsideDomainError(ValueError):
    """A request's size parameters or refractive indices leave :data:`VALIDATED_DOMAIN`.

    The message names what left it, the domain, and that ``allow_unvalidated=True``
    (``--allow-unvalidated``) goes ahead.
    """


class UnvalidatedWarning(UserWarning):
    """A table was computed outside :data:`VALIDATED_DOMAIN` because the caller asked."""


def _departures(m: np.ndarray, x_lo: float, x_hi: float, domain: ValidatedDomain) -> list[str]:
    """Plain-language descriptions of what leaves the domain (empty if nothing)."""
    out = []
    if x_lo < domain.min_size_parameter:
        out.append(f"size parameter {x_lo:.3g} < {domain.min_size_parameter:g}")
    if x_hi > domain.max_size_parameter:
        out.append(f"size parameter {x_hi:.4g} > {domain.max_size_parameter:g}")
    outside = ~domain.contains_index(m)
    if np.any(outside):
        bad = np.asarray(m, dtype=complex)[outside]
        shown = ", ".join(f"{complex(v):.4g}" for v in bad[:3])
        more = f" and {bad.size - 3} more" if bad.size > 3 else ""
        out.append(f"refractive index {shown}{more}")
    return out


def domain_text(domain: ValidatedDomain = VALIDATED_DOMAIN) -> str:
    """The domain in one sentence, as the README, the docs and the messages state it."""
    return (
        f"{domain.min_size_parameter:g} <= x <= {domain.max_size_parameter:g}, "
        f"{domain.min_n:g} <= n <= {domain.max_n:g}, 0 <= k <= {domain.max_k:g}, "
        f"abs(m - 1) >= {domain.min_index_contrast:g}"
    )


def check_domain(
    *,
    m: np.ndarray,
    min_size_parameter: float,
    max_size_parameter: float,
    allow_unvalidated: bool,
    caller: str = "compute_optics",
) -> bool:
    """Refuse (or, if allowed, warn about) a request outside :data:`VALIDATED_DOMAIN`.

    Parameters
    ----------
    m : array_like of complex
        Every refractive index the request uses (shell and core). [-]
    min_size_parameter, max_size_parameter : float
        The size-parameter range of its radius quadrature (the distribution's
        tails at the longest and shortest wavelengths). [-]
    allow_unvalidated : bool
        Go ahead outside the domain, with an :class:`UnvalidatedWarning`.
    caller : str
        Named in the message.

    Returns
    -------
    bool
        True if the request lies inside the domain.

    Raises
    ------
    OutsideDomainError
        Outside the domain and ``allow_unvalidated`` is False (before any work).
    TypeError
        ``allow_unvalidated`` not a bool.
    """
    if not isinstance(allow_unvalidated, bool):
        raise TypeError(f"allow_unvalidated must be True or False; got {allow_unvalidated!r}")
    departures = _departures(
        np.atleast_1d(np.asarray(m, dtype=complex)),
        float(min_size_parameter),
        float(max_size_parameter),
        VALIDATED_DOMAIN,
    )
    if not departures:
        return True
    what = "; ".join(departures)
    if not allow_unvalidated:
        raise OutsideDomainError(
            f"{caller}: {what}: outside the validated domain ({domain_text()}), where the "
            "accuracy of the outputs has been verified against arbitrary-precision references; "
            "pass allow_unvalidated=True (--allow-unvalidated on the command line) to go ahead, "
            "recorded in the table's provenance"
        )
    warnings.warn(
        f"{caller}: {what}: outside the validated domain ({domain_text()}); going ahead as "
        "asked (allow_unvalidated=True): the outputs' accuracy there has not been verified",
        UnvalidatedWarning,
        stacklevel=4,
    )
    return False


def domain_record(
    *, m: np.ndarray, min_size_parameter: float, max_size_parameter: float
) -> dict[str, Any]:
    """The provenance's record of a computation's domain (JSON-ready).

    Keys: ``inside`` (bool), ``size_parameter`` ([lowest, highest] of the
    request), ``n`` and ``k`` ([lowest, highest] of every index used) and
    ``validated`` (:func:`domain_text`).
    """
    m = np.atleast_1d(np.asarray(m, dtype=complex))
    inside = not _departures(
        m, float(min_size_parameter), float(max_size_parameter), VALIDATED_DOMAIN
    )
    return {
        "inside": inside,
        "size_parameter": [float(min_size_parameter), float(max_size_parameter)],
        "n": [float(m.real.min()), float(m.real.max())],
        "k": [float(m.imag.min()), float(m.imag.max())],
        "validated": domain_text(),
    }


def domain_summary() -> str:
    """The paragraph the README and the docs state the domain with (generated, never typed)."""
    acc = VERIFIED_ACCURACY
    return (
        f"Validated domain: {domain_text()} (x = 2 pi r / lambda, m = n + i k relative to the "
        "medium). Every output of a sphere there (extinction, scattering, absorption and "
        "backscattering cross-sections, g, the phase function F11 and F12, F33, F34) agrees "
        "with arbitrary-precision (mpmath) references at the domain's corners, the largest size "
        "parameters the Mars presets and the Earth aerosols reach, hematite's strongest "
        "ultraviolet absorption and random interior points: cross-sections within "
        f"{acc.cross_section_rtol:g} (relative; backscattering {acc.backscatter_rtol:g}), g within {acc.asymmetry_atol:g}, F11 within "
        f"{acc.phase_rtol:g} (relative, at every angle), F12, F33, F34 within "
        f"{acc.matrix_rtol:g} of F11; a size distribution adds its quadrature's own estimated "
        "error. Outside the domain compute_optics and dustoptics build refuse before any work "
        "unless asked to go on (allow_unvalidated=True, --allow-unvalidated), and dustoptics "
        "info says whether a table stayed inside."
    )
