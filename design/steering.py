"""Steering: the ring angles that put the tip where the user wants it.

The forward map is the state (:func:`design.equilibrium.solve_equilibria`: each
configuration's stable equilibrium reached by the load ramp) and its tip. Steering
inverts the tip's lateral position (y, z), base frame, as a function of the two ring
angles: two angles, two coordinates, so a target inside the workspace has isolated
solutions, in general more than one (the rings' moments add as two vectors, and the
same sum is reached with them mirrored about it).

Where the state is a regular stable equilibrium, the tip is a smooth function of the
angles with the exact derivative of the implicit function theorem,
d tip / d theta = dP/dtheta - dP/dx (dr/dx)^-1 dr/dtheta (r the model's residual, P its
pose; :func:`_sensitivity`, compiled from the model's own expressions).

For a batch of targets: the tip is solved on a grid of ring angles (SEED_STEP); every
local minimum of the distance to the target on that grid (the angles are periodic) seeds
a Levenberg-Marquardt iteration on the angles (Nocedal & Wright, *Numerical Optimization*,
2006, sec. 10.3), each trial angle pair solved for its state as every caller solves it;
so do the rim's closest points, offset to either side of parallel rings (:func:`_rim_seeds`), and
each result, its angles swapped, seeds one more (alike rings swapped give nearly the same
net moment: the pair of solutions that merges at the workspace's rim, too close together
for the grid).
Solutions whose angles agree to SAME_ANGLE are one. A solution reaches its target when the
tip is within REACHED of it; a target that no seed reaches gets the closest point found,
flagged ``reached = False`` (out of reach, or only reached through a snap).

Each solution carries its state's flags (``snapped``: the ramp to it passed a fold;
``multistable``: another stable state exists at those angles) and its **fold margin**: the
smallest real part of an eigenvalue of K^-1 dr/dx, K the unloaded robot's dr/dx (1 for the
unloaded robot, 0 at a fold, where the robot snaps). SI units throughout (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from design.compiled import compile_function
from design.equilibrium import kernels, solve_equilibria
from design.model import RingPairModel
from design.registry import index
from design.workspace import angle_grid

SEED_STEP = np.deg2rad(5.0)
"""Spacing of the grid of ring angles whose local minima of the distance to a target seed
the iterations. [rad]"""
SEEDS = 6
MAX_SEEDS = 24
"""Grid seeds per target: the SEEDS closest local minima, and more (up to MAX_SEEDS) where
they are closer than the grid resolves."""
RIM_STEP = np.deg2rad(2.0)
RIM_SEEDS = 2
RIM_OFFSET = np.deg2rad(1.0)
"""The rim of the workspace (the rings parallel) is sampled every RIM_STEP; its RIM_SEEDS
closest local minima to a target (within the seed grid's resolution of it) seed iterations
at RIM_OFFSET and 4 RIM_OFFSET to either side of parallel. [rad]"""
REACHED = 1e-9
"""A target is reached when the tip is this close to it. [m]"""
SAME_ANGLE = 1e-6
"""Two solutions are one when both ring angles agree to this. [rad]"""
MAX_TURN = 0.3
"""Largest change of a ring angle per iteration (keeps the iteration near its branch).
[rad]"""
SWAP_NEAR = np.deg2rad(5.0)
"""A solution's swapped angles seed one more iteration unless they are this close to a
solution already found (alike rings: the swap is nearly the mirror solution). [rad]"""
SEED_MERGE = np.deg2rad(1.0)
"""Grid seeds of one target that one Newton step brings this close are one. [rad]"""
MERGE = 1e-3
"""Iterations of one target whose angles come this close are merged (they go on to the
same solution). [rad]"""
MAX_ITERATIONS = 80
"""Levenberg-Marquardt iterations per seed at most."""
MAX_DAMPING = 1e8
"""Damping beyond which no step lowers the distance: the closest point is found."""


@dataclass(frozen=True)
class Steering:
    """Solutions for a batch of targets, one row per (target, distinct solution); a target
    with none that reaches it has one row, its closest point.

    target_index : shape (R,), the target each row answers.
    target : shape (R, 2), the target's (y, z), base frame. [m]
    theta : shape (R, 2), ring angles (distal, proximal) in [0, 2 pi). [rad]
    position : shape (R, 3), the tip of the state at those angles, base frame. [m]
    tangent : shape (R, 3), the tip tangent. [-]
    error : shape (R,), distance from the tip's (y, z) to the target. [m]
    reached : shape (R,), error <= REACHED.
    stable, snapped, multistable : shape (R,), the state's flags.
    fold_margin : shape (R,), smallest real eigenvalue of K^-1 dr/dx (module docstring). [-]
    """

    target_index: np.ndarray
    target: np.ndarray
    theta: np.ndarray
    position: np.ndarray
    tangent: np.ndarray
    error: np.ndarray
    reached: np.ndarray
    stable: np.ndarray
    snapped: np.ndarray
    multistable: np.ndarray
    fold_margin: np.ndarray

    def __len__(self) -> int:
        return len(self.target_index)


@lru_cache(maxsize=16)
def _sensitivity(model: RingPairModel) -> ca.Function:
    """(x, command, params) -> (tip (y, z), d(y, z)/d command (2x2, column-major), dr/dx
    (column-major)) at an equilibrium x, compiled."""
    x = ca.SX.sym("x", model.n_unknowns)
    command = ca.SX.sym("command", 2)
    prm = ca.SX.sym("params", model.residual.size1_in(2))
    r = model.residual.call([x, command, prm])[0]
    tip = model.pose.call([x, command, prm])[0][1:3]
    dr_dx = ca.jacobian(r, x)
    d_tip = ca.jacobian(tip, command) - ca.jacobian(tip, x) @ ca.solve(
        dr_dx, ca.jacobian(r, command)
    )
    return compile_function(
        ca.Function("sensitivity", [x, command, prm], [tip, ca.vec(d_tip), ca.vec(dr_dx)])
    )


def _evaluate(
    model: RingPairModel, params: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tip (y, z) of the state at each column of theta (2, P) [rad], its derivative
    (P, 2, 2) and whether it has a state; (NaN where not)."""
    eq = solve_equilibria(model, params, theta[0], theta[1])
    tip = np.full((2, theta.shape[1]), np.nan)
    jac = np.full((theta.shape[1], 2, 2), np.nan)
    ok = eq.stable.copy()
    if ok.any():
        d = kernels(model).run(_sensitivity(model), [eq.unknowns[ok].T, theta[:, ok]], params)[1]
        tip[:, ok] = eq.position[ok, 1:].T
        jac[ok] = d.T.reshape(-1, 2, 2).transpose(0, 2, 1)
        ok[ok] = np.isfinite(jac[ok]).all(axis=(1, 2))
    return tip, jac, ok


def _seeds(
    grid_tip: np.ndarray, targets: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """Local minima of the distance to each target on the periodic grid (G, G, 2) of tips
    (NaN where no state): the ``count`` closest, and any closer than the grid's resolution
    (the 90th percentile of the tip's move between neighbours: a valley of near-solutions
    has many), at most MAX_SEEDS. Returns (target index, flat grid index, the resolution
    [m])."""
    g = grid_tip.shape[0]
    moves = np.concatenate(
        [
            np.linalg.norm(np.diff(grid_tip, axis=k, append=grid_tip.take([0], axis=k)), axis=-1)
            for k in (0, 1)
        ]
    )
    resolution = np.nanpercentile(moves, 90) if np.isfinite(moves).any() else 0.0
    rows, cells = [], []
    tip = np.where(np.isfinite(grid_tip), grid_tip, np.inf)  # no state: infinitely far
    for start in range(0, len(targets), 128):
        t = targets[start : start + 128]
        d = (tip[None, :, :, 0] - t[:, None, None, 0]) ** 2
        d += (tip[None, :, :, 1] - t[:, None, None, 1]) ** 2
        d[np.isnan(d)] = np.inf
        # Local minima on the torus: no smaller neighbour (the grid padded periodically).
        wrap = np.pad(d, ((0, 0), (1, 1), (1, 1)), mode="wrap")
        minimum = np.isfinite(d)
        for di in (0, 1, 2):
            for dj in (0, 1, 2):
                if di != 1 or dj != 1:
                    minimum &= d <= wrap[:, di : di + g, dj : dj + g]
        flat = np.sqrt(np.where(minimum, d, np.inf)).reshape(len(t), g * g)
        best = np.argsort(flat, axis=1)[:, :MAX_SEEDS]
        dist = np.take_along_axis(flat, best, axis=1)
        keep = np.isfinite(dist) & ((np.arange(best.shape[1]) < count) | (dist <= resolution))
        rows.append(np.broadcast_to(np.arange(start, start + len(t))[:, None], best.shape)[keep])
        cells.append(best[keep])
    return np.concatenate(rows), np.concatenate(cells), float(resolution)


def _rim_seeds(
    model: RingPairModel, params: np.ndarray, targets: np.ndarray, near_rim: float
) -> tuple[np.ndarray, np.ndarray]:
    """Seeds on both sides of the parallel rings, near the closest points of the rim: (target
    index, angles (2, P)). With the rings parallel the tip is at the rim of the workspace,
    where the map from angles to tip folds and its solutions come in pairs closer together
    than the seed grid (one on each side of theta1 = theta2). Only for targets within
    ``near_rim`` of the rim. [m]"""
    loop = angle_grid(RIM_STEP)
    eq = solve_equilibria(model, params, loop, loop)
    rim = np.where(eq.stable[:, None], eq.position[:, 1:], np.nan)
    d = np.linalg.norm(rim[None] - targets[:, None, :], axis=-1)
    d = np.where(np.isfinite(d), d, np.inf)
    minimum = np.isfinite(d) & (d <= np.roll(d, 1, axis=1)) & (d <= np.roll(d, -1, axis=1))
    best = np.argsort(np.where(minimum, d, np.inf), axis=1)[:, :RIM_SEEDS]
    near = np.take_along_axis(d, best, axis=1) <= near_rim
    keep = near & np.take_along_axis(minimum, best, axis=1)
    owner = np.broadcast_to(np.arange(len(targets))[:, None], best.shape)[keep]
    phi = loop[best[keep]]
    starts = [
        np.vstack([phi + side, phi - side])
        for side in (RIM_OFFSET, -RIM_OFFSET, 4 * RIM_OFFSET, -4 * RIM_OFFSET)
    ]
    return np.tile(owner, len(starts)), np.hstack(starts)


def _step(jac: np.ndarray, residual: np.ndarray, damping: np.ndarray, limit: float) -> np.ndarray:
    """Levenberg-Marquardt steps (P, 2) of the angles for derivatives jac (P, 2, 2) and
    residuals (P, 2): -(J^T J + damping diag(J^T J))^-1 J^T r, each scaled to at most
    ``limit`` per angle [rad] (NaN where J is not finite)."""
    normal = jac.transpose(0, 2, 1) @ jac
    normal += damping[:, None, None] * (
        np.eye(2) * np.maximum(np.diagonal(normal, axis1=1, axis2=2), 1e-12)[:, :, None]
    )
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(normal).all(axis=(1, 2))
        step = np.full(residual.shape, np.nan)
        step[ok] = -np.linalg.solve(
            normal[ok], (jac[ok].transpose(0, 2, 1) @ residual[ok][:, :, None])
        )[:, :, 0]
    return step * np.minimum(1.0, limit / np.maximum(np.abs(step).max(axis=1), 1e-300))[:, None]


def _merged(owner: np.ndarray, theta: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """Of ``columns``, those whose angles fall in the same MERGE cell as an earlier column of
    the same target (they follow it to the same solution)."""
    cell = np.round(np.mod(theta[:, columns], 2 * np.pi) / MERGE).astype(np.int64)
    keys = np.vstack([owner[columns], cell])
    _, first = np.unique(keys, axis=1, return_index=True)
    later = np.ones(columns.size, bool)
    later[first] = False
    return columns[later]


def _iterate(
    model: RingPairModel,
    params: np.ndarray,
    target: np.ndarray,
    theta: np.ndarray,
    owner: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Levenberg-Marquardt on the ring angles of each column: (angles (2, P), distance of
    the tip to the target (P,), inf for a column merged into another of the same target
    (``owner``) on its way). target (2, P) [m], theta (2, P) starts [rad]."""
    theta = theta.copy()
    tip, jac, ok = _evaluate(model, params, theta)
    error = np.where(ok, np.linalg.norm(tip - target, axis=0), np.inf)
    damping = np.full(theta.shape[1], 1e-3)
    running = ok.copy()
    for _ in range(MAX_ITERATIONS):
        running &= (error > 1e-3 * REACHED) & (damping < MAX_DAMPING)
        merged = _merged(owner, theta, np.flatnonzero(running | (error <= REACHED)))
        running[merged], error[merged] = False, np.inf
        a = np.flatnonzero(running)
        if a.size == 0:
            break
        step = _step(jac[a], (tip - target)[:, a].T, damping[a], MAX_TURN)
        trial = theta[:, a] + step.T
        t_tip, t_jac, t_ok = _evaluate(model, params, trial)
        t_error = np.where(t_ok, np.linalg.norm(t_tip - target[:, a], axis=0), np.inf)
        better = t_error < error[a]
        b = a[better]
        theta[:, b], tip[:, b], jac[b], error[b] = (
            trial[:, better],
            t_tip[:, better],
            t_jac[better],
            t_error[better],
        )
        damping[b] = np.maximum(damping[b] / 5, 1e-12)
        damping[a[~better]] *= 5
        # Steps below rounding cannot lower the distance further.
        running[a[np.abs(step).max(axis=1) < 1e-14]] = False
    return np.mod(theta, 2 * np.pi), error


def _wrapped(difference: np.ndarray) -> np.ndarray:
    """|angle difference| wrapped to [0, pi]. [rad]"""
    return np.abs(np.angle(np.exp(1j * difference)))


def _distinct(theta: np.ndarray) -> np.ndarray:
    """Indices of the first of each group of angle pairs (P, 2) equal to SAME_ANGLE."""
    keep: list[int] = []
    for i, t in enumerate(theta):
        if not any(np.all(_wrapped(t - theta[k]) < SAME_ANGLE) for k in keep):
            keep.append(i)
    return np.array(keep, int)


def _fold_margin(
    model: RingPairModel, params: np.ndarray, unknowns: np.ndarray, theta: np.ndarray
) -> np.ndarray:
    """Smallest real eigenvalue of K^-1 dr/dx at each state (rows of unknowns (R, n),
    theta (R, 2)); NaN where there is no state."""
    out = np.full(len(theta), np.nan)
    ok = np.isfinite(unknowns).all(axis=1)
    if not ok.any():
        return out
    n, m = model.n_unknowns, int(ok.sum())
    f, kern = _sensitivity(model), kernels(model)
    unloaded = params.copy()
    unloaded[index("load_scale")] = 0.0
    rest = np.asarray(model.initial.map(m)(theta[ok].T, unloaded))
    dr_dx = kern.run(f, [unknowns[ok].T, theta[ok].T], params)[2].T.reshape(m, n, n)
    k = kern.run(f, [rest, theta[ok].T], unloaded)[2].T.reshape(m, n, n)
    ratio = np.linalg.solve(k.transpose(0, 2, 1), dr_dx.transpose(0, 2, 1))
    out[ok] = np.linalg.eigvals(ratio).real.min(axis=1)
    return out


def steer(
    model: RingPairModel,
    params: np.ndarray,
    targets: np.ndarray,
    *,
    seeds: int = SEEDS,
    seed_step: float = SEED_STEP,
) -> Steering:
    """Every pair of ring angles whose state puts the tip at each target (module
    docstring).

    targets : shape (M, 2), the tip's (y, z), base frame. [m]
    params : model parameter vector, shape (k,), from ``model.parameters(design)``. [SI]
    """
    params = np.asarray(params, float)
    targets = np.atleast_2d(np.asarray(targets, float))
    if targets.shape[1] != 2 or not np.isfinite(targets).all() or len(targets) == 0:
        raise ValueError("targets must be finite (y, z) pairs, shape (M, 2), M >= 1")
    angles = angle_grid(seed_step)
    g1, g2 = np.meshgrid(angles, angles, indexing="ij")
    grid_theta = np.vstack([g1.ravel(), g2.ravel()])
    grid_tip, grid_jac, _ = _evaluate(model, params, grid_theta)
    owner, cell, resolution = _seeds(
        grid_tip.T.reshape(len(angles), len(angles), 2), targets, seeds
    )
    # One Newton step from each seed with the grid's derivative (at most a grid step):
    # seeds that it brings together go on as one.
    residual = (grid_tip[:, cell] - targets[owner].T).T
    step = _step(grid_jac[cell], residual, np.full(cell.size, 1e-9), seed_step)
    start = grid_theta[:, cell] + np.where(np.isfinite(step), step, 0.0).T
    cells = np.round(np.mod(start, 2 * np.pi) / SEED_MERGE).astype(np.int64)
    _, first = np.unique(np.vstack([owner, cells]), axis=1, return_index=True)
    owner, start = owner[np.sort(first)], start[:, np.sort(first)]
    rim_owner, rim_start = _rim_seeds(model, params, targets, resolution)
    owner, start = np.concatenate([owner, rim_owner]), np.hstack([start, rim_start])
    theta, error = _iterate(model, params, targets[owner].T, start, owner)
    # The rings are alike, so the angles swapped give (nearly) the same net moment: the
    # other solution of a pair, which the grid cannot tell apart near the workspace's rim
    # (where the pair merges at the fold of the map).
    solved = np.flatnonzero(error <= REACHED)
    swapped_start = theta[::-1, solved]
    # A swapped start near a solution already solved of the same target would go there.
    near = np.zeros(solved.size, bool)
    for k in range(solved.size):
        mine = solved[owner[solved] == owner[solved[k]]]
        near[k] = (
            _wrapped(theta[:, mine] - swapped_start[:, k : k + 1]).max(axis=0).min() < SWAP_NEAR
        )
    more = solved[~near]
    swapped, swapped_error = _iterate(
        model, params, targets[owner[more]].T, theta[::-1, more], owner[more]
    )
    owner = np.concatenate([owner, owner[more]])
    theta = np.hstack([theta, swapped])
    error = np.concatenate([error, swapped_error])
    rows: list[int] = []
    answers: list[int] = []
    for t in range(len(targets)):
        mine = np.flatnonzero(owner == t)
        reached = mine[error[mine] <= REACHED]
        if reached.size:
            found = list(reached[_distinct(theta[:, reached].T)])
        elif np.isfinite(error[mine]).any():
            found = [
                int(mine[np.nanargmin(np.where(np.isfinite(error[mine]), error[mine], np.nan))])
            ]
        else:
            found = [-1]  # no seed had a state: no answer
        rows += found
        answers += [t] * len(found)
    picked, target_index = np.array(rows, int), np.array(answers, int)
    has = picked >= 0
    theta_rows = np.full((len(picked), 2), np.nan)
    theta_rows[has] = theta[:, picked[has]].T
    eq = solve_equilibria(model, params, *np.nan_to_num(theta_rows.T), multistable=True)
    valid = has & eq.stable
    nan = np.where(valid, 1.0, np.nan)
    position = eq.position * nan[:, None]
    err = np.linalg.norm(position[:, 1:] - targets[target_index], axis=1)
    return Steering(
        target_index=target_index,
        target=targets[target_index],
        theta=theta_rows,
        position=position,
        tangent=eq.tangent * nan[:, None],
        error=err,
        reached=valid & (err <= REACHED),
        stable=valid,
        snapped=valid & eq.snapped,
        multistable=valid & eq.multistable,
        fold_margin=_fold_margin(model, params, eq.unknowns * nan[:, None], theta_rows),
    )
