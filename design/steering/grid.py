"""The forward map (the state's tip and its exact derivative in the ring angles), solved
on a grid of ring angles, and the grid's piecewise-linear map inverted for starts."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from design.compiled import compile_function
from design.equilibrium import Equilibria, kernels, solve_equilibria
from design.model import RingPairModel
from design.registry import index
from design.steering.settings import EDGE, FOLD_BAND
from design.workspace import angle_grid


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
