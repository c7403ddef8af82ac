"""The fit of :func:`retrieve` (the package docstring says what) and the checks of its arguments.

Optical observations (``ssa``, ``g``, ``extinction_ratio``, ``phase``, read and checked
by :mod:`dustoptics.retrieve.observations`) are
predicted from one table with exact derivatives; sky observations
(``sky_radiance``, ``sky_chromaticity``) by :mod:`dustoptics.retrieve.sky`
from a second table on the sky's wavelengths and the default angles.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np
from scipy import optimize

from dustoptics._validation import BudgetError
from dustoptics.models.config import BuildConfig
from dustoptics.particles.mixing import Mixture
from dustoptics.particles.sizedist import Monodisperse, SizeDistribution
from dustoptics.particles.sizedist_derivatives import parameter_value, with_parameter
from dustoptics.retrieve.observations import (
    OBSERVABLES,
    Observation,
    observations_of,
    optical_grid,
    predict,
    sample_labels,
)
from dustoptics.retrieve.sky import (
    SkyModel,
    SkySettings,
    sky_progress,
)
from dustoptics.scattering import optics as _optics
from dustoptics.scattering.derivative_parameters import (
    INDEX_PARAMETERS,
    check_parameters,
    index_parameter_names,
)
from dustoptics.scattering.optics import (
    check_cost,
    compute_optics,
    default_theta_deg,
    optics_request,
)
from dustoptics.scattering.quadrature import QuadratureSettings
from dustoptics.table import Table

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["OBSERVABLES", "Retrieval", "retrieve"]


@dataclass(frozen=True)
class Retrieval:
    """The result of :func:`retrieve`.

    Attributes
    ----------
    parameters : tuple of str
        The fitted parameters, in the order of every array below.
    values : numpy.ndarray
        Fitted values (in each parameter's unit: um for ``*_um``, else 1).
    covariance : numpy.ndarray
        (J^T J)^-1 of the weighted residuals at the solution, shape
        (n_parameters, n_parameters).
    standard_errors : numpy.ndarray
        Square roots of the covariance's diagonal.
    initial_values : numpy.ndarray
        The model's values, where the fit started.
    residuals : numpy.ndarray
        Weighted residuals (model - observation) / uncertainty at the
        solution, the observations' (in the order of :attr:`labels`) then
        the priors'. [-]
    labels : tuple of str
        What each residual is: ``"ssa@550nm"``, ``"phase@550nm,30deg"``,
        ``"prior:r_eff_um"``.
    chi_square : float
        Sum of the squared residuals. [-]
    iterations : int
        Jacobian evaluations (each one table with derivatives).
    function_evaluations : int
        Residual evaluations (each one table).
    converged : bool
        Whether the optimizer met its tolerances (``message`` says which).
    message : str
        The optimizer's account of why it stopped.
    model : Mapping[str, Any]
        The compute_optics keywords at the fitted values.
    table : Table
        The table at the fitted values, with derivatives (with only sky
        observations, the sky's table).
    sky_solves : int
        Skies solved (orders of scattering), residuals and Jacobians together.
    history_values : numpy.ndarray
        The parameters at every point where the residuals were computed, in
        order (the start first), shape (n_points, n_parameters): the fit's path.
    history_residuals : numpy.ndarray
        Their weighted residuals, shape (n_points, n_residuals). [-]
    """

    parameters: tuple[str, ...]
    values: np.ndarray
    covariance: np.ndarray
    standard_errors: np.ndarray
    initial_values: np.ndarray
    residuals: np.ndarray
    labels: tuple[str, ...]
    chi_square: float
    iterations: int
    function_evaluations: int
    converged: bool
    message: str
    model: Mapping[str, Any] = dataclasses.field(repr=False)
    table: Table = dataclasses.field(repr=False)
    sky_solves: int = 0
    history_values: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))
    history_residuals: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))

    def value(self, parameter: str) -> float:
        """The fitted value of one parameter."""
        return float(self.values[self._index(parameter)])

    def standard_error(self, parameter: str) -> float:
        """The standard error of one parameter."""
        return float(self.standard_errors[self._index(parameter)])

    def _index(self, parameter: str) -> int:
        if parameter not in self.parameters:
            raise ValueError(
                f"parameter must be one of {', '.join(map(repr, self.parameters))}; "
                f"got {parameter!r}"
            )
        return self.parameters.index(parameter)


# ----------------------------------------------------------------- the model


def _model_keywords(model: Any) -> dict[str, Any]:
    """compute_optics keywords from a mapping or a BuildConfig."""
    if isinstance(model, BuildConfig):
        if model.material is None or model.size_distribution is None:
            raise ValueError(
                f"model: configuration {model.name!r} has no Mie dust (material and "
                "size_distribution); retrieve fits Mie models only"
            )
        out: dict[str, Any] = {
            "refractive_index": model.material.build(),
            "distribution": model.size_distribution.build(),
        }
        if model.optics.rtol is not None:
            out["rtol"] = model.optics.rtol
        if model.optics.weighting is not None:
            out["weighting"] = model.optics.weighting
        return out
    if not isinstance(model, Mapping):
        raise TypeError(
            "model must be a mapping of compute_optics keywords (refractive_index=, "
            f"distribution=, ...) or a BuildConfig; got {type(model).__name__}"
        )
    out = dict(model)
    for key in ("refractive_index", "distribution"):
        if key not in out:
            raise ValueError(f"model lacks the compute_optics keyword {key!r}")
    for key in ("wavelength_nm", "theta_deg", "derivatives", "progress"):
        if key in out:
            raise ValueError(
                f"model must not give {key!r}: retrieve chooses it from the observations"
            )
    if "allow_large" in out:
        raise ValueError("model must not give 'allow_large': pass it to retrieve itself")
    if not isinstance(out["distribution"], SizeDistribution):
        raise ValueError(
            f"model's distribution must be a SizeDistribution; got {out['distribution']!r}"
        )
    return out


def _fraction_name(index: Any, parameter: str) -> bool:
    return isinstance(index, Mixture) and parameter in index_parameter_names(index)


def _get(model: Mapping[str, Any], parameter: str) -> float:
    index, dist = model["refractive_index"], model["distribution"]
    if parameter in INDEX_PARAMETERS:
        m = complex(index)
        return m.real if parameter == "n" else m.imag
    if _fraction_name(index, parameter):
        return float(index.parameter_value(parameter))
    if isinstance(dist, Monodisperse):
        return float(dist.radius_um)
    return parameter_value(dist, parameter)


def _set(model: Mapping[str, Any], values: Mapping[str, float]) -> dict[str, Any]:
    out = dict(model)
    for parameter, v in values.items():
        index, dist = out["refractive_index"], out["distribution"]
        if parameter in INDEX_PARAMETERS:
            m = complex(index)
            out["refractive_index"] = complex(v, m.imag) if parameter == "n" else complex(m.real, v)
        elif _fraction_name(index, parameter):
            out["refractive_index"] = index.with_parameter(parameter, v)
        elif isinstance(dist, Monodisperse):
            out["distribution"] = Monodisperse(radius_um=v)
        else:
            out["distribution"] = with_parameter(dist, parameter, v)
    return out


def _check_bound(model: Mapping[str, Any], parameter: str, value: float, which: str) -> None:
    """Refuse a bound where the model cannot go (the fit may step onto its bounds):
    m = n + i k with n > 0 and k >= 0, and whatever the distribution's or the
    mixture's constructor refuses."""
    if parameter == "n" and not value > 0.0:
        raise ValueError(f"bounds: the {which} bound of 'n' must be > 0; got {value!r}")
    if parameter == "k" and not value >= 0.0:
        raise ValueError(
            f"bounds: the {which} bound of 'k' must be >= 0 (m = n + i k, k >= 0); got {value!r}"
        )
    try:
        _set(model, {parameter: value})
    except (ValueError, TypeError) as exc:
        raise ValueError(
            f"bounds: the {which} bound {parameter} = {value!r} is outside the model's domain: {exc}"
        ) from None


def _check_corner_cost(
    model: Mapping[str, Any],
    names: Sequence[str],
    upper: np.ndarray,
    wavelength_nm: np.ndarray,
    theta_deg: np.ndarray,
    allow_large: bool,
) -> None:
    """The table at the distribution's upper bounds must be within compute_optics'
    budget (unless ``allow_large``): the fit may step there, and each step computes
    one (checked before any)."""
    size = {p: float(u) for p, u in zip(names, upper.tolist(), strict=True)}
    size = {p: v for p, v in size.items() if p not in INDEX_PARAMETERS}
    size = {p: v for p, v in size.items() if not _fraction_name(model["refractive_index"], p)}
    if not size:
        return
    try:
        corner = _set(model, size)
    except (ValueError, TypeError):
        return  # each bound alone is valid (_check_bound); their corner is not a model
    settings = model.get("quadrature") or QuadratureSettings()
    workers = model.get("workers") or os.cpu_count() or 1
    try:
        request = optics_request(
            corner["refractive_index"],
            corner["distribution"],
            wavelength_nm,
            theta_deg,
            quadrature=settings,
            weighting=model.get("weighting", "scattering"),
        )
        check_cost(request, workers=workers, allow_large=allow_large)
    except (ValueError, BudgetError) as exc:
        raise type(exc)(
            f"bounds: at the upper bounds {size} the fit's table would be refused: {exc}"
        ) from None


def _check_fit_cost(
    model: Mapping[str, Any],
    grids: Sequence[tuple[np.ndarray, np.ndarray]],
    max_iterations: int,
    allow_large: bool,
) -> None:
    """The whole fit's work, estimated before any table: the start's tables (one per
    grid of wavelengths [nm] and angles [deg]) times the most evaluations
    (``max_iterations`` and the one at the solution), within compute_optics'
    :data:`~dustoptics.scattering.optics.WORK_BUDGET` unless ``allow_large``."""
    settings = model.get("quadrature") or QuadratureSettings()
    workers = model.get("workers") or os.cpu_count() or 1
    per_table = 0.0
    sizes = []
    for wavelength_nm, theta_deg in grids:
        request = optics_request(
            model["refractive_index"],
            model["distribution"],
            wavelength_nm,
            theta_deg,
            quadrature=settings,
            weighting=model.get("weighting", "scattering"),
        )
        per_table += check_cost(request, workers=workers, allow_large=allow_large).work
        sizes.append(f"{wavelength_nm.size} wavelengths x {theta_deg.size} angles")
    total = per_table * (max_iterations + 1)
    budget = _optics.WORK_BUDGET  # read at the call: a caller may lower it
    if total > budget and not allow_large:
        raise BudgetError(
            f"retrieve: the fit would need about {total:.3g} sphere-order-angle terms "
            f"({per_table:.3g} per evaluation at the start, {' and '.join(sizes)}, times "
            f"max_iterations={max_iterations} + 1 evaluations), beyond the budget of "
            f"{budget:g} (about ten minutes): observe fewer wavelengths or angles, lower "
            "max_iterations (--max-iterations), or pass allow_large=True (--allow-large) "
            "to go ahead"
        )


# ----------------------------------------------------------------- the fit


def _reporter(
    progress: Callable[[int, float], None] | TextIO | None,
) -> tuple[Callable[[int, float], None] | None, TextIO | None]:
    """The callback and the text stream of ``progress`` (one of them, or neither)."""
    if progress is None:
        return None, None
    if callable(getattr(progress, "write", None)):
        return None, progress  # type: ignore[return-value]
    if callable(progress):
        return progress, None
    raise TypeError(
        "progress must be a callable progress(evaluations, chi_square), a text stream "
        f"(e.g. sys.stderr) or None; got {progress!r}"
    )


def retrieve(
    observations: xr.Dataset | xr.DataArray,
    *,
    model: Mapping[str, Any] | BuildConfig,
    parameters: Sequence[str],
    bounds: Mapping[str, tuple[float, float]],
    priors: Mapping[str, tuple[float, float]] | None = None,
    max_iterations: int = 50,
    tolerance: float = 1e-6,
    sky: SkySettings | None = None,
    progress: Callable[[int, float], None] | TextIO | None = None,
    allow_large: bool = False,
) -> Retrieval:
    """Fit named parameters of a dust model to observations.

    Parameters
    ----------
    observations : xarray.Dataset or xarray.DataArray
        ``ssa``, ``g``, ``extinction_ratio``, ``phase``, ``sky_radiance`` and/or
        ``sky_chromaticity`` samples with their uncertainties (package docstring).
    model : mapping or BuildConfig
        The dust: compute_optics keywords (``refractive_index``,
        ``distribution``, and optionally ``rtol``, ``weighting``,
        ``cross_section_rtol``, ``quadrature``, ``workers``), or a build
        configuration of a Mie dust.  Its values are the starting point.
    parameters : sequence of str
        The parameters to fit: the distribution's by name (``"r_eff_um"``,
        ``"v_eff"``, ...), ``"n"`` and ``"k"`` (the refractive index must then be
        one constant complex number), a mixture's (``"hematite_fraction"``).
    bounds : mapping of str to (float, float)
        Lower and upper bound of every parameter (each parameter must have
        one; the start must lie inside).  They also set the finite-difference
        step of the sky's Jacobian (:class:`~dustoptics.retrieve.sky.SkySettings`).
    priors : mapping of str to (float, float), optional
        Gaussian priors (mean, standard deviation) of some parameters.
    max_iterations : int
        Most evaluations of the residuals (scipy's ``max_nfev``), each one table
        with derivatives (and one sky per scene); one more gives the result at
        the solution. [-]
    tolerance : float
        Relative tolerance of the cost, the parameters and the gradient
        (scipy's ftol, xtol, gtol). [-]
    sky : SkySettings, optional
        Streams, series tolerance and finite-difference step of the skies of
        sky observations (default ``SkySettings()``).
    progress : callable or text stream, optional
        A callable is called as ``progress(evaluations, chi_square)`` after
        each evaluation of the residuals; a text stream (``sys.stderr``) gets
        the number of sky solves and their estimated time first, then one line
        per evaluation (its number, chi-square, seconds since the start) and
        the sky solves of each Jacobian.  It does not change the result.
    allow_large : bool
        Go ahead when the sky solves are estimated beyond
        :data:`~dustoptics.retrieve.sky.MAX_SKY_SECONDS`, or a table the fit
        may compute beyond compute_optics' budget.

    Returns
    -------
    Retrieval
        Fitted values, covariance, standard errors, residuals and what the
        optimizer did.

    Raises
    ------
    ValueError
        Bad observations, an unknown parameter (the message lists the allowed
        ones), a parameter without bounds, bounds that are not finite or where
        the model cannot go (r_eff_um <= 0, k < 0, a fraction outside [0, 1],
        ...), a start outside them, a prior with a standard deviation <= 0;
        all before any table is computed.
    dustoptics._validation.BudgetError
        The table at the size distribution's upper bounds is beyond
        compute_optics' budget (:func:`~dustoptics.scattering.optics.check_cost`)
        and ``allow_large`` is False, before any table is computed; or
        With sky observations, the most sky solves the fit may need (``(1 +
        n_parameters) x scenes`` per iteration, forward differences) times
        the estimated seconds of one are beyond
        :data:`~dustoptics.retrieve.sky.MAX_SKY_SECONDS` and ``allow_large``
        is False: after the start's table (the estimate needs its optics),
        before any sky is solved.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> import dustoptics as do
    >>> from dustoptics.retrieve import retrieve
    >>> truth = do.compute_optics(1.5 + 0.004j, do.ModifiedGamma(r_eff_um=0.6, v_eff=0.1),
    ...                           [450.0, 550.0, 700.0], [0.0, 180.0])
    >>> obs = xr.Dataset({"ssa": ("wavelength_nm", truth.ssa, {"uncertainty": 1e-4})},
    ...                  coords={"wavelength_nm": truth.wavelength_nm})
    >>> fit = retrieve(obs, model={"refractive_index": 1.5 + 0.01j,
    ...                            "distribution": do.ModifiedGamma(r_eff_um=0.6, v_eff=0.1)},
    ...                parameters=["k"], bounds={"k": (0.0, 0.1)})
    >>> fit.converged, round(fit.value("k"), 5)
    (True, 0.004)
    """
    keywords = _model_keywords(model)
    obs, sky_list = observations_of(observations)
    names = _checked_parameters(keywords, parameters)
    start, lower, upper = _checked_bounds(keywords, names, bounds)
    prior_list = _checked_priors(names, priors)
    _check_options(max_iterations, tolerance, allow_large)
    if sky is None:
        sky = SkySettings()
    elif not isinstance(sky, SkySettings):
        raise TypeError(f"sky must be a SkySettings; got {type(sky).__name__}")
    callback, stream = _reporter(progress)
    began = time.perf_counter()
    sky_model = SkyModel(sky_list, sky) if sky_list else None
    wavelengths, theta = optical_grid(obs)
    grids = [(wavelengths, theta)] if obs else []
    if sky_model is not None:
        grids.append((sky_model.wavelength_nm, default_theta_deg()))
    _check_fit_cost(keywords, grids, max_iterations, allow_large)
    if obs:
        _check_corner_cost(keywords, names, upper, wavelengths, theta, allow_large)
    if sky_model is not None:  # the sky's table: its wavelengths, the default angles
        _check_corner_cost(
            keywords, names, upper, sky_model.wavelength_nm, default_theta_deg(), allow_large
        )
    problem = _Problem(
        keywords=keywords,
        names=names,
        obs=obs,
        sky_model=sky_model,
        prior_list=prior_list,
        wavelengths=wavelengths,
        theta=theta,
        steps=sky.relative_step * (upper - lower),
        n_streams=sky.n_streams,
        max_iterations=max_iterations,
        allow_large=allow_large,
        callback=callback,
        stream=stream,
        began=began,
    )
    result = optimize.least_squares(
        problem.residuals,
        start,
        jac=problem.jacobian,
        bounds=(lower, upper),
        method="trf",
        x_scale="jac",
        ftol=tolerance,
        xtol=tolerance,
        gtol=tolerance,
        max_nfev=max_iterations,
    )
    final = problem.evaluate(result.x)
    jac = problem.jacobian(result.x)
    residuals = final["residuals"]
    covariance, standard_errors, converged, message = _uncertainty(
        jac, upper - lower, names, bool(result.status > 0), str(result.message)
    )
    return Retrieval(
        parameters=names,
        values=np.array(result.x),
        covariance=covariance,
        standard_errors=standard_errors,
        initial_values=start,
        residuals=residuals,
        labels=problem.labels,
        chi_square=float(residuals @ residuals),
        iterations=int(result.njev or 0),
        function_evaluations=int(result.nfev),
        converged=converged,
        message=message,
        model=_set(keywords, dict(zip(names, result.x.tolist()))),
        table=final["table"] if obs else final["sky_table"],
        sky_solves=sky_model.solves if sky_model is not None else 0,
        history_values=np.array([h[0] for h in problem.history]),
        history_residuals=np.array([h[1] for h in problem.history]),
    )


def _uncertainty(
    jacobian: np.ndarray,
    width: np.ndarray,
    names: Sequence[str],
    converged: bool,
    message: str,
) -> tuple[np.ndarray, np.ndarray, bool, str]:
    """Covariance (J^T J)^-1, standard errors, convergence and message of a fit: the
    optimizer's, unless the data carry no information on a parameter (:func:`_uninformed`),
    whose variance is then infinite and the fit not converged, with the message saying why."""
    covariance = np.linalg.pinv(jacobian.T @ jacobian)
    standard_errors = np.sqrt(np.diag(covariance))
    uninformed = _uninformed(jacobian, width)
    if uninformed.any():
        covariance[uninformed, :] = covariance[:, uninformed] = np.nan
        covariance[uninformed, uninformed] = np.inf
        standard_errors[uninformed] = np.inf
        converged = False
        message = (
            "the data carry no information on "
            f"{', '.join(p for p, u in zip(names, uninformed, strict=True) if u)}: the "
            "chi-square is flat across the bounds (uncertainties too large, or observations "
            f"that do not depend on the parameter); not a fit (the optimizer: {message})"
        )
    return covariance, standard_errors, converged, message


#: A parameter is not constrained by the data when its standard error exceeds this
#: multiple of its bounds' width: across the bounds the chi-square changes by less than
#: its square's inverse (1e-6). [-]
UNINFORMED_WIDTHS = 1e3


def _uninformed(jacobian: np.ndarray, width: np.ndarray) -> np.ndarray:
    """Which parameters the weighted residuals' Jacobian says nothing about.

    The standard errors are computed from the Jacobian with its columns scaled to
    unit norm (so that uncertainties of 1e308, whose squared residuals underflow,
    still give the right answer).  A zero or non-finite column, a direction of the
    scaled Jacobian with a singular value below round-off, or a standard error
    beyond :data:`UNINFORMED_WIDTHS` times the bounds' ``width`` marks the
    parameters it involves.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        peak = np.max(np.abs(jacobian), axis=0, initial=0.0)
        norms = peak * np.sqrt(np.sum(np.square(jacobian / peak), axis=0))
    out = ~(np.isfinite(norms) & (norms > 0.0))
    if out.all():
        return out
    scaled = jacobian[:, ~out] / norms[~out]
    _, s, vt = np.linalg.svd(scaled, full_matrices=True)  # vt: (k, k) with fewer rows than k
    s = np.r_[s, np.zeros(vt.shape[0] - s.size)]
    rank = s > s.max() * max(scaled.shape) * np.finfo(float).eps
    flat = np.any(np.abs(vt[~rank]) > 1e-8, axis=0)
    with np.errstate(divide="ignore", over="ignore"):
        errors = np.sqrt(np.sum(np.square(vt[rank].T / s[rank]), axis=1)) / norms[~out]
    out[~out] = flat | ~(errors <= UNINFORMED_WIDTHS * width[~out])
    return out


def _checked_parameters(keywords: dict[str, Any], parameters: Sequence[str]) -> tuple[str, ...]:
    """The parameters to fit, checked against the model (:func:`retrieve`)."""
    try:
        names = check_parameters(
            parameters,
            keywords["distribution"],
            index_parameter_names(keywords["refractive_index"]),
        )
    except (TypeError, ValueError) as exc:  # worded for compute_optics(derivatives=...)
        text = str(exc)
        if text.startswith("derivatives"):
            text = "parameters" + text[len("derivatives") :]
        raise type(exc)(text) from None
    if not names:
        raise ValueError("parameters must name at least one parameter to fit")
    if any(p in INDEX_PARAMETERS for p in names):
        try:
            complex(keywords["refractive_index"])
        except TypeError:
            raise ValueError(
                "parameters 'n' and 'k' fit one constant refractive index: the model's "
                f"refractive_index must be a number; got {keywords['refractive_index']!r}"
            ) from None
    return names


def _real(value: Any) -> bool:
    """Whether ``value`` is a real number (not a bool, a string or an array)."""
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(
        value, bool | np.bool_
    )


def _pair(what: str, parameter: str, pair: Any, form: str) -> tuple[float, float]:
    """``pair`` as two floats, or a TypeError/ValueError naming ``what`` and ``parameter``."""
    if isinstance(pair, str) or not isinstance(pair, Sequence | np.ndarray):
        raise TypeError(f"{what}[{parameter!r}] must be a pair {form}; got {pair!r}")
    if len(pair) != 2:
        raise ValueError(
            f"{what}[{parameter!r}] must be a pair {form} of two numbers; got {pair!r} "
            f"({len(pair)} item{'s' if len(pair) != 1 else ''})"
        )
    if not all(_real(v) for v in pair):
        raise TypeError(f"{what}[{parameter!r}] must hold two real numbers {form}; got {pair!r}")
    return float(pair[0]), float(pair[1])


def _checked_bounds(
    keywords: dict[str, Any], names: Sequence[str], bounds: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The start, lower and upper bounds of ``names`` (:func:`retrieve`)."""
    if not isinstance(bounds, Mapping):
        raise TypeError(
            f"bounds must be a mapping {{parameter: (lower, upper)}}; got {type(bounds).__name__}"
        )
    if set(names) - set(bounds):
        raise ValueError(
            f"bounds must give (lower, upper) for every parameter {list(names)}; got {bounds!r}"
        )
    pairs = [_pair("bounds", p, bounds[p], "(lower, upper)") for p in names]
    start = np.array([_get(keywords, p) for p in names])
    lower = np.array([lo for lo, _ in pairs])
    upper = np.array([hi for _, hi in pairs])
    if not np.all(np.isfinite(lower) & np.isfinite(upper)):
        raise ValueError(
            f"bounds must be finite numbers (they also set the sky's finite-difference step); "
            f"got {dict(bounds)!r}"
        )
    if not np.all((lower < upper) & (lower <= start) & (start <= upper)):
        raise ValueError(
            f"bounds {dict(bounds)!r} must satisfy lower < upper and hold the model's values "
            f"{dict(zip(names, start.tolist()))}"
        )
    for p, lo, hi in zip(names, lower.tolist(), upper.tolist(), strict=True):
        _check_bound(keywords, p, lo, "lower")
        _check_bound(keywords, p, hi, "upper")
    return start, lower, upper


def _checked_priors(
    names: Sequence[str], priors: Mapping[str, tuple[float, float]] | None
) -> list[tuple[int, float, float]]:
    """(parameter index, mean, standard deviation) of each prior (:func:`retrieve`)."""
    if priors is not None and not isinstance(priors, Mapping):
        raise TypeError(
            f"priors must be a mapping {{parameter: (mean, sd)}} or None; "
            f"got {type(priors).__name__}"
        )
    prior_list = []
    for p, pair in (priors or {}).items():
        if p not in names:
            raise ValueError(f"priors: {p!r} is not a fitted parameter ({list(names)})")
        mean, sd = _pair("priors", p, pair, "(mean, sd)")
        if not (math.isfinite(mean) and math.isfinite(sd) and sd > 0):
            raise ValueError(
                f"priors: {p!r} needs a finite mean and a standard deviation > 0; "
                f"got mean={mean!r}, sd={sd!r}"
            )
        prior_list.append((list(names).index(p), mean, sd))
    return prior_list


#: Most evaluations of the residuals a fit may be asked for (scipy's ``max_nfev``). [-]
MAX_ITERATIONS = 100_000


def _check_options(max_iterations: Any, tolerance: Any, allow_large: Any) -> None:
    """The numerical options of :func:`retrieve`: types and domains."""
    if not (type(max_iterations) is int and 1 <= max_iterations <= MAX_ITERATIONS):
        raise ValueError(
            f"max_iterations must be an integer within [1, {MAX_ITERATIONS}]; "
            f"got {max_iterations!r}"
        )
    if not (_real(tolerance) and 1e-15 <= tolerance < 1.0):
        raise ValueError(f"tolerance must be a number within [1e-15, 1); got {tolerance!r}")
    if not isinstance(allow_large, bool | np.bool_):
        raise TypeError(f"allow_large must be True or False; got {allow_large!r}")


#: One point of the fit: residuals, the exact rows of the Jacobian (the sky's rows NaN
#: until asked for), the optical table, the sky's table and values.
_Entry = dict[str, Any]


class _Problem:
    """The residuals of :func:`retrieve` and their Jacobian, with the last points kept.

    Each evaluation computes the optical table (and the sky's) with their exact
    derivatives; the sky's rows of the Jacobian are filled by finite differences only
    when the optimizer asks for the Jacobian.  Reports each evaluation to the callback
    or the text stream.
    """

    def __init__(
        self,
        *,
        keywords: dict[str, Any],
        names: tuple[str, ...],
        obs: list[Observation],
        sky_model: SkyModel | None,
        prior_list: list[tuple[int, float, float]],
        wavelengths: np.ndarray,
        theta: np.ndarray,
        steps: np.ndarray,
        n_streams: int,
        max_iterations: int,
        allow_large: bool,
        callback: Callable[[int, float], None] | None,
        stream: TextIO | None,
        began: float,
    ) -> None:
        self.keywords = keywords
        self.names = names
        self.obs = obs
        self.sky_model = sky_model
        self.prior_list = prior_list
        self.wavelengths = wavelengths
        self.theta = theta
        self.steps = steps
        self.n_streams = n_streams
        self.max_iterations = max_iterations
        self.allow_large = allow_large
        self.callback = callback
        self.stream = stream
        self.began = began
        self.sky_report = sky_progress(stream)
        self.labels = tuple(label for o in obs for label in sample_labels(o))
        self.sky_value = self.sky_sigma = np.zeros(0)
        if sky_model is not None:
            self.sky_value, self.sky_sigma, sky_labels = sky_model.order()
            self.labels += tuple(sky_labels)
        self.labels += tuple(f"prior:{names[i]}" for i, _, _ in prior_list)
        self.cache: dict[bytes, _Entry] = {}
        self.evaluations = 0
        self.sky_budget: int | None = None
        self.history: list[tuple[np.ndarray, np.ndarray]] = []

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """The residuals at ``x`` (what the optimizer minimizes)."""
        return np.asarray(self.evaluate(x)["residuals"])

    def evaluate(self, x: np.ndarray) -> _Entry:
        """The point ``x``: from the cache, or computed, kept and reported."""
        key = np.asarray(x, dtype=np.float64).tobytes()
        if key in self.cache:
            return self.cache[key]
        current = _set(self.keywords, dict(zip(self.names, x.tolist())))
        res, jac = [], []
        entry: _Entry = {"x": np.array(x, dtype=np.float64)}
        if self.obs:
            table = compute_optics(
                **current,
                wavelength_nm=self.wavelengths,
                theta_deg=self.theta,
                derivatives=self.names,
                allow_large=self.allow_large,
            )
            entry["table"] = table
            for o in self.obs:
                value, d = predict(table, o, self.names)
                res.append((value - o.value) / o.sigma)
                jac.append(d / o.sigma[:, None])
        if self.sky_model is not None:
            self._evaluate_sky(current, entry, res, jac)
        for i, mean, sd in self.prior_list:
            res.append(np.array([(x[i] - mean) / sd]))
            row = np.zeros((1, len(self.names)))
            row[0, i] = 1.0 / sd
            jac.append(row)
        entry["residuals"] = np.concatenate(res)
        entry["jacobian"] = np.vstack(jac)
        if len(self.cache) >= 3:  # the accepted point, a trial, the next: enough for scipy
            self.cache.pop(next(iter(self.cache)))
        self.cache[key] = entry
        self.history.append((entry["x"], entry["residuals"]))
        self.evaluations += 1
        chi_square = float(entry["residuals"] @ entry["residuals"])
        if self.callback is not None:
            self.callback(self.evaluations, chi_square)
        self._say(
            f"retrieve: evaluation {self.evaluations}: chi-square {chi_square:.6g}, "
            f"{time.perf_counter() - self.began:.1f} s\n"
        )
        return entry

    def _evaluate_sky(
        self, current: dict[str, Any], entry: _Entry, res: list[Any], jac: list[Any]
    ) -> None:
        """The sky's table and values at the point, and their rows (Jacobian's NaN)."""
        assert self.sky_model is not None
        sky_model = self.sky_model
        table_began = time.perf_counter()
        sky_table = compute_optics(
            **current,
            wavelength_nm=sky_model.wavelength_nm,
            derivatives=self.names,
            allow_large=self.allow_large,
        )
        entry["sky_table"] = sky_table
        if self.sky_budget is None:
            n, seconds = sky_model.check_cost(
                sky_table,
                table_seconds=time.perf_counter() - table_began,
                max_iterations=self.max_iterations,
                n_parameters=len(self.names),
                allow_large=self.allow_large,
            )
            self.sky_budget = n
            self._say(
                f"retrieve: at most {n} sky solves, the fit about {seconds:.0f} s at most "
                f"({sky_model.wavelength_nm.size} wavelengths, "
                f"n_streams={self.n_streams})\n"
            )
        entry["sky_values"] = sky_model.values(sky_table, self.sky_report)
        res.append((entry["sky_values"] - self.sky_value) / self.sky_sigma)
        jac.append(np.full((self.sky_value.size, len(self.names)), np.nan))

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """The Jacobian at ``x``, the sky's rows by finite differences once asked for."""
        entry = self.evaluate(x)
        jac = entry["jacobian"]
        if self.sky_model is not None and np.isnan(jac).any():
            n_obs = sum(o.value.size for o in self.obs)
            rows = slice(n_obs, n_obs + self.sky_value.size)
            jac[rows] = (
                self.sky_model.jacobian(
                    entry["sky_table"],
                    entry["sky_values"],
                    self.names,
                    self.steps,
                    self.sky_report,
                )
                / self.sky_sigma[:, None]
            )
            self._say(
                f"retrieve: Jacobian at evaluation {self.evaluations}: "
                f"{self.sky_model.solves} sky solves so far, "
                f"{time.perf_counter() - self.began:.1f} s\n"
            )
        return np.asarray(jac)

    def _say(self, line: str) -> None:
        if self.stream is not None:
            self.stream.write(line)
            self.stream.flush()
