"""Tip pose along the equilibrium and its exact derivatives: the implicit function theorem.

At an equilibrium r(x, c, p) = 0 of :class:`design.model.RingPairModel` the unknowns move
with the parameters as dx/dp = -(dr/dx)^-1 dr/dp, so the tip position and ring angles
y(x, c, p) of ``model.pose`` move as dy/dp = dy/dx dx/dp + dy/dp|_x (and likewise with the
commands c). One CasADi function, compiled once per model and mapped over a batch
(:func:`sensitivity_function`), returns y and these total derivatives. With
``hysteresis`` the commands reach the rings through the friction play, so the friction
angles w act through the commands: dy/dw = dy/dc dc/dw, with dc/dw from the same play
operator on symbols (:func:`design.friction.play_step`). SI units are used for all
inputs and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, lru_cache
from typing import Literal

import casadi as ca
import numpy as np

from design.compiled import ColumnEvaluator, compile_function, map_threads, mapped
from design.equilibrium import Equilibria, kernels, solve_equilibria, solve_sequence
from design.friction import play, play_step
from design.model import RingPairModel, model_for
from design.registry import FITTED, NAMES, index
from optimize.fitting.measurements import Measurements

COMPILE_LIMIT = 12000
"""Sensitivity functions up to this many operations are compiled to C (seconds, once per
machine); larger ones (the exact cylinder field: ~23,000, about 25 s to compile) run in
CasADi's virtual machine, about 10 ms per batch of 60 configurations."""
PATH_INDEPENDENT = frozenset({"hysteresis", "near_field", "gravity"})
"""Effects under which the tip pose is a function of the rings' angles alone (linear rod,
transmissions rigid in torsion, one equilibrium per pair of angles): along a path only the
friction play depends on the order. With ``torsion`` (multistable rings) or
``large_deflection`` the path itself is followed."""


SENSITIVE = FITTED
"""Parameters whose derivatives :func:`sensitivity_function` returns, in this order: the
ones calibration can free (:data:`design.registry.FITTED`)."""


@cache
def sensitivity_function(model: RingPairModel) -> ca.Function:
    """(x, command, params) -> (out, d_out) at an equilibrium x of ``model``, compiled
    when small enough (COMPILE_LIMIT); built once per process and kept for every model
    (a diagnosis screens up to all 32 sets of effects, and building one takes up to 2 s:
    a cache of 16 built most of them again at every screen).

    out : shape (5,), tip position (base frame) [m] and tip ring angles [rad].
    d_out : shape (5, len(SENSITIVE) + 2), total derivatives of ``out`` along the
        equilibrium, by the implicit function theorem, with respect to the parameters of
        SENSITIVE [SI] and then the two commands [rad].
    """
    x = ca.SX.sym("x", model.n_unknowns)
    command = ca.SX.sym("command", 2)
    prm = ca.SX.sym("params", len(NAMES))
    free = ca.vertcat(*[prm[index(n)] for n in SENSITIVE])
    r, dr_dx = model.residual(x, command, prm)
    position, _, angles = model.pose(x, command, prm)
    out = ca.vertcat(position, angles)
    direct = ca.horzcat(ca.jacobian(out, free), ca.jacobian(out, command))
    dx = -ca.solve(dr_dx, ca.horzcat(ca.jacobian(r, free), ca.jacobian(r, command)))
    d_out = direct + ca.jacobian(out, x) @ dx
    fn = ca.Function(
        "sensitivity",
        [x, command, prm],
        [out, ca.densify(d_out)],  # dense: evaluated on flat buffers
        ["x", "command", "params"],
        ["out", "d_out"],
        {"cse": True},
    )
    if fn.n_instructions() > COMPILE_LIMIT:
        return fn
    return compile_function(fn)


def built_model(effects: frozenset[str]) -> RingPairModel:
    """:func:`design.model.model_for` ``effects`` with its compiled solver and sensitivity
    functions built now, in this process (worker processes forked after this inherit
    them instead of each building its own, :mod:`optimize.fitting.workers`)."""
    model = model_for(effects)
    kernels(model)
    sensitivity_function(model)
    return model


def _mapped_sensitivity(model: RingPairModel, size: int) -> ColumnEvaluator:
    return _mapped_on(model, size, map_threads(size))


@lru_cache(maxsize=64)
def _mapped_on(model: RingPairModel, size: int, threads: int) -> ColumnEvaluator:
    """(``threads``: part of the key, as :func:`design.compiled.use_threads` changes it)"""
    return mapped(sensitivity_function(model), size)


def sensitivities(
    model: RingPairModel, params: np.ndarray, unknowns: np.ndarray, command: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Tip position and angles and their total derivatives for a batch of equilibria.

    params : shape (n,). [SI]  unknowns : shape (N, n_unknowns), converged equilibria.
    command : shape (N, 2), the commands the rings received (after any play). [rad]
    Returns out (N, 5) [m, rad] and d_out (N, 5, len(SENSITIVE) + 2). [SI]
    """
    n = len(command)
    k = len(SENSITIVE) + 2
    if n == 0:
        return np.zeros((0, 5)), np.zeros((0, 5, k))
    fn = _mapped_sensitivity(model, n)
    columns = [unknowns.T, command.T, np.broadcast_to(params[:, None], (params.size, n))]
    out, d_out = fn(columns)
    d_out = d_out.reshape(5, n, k).transpose(1, 0, 2)
    out = out.T
    return out, d_out


@lru_cache(maxsize=64)
def _play_jacobian(n: int) -> ca.Function:
    """(commands (2, n), half widths (2,)) -> d(ring angles)/d(half widths), (2n, 2),
    rows in column-major order of the (2, n) angles."""
    u = ca.SX.sym("u", 2, n)
    w = ca.SX.sym("w", 2)
    y = u[:, 0]
    ys = [y]
    for k in range(1, n):
        y = play_step(y, u[:, k], w)
        ys.append(y)
    return ca.Function("play_jacobian", [u, w], [ca.jacobian(ca.vertcat(*ys), w)])


# ------------------------------------------------------------------------- prediction


@dataclass(frozen=True)
class Prediction:
    """The model's view of measured configurations, rows as in the measurements.

    equilibria : the equilibria, row k for measurement k.
    applied : shape (N, 2), the commands the rings received (after friction play). [rad]
    dapplied_dfriction : shape (N, 2, 2) or None, d(applied)/d(wire, catheter friction
        angle) along the path (hysteresis only). [-]
    """

    equilibria: Equilibria
    applied: np.ndarray
    dapplied_dfriction: np.ndarray | None


def predict(
    model: RingPairModel,
    params: np.ndarray,
    m: Measurements,
    ordered: bool | Literal["driven"] | None = None,
) -> Prediction:
    """Simulate the configurations of ``m`` with ``model`` and parameters ``params`` [SI].

    ordered : drive the robot through the rows in acquisition order
        (:meth:`Measurements.order`) as the bench did, with
        :func:`design.equilibrium.solve_sequence`; default: only when the model has
        ``hysteresis``. Otherwise each configuration is solved from the straight robot.
        For models in PATH_INDEPENDENT the order acts only through the friction play, so
        the played commands are solved in one batch (the same equilibria, much faster,
        while the robot has one stable equilibrium per configuration). ``"driven"``:
        follow the path step by step for every model (a robot near a strong magnet can
        be multistable even without twist; then the state depends on the path).
    """
    if ordered is None:
        ordered = "hysteresis" in model.effects
    params = np.asarray(params, float)
    if not ordered:
        eq = solve_equilibria(model, params, m.command[:, 0], m.command[:, 1])
        return Prediction(eq, m.command.copy(), None)
    order = m.order()
    cmd = m.command[order]
    applied_o, d_o = _played(model, params, cmd)
    if model.effects <= PATH_INDEPENDENT and ordered != "driven":
        # the path acts only through the play: one batch solve of the rings' angles
        eq_o = solve_equilibria(model, params, applied_o[:, 0], applied_o[:, 1])
        eq_o = Equilibria(**{**eq_o.__dict__, "command": cmd.copy()})
    else:
        eq_o = solve_sequence(model, params, cmd[:, 0], cmd[:, 1])
    inverse = np.empty_like(order)
    inverse[order] = np.arange(len(order))
    eq = Equilibria(**{k: v[inverse] for k, v in eq_o.__dict__.items()})
    return Prediction(eq, applied_o[inverse], None if d_o is None else d_o[inverse])


def _played(
    model: RingPairModel, params: np.ndarray, cmd: np.ndarray
) -> tuple[np.ndarray, np.ndarray | None]:
    """The commands (N, 2) of an ordered path as the rings receive them, and their
    derivatives (N, 2, 2) with respect to the friction angles (None without hysteresis)."""
    if "hysteresis" not in model.effects:
        return cmd, None
    width = params[[index("wire_friction_angle"), index("catheter_friction_angle")]]
    applied = play(cmd.T, width).T
    jac = np.asarray(_play_jacobian(len(cmd))(cmd.T, width))
    return applied, jac.reshape(len(cmd), 2, 2)


def applied_commands(
    model: RingPairModel,
    params: np.ndarray,
    m: Measurements,
    ordered: bool | Literal["driven"] | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """What :func:`predict` gives the rings, rows as in ``m``: the commands (N, 2) after
    any friction play along the order, and their derivatives (N, 2, 2) with respect to
    the friction angles (None without the play). [rad]"""
    if ordered is None:
        ordered = "hysteresis" in model.effects
    if not ordered:
        return m.command.copy(), None
    order = m.order()
    applied_o, d_o = _played(model, np.asarray(params, float), m.command[order])
    inverse = np.empty_like(order)
    inverse[order] = np.arange(len(order))
    return applied_o[inverse], None if d_o is None else d_o[inverse]


def prediction_sensitivities(
    model: RingPairModel, params: np.ndarray, pred: Prediction
) -> tuple[np.ndarray, np.ndarray]:
    """Tip position/angles (N, 5) and their derivatives (N, 5, len(SENSITIVE)) with
    respect to the parameters of SENSITIVE, friction play included. Rows whose
    equilibrium did not converge are NaN. [SI]"""
    eq = pred.equilibria
    n = len(eq)
    out = np.full((n, 5), np.nan)
    d_out = np.full((n, 5, len(SENSITIVE)), np.nan)
    ok = np.flatnonzero(eq.converged)
    if ok.size:
        o, d = sensitivities(model, params, eq.unknowns[ok], pred.applied[ok])
        dp = d[:, :, : len(SENSITIVE)].copy()
        if pred.dapplied_dfriction is not None:
            dc = d[:, :, len(SENSITIVE) :]
            for j, name in enumerate(("wire_friction_angle", "catheter_friction_angle")):
                col = SENSITIVE.index(name)
                dp[:, :, col] += np.einsum("nij,nj->ni", dc, pred.dapplied_dfriction[ok, :, j])
        out[ok], d_out[ok] = o, dp
    return out, d_out


def position_errors(position: np.ndarray, m: Measurements) -> np.ndarray:
    """Distance between model and measured tip over the measured coordinates, per row;
    NaN where the model has no equilibrium or the row was not seen. shape (N,) [m]"""
    diff = np.where(m.measured, position - m.position, 0.0)
    dist = np.sqrt(np.sum(diff**2, axis=1))
    return np.where(np.isfinite(position).all(axis=1) & m.seen, dist, np.nan)
