"""The fit: :func:`calibrate`, nonlinear least squares from one start, warm-started, its
answer checked with the load ramp (module docstring of
:mod:`optimize.fitting.calibrate`). SI units.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Iterable, Mapping, Sequence
from typing import Literal

import numpy as np
from scipy.optimize import OptimizeResult, least_squares

from design.model import model_for
from design.records import Design
from design.registry import index
from design.units import MM
from optimize.fitting.calibrate.policy import FREE_PARAMETERS, _check_free, default_free
from optimize.fitting.calibrate.priors import Priors, prior_widths
from optimize.fitting.calibrate.problem import _Problem
from optimize.fitting.calibrate.result import DEFAULT_SIGMA, CalibrationResult, row_sigma
from optimize.fitting.measurements import Measurements
from optimize.fitting.sensitivity import position_errors

WARM_RETRIES = 1
"""Fits made again from the start with warm starts, the rows whose warm start went
elsewhere by the ramp, before one with every row by the ramp."""
NOISE_AGREES = 1.25
"""With priors and no stated noise, a fit is made again with the noise its residuals
imply unless that lies within this factor of the one assumed (the priors' weight then
within 1.6x of the data's). [-]"""
WARM_TOLERANCE = 1e-3
"""The warm-started states of a fit's answer are the ramp's where every fitted row's tip
lies within this fraction of its sigma of the ramp's (else the fit goes on with the
ramp's). [-]"""


class UnsolvedStart(ValueError):
    """Too few configurations have an equilibrium where a fit would start."""


def _mixes(u: np.ndarray, start: np.ndarray) -> list[np.ndarray]:
    """u itself, and u with each one and each two of its parameters set to the start's."""
    mixes = [u.copy()]
    for size in (1, 2):
        for cols in itertools.combinations(range(len(u)), size):
            v = u.copy()
            v[list(cols)] = start[list(cols)]
            mixes.append(v)
    return mixes


def calibrate(
    design: Design,
    m: Measurements,
    effects: Iterable[str] = (),
    free: Sequence[str] | None = None,
    *,
    rows: np.ndarray | Sequence[int] | None = None,
    fixed: Mapping[str, float] | None = None,
    initial: Mapping[str, float] | None = None,
    priors: bool | Priors = False,
    sigma: float | None = None,
    ordered: bool | Literal["driven"] | None = None,
    tip_angles: bool = True,
    max_nfev: int | None = None,
    min_solved: float = 0.0,
    anchor: Mapping[str, tuple[float, float]] | None = None,
    warm_start: bool = True,
    states: np.ndarray | None = None,
    within: float | None = None,
    posterior: bool = True,
) -> CalibrationResult:
    """Fit the free parameters of the model with ``effects`` to the measurements ``m``.

    free : names from :data:`FREE_PARAMETERS`; default :func:`default_free` (effects).
    rows : the rows to fit (indices or mask); default all. The others are still simulated
        (along the path when ordered) and get residuals, for cross-validation.
    fixed : values of other model parameters (names of ``design.registry.NAMES``) that
        differ from the design, e.g. an earlier fit's. [SI]
    initial : starting values of free parameters; default the nominal design's. [SI]
    priors : maximise the posterior: a Gaussian residual per free parameter, centred on
        the nominal design (:mod:`optimize.fitting.calibrate.priors`): True with the
        default widths, a mapping with those widths overridden (fit units, as
        :func:`optimize.fitting.calibrate.priors.parse_priors` gives them).
    sigma : one-sigma position uncertainty for rows whose data give none. [m]
    ordered : see :func:`predict`.
    tip_angles : also fit measured tip angles (sigma TIP_ANGLE_SIGMA) where present.
    max_nfev : model evaluations at most (default 50 per free parameter and one).
    anchor : free parameter -> (centre, width) [SI]: a Gaussian penalty row
        (value - centre) / width on the weighted residuals' scale (e.g. a fold of a
        cross-validation kept near the fit of all the data, :func:`cross_validate`).
    warm_start : solve each evaluation from the states of the last one (module docstring);
        False: every evaluation by the load ramp (or the path).
    states : shape (N, n_unknowns), each row's state at parameters near the start (e.g.
        the fit of all the data, for a fold of a cross-validation that starts there; NaN:
        none): the first evaluation is warm-started from them too.
    within : with priors, bound each free parameter to its nominal value +- this many
        prior sigmas (the prior-bounded fit: what the model can do with physical
        parameters only, e.g. PULL_LIMIT). [-]
    posterior : False: the priors only bound the fit (``within``), without their residuals
        (a least-squares fit within what the bench allows; the power of the data refits
        so, where its first order, a projection on the data's Jacobian, has no priors
        either).
    min_solved : the fraction of fitted rows that must have an equilibrium at the start;
        below it :class:`UnsolvedStart` is raised before any fitting (a least-squares fit
        from a start where most rows have no state rarely finds one). [-]
    """
    t0 = time.perf_counter()
    model = model_for(frozenset(effects))
    names = _check_free(default_free(model.effects) if free is None else free)
    base = model.parameters(design)
    for name, value in (fixed or {}).items():
        base[index(name)] = float(value)
    nominal = {n: float(base[index(n)]) for n in names}
    for n in names:
        if FREE_PARAMETERS[n].kind == "log" and not nominal[n] > 0:
            raise ValueError(f"{n} must be positive to be fitted on a log scale; got {nominal[n]}")
    start = dict(nominal)
    for name, value in (initial or {}).items():
        if name not in names:
            raise ValueError(f"initial value for {name!r}, which is not free ({list(names)})")
        start[name] = float(value)
    fit_rows = np.arange(len(m)) if rows is None else np.arange(len(m))[np.asarray(rows)]
    s_rows = row_sigma(m, sigma)
    table = prior_widths(priors if isinstance(priors, Mapping) else None)
    bounding = np.array([table[n] for n in names])  # what ``within`` counts sigmas of
    widths = bounding if priors is not False and posterior else np.full(len(names), np.inf)
    prob = _Problem(
        model, base, names, m, fit_rows, s_rows, ordered, widths, tip_angles, np.zeros(len(names))
    )
    prob.warm = warm_start
    prob.prior_sigma = bounding.copy()
    prob.within = within
    if states is not None:
        if states.shape != (len(m), model.n_unknowns):
            raise ValueError(
                f"states: expected shape {(len(m), model.n_unknowns)} for the "
                f"{model.name} model, got {states.shape}"
            )
        prob.states = np.array(states, float)
    restarted = False
    for name, (centre, width) in (anchor or {}).items():
        j, spec = names.index(name), FREE_PARAMETERS[name]
        prob.prior_centre[j] = spec.fit_unit(centre, nominal[name])
        prob.prior_width[j] = width / spec.unit_size(centre)
    lo, hi = prob.bounds()
    u0 = np.array([FREE_PARAMETERS[n].fit_unit(start[n], nominal[n]) for n in names])
    # Start strictly inside the bounds: a parameter whose nominal value is a bound (no
    # friction, no tip mass) would otherwise start where its derivative is one-sided.
    inset = np.minimum(0.05 * np.array([FREE_PARAMETERS[n].prior for n in names]), 0.01 * (hi - lo))
    u0 = np.clip(u0, lo + inset, hi - inset)
    if prob.n_data() < len(names):
        raise ValueError(
            f"{prob.n_data()} measured coordinates cannot determine {len(names)} parameters"
        )
    dof = max(prob.n_data() - len(names), 1)
    fit_rows = np.flatnonzero(prob.fit)
    if min_solved > 0:
        solved = prob.evaluate(u0)[2].equilibria.converged[fit_rows]
        if solved.mean() < min_solved:
            raise UnsolvedStart(
                f"the {model.name} model has no equilibrium for {solved.size - solved.sum()} "
                f"of {solved.size} configurations at the start"
            )
    # With priors, the weight of the data against them needs the noise: when the data do
    # not give it, estimate it from a first fit's residuals and fit again.
    noise_known = sigma is not None or bool(np.isfinite(m.sigma[fit_rows]).all())
    passes = 2 if np.isfinite(widths).any() and not noise_known else 1
    u_start = u0.copy()

    def solve(u_from: np.ndarray) -> OptimizeResult:
        return least_squares(
            prob.residuals,
            u_from,
            jac=prob.jacobian,
            bounds=(lo, hi),
            method="trf",
            x_scale=1.0,
            max_nfev=max_nfev or 50 * (len(names) + 1),
        )

    rescaled = 1.0  # the factor on the rows' sigmas of the fit's last pass
    for attempt in range(passes):
        sol = solve(u0)
        u0 = sol.x
        if attempt + 1 < passes:
            r = prob.residuals(sol.x)[: prob.n_data()]
            scale = math.sqrt(float(r @ r) / dof)
            if 1 / NOISE_AGREES < scale < NOISE_AGREES:
                break  # the assumed noise was the data's: the weights stand
            prob.sigma = prob.sigma * scale
            rescaled *= scale
            prob.invalidate()
    u = sol.x
    tolerance = WARM_TOLERANCE * float(np.min(prob.sigma[fit_rows]))
    second_start = False
    for retry in range(WARM_RETRIES + 1):
        other = prob.settle(u, tolerance) if prob.warm else np.zeros(len(m), bool)
        if not other.any():
            break
        # The warm starts followed other states than the ramp's (e.g. a state that
        # persists at full load where the ramp from rest is pulled into the magnet): the
        # fit again from its start, those rows by the ramp (at last every row).
        warm_u, warm_cost = u, 2 * float(sol.cost)
        prob.ramp_only |= other
        prob.warm = retry < WARM_RETRIES
        prob.invalidate()
        sol = solve(u_start)
        u = sol.x
        restarted = True
        # From a start on a symmetric bifurcation (an off-axis offset the fit frees at
        # zero) every step of the restart may tip rows to the other side: it then stays
        # far above the warm answer. The warm answer with some of its parameters back at
        # the start may lie where the ramp reaches the data's states: fit from the best
        # such point too and keep the better.
        kept = prob.ramp_cost(u)
        if kept - warm_cost > len(names) * warm_cost / dof:
            states = None if prob.states is None else prob.states.copy()
            best = prob.best_cost
            mixes = _mixes(warm_u, u_start)
            costs = [prob.ramp_cost(v) for v in mixes]
            if min(costs) < kept:
                prob.invalidate()
                other_sol = solve(mixes[int(np.argmin(costs))])
                if prob.ramp_cost(other_sol.x) < kept:
                    sol, u, second_start = other_sol, other_sol.x, True
                else:
                    prob.invalidate()
                    prob.states, prob.best_cost = states, best
    out, _, pred = prob.evaluate(u, cold=True)
    p = prob.params(u)
    r_data = prob.residuals(u)[: prob.n_data()]
    chi2 = float(r_data @ r_data)
    s2 = chi2 / dof
    jac = prob.jacobian(u)
    # the posterior's (with the priors' rows), and the data's alone (what they separate)
    sd_u, corr, _, rank = _covariance(jac, s2)
    data_sd_u, data_corr, data_undetermined, data_rank = _covariance(jac[: prob.n_data()], s2)
    message = str(sol.message).rstrip(".")
    if restarted:
        message += (
            f"; fitted again from the start with {int(prob.ramp_only.sum())} row(s) by the "
            "load ramp (their warm starts had followed other states)"
        )
    if second_start:
        message += (
            "; better from the first answer with some parameters back at the start "
            "(the start lies where the ramp tips those rows to other states)"
        )
    if data_rank < len(names):
        loose = ", ".join(n for n, u in zip(names, data_undetermined, strict=True) if u)
        message += (
            f"; the data determine only {data_rank} of {len(names)} parameter combinations "
            f"({loose} trade off against each other: free fewer"
            + (", or use priors)" if rank < len(names) else "; the priors fix them)")
        )
    dpdu = prob.dp_du(u)
    at_bounds = tuple(
        n
        for n, ui, a, b in zip(names, u, lo, hi, strict=True)
        if min(ui - a, b - ui) < 1e-6 * max(1.0, abs(ui))
    )
    position = out[:, :3]
    residuals = np.where(m.measured, m.position - position, np.nan)
    errors = position_errors(position, m)
    fitted = prob.fit
    unconverged = int(np.count_nonzero(fitted & ~pred.equilibria.converged))
    e = errors[fitted]
    e = e[np.isfinite(e)]
    common = np.median(prob.sigma[fitted]) if fitted.any() else DEFAULT_SIGMA
    return CalibrationResult(
        names=names,
        estimate={n: float(p[index(n)]) for n in names},
        standard_error={n: float(abs(dpdu[j]) * sd_u[j]) for j, n in enumerate(names)},
        nominal=nominal,
        correlation=corr,
        data_standard_error={n: float(abs(dpdu[j]) * data_sd_u[j]) for j, n in enumerate(names)},
        data_correlation=data_corr,
        params=p,
        effects=model.effects,
        residuals=residuals,
        errors=errors,
        rows=fitted,
        rmse_mm=float(np.sqrt(np.mean(e**2)) / MM) if e.size else float("nan"),
        max_abs_mm=float(e.max() / MM) if e.size else float("nan"),
        noise_mm=float(np.sqrt(s2) * common / MM),
        # on the rows' own sigmas (fits from several starts compare it; a second pass
        # weighs the data by the noise it found, which differs from fit to fit)
        chi2=chi2 * rescaled**2,
        dof=dof,
        converged=bool(sol.status > 0 and unconverged == 0),
        at_bounds=at_bounds,
        unconverged=unconverged,
        evaluations=prob.evaluations,
        time_s=time.perf_counter() - t0,
        message=message,
        priors=bool(np.isfinite(widths).any()),
        prior_width={} if priors is False else dict(zip(names, map(float, bounding), strict=True)),
        within=prob.within,
        prior_chi2=float(np.sum(np.where(np.isfinite(widths), u / widths, 0.0) ** 2)),
        states=np.where(pred.equilibria.converged[:, None], pred.equilibria.unknowns, np.nan),
        jacobian=jac[: prob.n_data()],
        jacobian_rows=np.concatenate([np.nonzero(prob.pos_mask)[0], np.nonzero(prob.ang_mask)[0]]),
    )


def _covariance(jac: np.ndarray, s2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The Gauss-Newton covariance (J^T J)^-1 s2 of weighted residuals with Jacobian
    ``jac`` (fit units): the standard errors, the correlation, which parameters lie along
    directions ``jac`` does not determine (eigenvalues of J^T J below 1e-10 of the
    largest: their error infinite, their correlations NaN), and the rank."""
    evals, evecs = np.linalg.eigh(jac.T @ jac)
    determined = evals > 1e-10 * max(evals.max(initial=0.0), 1e-300)
    inv = evecs[:, determined] @ np.diag(1 / evals[determined]) @ evecs[:, determined].T
    cov_u = inv * s2
    sd_u = np.sqrt(np.clip(np.diag(cov_u), 0, None))
    undetermined = (np.abs(evecs[:, ~determined]) > 1e-3).any(axis=1)
    sd_u[undetermined] = np.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov_u / np.outer(sd_u, sd_u)
    corr[undetermined, :] = np.nan
    corr[:, undetermined] = np.nan
    np.fill_diagonal(corr, 1.0)
    return sd_u, corr, undetermined, int(determined.sum())
