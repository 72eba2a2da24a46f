"""Driven paths: states continued from the state before as the commands change along
one ordered path with falls and snaps (:func:`solve_sequence`; the batch form without
falls is :func:`design.equilibrium.drive.drive`)."""

from __future__ import annotations

import math
import threading
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from design.compiled import BufferEvaluator
from design.equilibrium import settings
from design.equilibrium.fall import _fall
from design.equilibrium.finish import Equilibria, _commands, _finish
from design.equilibrium.kernels import kernels
from design.equilibrium.newton import _Checks
from design.equilibrium.ramp import _ramp
from design.equilibrium.stability import _fold_free
from design.friction import play
from design.model import RingPairModel
from design.registry import index


@lru_cache(maxsize=128)
def _path_evaluator(model: RingPairModel, thread: int) -> BufferEvaluator:
    """The path's Newton corrections of ``model`` (``corrections``) on reusable buffers,
    one per thread (the buffers are not shared between threads)."""
    return BufferEvaluator(kernels(model).corrections)


def solve_sequence(
    model: RingPairModel, params: np.ndarray, theta1: ArrayLike, theta2: ArrayLike
) -> Equilibria:
    """Equilibria along an ordered path of commanded angles, as the robot is driven. [rad]

    ``params``: shape (k,), or one column per command (k, N) where the set-up changes
    along the path (a moved magnet, :mod:`design.moving`): between two commands the
    parameters then change linearly with the sub-steps, so the changes between listed
    commands must be small (the caller refines the path).

    The first command's state is that of the configuration on its own (the load ramp of
    :func:`solve_equilibria`: the robot enters its loads as on a bench). Each later command
    is reached in sub-steps of at most SUBSTEP, each Newton solve starting from the
    previous state, so the robot stays on its branch. With ``hysteresis`` the commands
    first pass through each transmission's play (:func:`design.friction.play`). Where the
    branch ends (Newton stops contracting or the state crosses a fold) the robot falls into
    the stable state it relaxes to, and where that or a plain step changes a ring's lag by
    more than SNAP_LAG_JUMP, ``snapped`` is set for that command.
    """
    params = np.asarray(params, float)
    command = _commands(theta1, theta2)

    def column(k: int) -> np.ndarray:
        return params[:, k] if params.ndim == 2 else params

    effective = command
    if "hysteresis" in model.effects:
        first = column(0)
        width = np.array(
            [first[index("wire_friction_angle")], first[index("catheter_friction_angle")]]
        )
        effective = play(command, width)
    corrections = _path_evaluator(model, threading.get_ident())
    scale = model.unknown_scale(column(0))
    corrections.fix(2, column(0))  # the same along the whole path unless it changes
    corrections.fix(3, scale)
    n_rod = model.n_rod
    torsion = model.n_unknowns > n_rod
    step_tolerance = float(settings.step_tolerance(np.ones(1))[0])

    def newton(x0: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, bool]:
        """Newton from x0 at the command c; (state, converged on the stable side)."""
        x, last, k = x0, math.inf, 0
        while True:
            # (views of the evaluator's buffers, and plain floats: this loop runs ~10^5
            # times a fit)
            states, sizes, monitors, clearances = corrections.views(x, c)
            for j, (size, largest, residual, total) in enumerate(zip(*sizes.tolist(), strict=True)):
                finite = math.isfinite(size) and math.isfinite(total)
                if not finite or (k > 0 and size > settings.CONTRACTION * last):
                    return x, False
                if largest < step_tolerance or residual < settings.TOLERANCE:
                    ok = _fold_free(model, monitors[:, j : j + 1])[0] and clearances[0, j] >= 0
                    return states[:, j].copy(), bool(ok)
                x, last, k = states[:, j].copy(), size, k + 1
                if k == settings.MAX_CORRECTIONS + 2:
                    return x, False

    def lags(x: np.ndarray, c: np.ndarray) -> np.ndarray:
        return x[n_rod:] - c if torsion else np.zeros(2)

    def fall(x: np.ndarray, c: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, str]:
        """The state the robot falls into from x at c (parameters p), or NaN and why not."""
        fallen, found, contact = _fall(
            model, p, c[:, None], x[:, None], np.ones(1), _Checks(1), np.arange(1)
        )
        if found[0]:
            return fallen[:, 0], ""
        return np.full_like(x, np.nan), settings.FAILURES["pulled" if contact[0] else "unstable"]

    def alone(c: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, bool, str]:
        """The state at c (parameters p) as a configuration on its own: (state or NaN,
        snapped, failure)."""
        x, ok, snap, why = _ramp(model, p, c[:, None], _Checks(1))
        return (x[:, 0] if ok[0] else np.full(model.n_unknowns, np.nan)), bool(snap[0]), why[0]

    snapped = np.zeros(command.shape[1], bool)
    failure = np.full(command.shape[1], "", dtype=object)
    first, snapped[0], failure[0] = alone(effective[:, 0], column(0))
    states = [first]
    stride = 1
    for k in range(1, command.shape[1]):
        prev = states[-1]
        a, b = effective[:, k - 1], effective[:, k]
        pa, pb = column(k - 1), column(k)
        if not np.isfinite(prev).all():  # lost: start again as a configuration on its own
            x, snapped[k], failure[k] = alone(b, pb)
            states.append(x)
            continue
        n_sub = max(1, int(np.ceil(np.abs(b - a).max() / settings.SUBSTEP)))
        path = a[:, None] + np.outer(b - a, np.arange(n_sub + 1) / n_sub)  # (2, n_sub + 1)
        lag = lags(prev, a)
        j = 0
        while j < n_sub:
            step = min(stride, n_sub - j)
            c = path[:, j + step]
            p = pa + (pb - pa) * ((j + step) / n_sub) if params.ndim == 2 else params
            if params.ndim == 2:
                corrections.fix(2, p)
            out, ok = newton(prev, c)
            jump = float(np.abs(lags(out, c) - lag).max()) if ok else np.inf
            if step > 1 and not (ok and jump < settings.SMOOTH_LAG_CHANGE):
                stride = 1  # not plainly smooth: look again in single sub-steps
                continue
            if not ok:
                snapped[k] = True
                out, why = fall(out if np.isfinite(out).all() else prev, c, p)
                if why:
                    prev = out
                    failure[k] = why
                    break
                jump = float(np.abs(lags(out, c) - lag).max())
            if jump > settings.SNAP_LAG_JUMP:
                snapped[k] = True
            stride = (
                min(2 * stride, settings.MAX_STRIDE) if jump < settings.SMOOTH_LAG_CHANGE / 2 else 1
            )
            prev, lag = out, lags(out, c)
            j += step
        states.append(prev)
    x = np.column_stack(states)
    reached = np.isfinite(x).all(axis=0)
    eq = _finish(model, params, effective, x, reached, snapped, failure, _Checks(x.shape[1]))
    return Equilibria(**{**eq.__dict__, "command": command.T.copy()})
