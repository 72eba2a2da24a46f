"""The ring-pair model: one set of CasADi expressions, with switchable physical effects,
from which every numeric function (equilibrium residual, Jacobian, stability indicator,
tip pose) is built.

Baseline (the paper's model, derived anew): point-dipole external field, linear cantilever
under the tip wrench, transmissions rigid in torsion, no ring coupling, no gravity, no
friction. Effects (docs/formats.md names), each reducing to the baseline in its limit:

- ``near_field``: exact field of the axially magnetised cylinder (:mod:`design.cylinder_field`)
  instead of its point dipole.
- ``large_deflection``: Kirchhoff rod (:mod:`design.rod`) instead of the linear cantilever.
- ``torsion``: each transmission twists under the axial torque on its ring, T = GJ/L (tip
  angle - commanded angle); the axial torque includes the other ring's
  (:mod:`design.ring_coupling`). Unknowns gain the two tip angles.
- ``gravity``: weight of catheter and wire (distributed) and of rings and tip mass (at the
  tip), along ``environment.gravity_m_s2``.
- ``hysteresis``: backlash/friction play in each transmission; acts on ordered command
  sequences (:func:`design.equilibrium.solve_sequence`) through :func:`play`.
- ``printed_tip`` (a switch beside the effects, :data:`PRINTED_TIP`): the tip as built
  (:mod:`design.mounting`): the flexible rod ends at the proximal mounting piece's
  proximal face, a rigid segment carries the rings, the tracked point (the proximal ring's
  centre, still at ``free_length`` from the base on the straight robot) lies
  ``rigid_offset`` along it; with ``gravity``, each piece's weight acts at its centre of
  mass; with ``torsion``, the pieces' rotational stops hold the rings' relative angle and
  the pre-twist offsets the wire's command (:mod:`design.stops`). Its limit, pieces of no
  size, is the bare rings of the other effects.

The baseline leaves the rigid segment out on purpose: it is the paper's model, whose rod is
the catheter's whole free length with the rings at its end (eq. 6, L = 150 mm) and whose
stiffness scale K_E was tuned on that geometry; adding the segment would change the
reproduced results without making them the paper's. ``printed_tip`` is part of the model
for design work, :data:`DEFAULT_EFFECTS` (issue 16); the state tests check it against an
independent solve with the rigid segment, the pieces' weights and the stops
(tests/support/oracle.py, tests/design/test_state_properties.py).

Unknowns x: rod coordinates (linear: q = (dy, dz, phi_y, phi_z); large deflection: the
base internal force n0 and moment m0, scaled to (n0 L^3 / EI, m0 L / EI)), then the tip
angles with ``torsion``. The residual is scaled to metres/radians (its infinity norm is
the convergence measure). Every load (field, gravity, the rings' mutual torque) is
multiplied by the parameter ``load_scale`` (1: physical), along which
:mod:`design.equilibrium` ramps the robot from its unloaded state. SI units are used for
all inputs and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import casadi as ca
import numpy as np

from design import cantilever, rod
from design.model.effects import PRINTED_TIP, SWITCHES
from design.model.field import CLASSIC, FieldLayout, field_model, layout_of, magnet_clearance
from design.model.loads import TipFrame, tip_effects
from design.model.symbols import Symbols, ring_positions
from design.records import Design
from design.registry import NAMES, index, model_vector
from design.stops import commanded_angles, resting_angles, stop_stiffness, stop_torque
from design.wrench import tip_wrench


def _rotation_rates(quaternion: ca.SX) -> ca.SX:
    """E(Q), shape (4, 3): the quaternion (w, v) turned by a small spatial rotation dtheta
    changes by dQ = E(Q) dtheta / 2, and dtheta = 2 E(Q)^T dQ / |Q|^2. [-]"""
    w, v = quaternion[0], quaternion[1:4]
    return ca.vertcat(-v.T, w * ca.SX.eye(3) - ca.skew(v))


def _dense_function(name: str, inputs: list, outputs: list, *rest) -> ca.Function:
    """A Function whose outputs are dense (a field without gradient, a uniform one, makes
    some structurally sparse; the solvers read outputs as dense columns)."""
    return ca.Function(name, inputs, [ca.densify(o) for o in outputs], *rest)


COARSE_STEPS = 5
"""Runge-Kutta steps of the rod from which the solver's Newton matrix is built (the
residual always uses :data:`design.rod.STEPS`): its relative error, about 1e-4, only makes
Newton's convergence linear at that rate, for a quarter of the cost of the exact matrix."""


def sylvester_minors(stiffness: ca.SX) -> ca.SX:
    """Leading principal minors of the symmetric part of ``stiffness`` after a diagonal
    congruence scaling (Sylvester's criterion: all > 0 iff positive definite). [-]"""
    n = stiffness.size1()
    hs = 0.5 * (stiffness + stiffness.T)
    scale = 1 / ca.sqrt(ca.fmax(ca.fabs(ca.diag(hs)), 1e-300))
    hn = hs * (scale @ scale.T)
    return ca.vertcat(*[ca.det(hn[:k, :k]) for k in range(1, n + 1)])


@dataclass(frozen=True)
class RingPairModel:
    """The model with a set of effects switched on (empty: the baseline).

    Built once, as CasADi functions of (x, command, params), ``command`` being the ring
    angles set at the base (theta1 distal, theta2 proximal) [rad]:

    - ``residual`` -> (r, dr/dx): r = 0 at equilibrium, in m or rad, with exact
      derivatives (NLPs, sensitivities);
    - ``newton`` -> (r, Newton's step (dr/dx)^-1 r, load tangent dx/d(load_scale) =
      -(dr/dx)^-1 dr/d(load_scale), stability monitor, clearance of the rings to the
      external magnet (:func:`magnet_clearance`)), the equilibrium solver's iteration;
    - ``relaxation`` -> K^-1 r (K = dr/dx with the loads frozen: the robot's own elastic
      stiffness; -K^-1 r points down the total potential), how the robot falls;
    - ``descent`` -> (G^-1 g, M = G^-1 H column-major, clearance): the gradient g of the
      total potential energy in the unknowns and its Hessian H (exact at equilibria,
      Gauss-Newton away from them), in a metric G: the elastic stiffness for the linear
      rod (so M = dr/dx), the unknowns over :meth:`unknown_scale` with the energy over
      EI / L for the large-deflection rod (whose own stiffness can be indefinite); the
      elastic modes have eigenvalues of order one. How the robot falls;
    - ``check`` -> (r, monitor, position, frame, tip angles, clearance of the rings to the
      external magnet (:func:`magnet_clearance`)), for a final state;
    - ``pose`` -> (position (3), frame (3x3), tip angles (2));
    - ``internal`` -> (the rod's bending moment at the clamp (3) and at its end (3, the
      part across the end's tangent) [N m], base frame; each transmission's twist (2),
      L / GJ times the axial torque on its ring, the stops' included [rad]: the twist with
      ``torsion``, its first-order estimate without), at equilibrium; the strain and twist
      limits of design studies;
    - ``initial`` (command, params) -> x0, the unloaded robot (straight, tip angles =
      command; against its stops with ``torsion`` and ``printed_tip``,
      :func:`design.stops.resting_angles`).

    Stability monitors. Linear rod: the Sylvester minors of the stiffness form (all > 0 iff
    the equilibrium is stable), in ``newton`` and ``check`` alike. Large-deflection rod:
    ``newton``'s monitor is dr/dx itself (column-major), whose determinant changes sign at
    every fold of a branch followed from rest; ``check``'s is the stack of the Jacobians
    J(s_k) of the problems restricted to bending on [0, s_k] (the rod rigid beyond), at
    s_k = k L / COARSE_STEPS, k = 0 .. COARSE_STEPS - 1, then J(L) = dr/dx, then the
    energy's Hessian in the unknowns H = U^T D dr/dx (U the tip pose per unknown;
    dimensionless). The variations of the restricted problems are nested, so the lowest
    eigenvalue of the second variation falls with s and a single unstable mode shows as a
    sign change of det J(s) on (0, L]; H is congruent to the Hessian in tip-pose
    coordinates, so its eigenvalues count the unstable modes (Sylvester's law of inertia),
    which catches pairs of modes that turn unstable together (near an axisymmetric
    magnet). Near a straight rod the axial force and moment are constraint-like and H has
    eigenvalues near zero there. The state is stable iff every det J(s_k) > 0, H has no
    eigenvalue below -HESSIAN_TOLERANCE (:mod:`design.equilibrium`) and, with torsion,
    J(0)'s angle block has eigenvalues with positive real parts. (The eigenvalues of K^-1
    dr/dx, K the rod's own stiffness, are no test: a rod compressed beyond its dead-load
    buckling load, held by the field, has an indefinite K.) The solver's matrices of the
    large-deflection rod (``newton``, ``relaxation``, ``descent``) and ``check``'s
    stability monitor come from a COARSE_STEPS integration of the same rod: their relative
    error, about 1e-5, makes Newton converge linearly at that rate and places a fold (and
    a stability verdict's change) to that accuracy, for a fifth of the cost; the residual,
    the pose and ``residual``'s dr/dx are those of the full :data:`design.rod.STEPS`
    integration.
    """

    effects: frozenset[str] = frozenset()
    layout: FieldLayout = CLASSIC
    """The field's structure (:class:`design.model.field.FieldLayout`): the external
    magnet alone by default; :meth:`for_design` gives the model of a design's field."""
    n_unknowns: int = field(init=False)
    n_rod: int = field(init=False)
    linear_rod: bool = field(init=False)
    residual: ca.Function = field(init=False, repr=False, compare=False)
    newton: ca.Function = field(init=False, repr=False, compare=False)
    relaxation: ca.Function = field(init=False, repr=False, compare=False)
    descent: ca.Function = field(init=False, repr=False, compare=False)
    check: ca.Function = field(init=False, repr=False, compare=False)
    pose: ca.Function = field(init=False, repr=False, compare=False)
    initial: ca.Function = field(init=False, repr=False, compare=False)
    internal: ca.Function = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        effects = frozenset(self.effects)
        object.__setattr__(self, "effects", effects)
        unknown = effects - set(SWITCHES)
        if unknown:
            raise ValueError(
                f"unknown model effect(s) {sorted(unknown)}; expected any of {list(SWITCHES)}"
            )
        large = "large_deflection" in effects
        torsion = "torsion" in effects
        n_rod = 6 if large else 4
        n = n_rod + (2 if torsion else 0)
        object.__setattr__(self, "n_unknowns", n)
        object.__setattr__(self, "n_rod", n_rod)
        object.__setattr__(self, "linear_rod", not large)

        x = ca.SX.sym("x", n)
        command = ca.SX.sym("command", 2)
        prm = ca.SX.sym("params", len(NAMES) + self.layout.size)
        s = Symbols(prm, self.layout)
        load = s["load_scale"]
        length, ei = s["free_length"], s.bending_rigidity
        printed = PRINTED_TIP in effects
        stops = printed and torsion
        # The flexible rod ends where the rigid tip segment starts, ``offset`` before the
        # tracked point (the proximal ring's centre); the baseline has no segment (see the
        # module's docstring).
        offset = s.tip.rigid_offset if printed else 0
        s.rod_length = s.tip.rod_length(length) if printed else length
        rod_length = s.rod_length
        angles = x[n_rod:] if torsion else command
        moment = load * s.ring_moment
        loaded = tip_effects(effects)  # the effects with loads of their own
        weight_rate = ca.SX.zeros(3)  # distributed load per unit load_scale [N/m]
        for effect in loaded:
            rate = effect.weight_rate(s)
            weight_rate = weight_rate if rate is None else weight_rate + rate
        distributed = load * weight_rate
        field_model = self._field_model(s)
        # Point masses on the rigid segment: (arm from the rod's end along the tangent, mass).
        masses = [
            (offset, s.ring_mass),
            (offset + s.magnet_spacing, s.ring_mass),
            (offset, s["tip_mass"]),
        ]
        for effect in loaded:
            masses += effect.masses(s)
        # Twist of each transmission per unit axial torque, L / GJ. [rad / (N m)]
        twist_compliance = length / s.torsional_rigidity
        twist = twist_compliance if torsion else None
        commanded = command
        if stops:
            commanded = ca.vertcat(*commanded_angles(command, s["stop_angle"], s["pretwist"]))
            contact = stop_stiffness(twist)

        def applied(position: ca.SX, frame: ca.SX, tip_angles: ca.SX) -> ca.SX:
            """Loads at the rod's end ``position`` with ``frame``: force (3) [N] and moment
            about the rod's end (3) [N m], base frame, then with torsion the axial torque on
            each ring (2) [N m], the stops' included."""
            tangent = frame[:, 0]
            tracked = position + offset * tangent if printed else position
            force, torque = tip_wrench(
                field_model, tracked, frame, tip_angles, moment, s.magnet_spacing
            )
            force = force + load * s.applied_force  # (an external wrench, 0 in a design)
            torque = torque + load * s.applied_moment
            at = TipFrame(s, load, offset, tangent, tuple(masses))
            for effect in loaded:
                force, torque = effect.add(at, force, torque)
            out = [force, torque]
            if torsion:
                axial = self._axial_torques(
                    field_model, tracked, frame, tip_angles, moment, s, load
                )
                if stops:
                    lam = stop_torque(tip_angles[0] - tip_angles[1], s["stop_angle"], contact)
                    axial = axial + ca.vertcat(lam, -lam)
                out.append(axial)
            return ca.vertcat(*out)

        def with_twist(r_rod: ca.SX, loads: ca.SX) -> ca.SX:
            if twist is None:
                return r_rod
            return ca.vertcat(r_rod, angles - commanded - twist * loads[6:8])

        if large:
            kirchhoff = self._kirchhoff(x, prm, s, angles, weight_rate, applied, with_twist, twist)
            r, jac, jac_solver, k_solver, dr_dload, monitor, gradient_map, position, frame = (
                kirchhoff
            )
            monitor_solver = ca.vec(jac_solver)
            relaxation = ca.solve(k_solver, r)
        else:
            position, frame = cantilever.tip_pose(x[:4], rod_length)
            loads = applied(position, frame, angles)
            bending = cantilever.bending_load(loads[0:3], loads[3:6], frame[:, 0])
            r_rod = (
                x[:4]
                - cantilever.compliance(rod_length, ei) @ bending
                - cantilever.distributed_load_response(distributed, rod_length, ei)
            )
            r = with_twist(r_rod, loads)
            jac_solver = jac = ca.jacobian(r, x)
            dr_dload = ca.jacobian(r, load)
            stiffness = [cantilever.stiffness(rod_length, ei)]
            if torsion:
                stiffness.append(ca.diag(s.torsional_rigidity / length))
            # The stiffness form K_s dr/dx (K_s = blockdiag(K, GJ/L)) is the Hessian of the
            # total potential for these (to first order conservative) loads: positive
            # definite iff stable (Sylvester's criterion).
            monitor = monitor_solver = sylvester_minors(ca.diagcat(*stiffness) @ jac)
            relaxation = r  # with the loads frozen dr/dx = I
            # The fall's metric is the elastic stiffness K_s: K_s^-1 (K_s r) = r and
            # K_s^-1 (K_s dr/dx) = dr/dx. (These loads are conservative to first order
            # only: the antisymmetric part of K_s dr/dx matters at large tip rotations.)
            direction, fall_matrix = r, jac
        if not self.linear_rod:
            # The fall's metric is Euclidean in the unknowns over their scale, with the
            # energy over EI / L: P = (L / EI) diag(scale)^2 times the gradient map.
            scale = ca.vertcat(*[length if k < 3 else 1 for k in range(n)])
            metric = (length / ei) * ca.diag(scale**2) @ gradient_map
            direction, fall_matrix = metric @ r, metric @ jac_solver
        # The rod's internal loads (strain and twist limits of design studies).
        end_loads = applied(position, frame, angles)
        tangent = frame[:, 0]
        end_moment = end_loads[3:6] - ca.dot(end_loads[3:6], tangent) * tangent
        if large:  # the base wrench is an unknown: m0 = x[3:6] EI / L
            base_moment = x[3:6] * ei / rod_length
        else:
            base_moment = cantilever.base_moment(
                end_loads[0:3], end_moment, rod_length, distributed
            )
        if printed:  # the tracked point, from the rod's end
            position = position + offset * frame[:, 0]
        if torsion:
            axial = end_loads[6:8]
        else:
            axial = self._axial_torques(field_model, position, frame, angles, moment, s, load)
        transmission_twist = twist_compliance * axial
        clearance = magnet_clearance(s, position, frame)
        # Newton's step and the load tangent share one factorisation.
        newton_solve = ca.solve(jac_solver, ca.horzcat(r, -dr_dload))
        io = ["x", "command", "params"]
        opts = {"cse": True}
        arguments = [x, command, prm]
        functions = {
            "residual": _dense_function("residual", arguments, [r, jac], io, ["r", "dr_dx"], opts),
            "newton": _dense_function(
                "newton",
                arguments,
                [r, newton_solve[:, 0], newton_solve[:, 1], monitor_solver, clearance],
                io,
                ["r", "step", "load_tangent", "monitor", "clearance"],
                opts,
            ),
            "relaxation": _dense_function(
                "relaxation", arguments, [relaxation], io, ["direction"], opts
            ),
            "descent": _dense_function(
                "descent",
                arguments,
                [direction, ca.vec(fall_matrix), clearance],
                io,
                ["direction", "M", "clearance"],
                opts,
            ),
            "check": _dense_function(
                "check",
                arguments,
                [r, monitor, position, frame, angles, clearance],
                io,
                ["r", "monitor", "position", "frame", "tip_angles", "clearance"],
                opts,
            ),
            "pose": _dense_function(
                "pose",
                arguments,
                [position, frame, angles],
                io,
                ["position", "frame", "tip_angles"],
                opts,
            ),
            "internal": _dense_function(
                "internal",
                arguments,
                [base_moment, end_moment, transmission_twist],
                io,
                ["base_moment", "end_moment", "twist"],
                opts,
            ),
        }
        rest = command
        if stops:  # the unloaded robot against its stops
            rest = ca.vertcat(*resting_angles(command, s["stop_angle"], s["pretwist"], twist))
        x0 = ca.vertcat(ca.SX.zeros(n_rod), rest) if torsion else ca.SX.zeros(n_rod)
        functions["initial"] = _dense_function(
            "initial", [command, prm], [x0], ["command", "params"], ["x0"], opts
        )
        for name, fn in functions.items():
            object.__setattr__(self, name, fn)

    def _kirchhoff(self, x, prm, s, angles, weight_rate, applied, with_twist, twist):
        """Residual, derivatives and pose of the large-deflection rod (:mod:`design.rod`).

        The rod unknowns are the base wrench (n0, m0), scaled to deflection units
        (n0 L^3 / EI, m0 L / EI) [m, rad], so that they, the residual and the linear rod's
        coordinates share one scale; the residual is the tip boundary condition
        (n(L) - f, m(L) - tau), scaled alike. dr/dx follows from the shooting map's
        sensitivities by the chain rule, and so do K (the loads frozen: the rod's own tip
        wrench against its base wrench) and dr/d(load_scale). Returns (r, dr/dx, and from
        COARSE_STEPS the solver's dr/dx, K and dr/d(load_scale), the stability test's
        stacked Jacobians, the map from r to the energy's gradient, tip position, tip
        frame).
        """
        n_rod = self.n_rod
        length, ei = s.rod_length, s.bending_rigidity
        load = s["load_scale"]
        wrench_scale = ca.vertcat(ei / length**3 * ca.DM.ones(3), ei / length * ca.DM.ones(3))
        row_scale = ca.vertcat(length**3 / ei * ca.DM.ones(3), length / ei * ca.DM.ones(3))
        base_wrench = x[:n_rod] * wrench_scale
        p_sym, q_sym = ca.SX.sym("position", 3), ca.SX.sym("quaternion", 4)
        a_sym = ca.SX.sym("tip_angles", 2)
        loads = applied(p_sym, rod.frame_from_quaternion(q_sym), a_sym)
        loads_at = ca.Function(
            "tip_loads",
            [p_sym, q_sym, a_sym, prm],
            [
                loads,
                ca.jacobian(loads, ca.vertcat(p_sym, q_sym)),
                ca.jacobian(loads, a_sym),
                ca.jacobian(loads, load),
            ],
            {"cse": True, "never_inline": True},  # one copy in the compiled code of all uses
        )
        twist_rows = None if twist is None else ca.diag(twist)

        def at(tip: ca.SX):
            """The residual at an integrated tip, and the loads and their derivatives
            there."""
            tip_loads, d_pose, d_angles, d_load = loads_at(tip[0:3], tip[3:7], angles, prm)
            rod_wrench = ca.vertcat(base_wrench[0:3] - load * weight_rate * length, tip[7:10])
            r = with_twist(row_scale * (rod_wrench - tip_loads[:6]), tip_loads)
            return r, (d_pose, d_angles, d_load), tip_loads

        def restricted(nodes: list, tip: ca.SX, loads_derivatives, tip_loads: ca.SX) -> ca.SX:
            """The Jacobians J(s_k) of the problems restricted to variations that bend
            the rod on [0, s_k] only (beyond s_k it moves rigidly, with its loads), at the
            nodes s_k = k L / (len(nodes) - 1) before the tip, stacked column-major;
            J(0) concerns the rings' angles alone (the identity without torsion), J(L)
            would be dr/dx. Their admissible variations are nested, so the lowest
            eigenvalue of the second variation falls with s: the state is stable iff
            det J(s) > 0 on (0, L] (no focal point; Jacobi's condition, e.g. Bolza,
            *Lectures on the Calculus of Variations*, 1904, ch. 2) and, with torsion,
            J(0)'s angle block has positive eigenvalues."""
            d_pose, d_angles, _ = loads_derivatives
            f = tip_loads[0:3]
            q = load * weight_rate
            d_p = d_pose[:, 0:3]  # loads per tip displacement
            d_theta = d_pose[:, 3:7] @ (0.5 * _rotation_rates(tip[3:7]))  # per tip rotation
            h = length / (len(nodes) - 1)
            points = [state[0:3] for state, _ in nodes]
            tail = [ca.SX.zeros(3)]  # integral of p over [s_k, L], trapezoid, from the tip
            for k in range(len(nodes) - 1, 0, -1):
                tail.insert(0, tail[0] + h / 2 * (points[k] + points[k - 1]))
            out = []
            for k, (state, sens) in enumerate(nodes[:-1]):
                arm = tip[0:3] - points[k]  # tip about the node
                spread = tail[k] - (length - k * h) * points[k]  # weight beyond, about it
                rates = _rotation_rates(state[3:7])
                pose = ca.vertcat(
                    sens[0:3, 0:6], 2 * rates.T @ sens[3:7, 0:6] / ca.dot(state[3:7], state[3:7])
                )  # (displacement, spatial rotation) of the node per base wrench
                rigid = ca.horzcat(d_p, d_theta - d_p @ ca.skew(arm))  # loads per node motion
                d_force = rigid[0:3, :] @ pose
                d_torque = (
                    rigid[3:6, :] @ pose
                    + ca.skew(arm) @ d_force
                    + (ca.skew(f) @ ca.skew(arm) + ca.skew(q) @ ca.skew(spread)) @ pose[3:6, :]
                )
                rod_rows = ca.vertcat(ca.horzcat(ca.SX.eye(3), ca.SX.zeros(3, 3)), sens[7:10, 0:6])
                j = ca.diag(row_scale) @ (rod_rows - ca.vertcat(d_force, d_torque))
                j = j @ ca.diag(wrench_scale)
                if twist_rows is not None:
                    by_angles = ca.vertcat(
                        d_angles[0:3, :], d_angles[3:6, :] + ca.skew(arm) @ d_angles[0:3, :]
                    )
                    j = ca.vertcat(
                        ca.horzcat(j, -ca.diag(row_scale) @ by_angles),
                        ca.horzcat(
                            -twist_rows @ rigid[6:8, :] @ pose @ ca.diag(wrench_scale),
                            ca.SX.eye(2) - twist_rows @ d_angles[6:8, :],
                        ),
                    )
                out.append(ca.vec(j))
            return ca.vertcat(*out)

        def derivatives(sens: ca.SX, loads_derivatives) -> tuple[ca.SX, ca.SX, ca.SX]:
            """(dr/dx, K, dr/d(load_scale)) from the shooting sensitivities (columns: n0,
            m0, the load factor) and the loads' derivatives at the tip."""
            d_pose, d_angles, d_load = loads_derivatives
            d_rod = ca.vertcat(
                ca.horzcat(ca.SX.eye(3), ca.SX.zeros(3, 3), -weight_rate * length),
                sens[7:10, :],
            )
            d_loads = d_pose @ sens[0:7, :]
            d_loads[:, 6] += d_load
            k = ca.diag(row_scale) @ d_rod[:, :6] @ ca.diag(wrench_scale)
            j = k - ca.diag(row_scale) @ d_loads[:6, :6] @ ca.diag(wrench_scale)
            dr_dload = row_scale * (d_rod[:, 6] - d_loads[:6, 6])
            if twist_rows is not None:
                j = ca.vertcat(
                    ca.horzcat(j, -ca.diag(row_scale) @ d_angles[:6, :]),
                    ca.horzcat(
                        -twist_rows @ d_loads[6:8, :6] @ ca.diag(wrench_scale),
                        ca.SX.eye(2) - twist_rows @ d_angles[6:8, :],
                    ),
                )
                k = ca.diagcat(k, ca.SX.eye(2))
                dr_dload = ca.vertcat(dr_dload, -twist * d_loads[6:8, 6])
            return j, k, dr_dload

        def energy_gradient_map(sens: ca.SX, tip: ca.SX) -> ca.SX:
            """B, with g = B r the total potential's gradient in the unknowns and B dr/dx
            its Hessian at an equilibrium: the tip's (displacement, spatial rotation) per
            unknown, transposed, times the wrench imbalance (the rod's elastic energy
            changes by n(L).dp + m(L).dtheta, the loads' by -f.dp - tau.dtheta), and
            GJ / L times the twist residual per tip angle."""
            pose = ca.vertcat(
                sens[0:3, 0:6],
                2 * _rotation_rates(tip[3:7]).T @ sens[3:7, 0:6] / ca.dot(tip[3:7], tip[3:7]),
            ) @ ca.diag(wrench_scale)
            out = pose.T @ ca.diag(1 / row_scale)
            return out if twist is None else ca.diagcat(out, ca.diag(1 / twist))

        def shoot(steps: int, sensitivities: bool = False, nodes: list | None = None):
            rate = weight_rate if sensitivities else None
            return rod.shoot(base_wrench, length, ei, load * weight_rate, steps, rate, nodes)

        tip, _ = shoot(rod.STEPS)
        r, loads_derivatives, tip_loads = at(tip)
        # The solver's matrices: the coarse integration's sensitivities with the loads'
        # derivatives at the (full) tip, where the residual needs the loads anyway.
        coarse_nodes: list = []
        coarse_tip, coarse = shoot(COARSE_STEPS, True, coarse_nodes)
        jac_solver, k_solver, dr_dload = derivatives(coarse, loads_derivatives)
        gradient_map = energy_gradient_map(coarse, coarse_tip)
        # The exact dr/dx: sensitivities and loads of one full integration.
        tip_exact, exact = shoot(rod.STEPS, True)
        jac = derivatives(exact, at(tip_exact)[1])[0]
        # The stability test, from the coarse integration like the solver's matrices (a
        # relative error of about 1e-5 moves a verdict only that close to a fold, where
        # the solver places folds no closer; the full integration's sensitivities would
        # cost three Newton iterations more per state): the restricted Jacobians at its
        # nodes, dr/dx at the tip, and the energy's Hessian in the unknowns (see the class).
        unit = ca.vertcat(length * ca.DM.ones(3), ca.DM.ones(self.n_unknowns - 3))
        hessian = (length / ei) * ca.diag(unit) @ gradient_map
        focal = ca.vertcat(
            restricted(coarse_nodes, tip, loads_derivatives, tip_loads),
            ca.vec(jac_solver),
            ca.vec(hessian @ jac_solver @ ca.diag(unit)),
        )
        frame = rod.frame_from_quaternion(tip[3:7])
        return r, jac, jac_solver, k_solver, dr_dload, focal, gradient_map, tip[0:3], frame

    def _field_model(self, s: Symbols):
        """p (3) [m] -> (B [T], dB/dp [T/m]) of the model's field
        (:func:`design.model.field.field_model`): permanent magnets exact with
        ``near_field``, else their point dipoles."""
        return field_model(s, "near_field" in self.effects)

    def unknown_scale(self, params: np.ndarray) -> np.ndarray:
        """Scale of each unknown for dimensionless norms: the free length for those in
        metres, 1 for angles; shape (n_unknowns,) for params (k,), (n_unknowns, N) for
        params (k, N). [m or rad]"""
        params = np.asarray(params, float)
        length = params[index("free_length")]
        out = np.ones((self.n_unknowns,) + length.shape)
        out[: 2 if self.linear_rod else 3] = length
        return out

    @staticmethod
    def _axial_torques(field_model, position, frame, angles, moment, s, load) -> ca.SX:
        """Torque on each ring about the tip tangent: external field plus the other ring.
        [N m], shape (2,) (distal, proximal)."""
        from design.ring_coupling import coupling_coefficient, coupling_torques
        from design.wrench import magnet_torque, ring_moment_vector

        tangent = frame[:, 0]
        out = []
        proximal, distal = ring_positions(s, position, frame)
        for i, p in enumerate((distal, proximal)):
            m_i = ring_moment_vector(angles[i], frame, moment)
            out.append(ca.dot(tangent, magnet_torque(field_model(p)[0], m_i)))
        k12 = load**2 * coupling_coefficient(
            s["magnet_outer_diameter"],
            s["magnet_inner_diameter"],
            s["magnet_length"],
            s.magnet_spacing,
            s["magnet_remanence"],
        )
        t1, t2 = coupling_torques(angles[0], angles[1], k12)
        return ca.vertcat(out[0] + t1, out[1] + t2)

    def linear(self) -> RingPairModel:
        """The same model on the linear rod (``large_deflection`` switched off)."""
        return model_for(self.effects - {"large_deflection"}, self.layout)

    def for_design(self, design: Design) -> RingPairModel:
        """The model with these effects for ``design``'s field (its layout): itself where
        the layouts agree."""
        layout = layout_of(design)
        return self if layout == self.layout else model_for(self.effects, layout)

    @property
    def name(self) -> str:
        """'baseline' or the sorted effect names joined by '+'."""
        return "+".join(sorted(self.effects)) or "baseline"

    @staticmethod
    def parameters(design: Design) -> np.ndarray:
        """Parameter vector of ``design``: :data:`design.registry.NAMES`, then its field
        sources' (:func:`design.registry.model_vector`), shape (n,), for the model of its
        field (:meth:`for_design`). [SI]"""
        return model_vector(design)


@cache
def model_for(
    effects: frozenset[str] = frozenset(), layout: FieldLayout = CLASSIC
) -> RingPairModel:
    """The model with ``effects`` for the field ``layout``, built once per process
    (building its CasADi functions takes 50-100 ms; models are equal and hash by their
    effects and layout)."""
    return RingPairModel(frozenset(effects), layout)
