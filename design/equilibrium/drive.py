"""Driving states: each column's state continued from the state before in sub-steps as
its commands change, in batch and never across a fold (:func:`drive`)."""

from __future__ import annotations

import numpy as np

from design.equilibrium import settings
from design.equilibrium.kernels import kernels
from design.equilibrium.stability import _columns, _fold_free, _norm, _scale
from design.model import RingPairModel


def drive(
    model: RingPairModel,
    params: np.ndarray,
    x: np.ndarray,
    start: np.ndarray,
    end: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Each column's state x (n, N) at commands ``start`` (2, N), driven to ``end`` (2, N)
    [rad] in equal sub-steps of at most SUBSTEP, each solved by Newton from the state
    before (contracting by CONTRACTION, ending on the stable side of every fold seen from
    rest, :func:`_fold_free`, with the rings clear of the external magnet): (the states
    at ``end``, whether every sub-step did; NaN where not). The batch form of
    :func:`solve_sequence`'s continuation, without falls: a column that would snap
    fails."""
    kern = kernels(model)
    n_cols = x.shape[1]
    scale = _scale(model, params, n_cols)
    x = x.copy()
    ok = np.isfinite(x).all(axis=0)
    n_sub = max(1, int(np.ceil(np.max(np.abs(end - start), initial=0.0) / settings.SUBSTEP)))
    ones = np.ones((1, n_cols))
    tolerance = float(settings.step_tolerance(np.ones(1))[0])
    for k in range(1, n_sub + 1):
        command = start + (end - start) * (k / n_sub)
        running = ok.copy()
        done = np.zeros(n_cols, bool)
        last = np.full(n_cols, np.inf)
        for _ in range(settings.MAX_CORRECTIONS + 2):
            a = np.flatnonzero(running)
            if a.size == 0:
                break
            r, step, _, monitor, clearance = kern.run(
                "newton", [x[:, a], command[:, a], ones[:, a]], _columns(params, a)
            )
            size = _norm(step, scale[:, a])
            contracting = np.isfinite(size) & (size <= settings.CONTRACTION * last[a])
            x[:, a] -= np.where(np.isfinite(step), step, 0.0)
            small = (np.max(np.abs(step), axis=0) < tolerance) | (
                np.max(np.abs(r), axis=0) < settings.TOLERANCE
            )
            fine = _fold_free(model, monitor) & (clearance[0] >= 0)
            finished = small & np.isfinite(size)
            done[a[finished & fine]] = True
            failed = (finished & ~fine) | (~finished & ~contracting)
            running[a[finished | failed]] = False
            last[a] = size
        ok &= done
    x[:, ~ok] = np.nan
    return x, ok
