"""Final states: the record of N configurations' states, the last check of the states
reached at full load, their poses and the optional search for other stable states."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from design.equilibrium import settings
from design.equilibrium.drive import drive
from design.equilibrium.fall import _fall
from design.equilibrium.kernels import _initial
from design.equilibrium.newton import _check, _Checks, _newton
from design.equilibrium.stability import _columns, _norm, _scale, _stable
from design.model import RingPairModel


def _commands(theta1: ArrayLike, theta2: ArrayLike) -> np.ndarray:
    t1, t2 = np.broadcast_arrays(
        np.asarray(theta1, float).ravel(), np.asarray(theta2, float).ravel()
    )
    return np.vstack([t1, t2])


@dataclass(frozen=True)
class Equilibria:
    """Steady states of N configurations. Rows without a state hold NaN in every pose array.

    command : shape (N, 2), ring angles commanded at the base (theta1 distal, theta2). [rad]
    tip_angles : shape (N, 2), ring angles at the tip (differ with torsion/hysteresis). [rad]
    position : shape (N, 3), rod tip (proximal ring centre), base frame. [m]
    tangent : shape (N, 3), unit tip tangent, base frame. [-]
    frame : shape (N, 3, 3), tip frame, columns (tangent, y_tip, z_tip), base frame. [-]
    unknowns : shape (N, n), the model's unknowns x at equilibrium. [SI]
    converged : shape (N,), a state was found (residual below TOLERANCE).
    stable : shape (N,), converged and stable (every returned state is).
    residual : shape (N,), infinity norm of the final residual. [m or rad]
    snapped : shape (N,), the robot jumped to another branch on its way here (a fold of the
        load ramp, or along a path).
    multistable : shape (N,), another stable state exists at the same command (only looked
        for on request; False otherwise).
    failure : shape (N,), why a row has no state ('' where it has one).
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
    multistable: np.ndarray
    failure: np.ndarray

    def __len__(self) -> int:
        return len(self.converged)


def _finish(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    reached: np.ndarray,
    snapped: np.ndarray,
    failure: np.ndarray,
    checks: _Checks,
    multistable: bool = False,
    neighbours: np.ndarray | None = None,
) -> Equilibria:
    """Check the states reached at full load (an unstable one falls once more), poses, and
    the optional search for other stable states (continued to ``neighbours``:
    :func:`_other_stable_states`)."""
    n_cols = command.shape[1]
    x = np.where(reached, x, np.nan)
    todo = np.flatnonzero(~checks.done)
    if todo.size or checks.outs is None:
        todo = todo if checks.outs is not None else np.arange(n_cols)
        checks.put(todo, _check(model, _columns(params, todo), command[:, todo], x[:, todo])[2])
    outs = checks.outs
    assert outs is not None
    stable = (
        reached & (np.max(np.abs(outs[0]), axis=0) < settings.TOLERANCE) & _stable(model, outs[1])
    )
    fall = np.flatnonzero(reached & ~stable)
    if fall.size:
        fallen, found, contact = _fall(
            model,
            _columns(params, fall),
            command[:, fall],
            x[:, fall],
            np.ones(fall.size),
            checks,
            fall,
        )
        x[:, fall] = np.where(found, fallen, np.nan)
        snapped[fall[found]] = True
        stable[fall] = found
        failure[fall[~found]] = np.where(
            contact[~found], settings.FAILURES["pulled"], settings.FAILURES["unstable"]
        )
    failure[~stable & (failure == "")] = settings.FAILURES["diverged"]
    touching = stable & ~(outs[5][0] >= 0)
    stable &= ~touching
    failure[touching] = settings.FAILURES["contact"]
    multi = np.zeros(n_cols, bool)
    if multistable and stable.any():
        multi = _other_stable_states(model, params, command, x, stable, neighbours)[0]
    r, _, position, frame, angles, _ = outs
    nan = np.where(stable, 1.0, np.nan)
    frames = frame.T.reshape(n_cols, 3, 3).transpose(0, 2, 1) * nan[:, None, None]
    return Equilibria(
        command=command.T.copy(),
        tip_angles=angles.T * nan[:, None],
        position=position.T * nan[:, None],
        tangent=frames[:, :, 0].copy(),
        frame=frames,
        unknowns=x.T * nan[:, None],
        converged=stable.copy(),
        stable=stable,
        residual=np.max(np.abs(r), axis=0),
        snapped=snapped & stable,
        multistable=multi,
        failure=np.where(stable, "", failure).astype(object),
    )


def _mirror(model: RingPairModel, x: np.ndarray) -> np.ndarray:
    """The unknowns of the state turned by pi about the robot's axis (a start)."""
    m = x.copy()
    if model.linear_rod:
        m[:4] = -x[:4]
    else:
        m[[1, 2, 4, 5]] = -x[[1, 2, 4, 5]]
    return m


def _other_stable_states(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    stable: np.ndarray,
    neighbours: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Whether another stable state exists at each command, and the one found (n, N; NaN
    where none): Newton (then, if it lands on
    an unstable equilibrium, a fall from there) from the straight robot at full load, from
    the mirror image of the state and, with torsion, from the state with the rings' lags
    mirrored. With ``neighbours`` (shape (N, k), the columns next to each, -1 for none)
    another state found at a command is driven to its neighbours (:func:`drive`: sub-steps
    of Newton, never across a fold), until none is new:
    Newton from a far start lands in whichever basin its path meets, so a change of the
    design by a part in 10^8 can move it, while a branch found anywhere on a grid is
    followed over the grid."""
    n_cols = command.shape[1]
    starts = [_initial(model, params, command), _mirror(model, x)]
    if model.n_unknowns > model.n_rod:
        lagged = x.copy()
        lagged[model.n_rod :] = 2 * command - x[model.n_rod :]
        starts.append(lagged)
    scale = _scale(model, params, n_cols)
    found = np.zeros(n_cols, bool)
    others = np.full_like(x, np.nan)
    for start in starts:
        todo = np.flatnonzero(stable & ~found)
        if todo.size == 0:
            break
        _search(model, params, command, x, scale, todo, start[:, todo], found, others)
    fresh = found.copy()
    while neighbours is not None and fresh.any():
        before = found.copy()
        for j in range(neighbours.shape[1]):
            near = neighbours[:, j]
            todo = np.flatnonzero(stable & ~found & (near >= 0) & fresh[near])
            if todo.size == 0:
                continue
            src = near[todo]
            # Driven from the neighbour's command the short way round (periodic in 2 pi).
            turn = np.pi - np.mod(np.pi - (command[:, todo] - command[:, src]), 2 * np.pi)
            driven, ok = drive(model, _columns(params, src), others[:, src], command[:, src],
                               command[:, src] + turn)  # fmt: skip
            if model.n_unknowns > model.n_rod:  # its ring angles at this node's command
                driven[model.n_rod :] += command[:, todo] - (command[:, src] + turn)
            converged, good, _ = _check(
                model, _columns(params, todo), command[:, todo], np.nan_to_num(driven)
            )
            ok &= (
                converged & good & (_norm(driven - x[:, todo], scale[:, todo]) > settings.DISTINCT)
            )
            found[todo[ok]] = True
            others[:, todo[ok]] = driven[:, ok]
        fresh = found & ~before
    return found, others


def _search(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    scale: np.ndarray,
    todo: np.ndarray,
    start: np.ndarray,
    found: np.ndarray,
    others: np.ndarray,
) -> None:
    """One start per column ``todo``: Newton, a fall where it lands on an unstable
    equilibrium; a stable state distinct from x is marked in ``found`` and kept in
    ``others`` (both updated in place)."""
    p, c, ones = _columns(params, todo), command[:, todo], np.ones(todo.size)
    scratch = _Checks(todo.size)
    local = np.arange(todo.size)
    states, converged, good = _newton(model, p, c, start, ones, scratch, local, known=x[:, todo])
    unstable = np.flatnonzero(converged & ~good)
    if unstable.size:
        fallen, ok, _ = _fall(
            model,
            _columns(p, unstable),
            c[:, unstable],
            states[:, unstable],
            ones[unstable],
            scratch,
            unstable,
        )
        states[:, unstable] = fallen
        good[unstable] = ok
    new = good & (_norm(states - x[:, todo], scale[:, todo]) > settings.DISTINCT)
    found[todo[new]] = True
    others[:, todo[new]] = states[:, new]
