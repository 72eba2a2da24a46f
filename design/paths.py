"""Driving the tip along a path: a schedule of ring angles, confirmed by driving it.

Each point of the path is solved for every pair of ring angles that puts the tip there
(:func:`design.steering.steer`). A schedule picks one solution per point so that the
total ring rotation is smallest (dynamic programming over the points, Viterbi's
recursion; a closed path returns to its first choice): consecutive choices differ in each
ring by at most ``max_turn``, since a larger jump between the solutions of neighbouring
points means a switch to another solution branch, where the tip leaves the path on the
way. The schedule is then driven as the robot is (:func:`design.equilibrium.solve_sequence`:
each state continued from the one before, snaps detected), with ``between`` commands
interpolated between points; a move that snaps, or ends off the chosen solution's state,
is struck out and the schedule chosen again, at most MAX_ROUNDS times. The result states how closely
the driven tip follows the path (at the points and between them) and whether anything
snapped.

SI units throughout (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.ellipse import fit_ellipse
from design.equilibrium import solve_equilibria, solve_sequence
from design.model import RingPairModel
from design.steering import REACHED, steer
from design.workspace import angle_grid

MAX_TURN = np.deg2rad(30.0)
"""Largest change of a ring angle between the solutions of neighbouring path points. [rad]"""
BETWEEN = 4
"""Commands interpolated between neighbouring points when the schedule is driven."""
LANDED = 1e-6
"""A driven state lands on its point when its tip is this close (the driven state is the
solution's own unless the drive took another branch). [m]"""
MAX_ROUNDS = 4
"""Times a schedule is chosen again after its drive struck out a step."""
TIE = 1e-3
"""Weight of a move's length in the plane of the two angles, which breaks the ties of the
total rotation (every schedule that turns each ring one way costs the same) towards the
smoothest: without it a schedule may zig-zag between solution branches at no cost."""


def _rim(model: RingPairModel, params: np.ndarray) -> np.ndarray:
    """The tip (y, z) along the rim of the workspace, the loop of parallel rings, every 2
    deg where it has a state, shape (P, 2). [m]"""
    loop = angle_grid(np.deg2rad(2.0))
    eq = solve_equilibria(model, params, loop, loop)
    rim = eq.position[eq.stable, 1:]
    if len(rim) == 0:
        raise ValueError("no configuration of parallel rings has a state: no workspace")
    return rim


def workspace_center(model: RingPairModel, params: np.ndarray) -> tuple[float, float]:
    """The centre of the workspace, where paths are centred unless told: the mean tip (y, z)
    over the rim, the loop of parallel rings (the rest position's (0, 0) without loads
    that bend the robot on their own, e.g. gravity). [m]"""
    y, z = _rim(model, params).mean(axis=0)
    return float(y), float(z)


def largest_ellipse(
    model: RingPairModel, params: np.ndarray, count: int = 48, halvings: int = 7
) -> PathSchedule:
    """The largest ellipse about the workspace's centre, axes along y and z, that the tip
    can be driven around (:attr:`PathSchedule.followed`): the rim's half-extents along y
    and z scaled down by bisection (``halvings`` times; the paper steers "an elliptical
    pattern with the largest attainable bending"). Its schedule. [m]"""
    rim = _rim(model, params)
    center = rim.mean(axis=0)
    semi = (rim.max(axis=0) - rim.min(axis=0)) / 2
    low, high, best = 0.0, 1.0, None
    for k in range(halvings + 1):
        size = high if k == 0 else (low + high) / 2
        schedule = follow(
            model,
            params,
            ellipse(size * semi[0], size * semi[1], count, (center[0], center[1])),
            closed=True,
        )
        if schedule.followed:
            low, best = size, schedule
            if k == 0:
                break
        elif k > 0:
            high = size
    if best is None:
        raise ValueError("no ellipse about the workspace's centre can be followed")
    return best


def circle(radius: float, count: int, center: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """``count`` points (count, 2) on a circle of ``radius`` about ``center`` (y, z), counter-
    clockwise seen from the tip (from +x), starting at +y. [m]"""
    return ellipse(radius, radius, count, center)


def ellipse(
    semi_y: float, semi_z: float, count: int, center: tuple[float, float] = (0.0, 0.0)
) -> np.ndarray:
    """``count`` points (count, 2) on the ellipse with semi-axes ``semi_y`` along y and
    ``semi_z`` along z about ``center``, equally spaced in the parameter, starting at +y. [m]"""
    phi = 2 * np.pi * np.arange(count) / count
    return np.column_stack([center[0] + semi_y * np.cos(phi), center[1] + semi_z * np.sin(phi)])


def line(start: tuple[float, float], end: tuple[float, float], count: int) -> np.ndarray:
    """``count`` points (count, 2) from ``start`` to ``end`` (y, z), both included. [m]"""
    s = np.linspace(0.0, 1.0, count)[:, None]
    return (1 - s) * np.asarray(start, float) + s * np.asarray(end, float)


@dataclass(frozen=True)
class PathSchedule:
    """A schedule of ring angles along a path and what driving it gave.

    points : shape (M, 2), the requested path (y, z). [m]
    closed : the path returns to its first point.
    theta : shape (M, 2), the ring angles at each point, unwrapped (continuous along the
        path, starting in [0, 2 pi)). [rad]
    reached : shape (M,), the chosen solution puts the tip on the point (else it is the
        closest reachable point).
    position : shape (M, 3), the driven tip at each point, base frame. [m]
    error : shape (M,), distance from the driven tip's (y, z) to the point. [m]
    snapped : shape (M,), the drive snapped on the way to this point.
    driven : shape (K, 3), the driven tip at every command (points and those between),
        in order (the first point, then BETWEEN between each pair, then the next point).
    deviation : largest distance of the driven tip from the requested path, over every
        driven command. [m]
    rotation : shape (2,), total rotation of each ring along the schedule. [rad]
    struck : transitions struck out because their drive snapped or landed off its point.
    """

    points: np.ndarray
    closed: bool
    theta: np.ndarray
    reached: np.ndarray
    position: np.ndarray
    error: np.ndarray
    snapped: np.ndarray
    driven: np.ndarray
    deviation: float
    rotation: np.ndarray
    struck: int

    @property
    def followed(self) -> bool:
        """Every point reached, and by the drive (within LANDED), and nothing snapped."""
        return bool(self.reached.all() and np.all(self.error <= LANDED) and not self.snapped.any())


def _wrapped(difference: np.ndarray) -> np.ndarray:
    """Angle differences wrapped to [-pi, pi). [rad]"""
    return np.mod(difference + np.pi, 2 * np.pi) - np.pi


def _choose(
    options: list[np.ndarray], closed: bool, max_turn: float, struck: set
) -> list[int] | None:
    """One option per point (options[i]: (c_i, 2) angles) with the smallest total
    rotation (ties broken by TIE), each move at most ``max_turn`` per ring and not in
    ``struck`` ((i, a, b): option a at point i to b at the next); None if no choice
    passes."""
    m = len(options)
    starts = range(len(options[0])) if closed else [None]
    best: tuple[float, list[int]] | None = None
    for start in starts:
        cost = np.zeros(len(options[0]))
        if start is not None:
            cost[:] = np.inf
            cost[start] = 0.0
        back: list[np.ndarray] = []
        links = list(range(m - 1)) + ([m - 1] if closed else [])
        for i in links:
            j = (i + 1) % m
            turn = np.abs(_wrapped(options[j][None, :, :] - options[i][:, None, :]))
            cost_of = turn.sum(axis=2) + TIE * np.sqrt((turn**2).sum(axis=2))
            move = np.where(turn.max(axis=2) <= max_turn, cost_of, np.inf)
            for a, b in ((a, b) for (k, a, b) in struck if k == i):
                move[a, b] = np.inf
            if j == 0:  # back to the start's own choice
                keep = np.full(len(options[0]), np.inf)
                keep[start] = 0.0
                move = move + keep[None, :]
            total = cost[:, None] + move
            back.append(np.argmin(total, axis=0))
            cost = total.min(axis=0)
        end = int(np.argmin(cost))
        if not np.isfinite(cost[end]) or (best is not None and cost[end] >= best[0]):
            continue
        chain = [end]
        for b in reversed(back):
            chain.append(int(b[chain[-1]]))
        chain.reverse()
        best = (float(cost[end]), chain[:m])
    return None if best is None else best[1]


def _cheapest(options: list[np.ndarray], closed: bool) -> list[int]:
    """The chain of smallest rotation with no limit on the moves (where no smooth one is
    left: the moves as they come)."""
    chain = _choose(options, closed, np.inf, set())
    assert chain is not None  # without limits every chain passes
    return chain


def follow(
    model: RingPairModel,
    params: np.ndarray,
    points: np.ndarray,
    *,
    closed: bool = False,
    max_turn: float = MAX_TURN,
    between: int = BETWEEN,
) -> PathSchedule:
    """The schedule of ring angles that drives the tip along ``points`` (M, 2), (y, z) in
    the base frame [m], with the smallest total ring rotation and no snap (module
    docstring). A point out of reach gets its closest reachable point."""
    params = np.asarray(params, float)
    points = np.atleast_2d(np.asarray(points, float))
    if points.shape[1] != 2 or len(points) < 2 or not np.isfinite(points).all():
        raise ValueError("a path needs at least two finite (y, z) points, shape (M, 2)")
    m = len(points)
    solutions = steer(model, params, points)
    usable = solutions.stable & np.isfinite(solutions.theta).all(axis=1)
    lost = [i + 1 for i in range(m) if not (usable & (solutions.target_index == i)).any()]
    if lost:
        raise ValueError(f"no configuration has a state near path point(s) {lost}")
    mine = [usable & (solutions.target_index == i) for i in range(m)]
    options = [solutions.theta[k] for k in mine]
    reached_option = [solutions.reached[k] for k in mine]
    tip_option = [solutions.position[k, 1:] for k in mine]
    struck: set[tuple[int, int, int]] = set()
    fraction = np.arange(between + 1) / (between + 1)
    for _ in range(MAX_ROUNDS + 1):
        chain = _choose(options, closed, max_turn, struck) or _cheapest(options, closed)
        chosen = np.array([options[i][c] for i, c in enumerate(chain)])
        if closed:
            chosen = np.vstack([chosen, chosen[:1]])
        drive = chosen[0] + np.concatenate(
            [np.zeros((1, 2)), np.cumsum(_wrapped(np.diff(chosen, axis=0)), axis=0)]
        )
        commands = np.vstack(
            [a + fraction[:, None] * (b - a) for a, b in zip(drive[:-1], drive[1:], strict=True)]
            + [drive[-1:]]
        )
        eq = solve_sequence(model, params, commands[:, 0], commands[:, 1])
        ends = np.arange(len(drive)) * (between + 1)  # the commands at the points
        tips = eq.position[ends, 1:]
        order = [*range(m), 0][: len(drive)]
        own = np.array([tip_option[i][chain[i]] for i in order])
        landed = np.linalg.norm(tips - own, axis=1)  # on the chosen solution's own state
        landed = np.where(np.isfinite(landed), landed, np.inf)
        into = np.zeros(len(drive), bool)  # the move into each point snapped
        into[(np.flatnonzero(eq.snapped[1:]) // (between + 1)) + 1] = True
        bad = np.flatnonzero(into | (landed > LANDED))
        bad = bad[bad > 0]
        if bad.size == 0:
            break
        j = int(bad[0])  # the first miss: the later ones follow from it
        i = j - 1
        struck.add((i, chain[i], chain[j % m]))
    error = np.linalg.norm(tips - points[order], axis=1)
    error = np.where(np.isfinite(error), error, np.inf)
    snapped = into[:m].copy()
    if closed:  # the return to the first point
        error[0], snapped[0] = max(error[0], error[m]), into[m]
    error = error[:m]
    driven = eq.position
    return PathSchedule(
        points=points,
        closed=closed,
        theta=drive[:m],
        reached=np.array([reached_option[i][c] for i, c in enumerate(chain)]),
        position=eq.position[ends[:m]],
        error=error,
        snapped=snapped,
        driven=driven,
        deviation=float(np.max(_distance_to_path(driven[:, 1:], points, closed))),
        rotation=np.abs(np.diff(drive, axis=0)).sum(axis=0),
        struck=len(struck),
    )


@dataclass(frozen=True)
class Evaluation:
    """The paper's evaluation of a steered path (sec. "Workspace Evaluation": bi-plane
    tracking of the tip driven around an ellipse), on the driven tip at the path's points.

    max_y, max_z : largest deflection from the straight robot along y and along z. [m]
    mean_deflection : mean distance of the tip from the straight robot's axis. [m]
    rms_to_ellipse : RMS distance of the tip to the ellipse fitted to it
        (:func:`design.ellipse.fit_ellipse`). [m]
    """

    max_y: float
    max_z: float
    mean_deflection: float
    rms_to_ellipse: float


def evaluate(schedule: PathSchedule) -> Evaluation:
    """The paper's numbers for a driven path (:class:`Evaluation`)."""
    tip = schedule.position[:, 1:]
    tip = tip[np.isfinite(tip).all(axis=1)]
    rms = np.nan
    if len(tip) >= 5:
        rms = float(np.sqrt(np.mean(fit_ellipse(tip).distance(tip) ** 2)))
    return Evaluation(
        max_y=float(np.abs(tip[:, 0]).max()),
        max_z=float(np.abs(tip[:, 1]).max()),
        mean_deflection=float(np.linalg.norm(tip, axis=1).mean()),
        rms_to_ellipse=rms,
    )


def _distance_to_path(tips: np.ndarray, points: np.ndarray, closed: bool) -> np.ndarray:
    """Distance of each tip (K, 2) to the polyline through ``points`` (M, 2) (closed: back to
    the first); inf where a tip is not finite. [m]"""
    ends = np.vstack([points, points[:1]]) if closed else points
    a, b = ends[:-1], ends[1:]
    d = b - a
    length2 = np.maximum((d * d).sum(axis=1), 1e-300)
    s = np.clip(((tips[:, None, :] - a[None]) * d[None]).sum(axis=2) / length2, 0.0, 1.0)
    nearest = a[None] + s[:, :, None] * d[None]
    out = np.linalg.norm(tips[:, None, :] - nearest, axis=2).min(axis=1)
    return np.where(np.isfinite(out), out, np.inf)


__all__ = ["REACHED", "PathSchedule", "circle", "ellipse", "follow", "largest_ellipse", "line"]
