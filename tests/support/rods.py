"""The large-deflection rod (design.rod) under given tip loads, for tests and the rod
benchmark: the project's boundary residual (:func:`design.rod.boundary_residual`, the
shooting map and its exact Jacobian) driven to zero by scipy's MINPACK root finder
(``hybr``) from the straight rod's base wrench, the loads ramped up in :data:`RAMP` equal
steps (each solve starts from the last).

What the tests check is the rod's equations and their integration, against the
literature; the root finder only has to find the root, and the residual it reaches is
returned with the solution (``converged``: below :data:`TOLERANCE`). The unknowns are the
base wrench scaled as the model scales it, (n0 L^2 / EI, m0 L / EI). SI units throughout.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import root

from design import cantilever, rod
from design.compiled import compile_function

TOLERANCE = 1e-11
"""A solution counts as converged below this infinity norm of the dimensionless residual."""

RAMP = 4
"""Load steps from the straight rod to full load (Bisshopp-Drucker's F L^2 / EI = 5 needs
more than one from the straight start)."""

LoadedTipWrench = Callable[[ca.SX, ca.SX, ca.SX], tuple[ca.SX, ca.SX]]
"""(tip position (3,) [m], tip frame (3, 3) [-], load parameters) -> (force (3,) [N],
moment about the tip (3,) [N m]), base frame, on CasADi symbols."""


def dead_load(position: ca.SX, frame: ca.SX, load: ca.SX) -> tuple[ca.SX, ca.SX]:
    """A tip wrench independent of the pose: load = (force (3) [N], moment (3) [N m])."""
    return load[0:3], load[3:6]


@dataclass(frozen=True)
class RodSolution:
    """A solved rod, base frame throughout.

    base_force, base_moment : clamp reaction n(0), m(0), shape (3,). [N, N m]
    position : tip position, shape (3,). [m]
    frame : tip frame, columns (tangent, y_tip, z_tip), shape (3, 3). [-]
    tip_force, tip_moment : the applied tip wrench at the solution, shape (3,). [N, N m]
    centreline : p(s_k), s_k = k L / steps, shape (steps + 1, 3). [m]
    converged : residual below :data:`TOLERANCE`.
    residual : infinity norm of the dimensionless residual. [-]
    """

    base_force: np.ndarray
    base_moment: np.ndarray
    position: np.ndarray
    frame: np.ndarray
    tip_force: np.ndarray
    tip_moment: np.ndarray
    centreline: np.ndarray
    converged: bool
    residual: float


@lru_cache(maxsize=8)
def rod_functions(
    tip_wrench: LoadedTipWrench, load_size: int, steps: int, compile: bool = False
) -> tuple[ca.Function, ca.Function, ca.Function]:
    """(residual, shape, straight) of the rod under ``tip_wrench``, as CasADi functions of
    the scaled base wrench, L, EI, the distributed load and the load parameters: residual
    -> (r, dr/dz); shape -> (r, position, frame, tip force, tip moment, centreline, base
    wrench); straight (L, load) -> the tip wrench on the straight rod. ``compile``: native
    code (:func:`design.compiled.compile_function`)."""
    z = ca.SX.sym("scaled_base_wrench", 6)
    length, ei = ca.SX.sym("length"), ca.SX.sym("bending_rigidity")
    q = ca.SX.sym("distributed_load", 3)
    load = ca.SX.sym("load", load_size)
    scale = ca.vertcat(ei / length**2 * ca.DM.ones(3), ei / length * ca.DM.ones(3))
    wrench = z * scale

    def applied(position: ca.SX, frame: ca.SX) -> tuple[ca.SX, ca.SX]:
        return tip_wrench(position, frame, load)

    r, state = rod.boundary_residual(wrench, length, ei, applied, q, steps)
    force, moment = applied(state.position, state.frame)
    inputs = [z, length, ei, q, load]
    names = ["z", "length", "bending_rigidity", "distributed_load", "load"]
    residual = ca.Function("rod_residual", inputs, [r, ca.jacobian(r, z)], names, ["r", "dr_dz"])
    outputs = [r, state.position, state.frame, force, moment, state.centreline, wrench]
    shape = ca.Function("rod_shape", inputs, [ca.densify(e) for e in outputs])
    on_straight = applied(ca.vertcat(length, 0, 0), ca.SX.eye(3))
    straight = ca.Function("rod_straight", [length, load], [ca.densify(e) for e in on_straight])
    if compile:
        residual, shape = compile_function(residual), compile_function(shape)
    return residual, shape, straight


def solve_rod(
    length: float,
    bending_rigidity: float,
    load: ArrayLike,
    distributed_load: ArrayLike = (0.0, 0.0, 0.0),
    *,
    tip_wrench: LoadedTipWrench = dead_load,
    steps: int = rod.STEPS,
    compile: bool = False,
) -> RodSolution:
    """The clamped rod (length [m], EI [N m^2]) under ``tip_wrench`` with parameters
    ``load`` and the distributed load q (3,) [N/m], solved from the straight rod's base
    wrench under the loads at the straight pose (n0 = f + q L, m0 from
    :func:`design.cantilever.base_moment`), the loads ramped up in :data:`RAMP` steps
    (the tip wrench scales with its parameters, as the dead load and a follower force
    do)."""
    load = np.asarray(load, float)
    q = np.asarray(distributed_load, float)
    residual, shape, straight = rod_functions(tip_wrench, load.size, steps, compile)
    force, moment = (np.asarray(v, float).ravel() for v in straight(length, load / RAMP))
    base_wrench = np.concatenate(
        [force + q / RAMP * length, cantilever.base_moment(force, moment, length, q / RAMP)]
    )
    z = base_wrench / (bending_rigidity / np.array([length**2] * 3 + [length] * 3))
    for k in range(1, RAMP + 1):
        loads = (length, bending_rigidity, q * k / RAMP, load * k / RAMP)

        def fun(z: np.ndarray, loads=loads) -> tuple[np.ndarray, np.ndarray]:
            r, jac = residual(z, *loads)
            return np.asarray(r).ravel(), np.asarray(jac)

        z = root(fun, z, jac=True, method="hybr", options={"xtol": 1e-14}).x
    args = (length, bending_rigidity, q, load)
    r, position, frame, f, tau, centreline, wrench = (np.asarray(v) for v in shape(z, *args))
    norm = float(np.abs(r).max())
    return RodSolution(
        base_force=wrench[0:3].ravel(),
        base_moment=wrench[3:6].ravel(),
        position=position.ravel(),
        frame=frame,
        tip_force=f.ravel(),
        tip_moment=tau.ravel(),
        centreline=centreline.T.copy(),
        converged=norm < TOLERANCE,
        residual=norm,
    )


def solve_tip_load(
    length: float,
    bending_rigidity: float,
    tip_force: ArrayLike = (0.0, 0.0, 0.0),
    tip_moment: ArrayLike = (0.0, 0.0, 0.0),
    distributed_load: ArrayLike = (0.0, 0.0, 0.0),
    *,
    steps: int = rod.STEPS,
    compile: bool = False,
) -> RodSolution:
    """The clamped rod under a dead tip force f (3,) [N], tip moment tau (3,) about the tip
    [N m] and distributed load q (3,) [N/m], base frame."""
    load = np.concatenate([np.asarray(tip_force, float), np.asarray(tip_moment, float)])
    return solve_rod(length, bending_rigidity, load, distributed_load, steps=steps, compile=compile)
