"""Calibration: fit the model's uncertain physical parameters to measured tip positions.

Nonlinear least squares (``scipy.optimize.least_squares``, trust region reflective, with
bounds) on the position residuals weighted by their one-sigma uncertainty, with exact
Jacobians from the CasADi model by the implicit function theorem at each equilibrium
(:mod:`optimize.fitting.sensitivity`: dx/dp = -(dr/dx)^-1 dr/dp, through ``model.pose`` to the
tip, and through the friction play for ``hysteresis``).

Parameters are fitted in well-scaled units: scale factors, moduli and remanences by
their logarithm (relative change), lengths in millimetres, angles in degrees, masses in
grams (:data:`FREE_PARAMETERS`). Standard errors come from the Gauss-Newton covariance
(J^T J)^-1 s^2 with s^2 = chi^2 / (rows - parameters), mapped to SI by the delta method.
Optional priors (``priors=True``) add one Gaussian penalty row per parameter, centred on
the nominal design, with the widths of :data:`FREE_PARAMETERS`.

Warm starts: the state of each configuration is the load ramp's
(:func:`design.equilibrium.solve_equilibria`, or the driven path's), but between two
evaluations of a fit the parameters change little, so each evaluation after the first
takes every row's state at the fit's current iterate (the lowest cost so far, never a
rejected trial step's) and solves once by Newton at the new parameters, with the
checks of :func:`design.equilibrium.drive` (contraction, the stable side of the folds,
clear of the magnet); rows that fail go through the ramp. A state the ramp reached by a
fall (``snapped``) is warm-started too: near a fold the ramp may fall elsewhere at the
new parameters, which the check of the answer below finds (solving such rows by the
ramp at every evaluation cost a third of the time of fits of the large-deflection rod,
for the same answers). Fits along a driven path are not warm-started (a
row's state there depends on where the path snapped: tried, such fits went elsewhere
often enough to cost more than they saved). The fit's answer is then solved by the
ramp itself, and where any fitted row's tip differs
from the warm-started one by more than WARM_TOLERANCE of its sigma, or has a state in one
and none in the other, the fit is made again from its start with those rows by the ramp
(WARM_RETRIES times, then every row by the ramp). Where that start sits on a symmetric
bifurcation (the magnet on the robot's axis, the offsets free at zero), every step of the
fit again may tip those rows to the other side, and it stays far above the first answer;
then it is also fitted from the first answer with one or two of its parameters back at the
start, from the one of these points where the ramp fits best, and the better fit is kept.
The returned result is always the ramp's.

Identifiability, said plainly: without gravity or torsion the baseline's tip pose
depends on the external remanence and the bending rigidity only through their ratio, so
``bending_rigidity_scale`` and ``external_remanence`` cannot both be free without priors
(their correlation is reported as +-1 and the fit says so in ``message``).

The paper's method (an exhaustive grid over a stiffness scale and a field scale) is kept
as :func:`grid_search_two_factors` (:mod:`optimize.fitting.paper_grid`, re-exported here). SI
units are used for all inputs and outputs; the ``*_mm`` figures of the results are
millimetres.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np
from scipy.optimize import OptimizeResult, least_squares

from design.equilibrium import Equilibria, drive, solve_equilibria
from design.geometry import rest_position
from design.model import RingPairModel, model_for
from design.records import Design
from design.registry import PARAMETERS, Fit, file_unit, index
from design.units import MM
from optimize.fitting.measurements import Measurements
from optimize.fitting.paper_grid import (
    PAPER_FIELD_GRID,
    PAPER_STIFFNESS_GRID,
    GridResult,
    grid_search_two_factors,
    two_factor_parameters,
)
from optimize.fitting.sensitivity import (
    PATH_INDEPENDENT,
    SENSITIVE,
    Prediction,
    applied_commands,
    position_errors,
    predict,
    prediction_sensitivities,
    sensitivities,
    sensitivity_function,
)
from optimize.fitting.workers import parallel_map

__all__ = [
    "BASELINE_FREE",
    "EFFECT_FREE",
    "EFFECT_SEPARATES",
    "FIELD_RELATIVE",
    "FIELD_TOLERANCE",
    "FREE_PARAMETERS",
    "NESTED_START",
    "SOFT_START",
    "PAPER_FIELD_GRID",
    "PAPER_STIFFNESS_GRID",
    "SENSITIVE",
    "CalibrationResult",
    "UnsolvedStart",
    "CrossValidation",
    "FreeParameter",
    "GridResult",
    "Prediction",
    "calibrate",
    "calibrate_from_starts",
    "stiff_start",
    "configuration_folds",
    "cross_validate",
    "default_free",
    "path_matters",
    "grid_search_two_factors",
    "position_errors",
    "predict",
    "prediction_sensitivities",
    "row_sigma",
    "straight_miss",
    "sensitivities",
    "sensitivity_function",
    "two_factor_parameters",
]

DEFAULT_SIGMA = 1e-3
"""Weight of rows without a sigma when the data give none (the common noise is then
estimated from the residuals). [m]"""
WARM_RETRIES = 1
"""Fits made again from the start with warm starts, the rows whose warm start went
elsewhere by the ramp, before one with every row by the ramp."""
WARM_TOLERANCE = 1e-3
"""The warm-started states of a fit's answer are the ramp's where every fitted row's tip
lies within this fraction of its sigma of the ramp's (else the fit goes on with the
ramp's). [-]"""
TIP_ANGLE_SIGMA = np.deg2rad(3.0)
"""One-sigma uncertainty of measured tip angles when they are used. [rad]"""


@dataclass(frozen=True)
class FreeParameter(Fit):
    """How one model parameter is fitted: its :class:`design.registry.Fit`, its name and
    the unit shown in reports (label, factor from SI)."""

    name: str = ""
    label: tuple[str, float] = ("", 1.0)


def _free_parameter(name: str) -> FreeParameter:
    """How ``name`` is fitted, from the registry."""
    fit = PARAMETERS[name].fit
    assert fit is not None
    label, size = file_unit(name)
    shown = ("", 1.0) if PARAMETERS[name].unit == "-" else (label, 1 / size)
    return FreeParameter(**asdict(fit), name=name, label=shown)


FREE_PARAMETERS: dict[str, FreeParameter] = {n: _free_parameter(n) for n in SENSITIVE}
"""The parameters calibration can free, with their fit units, bounds and prior widths."""

BASELINE_FREE = (
    "bending_rigidity_scale",
    "external_center_x",
    "external_center_y",
    "external_center_z",
)
"""Default free parameters of the baseline: the rod's compliance (which the paper's
"compound" modulus could not pin down) and where the external magnet really is.
``external_remanence`` is left out: it is not separable from the bending rigidity
without gravity or torsion (see the module docstring)."""
EFFECT_FREE: dict[str, tuple[str, ...]] = {
    "torsion": ("wire_torsion_scale", "catheter_torsion_scale"),
    "hysteresis": ("wire_friction_angle", "catheter_friction_angle"),
    "gravity": ("tip_mass",),
    "near_field": (),
    "large_deflection": (),
}
"""Each effect's own parameters, freed with it by default."""
EFFECT_SEPARATES: dict[str, tuple[str, ...]] = {"gravity": ("external_remanence",)}
"""Parameters that are not an effect's own but that the effect makes separable: under
gravity the rod's own weight (a known load) fixes the scale of its compliance, so the
strength of the field (external remanence, which also absorbs the tip magnets'
remanence as built) is no longer bound to the bending rigidity. Not freed by default
(with torsion too the extra freedom slows the search and can lead it astray); the
diagnosis frees them in a refit once the effect is accepted (its ``_refine``)."""
FIELD_RELATIVE = (
    "bending_rigidity_scale",
    "wire_torsion_scale",
    "catheter_torsion_scale",
    "tip_mass",
)
"""Parameters the data fix only relative to the field's strength while the remanences are
not free: every magnetic torque goes with the rings' remanence times the external
magnet's (the rings' mutual torque with the rings' remanence squared), so scaling both
remanences by sqrt(s) and these by s leaves every tip where it was (exactly without
gravity: the rod's own weight does not scale; tests/design/test_state_properties.py).
A robot whose magnets are 5 % stronger than the design file says is fitted 5 % stiffer."""
NESTED_START = {"wire_torsion_scale": 10.0, "catheter_torsion_scale": 10.0}
"""A fit of torsion is also started where it all but reduces to the model without it
(transmissions 10 times stiffer than nominal, nearly rigid, the baseline's assumption; the
nominal value can lie beyond a snap-through of the rings from the data's branch, where
a local fit cannot come back from; :func:`calibrate_from_starts`, the diagnosis' screens)."""
SOFT_START = {"wire_torsion_scale": 0.5, "catheter_torsion_scale": 0.5}
"""... and on the other side of nominal (transmissions twice as compliant): driven along a
path, soft transmissions let the rings lag and snap where stiffer ones do not, a basin of
its own that fits from nominal or stiffer starts do not reach (seed [5, 13, 0], gravity
and torsion planted, wire 0.41 x nominal GJ: from nominal and stiffer starts the misfit
stayed 11 times the noise's, and friction play was named to absorb the rest; from the
nominal design with these it is the noise's)."""
FIELD_TOLERANCE = math.hypot(
    *(PARAMETERS[n].tolerance[1] for n in ("magnet_remanence", "external_remanence"))  # type: ignore[index]
)
"""Relative one-sigma uncertainty of the field's strength: the two remanences' tolerances
(design.registry) in quadrature. [-]"""


def default_free(effects: Iterable[str] = ()) -> tuple[str, ...]:
    """The baseline's free parameters plus each effect's own (in EFFECT_FREE order)."""
    effects = set(effects)
    extra = [n for e, names in EFFECT_FREE.items() if e in effects for n in names]
    return (*BASELINE_FREE, *extra)


def _check_free(free: Sequence[str]) -> tuple[str, ...]:
    free = tuple(free)
    for name in free:
        if name not in FREE_PARAMETERS:
            raise ValueError(
                f"parameter {name!r} cannot be calibrated; expected names from "
                f"{', '.join(FREE_PARAMETERS)}"
            )
    if len(set(free)) != len(free):
        raise ValueError(f"free parameters must be distinct; got {list(free)}")
    if not free:
        raise ValueError("at least one free parameter is needed")
    return free


# ------------------------------------------------------------------------ calibration


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


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


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
    states: np.ndarray | None = field(default=None, repr=False)
    jacobian: np.ndarray | None = field(default=None, repr=False)
    jacobian_rows: np.ndarray | None = field(default=None, repr=False)

    def table(self) -> list[dict[str, object]]:
        """One row per parameter in report units: name, unit, nominal, estimate, standard
        error, relative change."""
        rows = []
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
                }
            )
        return rows


def straight_miss(params: np.ndarray, m: Measurements) -> np.ndarray:
    """What a row without an equilibrium costs: the straight, unloaded robot's tip (at
    ``params``' free length) minus each measured position, shape (N, 3), zero where not
    measured. The fit's objective and the diagnosis' misfit use it alike. [m]"""
    rest = rest_position(params[index("free_length")])
    return np.where(m.measured, rest - m.position, 0.0)


class _Problem:
    """Residuals and Jacobian in fit units u, with the last solve cached (least_squares
    asks for the Jacobian at the point whose residuals it has just computed)."""

    def __init__(
        self,
        model: RingPairModel,
        base: np.ndarray,
        names: tuple[str, ...],
        m: Measurements,
        rows: np.ndarray,
        sigma: np.ndarray,
        ordered: bool | Literal["driven"] | None,
        priors: bool,
        tip_angles: bool,
        nominal_u: np.ndarray,
    ) -> None:
        self.model, self.base, self.names, self.m = model, base, names, m
        self.ordered = ordered
        self.spec = [FREE_PARAMETERS[n] for n in names]
        # Gaussian penalty rows (u - centre) / width, fit units; an infinite width: none.
        self.prior_centre = nominal_u.copy()
        self.prior_width = np.array([s.prior if priors else np.inf for s in self.spec])
        self.p0 = np.array([base[index(n)] for n in names])
        self.cols = [SENSITIVE.index(n) for n in names]
        self.idx = [index(n) for n in names]
        fit = np.zeros(len(m), bool)
        fit[rows] = True
        self.fit = fit & m.seen  # rows not seen only carry the path
        self.pos_mask = m.measured & fit[:, None]
        self.ang_mask = (
            np.isfinite(m.tip_angles) & fit[:, None] if tip_angles else np.zeros((len(m), 2), bool)
        )
        self.sigma = sigma
        # A row without an equilibrium costs what the straight robot would (a plateau the
        # trust region steps back from).
        self.fail_offset = straight_miss(base, m)
        self.evaluations = 0
        self._key: bytes | None = None
        self._cache: tuple[np.ndarray, np.ndarray, Prediction] | None = None
        # Warm starts (module docstring): each row's state at the best point so far, and
        # whether the cached solve came from them (then the fit's answer is checked with
        # the ramp, :meth:`settle`).
        self.warm = True
        self.states: np.ndarray | None = None
        self.best_cost = np.inf
        self.ramp_only = np.zeros(len(m), bool)  # rows whose warm start went elsewhere
        self._warm_cached = False
        # The ramp's solve at the point :meth:`ramp_cost` saw last (settle reuses it).
        self._ramp: tuple[bytes, tuple[np.ndarray, np.ndarray, Prediction]] | None = None
        self.warm_solves = 0
        # predict solves rows on their own (the ramp) unless it follows the path
        ordered = "hysteresis" in model.effects if ordered is None else ordered
        self.on_their_own = not ordered or (
            model.effects <= PATH_INDEPENDENT and ordered != "driven"
        )

    def invalidate(self) -> None:
        """Forget the cached solve and the best cost (after a change of weights, or
        before a fit starts again)."""
        self._key, self._cache = None, None
        self.best_cost = np.inf

    def params(self, u: np.ndarray) -> np.ndarray:
        p = self.base.copy()
        for j, (spec, p0) in enumerate(zip(self.spec, self.p0, strict=True)):
            p[self.idx[j]] = p0 * np.exp(u[j]) if spec.kind == "log" else p0 + spec.step * u[j]
        return p

    def dp_du(self, u: np.ndarray) -> np.ndarray:
        p = self.params(u)
        return np.array(
            [p[i] if s.kind == "log" else s.step for i, s in zip(self.idx, self.spec, strict=True)]
        )

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = [], []
        for spec, p0 in zip(self.spec, self.p0, strict=True):
            if spec.kind == "log":
                lo.append(np.log(spec.lower / p0))
                hi.append(np.log(spec.upper / p0))
            else:
                lo.append(max(spec.lower - p0, -spec.span) / spec.step)
                hi.append(min(spec.upper - p0, spec.span) / spec.step)
        return np.array(lo), np.array(hi)

    def evaluate(
        self, u: np.ndarray, cold: bool = False
    ) -> tuple[np.ndarray, np.ndarray, Prediction]:
        """Tip poses, their derivatives and the prediction at u (cached); ``cold``: by
        :func:`predict` itself, never from the last states."""
        key = np.asarray(u, float).tobytes()
        cold = cold or not self.warm
        if key != self._key or self._cache is None or (cold and self._warm_cached):
            p = self.params(u)
            pred = None
            if self.warm and not cold and self.states is not None:
                pred = self._warm_prediction(p)
            self._warm_cached = pred is not None
            if pred is None:
                solved = self._ramp_solve(u)
            else:
                solved = (*prediction_sensitivities(self.model, p, pred), pred)
                self.evaluations += 1
            self._key, self._cache = key, solved
        return self._cache

    def _warm_prediction(self, p: np.ndarray) -> Prediction | None:
        """The prediction at ``p`` from each row's last state: one Newton solve each with
        the checks of :func:`design.equilibrium.drive` (contraction, stable side of the
        folds, clear of the magnet). Rows solved on their own whose solve fails, that have
        no last state, or whose warm start went elsewhere before (``ramp_only``), go
        through the load ramp. None along a path (where a row's state depends on the rows
        before it and on where the path snapped): the path is followed again by
        :func:`predict`."""
        assert self.states is not None
        if not self.on_their_own:
            return None
        applied, d_applied = applied_commands(self.model, p, self.m, self.ordered)
        n, k = self.states.shape
        known = np.isfinite(self.states).all(axis=1) & ~self.ramp_only
        x = np.full((k, n), np.nan)
        ok = np.zeros(n, bool)
        cols = np.flatnonzero(known)
        if cols.size:
            c = applied[cols].T
            x[:, cols], ok[cols] = drive(self.model, p, self.states[cols].T, c, c)
            self.warm_solves += 1
        nan3 = np.full((n, 3), np.nan)
        eq = Equilibria(
            command=self.m.command.copy(),
            tip_angles=np.full((n, 2), np.nan),
            position=nan3.copy(),
            tangent=nan3.copy(),
            frame=np.full((n, 3, 3), np.nan),
            unknowns=x.T.copy(),
            converged=ok.copy(),
            stable=ok.copy(),
            residual=np.where(ok, 0.0, np.nan),
            snapped=np.zeros(n, bool),
            multistable=np.zeros(n, bool),
            failure=np.full(n, "", dtype=object),
        )
        ramp = np.flatnonzero(~ok)
        if ramp.size:
            cold = solve_equilibria(self.model, p, applied[ramp, 0], applied[ramp, 1])
            for name, value in cold.__dict__.items():
                if name != "command":
                    getattr(eq, name)[ramp] = value
        return Prediction(eq, applied, d_applied)

    def settle(self, u: np.ndarray, tolerance: float) -> np.ndarray:
        """The fitted rows (shape (N,) bool) whose warm-started state at u is not the
        load ramp's (the one definition of the state, :func:`predict`): a state in one and
        none in the other, or tips more than ``tolerance`` [m] apart; none if the cached
        solve already is the ramp's. The ramp's solve is cached either way."""
        if self._key == np.asarray(u, float).tobytes() and not self._warm_cached:
            return np.zeros(len(self.m), bool)
        warm_out, _, warm_pred = self.evaluate(u)
        out, _, pred = self.evaluate(u, cold=True)
        other = warm_pred.equilibria.converged != pred.equilibria.converged
        with np.errstate(invalid="ignore"):
            other |= np.abs(warm_out[:, :3] - out[:, :3]).max(axis=1) > tolerance
        return other & self.fit

    def residuals(self, u: np.ndarray) -> np.ndarray:
        r = self._residual_vector(u, self.evaluate(u)[0])
        self._keep_states(float(r @ r))
        return r

    def ramp_cost(self, u: np.ndarray) -> float:
        """The weighted sum of squares at u with every row by :func:`predict` (the one
        definition of the state), outside the cache and the warm starts. [-]"""
        r = self._residual_vector(u, self._ramp_solve(u)[0])
        return float(r @ r)

    def _ramp_solve(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, Prediction]:
        """Tip poses, their derivatives and the prediction at u by :func:`predict`, kept
        for the last u asked (:meth:`ramp_cost`, then :meth:`settle`, see the same u)."""
        key = np.asarray(u, float).tobytes()
        if self._ramp is None or self._ramp[0] != key:
            p = self.params(u)
            pred = predict(self.model, p, self.m, self.ordered)
            self._ramp = key, (*prediction_sensitivities(self.model, p, pred), pred)
            self.evaluations += 1
        return self._ramp[1]

    def _residual_vector(self, u: np.ndarray, out: np.ndarray) -> np.ndarray:
        r_pos = (out[:, :3] - self.m.position) / self.sigma[:, None]
        r_pos = np.where(np.isfinite(r_pos), r_pos, self.fail_offset / self.sigma[:, None])
        r_ang = _wrap(out[:, 3:] - self.m.tip_angles) / TIP_ANGLE_SIGMA
        r_ang = np.where(np.isfinite(r_ang), r_ang, 0.0)
        parts = [r_pos[self.pos_mask], r_ang[self.ang_mask]]
        rows = np.isfinite(self.prior_width)
        parts.append((u[rows] - self.prior_centre[rows]) / self.prior_width[rows])
        return np.concatenate(parts)

    def _keep_states(self, cost: float) -> None:
        """Keep the cached solve's states as the warm starts if its cost is the lowest so
        far: the trust region accepts a step only when it lowers the cost, so these are the
        states of its current iterate. A rejected trial step may have crossed a fold, and
        starting the next, shorter step from its states would follow that other state."""
        if cost >= self.best_cost or self._cache is None:
            return
        self.best_cost = cost
        eq = self._cache[2].equilibria
        if self.states is None:
            self.states = eq.unknowns.copy()
        else:
            self.states[eq.converged] = eq.unknowns[eq.converged]

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        _, d_out, _ = self.evaluate(u)
        d = d_out[:, :, self.cols] * self.dp_du(u)[None, None, :]
        d = np.where(np.isfinite(d), d, 0.0)
        j_pos = d[:, :3, :] / self.sigma[:, None, None]
        j_ang = d[:, 3:, :] / TIP_ANGLE_SIGMA
        parts = [j_pos[self.pos_mask], j_ang[self.ang_mask]]
        rows = np.isfinite(self.prior_width)
        parts.append(np.diag(1 / self.prior_width)[rows])
        return np.vstack(parts)

    def n_data(self) -> int:
        return int(self.pos_mask.sum() + self.ang_mask.sum())


def calibrate(
    design: Design,
    m: Measurements,
    effects: Iterable[str] = (),
    free: Sequence[str] | None = None,
    *,
    rows: np.ndarray | Sequence[int] | None = None,
    fixed: Mapping[str, float] | None = None,
    initial: Mapping[str, float] | None = None,
    priors: bool = False,
    sigma: float | None = None,
    ordered: bool | Literal["driven"] | None = None,
    tip_angles: bool = True,
    max_nfev: int | None = None,
    min_solved: float = 0.0,
    anchor: Mapping[str, tuple[float, float]] | None = None,
    warm_start: bool = True,
    states: np.ndarray | None = None,
) -> CalibrationResult:
    """Fit the free parameters of the model with ``effects`` to the measurements ``m``.

    free : names from :data:`FREE_PARAMETERS`; default :func:`default_free` (effects).
    rows : the rows to fit (indices or mask); default all. The others are still simulated
        (along the path when ordered) and get residuals, for cross-validation.
    fixed : values of other model parameters (names of ``design.registry.NAMES``) that
        differ from the design, e.g. an earlier fit's. [SI]
    initial : starting values of free parameters; default the nominal design's. [SI]
    priors : add a Gaussian penalty row per free parameter, centred on the nominal design,
        with the width of :data:`FREE_PARAMETERS`.
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
    prob = _Problem(
        model, base, names, m, fit_rows, s_rows, ordered, priors, tip_angles, np.zeros(len(names))
    )
    prob.warm = warm_start
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
        log = spec.kind == "log"
        prob.prior_centre[j] = (
            np.log(centre / nominal[name]) if log else (centre - nominal[name]) / spec.step
        )
        prob.prior_width[j] = width / centre if log else width / spec.step
    lo, hi = prob.bounds()
    u0 = np.array(
        [
            np.log(start[n] / nominal[n])
            if FREE_PARAMETERS[n].kind == "log"
            else (start[n] - nominal[n]) / FREE_PARAMETERS[n].step
            for n in names
        ]
    )
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
    passes = 2 if priors and not noise_known else 1
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

    for attempt in range(passes):
        sol = solve(u0)
        u0 = sol.x
        if attempt + 1 < passes:
            r = prob.residuals(sol.x)[: prob.n_data()]
            prob.sigma = prob.sigma * np.sqrt(float(r @ r) / dof)
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
    jtj = jac.T @ jac
    # Gauss-Newton covariance; along directions the data do not determine (eigenvalues of
    # J^T J below 1e-10 of the largest) the parameters involved get an infinite error.
    evals, evecs = np.linalg.eigh(jtj)
    determined = evals > 1e-10 * max(evals.max(), 1e-300)
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
    rank = int(determined.sum())
    if rank < len(names):
        loose = ", ".join(n for n, u in zip(names, undetermined, strict=True) if u)
        message += (
            f"; the data determine only {rank} of {len(names)} parameter combinations "
            f"({loose} trade off against each other: free fewer, or use priors)"
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
        params=p,
        effects=model.effects,
        residuals=residuals,
        errors=errors,
        rows=fitted,
        rmse_mm=float(np.sqrt(np.mean(e**2)) / MM) if e.size else float("nan"),
        max_abs_mm=float(e.max() / MM) if e.size else float("nan"),
        noise_mm=float(np.sqrt(s2) * common / MM),
        chi2=chi2,
        dof=dof,
        converged=bool(sol.status > 0 and unconverged == 0),
        at_bounds=at_bounds,
        unconverged=unconverged,
        evaluations=prob.evaluations,
        time_s=time.perf_counter() - t0,
        message=message,
        priors=priors,
        states=np.where(pred.equilibria.converged[:, None], pred.equilibria.unknowns, np.nan),
        jacobian=jac[: prob.n_data()],
        jacobian_rows=np.concatenate([np.nonzero(prob.pos_mask)[0], np.nonzero(prob.ang_mask)[0]]),
    )


def path_matters(
    model: RingPairModel,
    params: np.ndarray,
    m: Measurements,
    ordered: bool | Literal["driven"] | None = None,
) -> bool:
    """Whether driving the bench's path (the data's ``sequence``) ends in other states
    than solving ``m`` as ``ordered`` (:func:`predict`) at ``params``. Twisting
    transmissions, or a strong magnet near the tip, can make the robot multistable; then
    its state depends on the path driven, and the fast solve (each configuration on its
    own, or the played commands in one batch) is exact only where the two agree. False
    without a sequence."""
    if m.sequence is None:
        return False
    fast = predict(model, params, m, ordered=ordered).equilibria.position
    driven = predict(model, params, m, ordered="driven").equilibria.position
    same_solved = np.array_equal(np.isnan(fast), np.isnan(driven))
    return not (same_solved and np.nanmax(np.abs(fast - driven), initial=0.0) < 1e-6)


def stiff_start(
    design: Design,
    m: Measurements,
    effects: Iterable[str],
    free: Sequence[str],
    initial: Mapping[str, float] | None = None,
    **options: Any,
) -> dict[str, float] | None:
    """Where a fit of ``effects`` with ``free`` torsion scales also starts: the other free
    parameters fitted (from ``initial``, ``options`` of :func:`calibrate`) with the
    transmissions held nearly rigid (NESTED_START, the baseline's assumption), and the
    transmissions there; None where no torsion scale is free."""
    stiff = {n: v for n, v in NESTED_START.items() if n in free}
    if not stiff:
        return None
    others = [n for n in free if n not in stiff]
    held = {n: v for n, v in (initial or {}).items() if n in others}
    if others:
        fit = calibrate(design, m, effects, others, fixed=stiff, initial=held or None, **options)
        held = fit.estimate
    return {**held, **stiff}


def calibrate_from_starts(
    design: Design,
    m: Measurements,
    effects: Iterable[str] = (),
    free: Sequence[str] | None = None,
    **options: Any,
) -> tuple[CalibrationResult, dict[str, CalibrationResult]]:
    """:func:`calibrate` (``options`` are its own) from the nominal design and, where
    torsion scales are free, also from stiff and from soft transmissions: a local fit
    cannot cross a snap-through of the rings, and which side of one the nominal design
    lies on is chance. 'stiff': :func:`stiff_start`; 'soft': the nominal design with
    SOFT_START. Magnet on the robot's axis, torsion data drawn from the design space
    (``optimize.fitting.planted``, 15 sets): from the nominal design alone 5 fits ended at
    1.7-15 times the noise's RMS, from these three starts (and along the path, below) 2 at
    1.7 and 9 times.
    Where the data have a sequence and driving their path ends in other states than the
    fit's solve at the best estimate (:func:`path_matters`), the best is also fitted along
    the path ('along the path'; on-axis torsion set [99, 9], 15 rows: 1.7 -> 0.9x the
    noise's RMS). Returns the best (every fitted row solved, then the least chi-square)
    and the fit from each start by name."""
    names = default_free(effects) if free is None else tuple(free)
    fits = {"nominal": calibrate(design, m, effects, names, **options)}
    stiff = stiff_start(design, m, effects, names, **options)
    if stiff is not None:
        fits["stiff"] = calibrate(design, m, effects, names, initial=stiff, **options)
        soft = {n: SOFT_START[n] for n in NESTED_START if n in names}
        fits["soft"] = calibrate(design, m, effects, names, initial=soft, **options)

    def best_fit() -> CalibrationResult:
        return min(fits.values(), key=lambda f: (f.unconverged > 0, f.chi2))

    ordered = options.get("ordered")
    mode = "hysteresis" in set(effects) if ordered is None else ordered
    if mode != "driven" and path_matters(model_for(frozenset(effects)), best_fit().params, m, mode):
        driven = {**options, "ordered": "driven"}
        fits["along the path"] = calibrate(
            design, m, effects, names, initial=best_fit().estimate, **driven
        )
    return best_fit(), fits


# -------------------------------------------------------------------- cross-validation


@dataclass(frozen=True)
class CrossValidation:
    """K-fold cross-validation over held-out configurations.

    rmse_mm : RMS over all held-out rows of the model-measurement distance. [mm]
    fold_rmse_mm : shape (k,), the same per fold. [mm]
    errors : shape (N,), each row's distance when it was held out; NaN if unsolved. [m]
    folds : shape (N,) int, the fold of each row.
    unconverged : held-out rows the fitted model could not solve.
    expected_ratio : ``rmse_mm`` over the in-sample RMSE that a right model, linear in its
        parameters near the fit of all the data, gives on average with these
        configurations and folds (:func:`held_out_inflation`); NaN without that fit. [-]
    """

    rmse_mm: float
    fold_rmse_mm: np.ndarray
    errors: np.ndarray
    folds: np.ndarray
    unconverged: int
    expected_ratio: float = math.nan


def configuration_folds(m: Measurements, k: int, seed: int | None = 0) -> np.ndarray:
    """Fold number of each row (shape (N,)): rows with the same commanded angles share a
    fold, so a held-out configuration is never seen in training; folds are seeded. Only
    seen configurations are dealt into folds: a configuration driven but never seen
    carries no error to hold out and gets -1 (always in training, where it only keeps
    the path)."""
    seen = np.round(m.command[m.seen], 12)
    configurations = np.unique(seen, axis=0)
    n_groups = len(configurations)
    if not 2 <= k <= n_groups:
        raise ValueError(
            f"k must be between 2 and the number of distinct seen configurations ({n_groups}); "
            f"got {k}"
        )
    perm = np.random.default_rng(seed).permutation(n_groups)
    fold_of_group = np.empty(n_groups, int)
    fold_of_group[perm] = np.arange(n_groups) % k
    commands = np.round(m.command, 12)
    match = (commands[:, None, :] == configurations[None, :, :]).all(axis=2)
    return np.where(match.any(axis=1), fold_of_group[match.argmax(axis=1)], -1)


def held_out_inflation(jacobian: np.ndarray, fold: np.ndarray, position: np.ndarray) -> float:
    """The ratio of the cross-validated to the in-sample RMS position error that a right
    model, linear in its parameters near a fit of all the data, gives on average, for
    equal noise on every coordinate. [-]

    jacobian : shape (n, k), the fit's whitened Jacobian (:attr:`CalibrationResult.jacobian`).
    fold : shape (n,), the fold each residual is held out in.
    position : shape (n,) bool, the residuals that count (the position coordinates).

    With the hat matrix H = J (J^T J)^+ J^T, a held-out block f's prediction error is
    (I - H_ff)^-1 e_f (e the in-sample residuals), whose covariance is s^2 (I - H_ff)^-1;
    the in-sample residuals' is s^2 (I - H). So the expected squared errors are
    s^2 sum_f tr (I - H_ff)^-1 held out and s^2 tr (I - H) in sample. About
    sqrt((1 + p/(0.8 n)) / (1 - p/n)) for p parameters spread over n coordinates held out
    a fifth at a time; far above it where a few configurations alone fix a parameter
    (Hastie, Tibshirani & Friedman, *The Elements of Statistical Learning*, 2nd ed.,
    sec. 7.10: the leave-one-out form e_i / (1 - H_ii)).
    """
    # H from J's own singular vectors, an exact projection to rounding (from (J^T J)^+ it is
    # not where J is ill-conditioned, and I - H_ff of a fold whose configurations alone fix
    # a parameter, singular in theory, then had eigenvalues of either sign around 1e-9: a
    # negative held-out trace, a drawn null set of 16 rows). The same rank as (J^T J)^+ at
    # rcond 1e-10: singular values above 1e-5 of the largest.
    u, sv, _ = np.linalg.svd(np.asarray(jacobian, float), full_matrices=False)
    u = u[:, sv > 1e-5 * sv.max(initial=0.0)] if sv.size else u
    hat = u @ u.T
    held = 0.0
    for f in np.unique(fold[fold >= 0]):
        i = np.flatnonzero(fold == f)
        block = np.linalg.pinv(np.eye(i.size) - hat[np.ix_(i, i)], rcond=1e-12)
        held += float(np.trace(block[np.ix_(position[i], position[i])]))
    fitted = float(np.sum(1.0 - np.diag(hat)[position]))
    return math.sqrt(held / fitted) if fitted > 0 and held >= 0 else math.nan


def _continued(
    model: RingPairModel,
    full: CalibrationResult,
    fold: CalibrationResult,
    m: Measurements,
    held: np.ndarray,
    ordered: bool | Literal["driven"] | None,
) -> np.ndarray:
    """The held-out rows' distances (shape (N,), NaN elsewhere or unsolved) [m] at the
    ``fold``'s parameters, each from the state of the fit ``full`` of all the data, by
    :func:`design.equilibrium.drive` (Newton, contracting, on the stable side of the
    folds): the fold's miss on the state the robot is in."""
    errors = np.full(len(m), np.nan)
    assert full.states is not None
    cols = np.flatnonzero(held & np.isfinite(full.states).all(axis=1))
    if cols.size == 0:
        return errors
    start = applied_commands(model, full.params, m, ordered)[0][cols]
    end = applied_commands(model, fold.params, m, ordered)[0][cols]
    x, ok = drive(model, fold.params, full.states[cols].T, start.T, end.T)
    if ok.any():
        out, _ = sensitivities(model, fold.params, x.T[ok], end[ok])
        position = np.full((len(m), 3), np.nan)
        position[cols[ok]] = out[:, :3]
        errors[cols[ok]] = position_errors(position, m)[cols[ok]]
    return errors


def cross_validate(
    design: Design,
    m: Measurements,
    effects: Iterable[str] = (),
    free: Sequence[str] | None = None,
    *,
    k: int = 5,
    seed: int | None = 0,
    full: CalibrationResult | None = None,
    **options: object,
) -> CrossValidation:
    """K-fold cross-validated position error of :func:`calibrate` (same ``options``):
    fit on k-1 folds of configurations, predict the held-out fold.

    full : the fit of all the data. A held-out row with a state there is predicted from
        that state at the fold's parameters (:func:`_continued`); the fold's own solve
        (load ramp or path) only where that fails. Near a fold of the equilibria, a
        fold's parameters a little off the full fit's can make the ramp fall to another
        state; its error would then measure that jump, not how well the fold's
        parameters predict the robot in the state it is in. Its states also warm-start
        each fold's first evaluation (a fold starts at its estimate, options' ``initial``),
        which otherwise costs a load ramp of every row.
    """
    folds = configuration_folds(m, k, seed)
    model = model_for(frozenset(effects))
    ordered = options.get("ordered")

    def fold(f: int) -> np.ndarray:
        held = folds == f
        warm = None if full is None else full.states
        res = calibrate(design, m, effects, free, rows=~held, states=warm, **options)  # type: ignore[arg-type]
        errors = np.where(held, res.errors, np.nan)
        if full is not None and full.states is not None:
            continued = _continued(model, full, res, m, held, ordered)  # type: ignore[arg-type]
            errors = np.where(np.isfinite(continued), continued, errors)
        return errors

    per_fold = parallel_map(fold, range(k))
    errors = np.full(len(m), np.nan)
    fold_rmse = np.full(k, np.nan)
    for f, e_f in enumerate(per_fold):
        held = folds == f
        errors[held] = e_f[held]
        e = e_f[held]
        e = e[np.isfinite(e)]
        fold_rmse[f] = np.sqrt(np.mean(e**2)) / MM if e.size else np.nan
    ok = np.isfinite(errors)  # (rows not seen have no error)
    expected = math.nan
    if full is not None and full.jacobian is not None and full.jacobian_rows is not None:
        rows = full.jacobian_rows
        position = np.arange(rows.size) < int(m.measured[full.rows].sum())
        expected = held_out_inflation(full.jacobian, folds[rows], position)
    return CrossValidation(
        rmse_mm=float(np.sqrt(np.mean(errors[ok] ** 2)) / MM) if ok.any() else float("nan"),
        fold_rmse_mm=fold_rmse,
        errors=errors,
        folds=folds,
        unconverged=int(np.count_nonzero(m.seen & ~ok)),
        expected_ratio=expected,
    )
