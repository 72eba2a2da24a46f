"""Newton's method on batches of columns, and the judgement of the states it reaches.

The helpers work on the columns they are given: params (k,) shared or (k, m), one per
column; command (2, m); states x (n, m); load factors lam (m,).
"""

from __future__ import annotations

import numpy as np

from design.equilibrium import settings
from design.equilibrium.kernels import kernels
from design.equilibrium.stability import _columns, _fold_free, _norm, _scale, _stable
from design.model import RingPairModel


class _Checks:
    """The ``check`` outputs (r, monitor, position, frame, tip angles, clearance) of states
    at full load, kept per column of a solve (NaN where not checked)."""

    def __init__(self, n: int) -> None:
        self.outs: list[np.ndarray] | None = None
        self.done = np.zeros(n, bool)

    def put(self, idx: np.ndarray, outs: list[np.ndarray]) -> None:
        if self.outs is None:
            self.outs = [np.full((o.shape[0], self.done.size), np.nan) for o in outs]
        for acc, o in zip(self.outs, outs, strict=True):
            acc[:, idx] = o
        self.done[idx] = True


def _check(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The exact check of states at load factors lam (default full load): (converged to
    TOLERANCE, stable, check outputs)."""
    lam = np.ones(x.shape[1]) if lam is None else lam
    outs = kernels(model).run("check", [x, command, lam[None, :]], params)
    converged = np.max(np.abs(outs[0]), axis=0) < settings.TOLERANCE
    return converged, _stable(model, outs[1]), outs


def _judge(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray,
    monitor: np.ndarray,
    clearance: np.ndarray,
    checks: _Checks,
    where: np.ndarray,
    exact: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Judge candidate states x (n, m) at load factors lam, given the solver's monitor and
    clearance at (or within a last Newton step of) each: (converged, acceptable). At full
    load, or anywhere if ``exact`` (states not reached along a branch from rest), the
    exact check decides (full-load outputs are put in ``checks`` at columns ``where``);
    below full load a candidate is converged by construction and, along a branch, the
    monitor must show no fold crossed. A state whose rings are inside the external magnet
    is never acceptable."""
    converged = np.ones(lam.size, bool)
    ok = np.zeros(lam.size, bool)
    full = lam >= 1.0
    test = full | exact
    if test.any():
        done, ok[test], outs = _check(
            model, _columns(params, test), command[:, test], x[:, test], lam[test]
        )
        converged[full] = done[full[test]]
        ok[full] &= converged[full]
        at_full = full[test]
        checks.put(where[full], [o[:, at_full] for o in outs])
    ok[~test] = _fold_free(model, monitor[:, ~test])
    return converged, ok & (clearance.ravel() >= 0)


def _newton(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray,
    checks: _Checks,
    where: np.ndarray,
    iterations: int = 2 * settings.MAX_CORRECTIONS,
    exact: bool = False,
    known: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Newton from x at load factors lam (no contraction required): (states, converged,
    acceptable as :func:`_judge` judges, ``exact`` passed on; checks of full-load states
    go to ``checks`` at columns ``where``). A column whose iterate comes within DISTINCT of
    its ``known`` state (n, m), a regular root, stops unconverged: it would end there."""
    kern = kernels(model)
    xs = x.copy()
    ok = np.zeros(lam.size, bool)
    done = np.zeros(lam.size, bool)
    running = np.isfinite(xs).all(axis=0)
    for _ in range(iterations):
        if known is not None:
            a = np.flatnonzero(running)
            near = _norm(xs[:, a] - known[:, a], _scale(model, _columns(params, a), a.size))
            running[a[near <= settings.DISTINCT]] = False
        a = np.flatnonzero(running)
        if a.size == 0:
            break
        r, step, _, monitor, clearance = kern.run(
            "newton", [xs[:, a], command[:, a], lam[None, a]], _columns(params, a)
        )
        rn, sn = np.max(np.abs(r), axis=0), np.max(np.abs(step), axis=0)
        lost = ~np.isfinite(sn)
        running[a[lost]] = False
        candidate = ~lost & ((rn < settings.TOLERANCE) | (sn < settings.step_tolerance(lam[a])))
        xs[:, a[~lost]] -= step[:, ~lost]  # (a converged state takes its last step too)
        c = a[candidate]
        if c.size:
            converged, good = _judge(
                model,
                _columns(params, c),
                command[:, c],
                xs[:, c],
                lam[c],
                monitor[:, candidate],
                clearance[:, candidate],
                checks,
                where[c],
                exact,
            )
            ok[c], done[c] = good, converged
            running[c[converged]] = False
    return xs, done, ok
