"""The search for targets Newton does not settle (Levenberg-Marquardt on the ring
angles from the grid's local minima and the rim), the answers' rows and :func:`steer`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.equilibrium import Equilibria, solve_equilibria
from design.model import RingPairModel
from design.steering.grid import _evaluate, _fold_margin, _Grid, _interpolated_seeds, _solve_grid
from design.steering.newton import _distinct, _distinct_columns, _newton, _wrapped
from design.steering.settings import (
    MAX_DAMPING,
    MAX_ITERATIONS,
    MAX_SEEDS,
    MAX_TURN,
    MERGE,
    REACHED,
    RIM_OFFSET,
    RIM_SEEDS,
    RIM_STEP,
    SEED_MERGE,
    SEED_STEP,
    SEEDS,
    SWAP_NEAR,
)
from design.workspace import angle_grid


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


def _rows(
    model: RingPairModel,
    params: np.ndarray,
    targets: np.ndarray,
    target_index: np.ndarray,
    theta: np.ndarray,
    eq: Equilibria,
) -> Steering:
    """The answers ``theta`` (R, 2) [rad] (NaN: no answer) for targets ``target_index``
    (R,), with their states ``eq`` (solved with ``multistable=True``)."""
    valid = np.isfinite(theta).all(axis=1) & eq.stable
    nan = np.where(valid, 1.0, np.nan)
    position = eq.position * nan[:, None]
    err = np.linalg.norm(position[:, 1:] - targets[target_index], axis=1)
    return Steering(
        target_index=target_index,
        target=targets[target_index],
        theta=theta,
        position=position,
        tangent=eq.tangent * nan[:, None],
        error=err,
        reached=valid & (err <= REACHED),
        stable=valid,
        snapped=valid & eq.snapped,
        multistable=valid & eq.multistable,
        fold_margin=_fold_margin(model, params, eq.unknowns * nan[:, None], theta),
    )


def _answers(
    model: RingPairModel,
    params: np.ndarray,
    targets: np.ndarray,
    target_index: np.ndarray,
    theta: np.ndarray,
) -> Steering:
    """:func:`_rows` with the states at ``theta`` (R, 2) solved."""
    eq = solve_equilibria(model, params, *np.nan_to_num(theta.T), multistable=True)
    return _rows(model, params, targets, target_index, theta, eq)


def _search(
    model: RingPairModel, params: np.ndarray, targets: np.ndarray, grid: _Grid, seeds: int
) -> Steering:
    """Every solution for each target by Levenberg-Marquardt on the angles from the grid's
    local minima of the distance, the rim's closest points and swapped solutions (module
    docstring), or the closest point found."""
    g = grid.size
    angles = grid.step * np.arange(g)
    g1, g2 = np.meshgrid(angles, angles, indexing="ij")
    grid_theta = np.vstack([g1.ravel(), g2.ravel()])
    grid_tip, grid_jac = grid.tip.T, grid.jac
    owner, cell, resolution = _seeds(grid.tip.reshape(g, g, 2), targets, seeds)
    # One Newton step from each seed with the grid's derivative (at most a grid step):
    # seeds that it brings together go on as one.
    residual = (grid_tip[:, cell] - targets[owner].T).T
    step = _step(grid_jac[cell], residual, np.full(cell.size, 1e-9), grid.step)
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
    return _answers(model, params, targets, target_index, theta_rows)


def _concatenate(parts: list[Steering], order: np.ndarray) -> Steering:
    """The rows of ``parts`` one after the other, taken in ``order``."""
    return Steering(
        **{
            name: np.concatenate([getattr(p, name) for p in parts])[order]
            for name in Steering.__dataclass_fields__
        }
    )


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
    grid = _solve_grid(model, params, seed_step)
    m = len(targets)
    owner, start, x, optional, doubtful = _interpolated_seeds(grid, targets, model.n_rod)
    theta, converged, det, into, x = _newton(model, params, targets[owner].T, start, x, owner)
    # A target is doubtful where a start inside the grid's image neither converged nor
    # joined another start that did.
    np.logical_and.at(optional, into, optional.copy())
    doubtful[owner[~converged & ~optional & (into == np.arange(into.size))]] = True
    # The map from the angles (a torus) to the plane has degree 0: a target's regular
    # solutions come in pairs of opposite orientation. Where one is missing (near the
    # workspace's rim, where a pair merges at the fold), each solution's angles swapped
    # start once more (alike rings: the swap is nearly the other of the pair).
    keep = np.flatnonzero(converged)
    keep = keep[_distinct_columns(owner[keep], theta[:, keep])]
    positive = np.bincount(owner[keep], det[keep] > 0, minlength=m)
    negative = np.bincount(owner[keep], det[keep] < 0, minlength=m)
    odd = keep[(positive != negative)[owner[keep]]]
    if odd.size:
        swapped = x[:, odd].copy()
        swapped[model.n_rod :] = swapped[model.n_rod :][::-1]  # the rings' angles (torsion)
        more = _newton(model, params, targets[owner[odd]].T, theta[::-1, odd], swapped, owner[odd])
        owner = np.concatenate([owner, owner[odd]])
        theta = np.hstack([theta, more[0]])
        converged = np.concatenate([converged, more[1]])
        det = np.concatenate([det, more[2]])
        keep = np.flatnonzero(converged)
        keep = keep[_distinct_columns(owner[keep], theta[:, keep])]
        positive = np.bincount(owner[keep], det[keep] > 0, minlength=m)
        negative = np.bincount(owner[keep], det[keep] < 0, minlength=m)
    # A target is settled where its solutions pair up, the grid resolves the map about it
    # and every answer, solved as every caller solves it, is reached; the rest are left to
    # the search from the grid's local minima (out of reach, snaps, unresolved folds).
    settled = (positive == negative) & (positive > 0) & ~doubtful
    keep = keep[settled[owner[keep]]]
    fast = _answers(model, params, targets, owner[keep], theta[:, keep].T)
    settled[fast.target_index[~fast.reached]] = False
    fast = _concatenate([fast], np.flatnonzero(settled[fast.target_index]))
    parts = [fast]
    rest = np.flatnonzero(~settled)
    if rest.size:
        slow = _search(model, params, targets[rest], grid, seeds)
        parts.append(Steering(**{**slow.__dict__, "target_index": rest[slow.target_index]}))
    index_all = np.concatenate([p.target_index for p in parts])
    return _concatenate(parts, np.argsort(index_all, kind="stable"))
