"""Large-deflection rod: the static Kirchhoff rod, inextensible and unshearable.

Model. Arc length s in [0, L]; clamp at s = 0 at the origin with tangent e1 = +x (base
frame, right-handed). Along s, in the base frame: position p, frame R (columns tangent t,
y_tip, z_tip), internal force n and internal moment m (the force and moment that the part
beyond s exerts on the part before it). With bending rigidity EI and a distributed force
q per length that is constant in the base frame (self-weight, default zero):
    p' = R e1 = t,
    R' = R [u]^,   u = (0, m_body,y / EI, m_body,z / EI),   m_body = R^T m,
    n' = -q,
    m' = -p' x n.
There is no twist (u_x = 0): the frame is carried by bending alone, as the tip frame of
:mod:`design.cantilever` and docs/formats.md. The axial part of m (held by the torsionally
stiff transmissions) bends nothing where it is applied; carried along a curved rod it
does, through m' = -t x n and the change of t. In the base frame the frame turns at the
Darboux vector omega = R u = (m - (t . m) t) / EI, i.e. R' = [omega]^ R and t' = omega x t.

Boundary conditions: p(0) = 0, R(0) = I (clamp), n(L) = f, m(L) = tau (free tip loaded by
the force f and the moment tau about p(L); both may depend on the tip pose, e.g. the
magnetic wrench). Since q is constant, n(s) = n0 - q s exactly.

Shooting. The unknowns are the base force n0 and moment m0 (the clamp's reaction); the
initial value problem is integrated to the tip, and the six boundary conditions form the
residual, made dimensionless with the rod's own scales:
    r = [ (n(L) - f) L^2 / EI ;  (m(L) - tau) L / EI ].
On the straight rod the exact base wrench is n0 = f + q L and m0 the straight rod's base
moment (:func:`design.cantilever.base_moment`).

Use. A model with a pose-dependent tip wrench takes z = (n0, m0) as its unknowns and
solves ``boundary_residual(z, L, EI, wrench)[0] = 0``, where ``wrench(p, R)`` builds the
force and moment at the deformed tip on CasADi symbols; :mod:`design.model` builds the
ring pair's residual from the same shooting map (:func:`shoot`) and
:mod:`design.equilibrium` solves it.

Integration. The frame is a quaternion Q (Hamilton, scalar first), Q' = 1/2 (0, omega) Q;
the rotation matrix is built from Q / |Q|, so the frame is orthonormal to rounding whatever
the integrator does to |Q|. The state (p, Q, m) is integrated by the classical fourth-
order Runge-Kutta method with STEPS fixed steps, unrolled on CasADi symbols. Each step
is one CasADi function kept as a call node (``never_inline``), so that the rod compiles
in seconds to compact C and is differentiated by CasADi's own AD (a fully inlined 32-step
rod with its Jacobian is 150,000 instructions and takes minutes to compile).

Convergence (measured; fourth order, the error drops 16x per halving of h). Largest tip
position error against a 320-step solution, in units of L:
    steps                               10       20       40       80
    Bisshopp-Drucker, F L^2 / EI = 5    6.2e-6   4.0e-7   2.6e-8   1.6e-9
    tip moment, M L / EI = 3 (arc)      1.3e-5   8.4e-7   5.2e-8   3.3e-9
    3-D force, moment and weight        5.8e-6   3.8e-7   2.4e-8   1.5e-9
the tip frame likewise. STEPS = 20 keeps the integration error more than 100x below the
1e-4 of the tabulated elastica and below 0.2 um on the 150 mm demonstrator, at half the
cost of 40 steps: the compiled residual with its Jacobian takes about 70 us.

SI units are used for all inputs and outputs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca

STEPS = 20
"""Runge-Kutta steps along the rod (see the module docstring for the convergence)."""

TipWrench = Callable[[ca.SX, ca.SX], tuple[ca.SX, ca.SX]]
"""(tip position (3,) [m], tip frame (3, 3) [-]) -> (force (3,) [N], moment about the tip
(3,) [N m]), all in the base frame."""


def frame_from_quaternion(quaternion: ca.SX) -> ca.SX:
    """Rotation matrix of the quaternion (w, x, y, z) / |(w, x, y, z)|, shape (3, 3). [-]

    Columns (tangent, y_tip, z_tip) in the base frame; exactly orthonormal for any nonzero
    quaternion (up to rounding).
    """
    w, x, y, z = (quaternion[i] for i in range(4))
    s = 2 / ca.dot(quaternion, quaternion)
    return ca.vertcat(
        ca.horzcat(1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)),
        ca.horzcat(s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x)),
        ca.horzcat(s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y)),
    )


def _tangent(quaternion: ca.SX) -> ca.SX:
    """First column of :func:`frame_from_quaternion`: the tangent t = R e1. [-]"""
    w, x, y, z = (quaternion[i] for i in range(4))
    s = 2 / ca.dot(quaternion, quaternion)
    return ca.vertcat(1 - s * (y * y + z * z), s * (x * y + w * z), s * (x * z - w * y))


def _derivative(
    quaternion: ca.SX, moment: ca.SX, force: ca.SX, bending_rigidity: ca.SX
) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(p', Q', m') of the rod at one point: p' = t, Q' = 1/2 (0, omega) Q with the
    Darboux vector omega = (m - (t . m) t) / EI, and m' = n x t. [base frame, SI / m]"""
    t = _tangent(quaternion)
    omega = (moment - ca.dot(t, moment) * t) / bending_rigidity
    w, v = quaternion[0], quaternion[1:4]
    dq = 0.5 * ca.vertcat(-ca.dot(omega, v), w * omega + ca.cross(omega, v))
    return t, dq, ca.cross(force, t)


def _rk4_step(state: ca.SX, force: ca.SX, load: ca.SX, h: ca.SX, ei: ca.SX) -> ca.SX:
    """One classical Runge-Kutta step of the state (p, Q, m), expression. [SI]"""
    quaternion, moment = state[3:7], state[7:10]
    k1 = _derivative(quaternion, moment, force, ei)
    k2 = _derivative(quaternion + h / 2 * k1[1], moment + h / 2 * k1[2], force - load * (h / 2), ei)
    k3 = _derivative(quaternion + h / 2 * k2[1], moment + h / 2 * k2[2], force - load * (h / 2), ei)
    k4 = _derivative(quaternion + h * k3[1], moment + h * k3[2], force - load * h, ei)
    increments = [h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]) for i in range(3)]
    return state + ca.vertcat(*increments)


def _step_symbols() -> list[ca.SX]:
    return [
        ca.SX.sym("state", 10),
        ca.SX.sym("force", 3),
        ca.SX.sym("distributed_load", 3),
        ca.SX.sym("h"),
        ca.SX.sym("bending_rigidity"),
    ]


_STEP_NAMES = ["state", "force", "distributed_load", "h", "bending_rigidity"]


@lru_cache(maxsize=1)
def step_function() -> ca.Function:
    """One classical Runge-Kutta step of the rod, as a never-inlined CasADi function.

    Inputs: state (p (3) [m], Q (4) [-], m (3) [N m]) at s; the internal force n at s
    (3) [N]; the distributed load q (3) [N/m]; the step h [m]; EI [N m^2].
    Output: the state at s + h (10). The internal force along the step is n - q (s' - s),
    exact.
    """
    args = _step_symbols()
    return ca.Function(
        "rod_rk4_step",
        args,
        [_rk4_step(*args)],
        _STEP_NAMES,
        ["next_state"],
        {"never_inline": True},
    )


@lru_cache(maxsize=1)
def sensitivity_step_function() -> ca.Function:
    """:func:`step_function` with the forward sensitivities of the state to the base
    wrench (n0, m0) and to a load factor lambda that scales the distributed load
    (q = lambda q'), as one never-inlined CasADi function.

    Inputs as :func:`step_function`, then S = d state / d (n0, m0, lambda) at s, shape
    (10, 7), the load rate q' = dq/dlambda (3) [N/m] and the arc length s [m].
    Outputs: the state at s + h (10) and S there (10, 7). The internal force
    n(s) = n0 - q s has the sensitivities [I, 0, -q' s] to (n0, m0, lambda). One function
    for all seven directions shares the nominal arithmetic between them (about half the
    work of seven separate directional derivatives).
    """
    args = _step_symbols()
    state, force, load = args[0], args[1], args[2]
    sens = ca.SX.sym("sensitivity", 10, 7)
    rate = ca.SX.sym("load_rate", 3)
    position = ca.SX.sym("arc_length")
    new_state = _rk4_step(*args)
    force_seed = ca.horzcat(ca.SX.eye(3), ca.SX.zeros(3, 3), -position * rate)
    load_seed = ca.horzcat(ca.SX.zeros(3, 6), rate)
    new_sens = (
        ca.jtimes(new_state, state, sens)
        + ca.jtimes(new_state, force, force_seed)
        + ca.jtimes(new_state, load, load_seed)
    )
    return ca.Function(
        "rod_rk4_sensitivity_step",
        [*args, sens, rate, position],
        [new_state, new_sens],
        [*_STEP_NAMES, "sensitivity", "load_rate", "arc_length"],
        ["next_state", "next_sensitivity"],
        {"never_inline": True, "cse": True},
    )


def shoot(
    base_wrench: Any,
    length: Any,
    bending_rigidity: Any,
    distributed_load: Any,
    steps: int = STEPS,
    load_rate: Any = None,
    nodes: list | None = None,
) -> tuple[Any, Any]:
    """Integrate the clamped rod from its base wrench to the tip (the shooting map).

    base_wrench : (n0, m0), shape (6,). [N, N m]
    length, bending_rigidity, distributed_load : as :func:`integrate`. [m, N m^2, N/m]
    load_rate : with it, also the sensitivities: dq/dlambda for a load factor lambda that
        scales the distributed load, shape (3,). [N/m]
    nodes : with ``load_rate``, a list that receives (state, sensitivity) at every node
        s_k = k L / steps, k = 0..steps (the base included).
    Returns the tip state (p (3) [m], Q (4) [-], m(L) (3) [N m]), shape (10,), and, given
    ``load_rate``, its derivative with respect to (n0, m0, lambda), shape (10, 7) (else
    None). The tip force is n(L) = n0 - q L exactly.
    """
    n0, m0 = base_wrench[0:3], base_wrench[3:6]
    h = length / steps
    state = ca.vertcat(ca.SX.zeros(3), 1, 0, 0, 0, m0)
    if load_rate is None:
        step = step_function()
        for k in range(steps):
            state = step(
                state, n0 - distributed_load * (k * h), distributed_load, h, bending_rigidity
            )
        return state, None
    sens = ca.SX.zeros(10, 7)
    sens[7:10, 3:6] = ca.SX.eye(3)
    step = sensitivity_step_function()
    if nodes is not None:
        nodes.append((state, sens))
    for k in range(steps):
        state, sens = step(
            state,
            n0 - distributed_load * (k * h),
            distributed_load,
            h,
            bending_rigidity,
            sens,
            load_rate,
            k * h,
        )
        if nodes is not None:
            nodes.append((state, sens))
    return state, sens


@dataclass(frozen=True)
class RodState:
    """The rod integrated from its base (CasADi expressions), base frame throughout.

    position : tip position p(L), shape (3,). [m]
    frame : tip frame R(L), columns (tangent, y_tip, z_tip), shape (3, 3). [-]
    force : internal force at the tip n(L), shape (3,). [N]
    moment : internal moment at the tip m(L), shape (3,). [N m]
    centreline : positions p(s_k) at s_k = k L / steps, k = 0..steps, shape (3, steps + 1).
        [m]
    """

    position: ca.SX
    frame: ca.SX
    force: ca.SX
    moment: ca.SX
    centreline: ca.SX


def integrate(
    base_force: Any,
    base_moment: Any,
    length: Any,
    bending_rigidity: Any,
    distributed_load: Any = None,
    steps: int = STEPS,
) -> RodState:
    """Integrate the clamped rod from s = 0 to s = L (the shooting map).

    base_force : n0 = n(0), the internal force at the clamp, shape (3,). [N]
    base_moment : m0 = m(0), the internal moment at the clamp, shape (3,). [N m]
    length : L, free length. [m]
    bending_rigidity : EI. [N m^2]
    distributed_load : q, force per length, constant in the base frame, shape (3,); None is
        zero. [N/m]
    steps : Runge-Kutta steps. [-]
    """
    load = ca.SX.zeros(3) if distributed_load is None else ca.SX(distributed_load)
    n0, m0 = ca.SX(base_force), ca.SX(base_moment)
    h = length / steps
    state = ca.vertcat(ca.SX.zeros(3), 1, 0, 0, 0, m0)
    points = [state[0:3]]
    step = step_function()
    for k in range(steps):
        state = step(state, n0 - load * (k * h), load, h, bending_rigidity)
        points.append(state[0:3])
    return RodState(
        position=state[0:3],
        frame=frame_from_quaternion(state[3:7]),
        force=n0 - load * length,
        moment=state[7:10],
        centreline=ca.horzcat(*points),
    )


def shooting_function(steps: int = STEPS) -> ca.Function:
    """The shooting map as a CasADi function ``rod_shoot``:
    (base_force (3) [N], base_moment (3) [N m], length [m], bending_rigidity [N m^2],
    distributed_load (3) [N/m]) -> (position (3) [m], frame (3, 3) [-], force (3) [N],
    moment (3) [N m], centreline (3, steps + 1) [m]); see :class:`RodState`."""
    n0, m0 = ca.SX.sym("base_force", 3), ca.SX.sym("base_moment", 3)
    length, ei = ca.SX.sym("length"), ca.SX.sym("bending_rigidity")
    load = ca.SX.sym("distributed_load", 3)
    rod = integrate(n0, m0, length, ei, load, steps)
    return ca.Function(
        "rod_shoot",
        [n0, m0, length, ei, load],
        [rod.position, rod.frame, rod.force, rod.moment, rod.centreline],
        ["base_force", "base_moment", "length", "bending_rigidity", "distributed_load"],
        ["position", "frame", "force", "moment", "centreline"],
    )


def boundary_residual(
    base_wrench: ca.SX,
    length: Any,
    bending_rigidity: Any,
    tip_wrench: TipWrench,
    distributed_load: Any = None,
    steps: int = STEPS,
) -> tuple[ca.SX, RodState]:
    """The six tip boundary conditions as a function of the base wrench.

    base_wrench : unknowns (n0, m0), shape (6,). [N, N m]
    length, bending_rigidity, distributed_load : as :func:`integrate`. [m, N m^2, N/m]
    tip_wrench : callable (tip position, tip frame) -> (force, moment about the tip), on
        CasADi symbols, base frame; evaluated at the integrated (deformed) tip pose.
    Returns (r, rod): r = [(n(L) - f) L^2 / EI; (m(L) - tau) L / EI], shape (6,),
    dimensionless, zero at equilibrium; rod the integrated :class:`RodState`.
    """
    rod = integrate(
        base_wrench[0:3], base_wrench[3:6], length, bending_rigidity, distributed_load, steps
    )
    force, moment = tip_wrench(rod.position, rod.frame)
    residual = ca.vertcat(
        (rod.force - force) * (length**2 / bending_rigidity),
        (rod.moment - moment) * (length / bending_rigidity),
    )
    return residual, rod
