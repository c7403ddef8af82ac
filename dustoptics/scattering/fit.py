"""Analytic phase functions fitted to a table, per wavelength or per colour channel.

Engines without a lookup table take one analytic phase function: Unreal's sky
a Cornette-Shanks or HG g, OpenSpace one Cornette-Shanks G for its three channels
(``miePhaseFunction`` in ``modules/atmosphere/shaders/atmosphere_common.glsl``;
Costa et al. 2021's Mars branch a double HG), Celestia an HG g turned into
Schlick's k.  Bevy is not one of them: its ``PhaseFunction::Mie`` takes one HG g,
but ``PhaseFunction::ChromaticTexture`` takes the tabulated phase function of
each channel (:mod:`dustoptics.io.engines.bevy`).  :func:`fit_phase` finds the parameters of such a model that best
match each row of a tabulated phase function; :func:`fit_table` does it for a
:class:`~dustoptics.table.Table` per wavelength or per output channel
(:func:`dustoptics.colour.channel_weights`).

Models (:data:`FIT_MODELS`)
---------------------------
Every model of :data:`dustoptics.scattering.phase.ANALYTIC_MODELS` whose
record carries the ranges a fit searches, starting values and analytic
derivatives (:attr:`~dustoptics.scattering.phase.AnalyticModel.fittable`).
Their formulas, ranges, lobe order (``dhg_costa2021`` forward lobe first) and
citations are in the records; the hyphenated spellings (``dhg-costa2021``) and
short names (``hg``, ``cs``, ...) are aliases (:data:`FIT_MODEL_ALIASES`).

Loss
----
The residual at angle ``theta_j`` is the relative error
``r_j = M_j / T_j - 1`` of the model ``M`` against the table ``T``, and the
loss is its mean square over solid angle,
``L = sum_j w_j r_j^2 / sum_j w_j``, with ``w_j`` the solid angle each sample
stands for when the table is read linearly in angle (the weights of
:func:`dustoptics.scattering.tabulated_phase.sphere_integral`).  The model is compared as
it would be tabulated: sampled at the table's angles and scaled to the
table's own sphere integral under the same weights (1 for a renormalized
table), so a table made from one of the models, renormalized or sampled
as is, is recovered to round-off.

Forward peak: it is weighted by its solid angle like any other direction, in
relative terms, so the loss asks for the same relative accuracy everywhere.
Mie diffraction peaks that a model cannot follow cost only their small solid
angle (a few degrees around 0); angles below ``forward_cutoff_deg`` (default
0, none) can be left out entirely (as a delta-M truncation would treat them).
The reported errors are over all angles whatever the cutoff, so a missed peak
shows in ``max_relative_error``.

Method
------
Deterministic and vectorized over rows: Levenberg-Marquardt on the residual
vector in unbounded variables (each bounded parameter is an affine tanh of
one), analytic Jacobian (the models' derivatives, checked against finite
differences in the tests), a fixed iteration budget, started
from the table's Legendre moments (for two-lobe models, the two-node Gauss
rule matching the moments 1-3: ``<P_l>`` of HG(g) is ``g^l``) and from a few
fixed points; the best result of all starts is kept.  No random starts.  A
model that cannot represent a table returns its best parameters and their
(large) errors, never NaN.

Continuity in wavelength: fitted alone, neighbouring rows of a two-lobe model
can land in different minima (the Blue Moon's double HG swaps its lobes between
610 and 620 nm), and a renderer that interpolates the parameters between
wavelengths would then draw neither.  Rows with distinct wavelengths are
therefore fitted as one path: outward from an anchor row, each row starts from
its neighbour's solution (anchors: the first, the last and the best-fitted row;
the path of least total loss is kept).  Lobes are ordered by one fixed rule per
model.  Where the path is worse than a row's best fit alone, the result says by
how much (:attr:`FitResult.continuity_cost`); ``continuous=False`` gives the
rows' own best fits.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from dustoptics._validation import as_float_array, check_choice, check_closed_interval
from dustoptics.colour import channel_phase, channel_weights
from dustoptics.scattering.phase import ANALYTIC_MODELS, AnalyticModel
from dustoptics.scattering.tabulated_phase import _linear_theta_weights

__all__ = [
    "FIT_MODELS",
    "FIT_MODEL_ALIASES",
    "FitResult",
    "fit_phase",
    "fit_table",
]

FloatArray = np.ndarray


def _fittable() -> dict[str, AnalyticModel]:
    """The fittable models of the phase registry, read when called, by the name fits carry."""
    return {m.fit_label: m for m in ANALYTIC_MODELS.values() if m.fittable}


def _short_names(fittable: dict[str, AnalyticModel]) -> dict[str, str]:
    """Each fittable model's other aliases (``hg``, ``dhg``, ...), to the name fits carry."""
    return {a: label for label, m in fittable.items() for a in m.aliases if a != label}


#: The package's own models that :func:`fit_phase` fits, by the names their results and
#: files carry (:attr:`~dustoptics.scattering.phase.AnalyticModel.fit_label`).
FIT_MODELS: tuple[str, ...] = tuple(_fittable())

#: Short names accepted for :data:`FIT_MODELS`.
FIT_MODEL_ALIASES: dict[str, str] = _short_names(_fittable())

_SCREEN_ITERATIONS = 10  # from every start, on every _SCREEN_STRIDE-th angle
_SCREEN_STRIDE = 8
_ITERATIONS = 150  # the best start, on the same angles
_POLISH_ITERATIONS = 150  # then on all angles (only rows not yet converged cost time)
_U_MAX = 12.0  # tanh(12) = 1 - 7.6e-11: parameters stay strictly inside their ranges


@dataclass(frozen=True)
class FitResult:
    """Parameters of an analytic phase function fitted to rows of a table.

    Attributes
    ----------
    model : str
        One of :data:`FIT_MODELS`.
    formula : str
        The model, in words and symbols.
    citation : str
        Where the model comes from.
    parameter_names : tuple of str
        Names of the columns of ``parameters``.
    parameters : numpy.ndarray, shape (n_rows, n_parameters)
        Best parameters, each row within the model's valid ranges. [-]
    labels : tuple of str
        What each row is (``"550 nm"``, ``"R"``, ...).
    wavelength_nm : numpy.ndarray, shape (n_rows,)
        Wavelength of each row (a channel's weighted mean wavelength). [nm]
    max_relative_error : numpy.ndarray, shape (n_rows,)
        Largest ``|M / T - 1|`` over the table's angles. [-]
    median_relative_error : numpy.ndarray, shape (n_rows,)
        Median ``|M / T - 1|`` over the angles. [-]
    rms_relative_error : numpy.ndarray, shape (n_rows,)
        Square root of the loss (solid-angle weighted). [-]
    g_model : numpy.ndarray, shape (n_rows,)
        Mean cosine of the analytic model with these parameters. [-]
    g_error : numpy.ndarray, shape (n_rows,)
        Mean cosine of the model as tabulated minus the table's, both read
        linearly in angle (:func:`~dustoptics.scattering.tabulated_phase.mean_cosine`). [-]
    loss : str
        The loss, in words.
    forward_cutoff_deg : float
        Angles below this were left out of the loss. [deg]
    continuous : bool
        True when the rows were fitted as one path along wavelength, each row
        started from its neighbour's solution (see :func:`fit_phase`), so that a
        renderer can interpolate the parameters between rows.
    independent_rms_relative_error : numpy.ndarray, shape (n_rows,)
        ``rms_relative_error`` of each row's best fit on its own, whatever its
        neighbours; where it is below ``rms_relative_error``, the continuous path
        costs accuracy (:attr:`continuity_cost`). [-]
    """

    model: str
    formula: str
    citation: str
    parameter_names: tuple[str, ...]
    parameters: FloatArray
    labels: tuple[str, ...]
    wavelength_nm: FloatArray
    max_relative_error: FloatArray
    median_relative_error: FloatArray
    rms_relative_error: FloatArray
    g_model: FloatArray
    g_error: FloatArray
    loss: str
    forward_cutoff_deg: float
    continuous: bool
    independent_rms_relative_error: FloatArray

    def parameter(self, name: str) -> FloatArray:
        """One parameter over the rows, by name."""
        check_choice("name", name, self.parameter_names)
        return self.parameters[:, self.parameter_names.index(name)]

    @property
    def continuity_cost(self) -> FloatArray:
        """How much worse each row fits on the continuous path than on its own. [-]

        ``rms_relative_error - independent_rms_relative_error``: 0 where the
        continuous solution is also the best one found for that row alone.
        """
        return np.maximum(self.rms_relative_error - self.independent_rms_relative_error, 0.0)

    def largest_jump(self) -> dict[str, float]:
        """Largest change of each parameter between rows adjacent in wavelength.

        Returns
        -------
        dict
            Parameter name -> ``max |p[i + 1] - p[i]|`` over the rows sorted by
            wavelength (NaN wavelengths last). [parameter's unit]
        """
        order = np.argsort(self.wavelength_nm, kind="stable")
        steps = np.abs(np.diff(self.parameters[order], axis=0))
        return {
            name: float(steps[:, k].max()) if steps.size else 0.0
            for k, name in enumerate(self.parameter_names)
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping: model, parameters and errors per row."""
        rows = []
        for i, label in enumerate(self.labels):
            rows.append(
                {
                    "label": label,
                    "wavelength_nm": (
                        float(self.wavelength_nm[i]) if np.isfinite(self.wavelength_nm[i]) else None
                    ),
                    "parameters": {
                        n: float(self.parameters[i, k]) for k, n in enumerate(self.parameter_names)
                    },
                    "max_relative_error": float(self.max_relative_error[i]),
                    "median_relative_error": float(self.median_relative_error[i]),
                    "rms_relative_error": float(self.rms_relative_error[i]),
                    "independent_rms_relative_error": float(self.independent_rms_relative_error[i]),
                    "g_model": float(self.g_model[i]),
                    "g_error": float(self.g_error[i]),
                }
            )
        return {
            "model": self.model,
            "formula": self.formula,
            "citation": self.citation,
            "normalization": "2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian); mu = cos(theta), "
            "theta = 0 forward",
            "loss": self.loss,
            "forward_cutoff_deg": self.forward_cutoff_deg,
            "continuous": self.continuous,
            "rows": rows,
        }


def resolve_model(model: str) -> str:
    """The name fits carry for ``model``: a fittable model's name, registry name or alias.

    Read from :data:`~dustoptics.scattering.phase.ANALYTIC_MODELS` when called,
    so a model registered after import (:func:`~dustoptics.scattering.phase.
    register_analytic_model`) is fitted like the package's own.  The registry
    names (``dhg_costa2021``) are accepted too; the error for an unknown name
    lists the names of :data:`FIT_MODELS` and the short aliases.
    """
    fittable = _fittable()
    short = _short_names(fittable)
    registry = {m.name: label for label, m in fittable.items()}
    name = short.get(model, registry.get(model, model))
    check_choice("model", name, (*fittable, *short))
    return name


@cache
def _bounds(model: AnalyticModel) -> tuple[FloatArray, FloatArray]:
    """The lower and upper bounds of the model's parameters, shape (k,) each (read-only)."""
    low = np.array([low for low, _ in model.bounds])
    high = np.array([high for _, high in model.bounds])
    low.setflags(write=False)
    high.setflags(write=False)
    return low, high


def _to_u(model: AnalyticModel, p: FloatArray) -> FloatArray:
    low, high = _bounds(model)
    s = np.clip(2.0 * (p - low) / (high - low) - 1.0, -math.tanh(_U_MAX), math.tanh(_U_MAX))
    return np.arctanh(s)


def _to_p(model: AnalyticModel, u: FloatArray) -> FloatArray:
    low, high = _bounds(model)
    return low + (high - low) * 0.5 * (np.tanh(np.clip(u, -_U_MAX, _U_MAX)) + 1.0)


def _evaluate(model: AnalyticModel, mu: FloatArray, p: FloatArray) -> FloatArray:
    """The model's formula (its record's kernel) at ``mu`` (m,) for parameter rows ``p`` (n, k)."""
    assert model.kernel is not None  # every fittable model has one (tests/scattering/test_fit.py)
    return np.asarray(model.kernel(mu, *(p[:, i : i + 1] for i in range(p.shape[1]))))


def _asymmetry(model: AnalyticModel, p: FloatArray) -> FloatArray:
    """The model's mean cosine for parameter rows ``p`` (n, k), shape (n,). [-]"""
    values = model.asymmetry(**{name: p[:, k] for k, name in enumerate(model.parameters)})
    return np.asarray(values, dtype=np.float64).reshape(p.shape[0])


def _tabulated(
    model: AnalyticModel,
    mu: FloatArray,
    w: FloatArray,
    p: FloatArray,
    table: FloatArray,
) -> FloatArray:
    """The model sampled at the table's angles, scaled to the table's sphere integral.

    Both integrals use the same weights ``w`` (linear in angle), so a table
    that is the model, renormalized or not, is matched exactly.
    """
    f = _evaluate(model, mu, p)
    return f * ((table @ w) / (f @ w))[:, None]


def _residuals(
    model: AnalyticModel,
    mu: FloatArray,
    w: FloatArray,
    sqrt_w: FloatArray,
    table: FloatArray,
    u: FloatArray,
) -> FloatArray:
    return (_tabulated(model, mu, w, _to_p(model, u), table) / table - 1.0) * sqrt_w


def _jacobian(
    model: AnalyticModel,
    mu: FloatArray,
    w: FloatArray,
    sqrt_w: FloatArray,
    table: FloatArray,
    u: FloatArray,
) -> FloatArray:
    """d residual / d u, shape (n, m, k), from the models' analytic derivatives.

    With ``M = f S_T / S_f`` (``S = sum w f``), ``dM/dp = S_T (f' / S_f - f (w f') / S_f^2)``,
    and ``dp/du = (high - low) (1 - tanh(u)^2) / 2``.
    """
    low, high = _bounds(model)
    t = np.tanh(np.clip(u, -_U_MAX, _U_MAX))
    assert model.gradient is not None
    f, df = model.gradient(mu, low + (high - low) * 0.5 * (t + 1.0))  # _to_p(model, u)
    s_f = f @ w
    s_df = np.matmul(w, df)  # (n, k); matmul, not einsum: BLAS, several times faster
    scale = (table @ w) / s_f
    d_model = scale[:, None, None] * (df - f[:, :, None] * (s_df / s_f[:, None])[:, None, :])
    dp_du = 0.5 * (high - low) * (1.0 - t * t)
    return d_model * ((sqrt_w / table)[:, :, None] * dp_du[:, None, :])


def _levenberg_marquardt(
    model: AnalyticModel,
    mu: FloatArray,
    w: FloatArray,
    sqrt_w: FloatArray,
    table: FloatArray,
    u0: FloatArray,
    iterations: int,
) -> tuple[FloatArray, FloatArray]:
    """Minimize sum r^2 per row from u0 (n, k); returns u and the loss per row.

    Rows stop once a step lowers their loss by less than 1e-8 of itself, the
    step is below 1e-15 of the variables or the damping exceeds 1e6 (a stall); only the other
    rows are computed on.
    """
    n, k = u0.shape
    u = np.clip(u0, -_U_MAX, _U_MAX)
    r = _residuals(model, mu, w, sqrt_w, table, u)
    cost = np.einsum("ij,ij->i", r, r)
    cost = np.where(np.isfinite(cost), cost, np.inf)
    lam = np.full(n, 1e-3)
    active = np.isfinite(cost)
    eye = np.eye(k)
    for _ in range(iterations):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        ui, ri, ti = u[idx], r[idx], table[idx]
        jac = _jacobian(model, mu, w, sqrt_w, ti, ui)
        # J^T J and J^T r per row as batched matrix products (BLAS; einsum over the
        # angles is several times slower for a full table).
        jtj = np.matmul(jac.transpose(0, 2, 1), jac)
        jtr = np.matmul(ri[:, None, :], jac)[:, 0, :]
        diag = np.maximum(np.einsum("nii->ni", jtj), 1e-30)
        a = jtj + lam[idx, None, None] * (eye[None] * diag[:, :, None])
        # A parameter at its bound that the gradient pushes outward stays there
        # (active set): its row and column drop out of the step.
        pinned = (np.abs(ui) >= _U_MAX) & (np.sign(-jtr) == np.sign(ui))
        free = ~pinned
        a = np.where(free[:, :, None] & free[:, None, :], a, eye[None])
        jtr = np.where(free, jtr, 0.0)
        step = -np.linalg.solve(a, jtr[:, :, None])[:, :, 0]
        trial = np.clip(ui + step, -_U_MAX, _U_MAX)  # a parameter at its bound stays there
        r_trial = _residuals(model, mu, w, sqrt_w, ti, trial)
        cost_trial = np.einsum("ij,ij->i", r_trial, r_trial)
        old = cost[idx]
        better = np.isfinite(cost_trial) & (cost_trial <= old)
        u[idx] = np.where(better[:, None], trial, ui)
        r[idx] = np.where(better[:, None], r_trial, ri)
        cost[idx] = np.where(better, cost_trial, old)
        lam[idx] = np.where(better, np.maximum(lam[idx] / 3.0, 1e-12), lam[idx] * 4.0)
        small = np.all(np.abs(step) <= 1e-15 * np.maximum(1.0, np.abs(ui)), axis=1)
        done = (better & (old - cost_trial <= 1e-8 * old)) | (lam[idx] > 1e6) | small
        active[idx[done]] = False
    return u, cost


def _moments(theta_deg: FloatArray, phase: FloatArray) -> FloatArray:
    """Legendre moments <P_0..P_3> of each row (read linearly in angle)."""
    mu = np.cos(np.deg2rad(theta_deg))
    w = 2.0 * math.pi * _linear_theta_weights(theta_deg)
    legendre = np.stack([np.ones_like(mu), mu, 1.5 * mu * mu - 0.5, 2.5 * mu**3 - 1.5 * mu])
    return (phase * w) @ legendre.T


def _continuous_path(
    spec: AnalyticModel,
    mu: FloatArray,
    w: FloatArray,
    sqrt_w: FloatArray,
    table: FloatArray,
    order: np.ndarray,
    best_u: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """One solution per row that changes continuously along ``order`` (rows by wavelength).

    Each row is started from its neighbour's solution, outward from an anchor row
    that keeps its own best fit; the anchors tried are the first and last rows and
    the row fitted best on its own, and the path with the least total loss is kept.
    Returns the variables and the loss of each row.
    """
    n = order.size
    _, own = _levenberg_marquardt(spec, mu, w, sqrt_w, table, best_u, 0)
    anchors = sorted({0, n - 1, int(np.argmin(own[order]))})
    us = [best_u.copy() for _ in anchors]
    costs = [own.copy() for _ in anchors]
    # Every anchor's two walks (outward, one row a step) are taken together: each step
    # fits, as one batch, the next row of every walk from its predecessor's solution;
    # a row started from the same point by two walks is fitted once.
    walks = [
        (k, a, path)
        for k, a in enumerate(anchors)
        for path in (range(a + 1, n), range(a - 1, -1, -1))
        if len(path)
    ]
    prev = {(k, a): int(order[a]) for k, a, _ in walks}
    for step in range(max(len(path) for _, _, path in walks) if walks else 0):
        jobs: dict[tuple[int, bytes], list[tuple[int, int]]] = {}
        for k, a, path in walks:
            if step < len(path):
                i, j = int(order[path[step]]), prev[(k, a)]
                key = (i, us[k][j].tobytes())
                jobs.setdefault(key, []).append((k, j))
                prev[(k, a)] = i
        keys = list(jobs)
        rows = np.array([i for i, _ in keys])
        starts = np.array([us[jobs[key][0][0]][jobs[key][0][1]] for key in keys])
        ui, ci = _levenberg_marquardt(spec, mu, w, sqrt_w, table[rows], starts, _POLISH_ITERATIONS)
        for q, key in enumerate(keys):
            for k, _ in jobs[key]:
                us[k][key[0]], costs[k][key[0]] = ui[q], ci[q]
    best = min(range(len(anchors)), key=lambda k: costs[k].sum())
    return us[best], costs[best]


def fit_phase(
    theta_deg: Any,
    phase: Any,
    *,
    model: str,
    forward_cutoff_deg: float = 0.0,
    labels: Sequence[str] | None = None,
    wavelength_nm: Any = None,
    continuous: bool = True,
) -> FitResult:
    """Fit an analytic phase function to each row of a phase table.

    Parameters
    ----------
    theta_deg : array_like, shape (m,)
        Scattering angles, strictly increasing from 0 to 180. [deg]
    phase : array_like, shape (n, m) or (m,)
        Phase function rows, positive, normalized to 1 over the sphere. [sr^-1]
    model : str
        One of :data:`FIT_MODELS` or an alias in :data:`FIT_MODEL_ALIASES`.
    forward_cutoff_deg : float
        Leave angles below this out of the loss (default 0: none). [deg]
    labels : sequence of str, optional
        Names of the rows (default ``"row 0"``, ...).
    wavelength_nm : array_like, shape (n,), optional
        Wavelength of each row, recorded in the result (NaN if not given). [nm]
    continuous : bool
        With distinct wavelengths for two rows or more (default True): fit the
        rows as one path along wavelength, each started from its neighbour's
        solution, so that the parameters change continuously and a renderer can
        interpolate them (two-lobe models otherwise may swap lobes between
        neighbouring wavelengths).  The result reports what continuity costs
        each row (:attr:`FitResult.continuity_cost`).  False: each row's best
        fit on its own.

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        For an unknown model, angles that do not run from 0 to 180, a phase
        function that is not positive and finite, or a cutoff outside [0, 90).

    Notes
    -----
    The loss, its treatment of the forward peak, the starts and the optimizer
    are described in the module docstring.

    Examples
    --------
    >>> from dustoptics.scattering.phase import henyey_greenstein
    >>> theta = np.linspace(0.0, 180.0, 721)
    >>> p = henyey_greenstein(np.cos(np.deg2rad(theta)), g=0.6)
    >>> r = fit_phase(theta, p, model="hg")
    >>> bool(abs(r.parameters[0, 0] - 0.6) < 1e-12 and r.max_relative_error[0] < 1e-12)
    True
    """
    spec = _fittable()[resolve_model(model)]
    theta, table, cutoff = _checked_table(theta_deg, phase, forward_cutoff_deg)
    n = table.shape[0]
    row_labels = tuple(labels) if labels is not None else tuple(f"row {i}" for i in range(n))
    if len(row_labels) != n:
        raise ValueError(f"labels must name the {n} rows; got {len(row_labels)}")
    lam = (
        np.full(n, np.nan)
        if wavelength_nm is None
        else as_float_array("wavelength_nm", wavelength_nm, ndim=1)
    )
    if lam.shape != (n,):
        raise ValueError(f"wavelength_nm must have {n} values; got {lam.shape}")
    along = continuous and n > 1 and bool(np.all(np.isfinite(lam))) and np.unique(lam).size == n
    best_u, best_cost, independent_cost = _search(
        spec, theta, table, cutoff, np.argsort(lam, kind="stable") if along else None
    )
    return _result(
        spec, theta, table, cutoff, best_u, best_cost, independent_cost, row_labels, lam, along
    )


def _checked_table(
    theta_deg: Any, phase: Any, forward_cutoff_deg: float
) -> tuple[FloatArray, FloatArray, float]:
    """The angles [deg], rows (n, m) [sr^-1] and cutoff [deg] of :func:`fit_phase`, checked."""
    theta = as_float_array("theta_deg", theta_deg, ndim=1)
    if theta.size < 3 or theta[0] != 0.0 or theta[-1] != 180.0 or np.any(np.diff(theta) <= 0):
        raise ValueError(
            "theta_deg must be strictly increasing from exactly 0 to exactly 180 deg with at "
            f"least 3 angles; got {theta.size} angles from {theta[0]:g} to {theta[-1]:g}"
        )
    table = as_float_array("phase", phase)
    if table.ndim == 1:
        table = table[None, :]
    if table.ndim != 2 or table.shape[1] != theta.size:
        raise ValueError(
            f"phase must have shape (n_rows, {theta.size}) (angles last); got {np.shape(phase)}"
        )
    if np.any(table <= 0.0):
        raise ValueError(
            "phase must be positive at every angle for a relative-error fit; got a minimum of "
            f"{table.min():g} sr^-1"
        )
    cutoff = check_closed_interval("forward_cutoff_deg", forward_cutoff_deg, 0.0, 89.999)
    return theta, table, cutoff


def _loss_weights(theta: FloatArray, cutoff: float) -> tuple[FloatArray, FloatArray]:
    """The linear-in-angle weights of ``theta`` and the square roots of the loss's weights."""
    w = _linear_theta_weights(theta)
    w_loss = np.where(theta >= cutoff, w, 0.0) if cutoff > 0 else w
    return w, np.sqrt(w_loss / w_loss.sum())


def _search(
    spec: AnalyticModel,
    theta: FloatArray,
    table: FloatArray,
    cutoff: float,
    order: np.ndarray | None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Best variables per row, their loss, and each row's loss fitted on its own.

    Starts are screened on every few angles (the table's own subgrid, with its
    own weights), then the best is polished on all angles; with ``order`` (rows
    by wavelength) the rows are then followed as one continuous path.
    """
    n = table.shape[0]
    mu = np.cos(np.deg2rad(theta))
    w, sqrt_w = _loss_weights(theta, cutoff)
    best_u = np.zeros((n, len(spec.parameters)))
    best_cost = np.full(n, np.inf)
    sub = np.unique(np.concatenate([np.arange(0, theta.size, _SCREEN_STRIDE), [theta.size - 1]]))
    w_sub, sqrt_w_sub = _loss_weights(theta[sub], cutoff)
    on_sub = (spec, mu[sub], w_sub, sqrt_w_sub, table[:, sub])
    assert spec.starts is not None
    with np.errstate(all="ignore"):  # trial steps that leave the valid range are rejected
        for start in spec.starts(_moments(theta, table)):
            u, cost = _levenberg_marquardt(*on_sub, _to_u(spec, start), _SCREEN_ITERATIONS)
            better = cost < best_cost
            best_u = np.where(better[:, None], u, best_u)
            best_cost = np.where(better, cost, best_cost)
        best_u, _ = _levenberg_marquardt(*on_sub, best_u, _ITERATIONS)
        best_u, best_cost = _levenberg_marquardt(
            spec, mu, w, sqrt_w, table, best_u, _POLISH_ITERATIONS
        )
        independent_cost = best_cost
        if order is not None:
            # The path is followed on the screening angles, then polished on all of them
            # at once (from a neighbour's solution a row stays in its basin).
            path_u, _ = _continuous_path(*on_sub, order, best_u)
            best_u, best_cost = _levenberg_marquardt(
                spec, mu, w, sqrt_w, table, path_u, _POLISH_ITERATIONS
            )
    return best_u, best_cost, independent_cost


def _result(
    spec: AnalyticModel,
    theta: FloatArray,
    table: FloatArray,
    cutoff: float,
    best_u: FloatArray,
    best_cost: FloatArray,
    independent_cost: FloatArray,
    row_labels: tuple[str, ...],
    lam: FloatArray,
    along: bool,
) -> FitResult:
    """The :class:`FitResult` of the best variables: parameters, errors, the loss in words."""
    mu = np.cos(np.deg2rad(theta))
    w, sqrt_w = _loss_weights(theta, cutoff)
    params = _to_p(spec, best_u)
    if spec.canonical is not None:
        params = spec.canonical(params)
    model_tab = _tabulated(spec, mu, w, params, table)
    rel = np.abs(model_tab / table - 1.0)
    g_table = 0.5 * math.pi * (table @ _linear_theta_weights(2.0 * theta))
    g_model_tab = 0.5 * math.pi * (model_tab @ _linear_theta_weights(2.0 * theta))
    for array in (params, lam):
        array.setflags(write=False)
    loss = (
        "mean over solid angle of (M/T - 1)^2, M the model sampled at the table's angles and "
        "scaled to the table's sphere integral (both read linearly in angle), T the table"
        + (f"; angles below {cutoff:g} deg left out" if cutoff > 0 else "; all angles")
    )
    return FitResult(
        model=spec.fit_label,
        formula=spec.formula,
        citation=spec.fit_citation or spec.citation,
        parameter_names=spec.parameters,
        parameters=params,
        labels=row_labels,
        wavelength_nm=lam,
        max_relative_error=rel.max(axis=1),
        median_relative_error=np.median(rel, axis=1),
        rms_relative_error=np.sqrt(
            np.einsum("ij,ij->i", rel * rel, np.broadcast_to(sqrt_w**2, rel.shape))
        ),
        g_model=_asymmetry(spec, params),
        g_error=g_model_tab - g_table,
        loss=loss,
        forward_cutoff_deg=cutoff,
        continuous=along,
        independent_rms_relative_error=np.sqrt(np.minimum(independent_cost, best_cost)),
    )


def fit_table(
    table: Any,
    *,
    model: str,
    colour: str | None = None,
    channels_nm: Any = None,
    forward_cutoff_deg: float = 0.0,
) -> FitResult:
    """Fit an analytic phase function to a table per wavelength, or per channel.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table.
    model : str
        One of :data:`FIT_MODELS` or an alias.
    colour : {"wavelengths", "cie1931-xyz", "linear-srgb-astmg173"}, optional
        Fit three channels (:func:`dustoptics.colour.channel_weights`; the
        phase function of each weighted by scattering when the table has
        cross-sections, :func:`dustoptics.colour.channel_phase`) instead of
        every wavelength.
    channels_nm : sequence of 3 floats, optional
        Channel wavelengths for ``colour="wavelengths"`` (default 680, 550,
        440 nm). [nm]
    forward_cutoff_deg : float
        As for :func:`fit_phase`. [deg]

    Returns
    -------
    FitResult
        One row per wavelength, or per channel.
    """
    theta = np.asarray(table.theta_deg, dtype=np.float64)
    lam = np.asarray(table.wavelength_nm, dtype=np.float64)
    if colour is None:
        if channels_nm is not None:
            raise ValueError("channels_nm needs colour='wavelengths'")
        return fit_phase(
            theta,
            table.phase,
            model=model,
            forward_cutoff_deg=forward_cutoff_deg,
            labels=[f"{v:g} nm" for v in lam],
            wavelength_nm=lam,
        )
    resolve_model(model)
    channels = channel_weights(lam, mode=colour, channels_nm=channels_nm)
    phase = channel_phase(channels, table.phase, csca_um2=table.quantity("csca_um2"))
    return fit_phase(
        theta,
        phase,
        model=model,
        forward_cutoff_deg=forward_cutoff_deg,
        labels=list(channels.names),
        wavelength_nm=channels.centroid_nm,
    )
