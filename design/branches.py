"""Branch diagrams: the equilibria of one configuration as its loads are brought up.

The state (:mod:`design.equilibrium`) is the stable equilibrium reached by ramping every
load from zero (load factor lambda from 0 to 1) with the rings held. A branch diagram
shows that path beside the other equilibria at the same command: those Newton's method
finds at full load from the straight robot, from the mirror image of the state and, with
torsion, from the rings' lags mirrored (stable or not), each followed back down in lambda
by natural-parameter continuation until it ends in a fold. SI units are used for all
inputs and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from design.equilibrium import (
    DISTINCT,
    TOLERANCE,
    Equilibria,
    kernels,
    solve_equilibria,
    stable_states,
)
from design.model import RingPairModel
from design.registry import index

HALVINGS = 6
"""Times a continuation step in lambda is halved before the branch is taken to end."""
JUMP = 4.0
MIN_MOVE = 0.02
"""A continuation step may change the unknowns (over their scale) by at most JUMP times
the step before, or MIN_MOVE. [-]"""


@dataclass(frozen=True)
class Branch:
    """One branch of equilibria at the load factors of a diagram (NaN where it does not
    exist).

    load_factor : shape (k,), lambda. [-]
    unknowns : shape (k, n), the model's unknowns. [SI]
    position : shape (k, 3), rod tip, base frame. [m]
    tip_angles : shape (k, 2), ring angles at the tip. [rad]
    stable : shape (k,), a stable equilibrium there.
    """

    load_factor: np.ndarray
    unknowns: np.ndarray
    position: np.ndarray
    tip_angles: np.ndarray
    stable: np.ndarray


def scaled_loads(model: RingPairModel, params: np.ndarray, load_factors: ArrayLike) -> np.ndarray:
    """The parameter vector once per load factor, every load scaled by it, shape (k, K)."""
    lam = np.asarray(load_factors, float)
    columns = np.repeat(np.asarray(params, float)[:, None], lam.size, axis=1)
    columns[index("load_scale")] *= lam
    return columns


def load_path(
    model: RingPairModel, params: np.ndarray, command: ArrayLike, load_factors: ArrayLike
) -> Equilibria:
    """The state at each load factor: the configuration (``command`` (2,) [rad]) with its
    loads ramped from zero to lambda, as the robot reaches it when a magnet is brought
    up. One batch; row i belongs to ``load_factors[i]``."""
    columns = scaled_loads(model, params, load_factors)
    c = np.broadcast_to(np.asarray(command, float)[:, None], (2, columns.shape[1]))
    return solve_equilibria(model, columns, c[0], c[1])


def _newton(model, params, command, x, iterations=30):
    """Plain Newton at one load (no ramp, no stability test): (x, converged)."""
    kern = kernels(model)
    for _ in range(iterations):
        r, step, *_ = kern.run("newton", [x[:, None], command[:, None], np.ones((1, 1))], params)
        if not np.isfinite(step).all():
            return x, False
        if np.abs(r).max() < TOLERANCE:
            return x, True
        x = x - step[:, 0]
    return x, False


def _follow(model, params, command, x, load_factors) -> np.ndarray:
    """Continue the equilibrium x at load_factors[0] through the others: Newton from the
    last point, a step accepted where it converges no further from the last point than
    JUMP times the step before (else it may have crossed to another branch), the step in
    lambda halved where it is not; NaN past a fold."""
    scale = model.unknown_scale(params)
    out = np.full((load_factors.size, model.n_unknowns), np.nan)
    out[0] = x
    moved = MIN_MOVE
    for k in range(1, load_factors.size):
        lam = load_factors[k - 1]
        y, reached = x, lam
        for _ in range(HALVINGS + 1):
            target = load_factors[k]
            while reached != target:
                z, ok = _newton(model, scaled_loads(model, params, [target])[:, 0], command, y)
                change = np.max(np.abs(z - y) / scale)
                if ok and change <= JUMP * max(moved, MIN_MOVE):
                    y, reached, moved = z, target, change
                    target = load_factors[k]
                elif abs(target - reached) < abs(load_factors[k] - lam) / 2**HALVINGS:
                    return out  # the branch ends here (a fold)
                else:
                    target = reached + (target - reached) / 2
            break
        out[k] = x = y
    return out


def branches(
    model: RingPairModel, params: np.ndarray, command: ArrayLike, load_factors: ArrayLike
) -> tuple[Equilibria, list[Branch]]:
    """The branch diagram of one configuration: (the state at each load factor, the other
    branches of equilibria found at full load, each followed down in lambda).

    command : (theta1, theta2) at the base. [rad]
    load_factors : increasing, ending at 1. [-]
    """
    params = np.asarray(params, float)
    command = np.asarray(command, float)
    lam = np.asarray(load_factors, float)
    path = load_path(model, params, command, lam)
    found = [] if not path.stable[-1] else [path.unknowns[-1]]
    scale = model.unknown_scale(params)
    straight = np.zeros(model.n_unknowns)
    if model.n_unknowns > model.n_rod:
        straight[model.n_rod :] = command
    starts = [straight]
    if path.stable[-1]:
        x = path.unknowns[-1]
        mirror = x.copy()
        rod = slice(0, 4) if model.linear_rod else [1, 2, 4, 5]
        mirror[rod] = -x[rod]
        starts.append(mirror)
        if model.n_unknowns > model.n_rod:
            lagged = x.copy()
            lagged[model.n_rod :] = 2 * command - x[model.n_rod :]
            starts.append(lagged)
    full = scaled_loads(model, params, [1.0])[:, 0]
    for start in starts:
        x, ok = _newton(model, full, command, start)
        if ok and all(np.max(np.abs(x - f) / scale) > DISTINCT for f in found):
            found.append(x)
    down = lam[::-1]
    out = []
    for x in found[1:] if path.stable[-1] else found:
        unknowns = _follow(model, params, command, x, down)[::-1]
        out.append(_branch(model, params, command, lam, unknowns))
    return path, out


def _branch(model, params, command, lam, unknowns) -> Branch:
    exists = np.isfinite(unknowns).all(axis=1)
    columns = scaled_loads(model, params, lam)
    position = np.full((lam.size, 3), np.nan)
    angles = np.full((lam.size, 2), np.nan)
    stable = np.zeros(lam.size, bool)
    for k in np.flatnonzero(exists):
        p, _, a = model.pose(unknowns[k], command, columns[:, k])
        position[k], angles[k] = np.asarray(p).ravel(), np.asarray(a).ravel()
    if exists.any():
        c = np.repeat(command[:, None], exists.sum(), axis=1)
        stable[exists] = stable_states(model, columns[:, exists], unknowns[exists].T, c)
    return Branch(lam.copy(), unknowns, position, angles, stable)
