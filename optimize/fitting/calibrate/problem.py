"""The least-squares problem of a calibration: residuals and exact Jacobian in fit units,
with the warm starts of :func:`optimize.fitting.calibrate.calibrate` (see its module
docstring). SI units.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from design.equilibrium import Equilibria, drive, solve_equilibria
from design.model import RingPairModel
from design.registry import index
from optimize.fitting.calibrate.policy import FREE_PARAMETERS
from optimize.fitting.calibrate.result import straight_miss
from optimize.fitting.measurements import Measurements
from optimize.fitting.sensitivity import (
    PATH_INDEPENDENT,
    SENSITIVE,
    Prediction,
    applied_commands,
    predict,
    prediction_sensitivities,
)

TIP_ANGLE_SIGMA = np.deg2rad(3.0)
"""One-sigma uncertainty of measured tip angles when they are used. [rad]"""


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


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
        widths: np.ndarray,
        tip_angles: bool,
        nominal_u: np.ndarray,
    ) -> None:
        self.model, self.base, self.names, self.m = model, base, names, m
        self.ordered = ordered
        self.spec = [FREE_PARAMETERS[n] for n in names]
        # Gaussian penalty rows (u - centre) / width, fit units; an infinite width: none.
        self.prior_centre = nominal_u.copy()
        self.prior_width = np.asarray(widths, float).copy()
        self.prior_sigma = self.prior_width.copy()  # the priors' own (anchors change the rows')
        self.within: float | None = None  # bounds at this many prior sigmas, if set
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
            p[self.idx[j]] = spec.physical(u[j], p0)
        return p

    def dp_du(self, u: np.ndarray) -> np.ndarray:
        p = self.params(u)
        return np.array([s.unit_size(p[i]) for i, s in zip(self.idx, self.spec, strict=True)])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = [], []
        for spec, p0 in zip(self.spec, self.p0, strict=True):
            lo.append(spec.fit_unit(max(spec.lower, p0 - spec.span), p0))
            hi.append(spec.fit_unit(min(spec.upper, p0 + spec.span), p0))
        lower, upper = np.array(lo), np.array(hi)
        if self.within is not None:  # the prior-bounded fit: nominal +- within sigmas
            reach = np.where(np.isfinite(self.prior_sigma), self.within * self.prior_sigma, np.inf)
            lower, upper = np.maximum(lower, -reach), np.minimum(upper, reach)
        return lower, upper

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
