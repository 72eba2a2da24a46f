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

For a batch of targets: the state and its tip are solved on a grid of ring angles
(SEED_STEP), each cell split into two triangles, and the grid's piecewise-linear map is
inverted: every triangle whose image holds a target gives a start, the angles and the
state interpolated (:func:`_interpolated_seeds`). From there Newton on the state and the
angles together (the model's residual and the tip's distance to the target: n + 2
equations in n + 2 unknowns, exact Jacobian compiled from the model's own expressions,
:func:`_inverse_step`) converges in a few steps, the whole batch in one mapped call per
step, each start leaving the batch as it converges or joins another. The map from the
angles (a torus) to the plane has degree zero, so a target's regular solutions come in
pairs of opposite orientation (the sign of det d tip / d theta): where one is missing,
each solution's angles swapped start once more (alike rings swapped give nearly the same
net moment: the pair of solutions that merges at the workspace's rim, too close together
for the grid). A target is settled where its solutions pair up, each one solved on its
own as every caller solves it (the load ramp) lands on it, and the grid resolves the map
about it (no corner nearby without a state or after a snap).

The other targets (out of reach, snaps, the map unresolved) are searched: every local
minimum of the distance to the target on the grid (the angles are periodic) seeds a
Levenberg-Marquardt iteration on the angles (Nocedal & Wright, *Numerical Optimization*,
2006, sec. 10.3), each trial angle pair solved for its state as every caller solves it;
so do the rim's closest points, offset to either side of parallel rings
(:func:`_rim_seeds`), and each result's angles swapped.
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
from design.equilibrium import Equilibria, kernels, solve_equilibria
from design.model import RingPairModel
from design.registry import index
from design.workspace import angle_grid

SEED_STEP = np.deg2rad(5.0)
"""Spacing of the grid of ring angles whose interpolated map starts Newton (and whose
local minima of the distance to a target seed the search). [rad]"""
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

NEWTON_ITERATIONS = 12
"""Newton iterations on (state, angles) per seed at most (from an interpolated start they
converge in three to five)."""
CONVERGED = 1e-12
"""Newton on (state, angles) has converged where every residual (the model's, m or rad,
and the tip's distance to the target, m) is below this."""
EDGE = 1e-9
"""A target on a grid triangle's edge (barycentric coordinate down to -EDGE) is in it."""
FOLD_BAND = 4.0
"""Safety factor on the estimated reach of the map beyond a folded grid triangle's image
(where a target's solutions may lie between the grid's points)."""


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


def _sensitivities(
    model: RingPairModel, params: np.ndarray, eq: Equilibria, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tip (y, z) of the states ``eq`` at the columns of theta (2, P) [rad], its
    derivative (P, 2, 2) and whether it has a state; (NaN where not)."""
    tip = np.full((2, theta.shape[1]), np.nan)
    jac = np.full((theta.shape[1], 2, 2), np.nan)
    ok = eq.stable.copy()
    if ok.any():
        d = kernels(model).run(_sensitivity(model), [eq.unknowns[ok].T, theta[:, ok]], params)[1]
        tip[:, ok] = eq.position[ok, 1:].T
        jac[ok] = d.T.reshape(-1, 2, 2).transpose(0, 2, 1)
        ok[ok] = np.isfinite(jac[ok]).all(axis=(1, 2))
    return tip, jac, ok


def _evaluate(
    model: RingPairModel, params: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tip (y, z) of the state at each column of theta (2, P) [rad], its derivative
    (P, 2, 2) and whether it has a state; (NaN where not)."""
    return _sensitivities(model, params, solve_equilibria(model, params, theta[0], theta[1]), theta)


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
    return np.abs(np.mod(difference + np.pi, 2 * np.pi) - np.pi)


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
    rest = kern.run(model.initial, [theta[ok].T], unloaded)[0]
    dr_dx = kern.run(f, [unknowns[ok].T, theta[ok].T], params)[2].T.reshape(m, n, n)
    k = kern.run(f, [rest, theta[ok].T], unloaded)[2].T.reshape(m, n, n)
    ratio = np.linalg.solve(k.transpose(0, 2, 1), dr_dx.transpose(0, 2, 1))
    out[ok] = np.linalg.eigvals(ratio).real.min(axis=1)
    return out


@dataclass(frozen=True)
class _Grid:
    """The state on the periodic grid of ring angles ``step`` apart, G per ring, theta1
    varying slowest (flat index i G + j at (i step, j step)).

    tip : shape (G*G, 2), the tip (y, z), base frame, NaN where no state. [m]
    jac : shape (G*G, 2, 2), d tip / d theta. [m/rad]
    lag : shape (G*G, n), the state's unknowns, those that are ring angles less the
        command (so that they interpolate across 2 pi). [SI]
    snapped : shape (G*G,), the ramp to the state passed a fold.
    """

    step: float
    tip: np.ndarray
    jac: np.ndarray
    lag: np.ndarray
    snapped: np.ndarray

    @property
    def size(self) -> int:
        return int(round(np.sqrt(len(self.tip))))


def _solve_grid(model: RingPairModel, params: np.ndarray, step: float) -> _Grid:
    """The state, its tip and the tip's derivative on the grid of ring angles ``step``
    apart [rad]; kept for the last few set-ups (a path steered at every trial size, a
    design steered again)."""
    return _solved_grid(model, np.asarray(params, float).tobytes(), float(step))


@lru_cache(maxsize=4)
def _solved_grid(model: RingPairModel, params_bytes: bytes, step: float) -> _Grid:
    params = np.frombuffer(params_bytes).copy()
    angles = angle_grid(step)
    g1, g2 = np.meshgrid(angles, angles, indexing="ij")
    theta = np.vstack([g1.ravel(), g2.ravel()])
    eq = solve_equilibria(model, params, theta[0], theta[1])
    tip, jac, _ = _sensitivities(model, params, eq, theta)
    lag = eq.unknowns.copy()
    if model.n_unknowns > model.n_rod:  # the rings' angles at the tip (torsion)
        lag[:, model.n_rod :] = np.mod(lag[:, model.n_rod :] - theta.T + np.pi, 2 * np.pi) - np.pi
    grid = _Grid(float(angles[1] - angles[0]), tip.T, jac, lag, eq.snapped.copy())
    for a in (grid.tip, grid.jac, grid.lag, grid.snapped):
        a.setflags(write=False)  # shared by every later call
    return grid


def _triangles(g: int) -> tuple[np.ndarray, np.ndarray]:
    """The grid's cells split along their diagonal into triangles: (flat indices of the
    vertices (T, 3), their (i, j) offsets from the cell's corner (T, 3, 2)); T = 2 g^2."""
    i, j = (a.ravel() for a in np.meshgrid(np.arange(g), np.arange(g), indexing="ij"))
    shapes = np.array([[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]])
    corner = np.stack([i, j], axis=-1)  # (g*g, 2)
    vertex = corner[:, None, None, :] + shapes[None]  # (g*g, 2, 3, 2)
    flat = (vertex[..., 0] % g) * g + vertex[..., 1] % g
    return flat.reshape(-1, 3), vertex.reshape(-1, 3, 2)


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """z component of u x v for rows of (P, 2)."""
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


def _in_boxes(
    low: np.ndarray, high: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Every (box, point) with the point (P, 2) in the box from ``low`` to ``high`` (B, 2),
    found through square bins of half a box's size: (box index, point index). [m]"""
    extent = (high - low).max(axis=1)
    extent = extent[np.isfinite(extent)]
    if extent.size == 0:
        return np.zeros(0, int), np.zeros(0, int)
    origin, top = points.min(axis=0), points.max(axis=0)
    side = max(float(np.median(extent)) / 2, float((top - origin).max()) / 256, 1e-12)
    shape = np.floor((top - origin) / side).astype(np.int64) + 1
    cells = np.floor((points - origin) / side).astype(np.int64)
    key = cells[:, 0] * shape[1] + cells[:, 1]
    order = np.argsort(key, kind="stable")
    bounds = np.searchsorted(key[order], np.arange(shape[0] * shape[1] + 1))
    with np.errstate(invalid="ignore"):
        first = np.floor((low - origin) / side)
        last = np.floor((high - origin) / side)
    hit = np.isfinite(first).all(axis=1) & (last >= 0).all(axis=1) & (first < shape).all(axis=1)
    box = np.flatnonzero(hit)
    first = np.maximum(first[box], 0).astype(np.int64)
    last = np.minimum(last[box], shape - 1).astype(np.int64)
    span = last - first + 1
    # Each box's bins, then each bin's points.
    count = span[:, 0] * span[:, 1]
    rep = np.repeat(np.arange(box.size), count)
    k = np.arange(rep.size) - np.repeat(np.cumsum(count) - count, count)
    bins = (first[rep, 0] + k // span[rep, 1]) * shape[1] + first[rep, 1] + k % span[rep, 1]
    count = bounds[bins + 1] - bounds[bins]
    rep = np.repeat(rep, count)
    k = np.arange(rep.size) - np.repeat(np.cumsum(count) - count, count)
    point = order[np.repeat(bounds[bins], count) + k]
    inside = ((points[point] >= low[box[rep]]) & (points[point] <= high[box[rep]])).all(axis=1)
    return box[rep[inside]], point[inside]


def _interpolated_seeds(
    grid: _Grid, targets: np.ndarray, n_rod: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Starts for Newton from the grid's piecewise-linear map: every grid triangle whose
    image holds a target gives the angles and the state there, interpolated; so does a
    triangle across which the map folds (the derivative's determinant changes sign) for
    a target just outside its image (the map's image there reaches beyond the
    triangle's by about its curvature: FOLD_BAND times the change of the derivative along
    an edge times the edge, over 8). Returns (target index (P,), angles (2, P) [rad],
    unknowns (n, P) [SI], optional (P,): from a folded triangle, where the solution may
    not exist; doubtful (M,): within twice a triangle's size of one whose corners lack a
    state or snapped, where the grid may not resolve the solutions)."""
    vertices, offsets = _triangles(grid.size)
    corners = grid.tip[vertices]  # (T, 3, 2)
    j = grid.jac
    det = (j[:, 0, 0] * j[:, 1, 1] - j[:, 0, 1] * j[:, 1, 0])[vertices]
    has = np.isfinite(corners).all(axis=(1, 2)) & np.isfinite(det).all(axis=1)
    fold = has & ~((det > 0).all(axis=1) | (det < 0).all(axis=1))
    # The linear interpolation's error along each edge (a, b): |(J(b) - J(a)) (b - a)| / 8.
    jac = grid.jac[vertices]  # (T, 3, 2, 2)
    edge = np.diff(offsets[:, [0, 1, 2, 0]], axis=1) * grid.step  # (T, 3, 2)
    bend = np.einsum("tkij,tkj->tki", np.diff(jac[:, [0, 1, 2, 0]], axis=1), edge)
    band = np.where(fold, FOLD_BAND * np.linalg.norm(bend, axis=2).max(axis=1) / 8, 0.0)
    # Each triangle's bounding box (corners without a state left out; NaN if all are).
    low, high = np.fmin.reduce(corners, axis=1), np.fmax.reduce(corners, axis=1)
    doubtful = np.zeros(len(targets), bool)
    odd = np.flatnonzero(np.isfinite(low).all(axis=1) & (~has | grid.snapped[vertices].any(1)))
    if odd.size:  # twice the triangle's size about it
        size = (high - low)[odd]
        doubtful[_in_boxes(low[odd] - size, high[odd] + size, targets)[1]] = True
    cand = np.flatnonzero(has)
    reach = (band + EDGE * (high - low).max(axis=1))[cand, None]
    tri, owner = _in_boxes(low[cand] - reach, high[cand] + reach, targets)
    tri = cand[tri]
    a, b, c = (corners[tri, k] for k in range(3))
    p = targets[owner]
    area = _cross(b - a, c - a)
    with np.errstate(divide="ignore", invalid="ignore"):
        weights = np.stack([_cross(c - b, p - b), _cross(a - c, p - c), _cross(b - a, p - a)], 1)
        weights /= area[:, None]  # barycentric coordinates (P, 3)
        # The distance to the triangle is at least that to the line of the farthest edge
        # it is outside of (the height over that edge times minus its coordinate).
        lengths = np.linalg.norm(np.stack([c - b, a - c, b - a], axis=1), axis=2)
        outside = np.max(-weights * np.abs(area)[:, None] / lengths, axis=1)
    inside = (area != 0) & (weights >= -EDGE).all(axis=1)
    # Near a fold, also from inside the folded triangle next to the target (halfway from
    # its closest corner or edge to its centre): the solutions there, if any, may lie
    # beyond the grid's image.
    beside = ~inside & fold[tri] & (outside <= band[tri])
    weights[beside] = np.maximum(weights[beside], 0.0)
    weights[beside] /= weights[beside].sum(axis=1, keepdims=True)
    weights[beside] = 0.5 * weights[beside] + 0.5 / 3
    use = inside | beside
    tri, owner, weights, optional = tri[use], owner[use], weights[use], fold[tri[use]]
    theta = grid.step * np.einsum("pk,pkc->cp", weights, offsets[tri])
    lag = np.einsum("pk,pkn->np", weights, grid.lag[vertices[tri]])
    if len(lag) > n_rod:
        lag[n_rod:] += theta
    return owner, theta, lag, optional, doubtful


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
