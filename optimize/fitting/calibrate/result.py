"""A calibration's result (:class:`CalibrationResult`), the weights of the rows
(:func:`row_sigma`) and what a row without an equilibrium costs
(:func:`straight_miss`). SI units; the ``*_mm`` figures are millimetres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from design.geometry import rest_position
from design.registry import index
from optimize.fitting.calibrate.policy import FREE_PARAMETERS
from optimize.fitting.calibrate.priors import PULL_LIMIT, conflict, prior_sigma_shown, pull
from optimize.fitting.measurements import Measurements

DEFAULT_SIGMA = 1e-3
"""Weight of rows without a sigma when the data give none (the common noise is then
estimated from the residuals). [m]"""


def row_sigma(m: Measurements, sigma: float | None = None) -> np.ndarray:
    """One-sigma position uncertainty of each row [m], shape (N,): the data's own where
    given, else ``sigma``, else the median of the given ones, else DEFAULT_SIGMA."""
    s = m.sigma.copy()
    given = np.isfinite(s)
    if sigma is not None:
        fill = float(sigma)
    elif given.any():
        fill = float(np.median(s[given]))
    else:
        fill = DEFAULT_SIGMA
    s[~given] = fill
    return s


@dataclass(frozen=True)
class CalibrationResult:
    """A fitted model.

    names : the free parameters.
    estimate, standard_error, nominal : by name [SI]; the standard error is infinite for
        parameters the data do not determine (see ``message``).
    correlation : shape (k, k), correlation of the estimates (Gauss-Newton); NaN rows and
        columns for undetermined parameters.
    params : shape (n,), full model parameter vector at the estimate. [SI]
    effects : the model's effects.
    residuals : shape (N, 3), measured - model tip position; NaN where not measured or
        not converged. [m]
    errors : shape (N,), distance model-measurement over the measured coordinates. [m]
    rows : shape (N,) bool, the rows that were fitted.
    rmse_mm, max_abs_mm : root mean square and largest of ``errors`` over the fitted rows. [mm]
    noise_mm : the common position noise the residuals imply, s * sigma. [mm]
    chi2, dof : weighted sum of squared data residuals and its degrees of freedom.
    converged : the optimiser met its tolerance and every fitted row has an equilibrium.
    at_bounds : names of parameters that ended on a bound (their errors are unreliable).
    unconverged : number of fitted rows without an equilibrium at the estimate.
    evaluations : number of model solves; time_s : wall time. [s]
    message : the optimiser's message, plus any warning on identifiability.
    states : shape (N, n_unknowns), the equilibria at the estimate; NaN rows where none.
    jacobian : shape (n, k), d(residual)/d(fit units) of the n fitted data residuals at
        the estimate, each over its sigma: the measured position coordinates of the fitted
        rows (row-major), then their tip angles. [-]
    jacobian_rows : shape (n,), the row of each residual of ``jacobian``.
    """

    names: tuple[str, ...]
    estimate: dict[str, float]
    standard_error: dict[str, float]
    nominal: dict[str, float]
    correlation: np.ndarray
    params: np.ndarray
    effects: frozenset[str]
    residuals: np.ndarray
    errors: np.ndarray
    rows: np.ndarray
    rmse_mm: float
    max_abs_mm: float
    noise_mm: float
    chi2: float
    dof: int
    converged: bool
    at_bounds: tuple[str, ...]
    unconverged: int
    evaluations: int
    time_s: float
    message: str = ""
    priors: bool = field(default=False)
    data_standard_error: dict[str, float] = field(default_factory=dict)
    """The standard errors the data alone give (without the priors' residuals; the same
    as ``standard_error`` for a fit without priors): what the data separate. [SI]"""
    data_correlation: np.ndarray | None = field(default=None, repr=False)
    """The correlation of the data alone (as ``data_standard_error``)."""
    prior_width: dict[str, float] = field(default_factory=dict)
    """Each free parameter's one-sigma prior in fit units (log: of ln(value / nominal));
    infinite: none (:mod:`optimize.fitting.calibrate.priors`); empty for a fit given no
    priors (judged by the defaults)."""
    within: float | None = None
    """The prior-bounded fit's bounds, in prior sigmas (calibrate's ``within``); None: the
    registry's bounds only."""
    prior_chi2: float = 0.0
    """The sum of the squared pulls: what the priors add to ``chi2`` in the posterior. [-]"""
    states: np.ndarray | None = field(default=None, repr=False)
    jacobian: np.ndarray | None = field(default=None, repr=False)
    jacobian_rows: np.ndarray | None = field(default=None, repr=False)

    def pulls(self) -> dict[str, float]:
        """How many prior sigmas each estimate moved from its nominal value (signed; 0
        where it has no prior). A fit without priors is judged by the default ones. [-]"""
        return {n: pull(n, self.estimate[n], self.nominal[n], self.width(n)) for n in self.names}

    def width(self, name: str) -> float:
        """The prior width ``name`` is judged by, fit units: the fit's own, or the default
        (:func:`optimize.fitting.calibrate.priors.prior_widths`) for a fit without priors."""
        if name in self.prior_width:
            return self.prior_width[name]
        return math.inf if self.priors else float(FREE_PARAMETERS[name].prior)

    def conflict(self) -> float:
        """The prior-data conflict of the estimates: the largest pull of any combination
        of them, counting the data's uncertainty
        (:func:`optimize.fitting.calibrate.priors.conflict`, from the data's standard
        errors and correlation). For a posterior fit (``priors``), whose estimates the
        priors already shrank, the largest pull, a lower bound of it. [-]"""
        pulls = self.pulls()
        if self.priors:
            return max((abs(p) for p in pulls.values()), default=0.0)
        offset, width, error = [], [], []
        for n in self.names:
            spec = FREE_PARAMETERS[n]
            scale = spec.unit_size(self.estimate[n])
            w = self.width(n)
            offset.append(pulls[n] * w if math.isfinite(w) else math.nan)
            width.append(w)
            error.append(self.data_standard_error.get(n, self.standard_error[n]) / scale)
        s = np.array(error)
        corr = self.data_correlation if self.data_correlation is not None else self.correlation
        return conflict(np.array(offset), np.array(width), np.outer(s, s) * corr)

    def beyond_prior(self, limit: float = PULL_LIMIT) -> dict[str, float]:
        """The estimates more than ``limit`` prior sigmas from nominal where the data need
        them there (the :meth:`conflict` beyond ``limit`` too), with their pulls: not
        physical (:mod:`optimize.fitting.calibrate.priors`). Estimates beyond only because
        the data do not determine them (they wandered along a direction the data leave
        free) are not. [-]"""
        beyond = self.outside_prior(limit)
        return beyond if beyond and self.conflict() > limit else {}

    def outside_prior(self, limit: float = PULL_LIMIT) -> dict[str, float]:
        """The estimates more than ``limit`` prior sigmas from nominal, with their pulls,
        whether or not the data need them there (:meth:`beyond_prior`). [-]"""
        return {n: p for n, p in self.pulls().items() if abs(p) > limit}

    def table(self) -> list[dict[str, object]]:
        """One row per parameter in report units: name, unit, nominal, estimate, standard
        error, relative change, prior width (:func:`prior_sigma_shown`) and pull."""
        rows = []
        pulls = self.pulls()
        for name in self.names:
            label, factor = FREE_PARAMETERS[name].label
            nom, est = self.nominal[name], self.estimate[name]
            rows.append(
                {
                    "name": name,
                    "unit": label,
                    "nominal": nom * factor,
                    "estimate": est * factor,
                    "standard_error": self.standard_error[name] * factor,
                    "change": (est / nom - 1) if nom else float("nan"),
                    "prior_sigma": prior_sigma_shown(name, self.width(name)),
                    "pull": pulls[name],
                }
            )
        return rows


def straight_miss(params: np.ndarray, m: Measurements) -> np.ndarray:
    """What a row without an equilibrium costs: the straight, unloaded robot's tip (at
    ``params``' free length) minus each measured position, shape (N, 3), zero where not
    measured. The fit's objective and the diagnosis' misfit use it alike. [m]"""
    rest = rest_position(params[index("free_length")])
    return np.where(m.measured, rest - m.position, 0.0)
