"""The load ramp: each configuration followed from the unloaded robot to full load."""

from __future__ import annotations

import numpy as np

from design.equilibrium import settings
from design.equilibrium.fall import _fall
from design.equilibrium.kernels import _initial, kernels
from design.equilibrium.newton import _Checks, _judge
from design.equilibrium.stability import _columns, _norm, _scale
from design.model import RingPairModel

_RUN, _DONE, _FOLD, _FAIL = range(4)


def _near(predicted: np.ndarray) -> np.ndarray:
    """How far a ramp step's first correction may go for a predicted change of state
    ``predicted`` (dimensionless): CORRECTION_RATIO of it, or MIN_CORRECTION."""
    return np.maximum(settings.CORRECTION_RATIO * predicted, settings.MIN_CORRECTION)


def _leap(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    count: int,
    checks: _Checks,
    where: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ramp in ``count`` equal steps, from the compiled ``leap<count>``
    (:meth:`_Kernels._leap`): (the tangent at rest (n, N), which columns it takes to full
    load, their states). The checks of the columns taken are put in ``checks`` at
    ``where``; other columns are left to the ramp's adaptive steps."""
    outs = kernels(model).run(f"leap{count}", [command], params)
    tangent, taken, x, checked = outs[0], outs[1][0] > 0.5, outs[2], outs[3:]
    idx = np.flatnonzero(taken)
    checks.put(where[idx], [o[:, idx] for o in checked])
    return tangent, idx, x[:, idx]


class _Ramp:
    """The load ramp of N columns (configurations) from the unloaded robot (lambda = 0) to
    full load (lambda = 1) (:mod:`design.equilibrium`), its state per column in named
    fields; :meth:`run` follows every column to the end.

    Predictor: the state's tangent dx/dlambda = -(dr/dx)^-1 dr/dlambda (from the solver's
    last evaluation), with the curvature of the branch from the change of the tangent
    since the step before (a second-order predictor); from rest the tangent alone.

    x : (n, N), the state on the branch at ``lam``. [SI]
    lam : (N,), its load factor; ``lam_prev`` the one of the step before (-1: none, no
        curvature for the predictor). [-]
    h : (N,), the next step in lambda; ``target`` the load factor the current step aims at.
    xs : (n, N), the corrector's iterate of the current step. [SI]
    tangent, tangent_prev : (n, N), dx/dlambda at ``x`` and at the state before;
        ``tangent_xs`` at the iterate.
    corrections : (N,), Newton corrections made in the current step; ``last`` the size of
        the last (dimensionless), ``contraction`` the first contraction, ``predicted`` the
        predictor's change of state (dimensionless).
    phase : (N,), running, done, at a fold (to fall) or failed; ``falls`` the falls so
        far; ``refused`` the current step was refused before; ``failure`` why a column
        failed ('' otherwise).
    """

    def __init__(
        self,
        model: RingPairModel,
        params: np.ndarray,
        command: np.ndarray,
        checks: _Checks,
        max_step: float,
    ) -> None:
        self.model, self.params, self.command = model, params, command
        self.checks, self.max_step = checks, max_step
        self.kern = kernels(model)
        n_cols = command.shape[1]
        self.x = _initial(model, params, command)
        self.scale = _scale(model, params, n_cols)
        self.lam = np.zeros(n_cols)
        self.lam_prev = np.full(n_cols, -1.0)
        self.h = np.full(n_cols, max_step)
        self.target = np.zeros(n_cols)
        self.xs = self.x.copy()
        self.corrections = np.zeros(n_cols, int)
        self.last = np.full(n_cols, np.inf)
        self.contraction = np.zeros(n_cols)
        self.predicted = np.zeros(n_cols)
        self.phase = np.full(n_cols, _RUN)
        self.falls = np.zeros(n_cols, int)
        self.refused = np.zeros(n_cols, bool)
        self.failure = np.full(n_cols, "", dtype=object)
        self.tangent = self._start()
        self.tangent_prev = np.zeros_like(self.tangent)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.h[:] = np.clip(
                settings.FIRST_DISPLACEMENT / _norm(self.tangent, self.scale),
                settings.MIN_LOAD_STEP,
                max_step,
            )
        self.h[~np.isfinite(self.h)] = max_step
        self.tangent_xs = np.zeros_like(self.tangent)

    def _start(self) -> np.ndarray:
        """The tangent at rest. The first step is sized so that it predicts a change of
        state of at most FIRST_DISPLACEMENT; where that step is the whole ramp (or two
        such steps), it is taken by ``leap`` and the column is done."""
        model, params, command, x = self.model, self.params, self.command, self.x
        n_cols = command.shape[1]
        if not (self.max_step >= 1.0 and model.linear_rod):
            return -self.kern.run("relaxation", [x, command, np.ones((1, n_cols))], params)[0]
        tangent = np.zeros_like(x)
        left = np.arange(n_cols)
        for count in range(1, settings.LEAP_STEPS + 1):
            if left.size == 0:
                break
            p = _columns(params, left)
            t, idx, states = _leap(model, p, command[:, left], count, self.checks, left)
            if count == 1:
                tangent[:] = t
            x[:, left[idx]], self.lam[left[idx]], self.phase[left[idx]] = states, 1.0, _DONE
            left = np.delete(left, idx)
            reach = (count + 1) * settings.FIRST_DISPLACEMENT
            left = left[_norm(tangent[:, left], self.scale[:, left]) <= reach]
        return tangent

    def predict(self, cols: np.ndarray) -> None:
        """Targets and predictions for the next step of columns ``cols``."""
        if cols.size == 0:  # (most iterations: the loop runs on a few columns)
            return
        lam, x, tangent = self.lam, self.x, self.tangent
        self.target[cols] = np.minimum(lam[cols] + self.h[cols], 1.0)
        step = (self.target[cols] - lam[cols])[None, :]
        self.xs[:, cols] = x[:, cols] + step * tangent[:, cols]
        curved = self.lam_prev[cols] >= 0
        if curved.any():
            c = cols[curved]
            bend = (tangent[:, c] - self.tangent_prev[:, c]) / (lam[c] - self.lam_prev[c])
            self.xs[:, c] += 0.5 * step[:, curved] ** 2 * bend
        self.predicted[cols] = _norm(self.xs[:, cols] - x[:, cols], self.scale[:, cols])
        self.corrections[cols] = 0
        self.last[cols] = np.inf
        self.contraction[cols] = 0.0

    def fall(self, f: np.ndarray) -> None:
        """Columns f end in a fold at lam: they fall, a little further loaded."""
        lam, phase, params, command = self.lam, self.phase, self.params, self.command
        lam_fall = np.minimum(lam[f] + np.maximum(settings.SETTLE_OVERSHOOT, self.h[f]), 1.0)
        fallen, found, contact = _fall(
            self.model, _columns(params, f), command[:, f], self.x[:, f], lam_fall, self.checks, f
        )
        ok, lost = f[found], f[~found]
        phase[lost] = _FAIL
        self.failure[lost] = np.where(
            contact[~found], settings.FAILURES["pulled"], settings.FAILURES["fold"]
        )
        self.x[:, ok] = fallen[:, found]
        lam[ok] = lam_fall[found]
        self.lam_prev[ok] = -1.0
        if ok.size:  # the branch's tangent at the state fallen into: the next predictor
            self.tangent[:, ok] = self.kern.run(
                "newton", [self.x[:, ok], command[:, ok], lam[None, ok]], _columns(params, ok)
            )[2]
        self.falls[ok] += 1
        self.h[ok] = settings.RESTART_STEP
        phase[ok[lam[ok] >= 1.0]] = _DONE
        rest = ok[lam[ok] < 1.0]
        phase[rest] = _RUN
        self.predict(rest)
        too_many = ok[self.falls[ok] > settings.MAX_FALLS]
        phase[too_many] = _FAIL
        self.failure[too_many] = settings.FAILURES["falls"]

    def correct(self, a: np.ndarray) -> None:
        """One Newton correction of the running columns ``a``; each step is then accepted
        (converged, on the stable side of every fold: the next is predicted), refused (the
        corrector left the prediction or does not contract: a shorter step, or a fold),
        or carried on."""
        params, command, xs, target = self.params, self.command, self.xs, self.target
        corrections, last = self.corrections, self.last
        r, step, load_tangent, monitor, clearance = self.kern.run(
            "newton", [xs[:, a], command[:, a], target[None, a]], _columns(params, a)
        )
        self.tangent_xs[:, a] = load_tangent
        rn, sn = np.max(np.abs(r), axis=0), _norm(step, self.scale[:, a])
        tol = np.where(target[a] >= 1.0, settings.TOLERANCE, settings.RAMP_TOLERANCE)
        conv = rn < tol
        small = np.max(np.abs(step), axis=0) < settings.step_tolerance(target[a])
        candidate = conv | small
        moved = np.isfinite(sn)  # every finite step is taken, a candidate's last one too
        xs[:, a[moved]] -= step[:, moved]
        # The corrector must stay near the prediction (its first correction at most
        # CORRECTION_RATIO of the predicted change, or MIN_CORRECTION), and contract.
        near = _near(self.predicted[a])
        contracting = np.where(
            corrections[a] == 0, sn <= near, sn <= settings.CONTRACTION * last[a]
        )
        give_up = ~candidate & (
            ~np.isfinite(sn) | ~contracting | (corrections[a] >= settings.MAX_CORRECTIONS)
        )
        refuse = give_up.copy()
        accept = np.zeros(a.size, bool)
        cand = a[candidate]
        if cand.size:
            converged, good = _judge(
                self.model,
                _columns(params, cand),
                command[:, cand],
                xs[:, cand],
                target[cand],
                monitor[:, candidate],
                clearance[:, candidate],
                self.checks,
                cand,
            )
            accept[candidate] = converged & good
            refuse[candidate] = converged & ~good
            stalled = cand[~converged & (corrections[cand] >= settings.MAX_CORRECTIONS)]
            if stalled.size:
                self.phase[stalled] = _FAIL
                self.failure[stalled] = settings.FAILURES["stalled"]
                accept[np.isin(a, stalled)] = False
        acc = a[accept]
        if acc.size:  # (most iterations accept or refuse nothing: skip their bookkeeping)
            self._accept(acc)
        running = self.phase[a] == _RUN
        refusing = refuse & running
        if refusing.any():
            self._refuse(a[refusing], sn[refusing], near[refusing])
        carry_on = ~accept & ~refuse & running
        go = a[carry_on]
        first = corrections[go] == 1
        self.contraction[go[first]] = sn[carry_on][first] / last[go[first]]
        last[go] = sn[carry_on]
        corrections[go] += 1

    def _accept(self, acc: np.ndarray) -> None:
        """Columns ``acc`` take their step; the next grows or shrinks with the first
        contraction (no growth right after a refusal)."""
        tangent, lam = self.tangent, self.lam
        self.lam_prev[acc] = np.where(tangent[:, acc].any(axis=0), lam[acc], -1.0)
        self.tangent_prev[:, acc] = tangent[:, acc]
        self.x[:, acc], lam[acc] = self.xs[:, acc], self.target[acc]
        tangent[:, acc] = self.tangent_xs[:, acc]
        factor = np.sqrt(settings.TARGET_CONTRACTION / np.maximum(self.contraction[acc], 1e-12))
        growth = np.where(self.refused[acc], 1.0, settings.GROWTH)
        self.h[acc] = np.minimum(
            self.h[acc] * np.clip(factor, 1 / settings.SHRINK, growth), self.max_step
        )
        self.refused[acc] = False
        self.phase[acc[lam[acc] >= 1.0]] = _DONE
        self.predict(acc[lam[acc] < 1.0])

    def _refuse(self, ref: np.ndarray, sn: np.ndarray, near: np.ndarray) -> None:
        """Columns ``ref`` refuse their step (last correction sizes ``sn``, the first
        correction's bound ``near``): a shorter one, or below MIN_LOAD_STEP a fold."""
        self.refused[ref] = True
        last, h = self.last, self.h
        with np.errstate(invalid="ignore", divide="ignore"):
            # Newton's contraction; for a first correction that missed the prediction,
            # how far it missed (the predictor's error grows with the step's square).
            theta = np.where(
                self.corrections[ref] == 0,
                settings.TARGET_CONTRACTION * sn / near,
                np.where(np.isfinite(last[ref]), sn / last[ref], np.inf),
            )
            theta = np.where(np.isfinite(theta), theta, np.inf)
        factor = np.sqrt(settings.TARGET_CONTRACTION / np.maximum(theta, 1e-12))
        h[ref] *= np.clip(factor, 1 / settings.SHRINK, 0.5)
        self.phase[ref[h[ref] < settings.MIN_LOAD_STEP]] = _FOLD
        self.predict(ref[h[ref] >= settings.MIN_LOAD_STEP])

    def run(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Follow every column to its end: (x (n, N), reached full load, snapped, failure
        reasons); the states reached are checked (in ``checks``)."""
        self.predict(np.flatnonzero(self.phase == _RUN))
        while True:
            a = np.flatnonzero(self.phase == _RUN)
            if a.size:
                self.correct(a)
                continue
            f = np.flatnonzero(self.phase == _FOLD)
            if f.size == 0:
                break
            self.fall(f)
        return self.x, self.phase == _DONE, self.falls > 0, self.failure


def _ramp(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    checks: _Checks,
    max_step: float = settings.MAX_LOAD_STEP,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Follow each column from the unloaded robot to full load (:class:`_Ramp`). Returns
    (x (n, N), reached full load, snapped, failure reasons); the states reached are
    checked (in ``checks``)."""
    return _Ramp(model, params, command, checks, max_step).run()
