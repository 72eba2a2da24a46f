"""Equilibrium of the ring-pair robot: Newton's method, in batch or along a command path.

The magnetic wrench depends on the tip pose, so the steady state solves r(x) = 0
(:mod:`design.model`). For N independent configurations a fixed number of Newton steps
from the straight robot is compiled into one function and mapped over the batch;
configurations whose residual is not below tolerance afterwards are re-solved by load
continuation (all loads ramped from zero), and any still unconverged are flagged and
returned as NaN. Along an ordered command path (:func:`solve_sequence`) each state starts
from the previous one, so the robot follows its branch of equilibria as a real one does:
friction play (``hysteresis``) acts on the commands, and a jump to another branch
(snap-through of a lagging ring) is detected and flagged.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from design.compiled import BufferEvaluator, compile_function, evaluate_columns
from design.friction import play
from design.model import RingPairModel
from design.parameters import index
from design.params import Design

NEWTON_STEPS = 6
TOLERANCE = 1e-10
"""Convergence: infinity norm of the scaled residual below this. [m or rad]"""
CHUNK = 65536
GRAIN = 1024
THREADS = 2
CONTINUATION_STEPS = (4, 16, 64)
SUBSTEP = np.deg2rad(1.0)
"""Largest command increment per solve along a path. [rad]"""
SNAP_LAG_JUMP = 0.1
"""A change of a ring's lag (tip angle - command) larger than this within one sub-step is a
jump to another branch of equilibria (snap-through). [rad]"""
MAX_STRIDE = 4
SMOOTH_LAG_CHANGE = 0.02
"""Where the lags change by less than this per solve, the path is plainly smooth and is
followed in strides of up to MAX_STRIDE sub-steps; any larger change, instability or
failure sends it back to single sub-steps, where snaps are judged. [rad]"""
SETTLE_ANGLE = 0.05
"""Perturbation of the tip angles when looking for the state an unstable one falls into. [rad]"""
SETTLE_RELAXATION = 60
"""Downhill relaxation steps before Newton when settling from an unstable state."""
ENTRY_STEPS = 16
"""Load steps in which a driven robot is brought into its loads at the first command."""
INLINE_LIMIT = 4000
"""Residuals cheaper than this many operations are inlined into the unrolled Newton steps;
costlier ones are called (smaller C code, faster compilation)."""


@dataclass(frozen=True)
class Equilibria:
    """Steady states of N configurations. Unconverged rows hold NaN in every pose array.

    command : shape (N, 2), ring angles commanded at the base (theta1 distal, theta2). [rad]
    tip_angles : shape (N, 2), ring angles at the tip (differ with torsion/hysteresis). [rad]
    position : shape (N, 3), rod tip (proximal ring centre), base frame. [m]
    tangent : shape (N, 3), unit tip tangent, base frame. [-]
    frame : shape (N, 3, 3), tip frame, columns (tangent, y_tip, z_tip), base frame. [-]
    unknowns : shape (N, n), the model's unknowns x at equilibrium. [SI]
    converged : shape (N,), residual below TOLERANCE.
    stable : shape (N,), converged and the equilibrium is stable.
    residual : shape (N,), infinity norm of the final residual. [m or rad]
    snapped : shape (N,), along a path: the robot jumped to another branch on its way here.
    """

    command: np.ndarray
    tip_angles: np.ndarray
    position: np.ndarray
    tangent: np.ndarray
    frame: np.ndarray
    unknowns: np.ndarray
    converged: np.ndarray
    stable: np.ndarray
    residual: np.ndarray
    snapped: np.ndarray

    def __len__(self) -> int:
        return len(self.converged)


@lru_cache(maxsize=16)
def newton_function(model: RingPairModel) -> ca.Function:
    """Compiled single-configuration solver: (x0, command, params) ->
    (x, |r|_inf, stability indicator, position, frame (9, column-major), tip angles)."""
    inline = model.residual.n_instructions() < INLINE_LIMIT
    sym: Any = ca.SX.sym if inline else ca.MX.sym
    x0: Any = sym("x0", model.n_unknowns)
    command: Any = sym("command", 2)
    prm: Any = sym("params", model.residual.size1_in(2))
    x = x0
    for _ in range(NEWTON_STEPS):
        r, jac = model.residual(x, command, prm)
        x = x - ca.solve(jac, r) if inline else x - ca.solve(jac, r, "qr")
    r, _ = model.residual(x, command, prm)
    indicator = model.stability(x, command, prm)
    position, frame, angles = model.pose(x, command, prm)
    fn = ca.Function(
        "newton",
        [x0, command, prm],
        [x, ca.norm_inf(r), indicator, position, ca.reshape(frame, 9, 1), angles],
    )
    return compile_function(fn)


@lru_cache(maxsize=128)
def _mapped(model: RingPairModel, size: int) -> ca.Function:
    return newton_function(model).map(size, "thread", THREADS)


def _chunked(function: Any, args: list[np.ndarray], n: int) -> list[np.ndarray]:
    """Evaluate ``function(size)`` (a mapped CasADi function of ``size`` columns) on the
    columns of ``args`` in chunks of CHUNK; the last chunk is padded to a power of two
    below GRAIN columns and to a multiple of GRAIN above (few distinct map sizes, at most
    half the work wasted: a path's single configurations must not pay for GRAIN).
    Returns (rows, n) outputs."""
    outs: list[list[np.ndarray]] = []
    for start in range(0, n, CHUNK):
        stop = min(start + CHUNK, n)
        count = stop - start
        size = min(CHUNK, -(-count // GRAIN) * GRAIN, 1 << (count - 1).bit_length())
        pad = size - (stop - start)
        chunk = [a[:, start:stop] for a in args]
        if pad:
            chunk = [np.pad(a, ((0, 0), (0, pad)), mode="edge") for a in chunk]
        results = evaluate_columns(function(size), chunk)
        outs = outs or [[] for _ in results]
        for acc, out in zip(outs, results, strict=True):
            acc.append(out[:, : stop - start])
    return [np.concatenate(acc, axis=1) for acc in outs]


def _columns(params: np.ndarray, n: int) -> np.ndarray:
    """params (k,) shared by all columns, or (k, n) one per column -> (k, n)."""
    return np.broadcast_to(params[:, None], (params.size, n)) if params.ndim == 1 else params


def _run(
    model: RingPairModel, x0: np.ndarray, command: np.ndarray, params: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Run the compiled solver on columns (x0, command, params).

    params : shape (n,) shared by all columns, or (n, N) one per column.
    """
    n = command.shape[1]
    args = [x0, command, _columns(params, n)]
    return tuple(_chunked(lambda size: _mapped(model, size), args, n))


@lru_cache(maxsize=128)
def _mapped_initial(model: RingPairModel, size: int) -> ca.Function:
    return model.initial.map(size)


def _initial(model: RingPairModel, command: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Newton's start: the straight robot; for the large-deflection rod the prediction from
    the linear model's equilibrium, and NaN where that did not converge (so that the
    column goes to load continuation rather than start from a coiled rod)."""
    n = command.shape[1]
    x0 = _chunked(lambda size: _mapped_initial(model, size), [command, _columns(params, n)], n)[0]
    if model.predictor is None:
        return x0
    x_lin, res = _solve_columns(model.linear(), params, command)[:2]
    good = res[0] < TOLERANCE
    x0[:] = np.nan
    if good.any():
        prm = params if params.ndim == 1 else params[:, good]
        predict = model.predictor.map(int(good.sum()))
        x0[:, good] = np.asarray(predict(x_lin[:, good], command[:, good], prm))
    return x0


def _solve_columns(
    model: RingPairModel, params: np.ndarray, command: np.ndarray
) -> list[np.ndarray]:
    """Newton from the straight robot, then load continuation for what did not converge.

    params : shape (n,) shared by all columns, or (n, N) one per column. [SI]
    """
    outs = list(_run(model, _initial(model, command, params), command, params))
    bad = ~(outs[1][0] < TOLERANCE)
    scale = index("load_scale")
    for steps in CONTINUATION_STEPS:
        idx = np.flatnonzero(bad)
        if idx.size == 0:
            break
        sub = command[:, idx]
        full = params[:, idx] if params.ndim == 2 else np.repeat(params[:, None], idx.size, 1)
        prm = full.copy()
        xc = None
        for lam in np.linspace(0.0, 1.0, steps + 1)[1:]:
            prm[scale] = lam * full[scale]
            if xc is None:
                xc = _initial(model, sub, prm)
            out = _run(model, xc, sub, prm)
            xc = np.where(np.isfinite(out[0]), out[0], xc)
        for arr, new in zip(outs, out, strict=True):
            arr[:, idx] = new
        bad = ~(outs[1][0] < TOLERANCE)
    return outs


def _stable(out: list[np.ndarray]) -> bool:
    """Converged and stable, for one configuration's solver outputs."""
    return bool(out[1][0] < TOLERANCE and out[2].min() > 0)


def _equilibria(
    command: np.ndarray, outs: list[np.ndarray], snapped: np.ndarray | None = None
) -> Equilibria:
    x, res, indicator, pos, frame, angles = outs
    n = command.shape[1]
    converged = res[0] < TOLERANCE
    stable = converged & np.all(indicator > 0, axis=0)
    nan = np.where(converged, 1.0, np.nan)
    frames = frame.T.reshape(n, 3, 3).transpose(0, 2, 1) * nan[:, None, None]
    return Equilibria(
        command=command.T.copy(),
        tip_angles=angles.T * nan[:, None],
        position=pos.T * nan[:, None],
        tangent=frames[:, :, 0].copy(),
        frame=frames,
        unknowns=x.T * nan[:, None],
        converged=converged,
        stable=stable,
        residual=res[0].copy(),
        snapped=np.zeros(n, bool) if snapped is None else snapped,
    )


def _commands(theta1: ArrayLike, theta2: ArrayLike) -> np.ndarray:
    t1, t2 = np.broadcast_arrays(
        np.asarray(theta1, float).ravel(), np.asarray(theta2, float).ravel()
    )
    return np.vstack([t1, t2])


def solve_equilibria(
    model: RingPairModel, params: np.ndarray, theta1: ArrayLike, theta2: ArrayLike
) -> Equilibria:
    """Independent equilibria for commanded ring angles (theta1[i], theta2[i]). [rad]

    Each configuration starts from the straight robot. ``hysteresis`` needs an order, so
    here it is ignored (the commands are taken as reached from the centre of the play);
    use :func:`solve_sequence` for ordered commands.
    params : model parameter vector, shape (n,), from ``model.parameters(design)``. [SI]
    """
    command = _commands(theta1, theta2)
    return _equilibria(command, _solve_columns(model, np.asarray(params, float), command))


@lru_cache(maxsize=128)
def _path_evaluators(model: RingPairModel, thread: int) -> tuple[BufferEvaluator, BufferEvaluator]:
    """The single-configuration Newton solver and residual of ``model`` on reusable buffers,
    one pair per thread (the buffers are not shared between threads)."""
    return BufferEvaluator(newton_function(model)), BufferEvaluator(
        compile_function(model.residual)
    )


def solve_sequence(
    model: RingPairModel, params: np.ndarray, theta1: ArrayLike, theta2: ArrayLike
) -> Equilibria:
    """Equilibria along an ordered path of commanded angles, as the robot is driven. [rad]

    At the first command the robot enters its loads as on a bench (the field brought up):
    every load is ramped from zero in ENTRY_STEPS, each Newton solve starting from the
    previous state, so the robot starts on the branch connected to the straight rod and
    not on whichever equilibrium Newton from the straight robot happens to reach (near a
    strong magnet that can be an unstable one). Each later command is reached in sub-steps
    of at most SUBSTEP in the same way, so the robot stays on its branch. With
    ``hysteresis`` the commands first pass through each transmission's play
    (:func:`design.friction.play`). Where the branch ends (Newton fails
    or the state turns unstable) the robot falls into the nearest stable state (Newton from
    small perturbations), and where that or a plain step changes a ring's lag by more than
    SNAP_LAG_JUMP, ``snapped`` is set for that command (the first command too, if the robot
    cannot start there).
    """
    params = np.asarray(params, float)
    command = _commands(theta1, theta2)
    effective = command
    if "hysteresis" in model.effects:
        width = np.array(
            [params[index("wire_friction_angle")], params[index("catheter_friction_angle")]]
        )
        effective = play(command, width)
    solver, residual = _path_evaluators(model, threading.get_ident())

    def solve(x0: np.ndarray, c: np.ndarray, p: np.ndarray = params) -> list[np.ndarray]:
        return solver.flat(x0, c, p)

    def settle(x: np.ndarray, c: np.ndarray, p: np.ndarray = params) -> list[np.ndarray] | None:
        """The stable state a real robot falls into from an unstable or lost one: from small
        perturbations of x, relax downhill (x <- x - r/2: -r points down the potential for
        these scaled residuals), then polish by Newton; the nearest stable result."""
        n_rod = model.n_unknowns - (2 if "torsion" in model.effects else 0)
        best, best_dist = None, np.inf
        for i in range(model.n_unknowns):
            step = SETTLE_ANGLE if i >= n_rod else 0.01 * max(abs(x[i]), 1e-3)
            for sign in (1.0, -1.0):
                xr = x.copy()
                xr[i] += sign * step
                for _ in range(SETTLE_RELAXATION):
                    xr = xr - 0.5 * residual(xr, c, p)[0].ravel()
                if not np.isfinite(xr).all():
                    continue
                out = solve(xr, c, p)
                dist = np.abs(out[0] - x).max()
                if _stable(out) and dist < best_dist:
                    best, best_dist = out, dist
        return best

    def enter(c: np.ndarray) -> tuple[list[np.ndarray], bool]:
        """The state at the first command ``c`` after the loads are ramped up, and whether
        the robot snapped on the way."""
        p = params.copy()
        jumped = False
        out = None
        for lam in np.linspace(0.0, 1.0, ENTRY_STEPS + 1)[1:]:
            p[scale] = lam * params[scale]
            if out is None:
                out = [o[:, 0] for o in _solve_columns(model, p, c[:, None])]
            else:
                out = solve(out[0], c, p)
            if not _stable(out):
                settled = settle(out[0], c, p) if np.isfinite(out[0]).all() else None
                if settled is None:  # lost the branch: the plain solve at full load
                    plain = [o[:, 0] for o in _solve_columns(model, params, c[:, None])]
                    return (plain if _stable(plain) else settle(plain[0], c) or plain), True
                out, jumped = settled, True
        assert out is not None
        return out, jumped

    scale = index("load_scale")
    snapped = np.zeros(command.shape[1], bool)
    first, snapped[0] = enter(effective[:, 0])
    columns = [first]
    stride = 1
    for k in range(1, command.shape[1]):
        prev = columns[-1]
        a, b = effective[:, k - 1], effective[:, k]
        n_sub = max(1, int(np.ceil(np.abs(b - a).max() / SUBSTEP)))
        path = a[:, None] + np.outer(b - a, np.arange(n_sub + 1) / n_sub)  # (2, n_sub + 1)
        lag = prev[5] - a
        j = 0
        while j < n_sub:
            step = min(stride, n_sub - j)
            c = path[:, j + step]
            out = solve(prev[0], c)
            new_lag = out[5] - c
            stable = _stable(out)
            jump = abs(new_lag - lag).max()
            if step > 1 and not (stable and jump < SMOOTH_LAG_CHANGE):
                stride = 1  # not plainly smooth: look again in single sub-steps
                continue
            if not stable or jump > SNAP_LAG_JUMP:
                snapped[k] = True
                if not stable:
                    settled = settle(out[0] if np.isfinite(out[0]).all() else prev[0], c)
                    if settled is None:
                        settled = [o[:, 0] for o in _solve_columns(model, params, c[:, None])]
                    out = settled
                    new_lag = out[5] - c
            stride = min(2 * stride, MAX_STRIDE) if jump < SMOOTH_LAG_CHANGE / 2 else 1
            prev, lag = out, new_lag
            j += step
        columns.append(prev)
    outs = [np.column_stack([col[i] for col in columns]) for i in range(6)]
    eq = _equilibria(effective, outs, snapped)
    return Equilibria(**{**eq.__dict__, "command": command.T.copy()})


def solve_design(
    design: Design,
    theta1: ArrayLike,
    theta2: ArrayLike,
    model: RingPairModel | None = None,
    ordered: bool = False,
) -> Equilibria:
    """Equilibria of ``design`` (baseline model unless given) for commanded angles. [rad]

    ordered : follow the commands as a path (:func:`solve_sequence`) instead of solving
        each from the straight robot; required for ``hysteresis`` and snap-through.
    """
    model = model or RingPairModel()
    solve = solve_sequence if ordered else solve_equilibria
    return solve(model, model.parameters(design), theta1, theta2)
