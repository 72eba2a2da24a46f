"""Newton on the state and the ring angles together, from the grid's starts, and the
distinct solutions it reaches."""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from design.compiled import compile_function
from design.equilibrium import kernels
from design.model import RingPairModel
from design.steering.settings import CONVERGED, MAX_TURN, MERGE, NEWTON_ITERATIONS, SAME_ANGLE


@lru_cache(maxsize=16)
def _inverse_step(model: RingPairModel) -> ca.Function:
    """(x, theta, target, params) -> (residual (n + 2): the model's r and the tip's (y, z)
    less the target; Newton's step in (x, theta) for it; d(y, z)/d theta of the state
    through x (2x2, column-major)), compiled: Newton on the state and the angles together,
    with the exact derivatives of the model's own expressions."""
    x = ca.SX.sym("x", model.n_unknowns)
    theta = ca.SX.sym("theta", 2)
    target = ca.SX.sym("target", 2)
    prm = ca.SX.sym("params", model.residual.size1_in(2))
    r = model.residual.call([x, theta, prm])[0]
    tip = model.pose.call([x, theta, prm])[0][1:3]
    dr_dx, dr_dtheta = ca.jacobian(r, x), ca.jacobian(r, theta)
    dtip_dx, dtip_dtheta = ca.jacobian(tip, x), ca.jacobian(tip, theta)
    residual = ca.vertcat(r, tip - target)
    jac = ca.blockcat([[dr_dx, dr_dtheta], [dtip_dx, dtip_dtheta]])
    d_tip = dtip_dtheta - dtip_dx @ ca.solve(dr_dx, dr_dtheta)
    return compile_function(
        ca.Function(
            "inverse_step",
            [x, theta, target, prm],
            [residual, -ca.solve(jac, residual), ca.vec(d_tip)],
        )
    )


def _newton(
    model: RingPairModel,
    params: np.ndarray,
    target: np.ndarray,
    theta: np.ndarray,
    x: np.ndarray,
    owner: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Newton on the state and the angles together from each column (target (2, P) [m],
    theta (2, P) [rad], x (n, P) [SI]), each angle turned at most MAX_TURN per step, a
    column leaving the batch as it converges, or as it comes within MERGE of another of
    the same target (``owner``) with the same orientation (it goes on to the same
    solution). Returns (angles (2, P) in [0, 2 pi), converged (P,), determinant of
    d tip / d theta there (P,) [m^2/rad^2], the column each one merged into (P,), itself
    if none; the unknowns (n, P))."""
    theta, x = theta.copy(), x.copy()
    n = model.n_unknowns
    converged = np.zeros(theta.shape[1], bool)
    det = np.full(theta.shape[1], np.nan)
    into = np.arange(theta.shape[1])
    a = np.arange(theta.shape[1])
    for _ in range(NEWTON_ITERATIONS):
        if a.size == 0:
            break
        residual, step, d_tip = kernels(model).run(
            _inverse_step(model), [x[:, a], theta[:, a], target[:, a]], params
        )
        det[a] = d_tip[0] * d_tip[3] - d_tip[1] * d_tip[2]
        done = np.abs(residual).max(axis=0) <= CONVERGED
        converged[a[done]] = True
        go = ~done & np.isfinite(step).all(axis=0)
        step, a = step[:, go], a[go]
        step *= np.minimum(1.0, MAX_TURN / np.maximum(np.abs(step[n:]).max(axis=0), 1e-300))
        x[:, a] += step[:n]
        theta[:, a] += step[n:]
        # Columns of one target in the same MERGE cell, with the same orientation, are one.
        cell = np.round(np.mod(theta[:, a], 2 * np.pi) / MERGE).astype(np.int64)
        keys = np.vstack([owner[a], cell, np.sign(det[a]).astype(np.int64)])
        into[a] = a[_groups(keys)]
        a = a[into[a] == a]
    det[~converged] = np.nan
    while (into[into] != into).any():  # through columns that merged later, to the last
        into = into[into]
    return np.mod(theta, 2 * np.pi), converged, det, into, x


def _groups(keys: np.ndarray) -> np.ndarray:
    """For each column of the integer keys (k, P), the first column with the same keys."""
    order = np.lexsort(keys[::-1])
    new = np.ones(order.size, bool)
    new[1:] = (np.diff(keys[:, order], axis=1) != 0).any(axis=0)
    first = np.minimum.reduceat(order, np.flatnonzero(new)) if order.size else order
    out = np.empty_like(order)
    out[order] = first[np.cumsum(new) - 1]
    return out


def _distinct_columns(owner: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Indices of the first of each group of columns of theta (2, P) of the same owner
    whose angles agree to SAME_ANGLE, ordered by owner."""
    # Columns in the same cell of SAME_ANGLE / 10 are one: few are left to compare in pairs.
    cell = np.round(np.mod(theta, 2 * np.pi) / (SAME_ANGLE / 10)).astype(np.int64)
    first = np.unique(_groups(np.vstack([owner, cell])))
    order = first[np.argsort(owner[first], kind="stable")]
    owner, theta = owner[order], theta[:, order]
    start = np.searchsorted(owner, owner)  # each column's position in its owner's group
    rank = np.arange(owner.size) - start
    width = int(rank.max()) + 1 if owner.size else 0
    groups = np.full((owner.size, width, 2), np.nan)
    groups[start, rank] = theta.T  # (group by its first column, rank, angle)
    earlier = groups[start]  # (P, width, 2): the columns of each one's group
    same = (_wrapped(earlier - theta.T[:, None, :]) < SAME_ANGLE).all(axis=2)
    same &= np.arange(width)[None, :] < rank[:, None]
    return order[~same.any(axis=1)]


def _wrapped(difference: np.ndarray) -> np.ndarray:
    """|angle difference| wrapped to [0, pi]. [rad]"""
    return np.abs(np.mod(difference + np.pi, 2 * np.pi) - np.pi)


def _distinct(theta: np.ndarray) -> np.ndarray:
    """Indices of the first of each group of angle pairs (P, 2) equal to SAME_ANGLE."""
    keep: list[int] = []
    for i, t in enumerate(theta):
        if not any(np.all(_wrapped(t - theta[k]) < SAME_ANGLE) for k in keep):
            keep.append(i)
    return np.array(keep, int)
