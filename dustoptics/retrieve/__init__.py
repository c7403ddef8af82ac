"""Retrieval: the dust parameters that fit observations, with their uncertainties.

:func:`retrieve` fits named parameters of a dust model (a size distribution's
``r_eff_um``, ``v_eff``, ..., the refractive index's ``n`` and ``k``, a
mixture's ``hematite_fraction``) to observations given as labelled data, by
weighted least squares with bounds and Gaussian priors:

    minimize  sum_i ((model_i(p) - obs_i) / sigma_i)^2 + sum_j ((p_j - mu_j) / s_j)^2

with :func:`scipy.optimize.least_squares` (trust-region reflective, which
honours the bounds; a Levenberg-Marquardt-type method) and the exact Jacobian of
:func:`dustoptics.compute_optics` (``derivatives=...``,
:mod:`dustoptics.scattering.table_derivatives`): one table per iteration gives
the residuals and their derivatives together.  The covariance is
(J^T J)^-1 of the weighted residuals at the solution (the observations'
stated uncertainties, not rescaled by the misfit), so a fit is as certain as
its data and priors say.

Observations
------------
An :class:`xarray.Dataset` (or one named :class:`xarray.DataArray`) whose
variables are, by name:

``ssa``
    single-scattering albedo, dimension ``wavelength_nm`` [nm]; [-]
``g``
    asymmetry parameter, dimension ``wavelength_nm``; [-]
``extinction_ratio``
    <C_ext>(lambda) / <C_ext>(lambda_ref), dimension ``wavelength_nm``, with
    the attribute ``reference_wavelength_nm``; for one dust population this is
    also the ratio of optical depths tau(lambda) / tau(lambda_ref); [-]
``phase``
    phase-function samples, dimensions ``wavelength_nm`` and ``theta_deg``
    [degree], normalized as the tables' (2 pi int P dmu = 1); [sr^-1]
``sky_radiance``
    the Mars sky's radiance per unit solar irradiance at given directions,
    dimensions ``sun_elevation_deg``, ``wavelength_nm`` and ``direction``
    (coordinates ``view_zenith_deg``, ``view_azimuth_deg``); [sr^-1]
``sky_chromaticity``
    the Mars sky's CIE 1931 (x, y) seen in one direction (default the rovers'
    view away from the Sun), dimensions ``sun_elevation_deg`` and
    ``chromaticity`` (``["x", "y"]``). [-]

Each variable carries its one-sigma uncertainty: a variable
``<name>_uncertainty`` of the same dimensions, or a number in the attribute
``uncertainty`` (in the variable's unit).  NaN samples are left out.  The sky
variables carry their scene (dust optical depth, ground albedo) in attributes
and are rendered through :mod:`dustoptics.sky`; their Jacobian is the chain
rule through the optics' exact derivatives with finite differences in the
radiative transfer only (:mod:`dustoptics.retrieve.sky`).

Modules: :mod:`~dustoptics.retrieve.fit` (the fit and its arguments' checks),
:mod:`~dustoptics.retrieve.observations` (the optical observations, checked),
:mod:`~dustoptics.retrieve.sky` (the sky observations).
"""

from dustoptics.retrieve.fit import OBSERVABLES, Retrieval, retrieve
from dustoptics.retrieve.sky import SKY_OBSERVABLES, SkyScene, SkySettings

__all__ = ["OBSERVABLES", "SKY_OBSERVABLES", "Retrieval", "SkyScene", "SkySettings", "retrieve"]
