"""How far the sky's radiance is from the converged answer: a documented error model.

The radiance differs from a converged solution of the same column for three
reasons, each bounded here:

- the series of orders of scattering is cut where its estimated remainder is
  below ``tol`` of the largest diffuse radiance
  (:attr:`~dustoptics.sky.orders.DiffuseField.error_estimate`);
- the multiple scattering resolves ``2 n_streams`` Legendre moments: what the
  delta-M truncation leaves after the TMS single scattering and the IMS
  aureole correction grows with the scattering optical depth put into the
  truncated forward peak, ``tau_f = sum_c tau_sca,c f_c`` (vertical, per
  wavelength), as ``c(n_streams) sqrt(tau_f)`` with ``c(16) = 1e-2`` and
  ``c(N) = c(16) (16 / N)^4`` below 16 streams, ``(16 / N)^2.3`` above;
- the layers, the samples along each line of sight and the interpolations:
  :data:`FLOOR` (1e-3).

The model is fitted to the largest errors against converged CDISORT
(``tests/reference/disort.py``, ``scripts/sky_vs_disort.py``) over the
validation cases (Rayleigh scattering, an Earth aerosol at optical depth
0.1-0.4, Mars dust at 0.5-2; 440, 550 and 670 nm; with 8, 12, 16 and 24
streams) in the directions a plane-parallel model can judge: Sun elevation
>= 20 deg, view zenith <= 75 deg, 3 deg or more from the Sun.  There it
bounds the measured error (``tests/sky/test_sky_vs_cdisort.py`` checks that it does).
Outside that domain (a lower Sun, the horizon, the Sun's disc) the spherical
shell and the plane-parallel references differ for physical reasons and the
model is not validated.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from dustoptics.sky.medium import Medium
from dustoptics.sky.orders import DiffuseField

__all__ = ["FLOOR", "VALIDATED_DOMAIN", "radiance_error_estimate", "stream_factor"]

#: Relative error of the discretization (layers, samples, interpolation). [-]
FLOOR: Final = 1e-3
#: Where the model is checked against CDISORT.
VALIDATED_DOMAIN: Final = (
    "plane-parallel directions: Sun elevation >= 20 deg, view zenith <= 75 deg, "
    ">= 3 deg from the Sun; particles' scattering optical depth <= 2"
)


def stream_factor(n_streams: int) -> float:
    """``c(N)``: the truncation error per ``sqrt(tau_f)`` with N streams. [-]"""
    n = float(n_streams)
    return 1e-2 * (16.0 / n) ** (4.0 if n <= 16.0 else 2.3)


def radiance_error_estimate(
    medium: Medium, field: DiffuseField, *, observer_altitude_m: float = 0.0
) -> np.ndarray:
    """Estimated relative error of the sky radiance, per wavelength (the model above).

    Parameters
    ----------
    medium : Medium
        The atmosphere's optics.
    field : DiffuseField
        The diffuse field the radiance was rendered with.
    observer_altitude_m : float
        The observer's altitude (the column above it counts). [m]

    Returns
    -------
    numpy.ndarray, shape (n_wavelength,)
        ``FLOOR + c(n_streams) sqrt(tau_f) + orders' remainder``. [-]
    """
    radius = np.array([medium.planet_radius_m + float(observer_altitude_m)])
    vertical = medium.slant.columns(radius, np.array([1.0]))[:, 0]  # (c,)
    tau_sca = medium.sigma_sca_m2 * (medium.number_density_per_m3 * vertical)[:, None]
    tau_f = (tau_sca * medium.truncation).sum(axis=0)
    return FLOOR + stream_factor(medium.n_streams) * np.sqrt(tau_f) + field.error_estimate
