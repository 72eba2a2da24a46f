"""The ring-pair model: one set of CasADi expressions, with switchable physical effects,
from which every numeric function (equilibrium residual, Jacobian, stability indicator,
tip pose) is built.

Baseline (the paper's model, derived anew): point-dipole external field, linear cantilever
under the tip wrench, transmissions rigid in torsion, no ring coupling, no gravity, no
friction. Effects (spec/formats.md names), each reducing to the baseline in its limit:

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

Unknowns x: rod coordinates (linear: q = (dy, dz, phi_y, phi_z); large deflection: the
base internal force n0 and moment m0, scaled to (n0 L^3 / EI, m0 L / EI)), then the tip
angles with ``torsion``. The residual is
scaled to metres/radians (its infinity norm is the convergence measure). SI units are
used for all inputs and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import casadi as ca
import numpy as np

from design import cantilever, rod
from design.dipole import dipole_field, dipole_field_gradient
from design.magnets import cylinder_moment, ring_moment, ring_volume
from design.parameters import NAMES, parameter_vector
from design.params import Design
from design.sections import polar_moment_of_area, second_moment_of_area, shear_modulus
from design.wrench import tip_wrench

EFFECTS = ("near_field", "large_deflection", "torsion", "gravity", "hysteresis")
"""Model extensions by name (spec/formats.md)."""


DEFAULT_EFFECTS = frozenset({"near_field", "large_deflection", "gravity"})
"""The model for design work: the most faithful that is well posed from a design file alone
and stays fast (about 2,100 configurations per second on two cores). ``torsion`` is left out:
with touching rings (kappa > 1) it makes the robot multistable, so the state depends on the
path driven and on mechanical stops, not on the commanded angles alone; ``hysteresis`` needs
friction angles, which come from bench data."""


def available_effects() -> tuple[str, ...]:
    """The effects this version implements (all of EFFECTS once each is wired in)."""
    return EFFECTS


def parse_effects(text: str) -> frozenset[str]:
    """'none', 'default' (:data:`DEFAULT_EFFECTS`), 'all' or a comma list of effect names;
    ValueError names the bad one."""
    text = text.strip()
    if text in ("", "none", "baseline"):
        return frozenset()
    if text == "default":
        return DEFAULT_EFFECTS
    if text == "all":
        return frozenset(available_effects())
    names = [t.strip() for t in text.split(",") if t.strip()]
    bad = [n for n in names if n not in EFFECTS]
    if bad:
        raise ValueError(
            f"unknown model effect {bad[0]!r}; expected 'none', 'default', 'all' or a comma "
            f"list of {', '.join(EFFECTS)}"
        )
    return frozenset(names)


class Symbols(dict):
    """Parameter symbols by name, with the derived quantities the model uses."""

    def __init__(self, prm: ca.SX) -> None:
        super().__init__(zip(NAMES, ca.vertsplit(prm), strict=True))
        s = self
        tubes = {}
        for tube in ("catheter", "wire"):
            od, idia = s[f"{tube}_outer_diameter"], s[f"{tube}_inner_diameter"]
            e = s[f"{tube}_youngs_modulus"]
            tubes[tube] = {
                "EI": e * second_moment_of_area(od, idia),
                "GJ": shear_modulus(e, s[f"{tube}_poisson_ratio"]) * polar_moment_of_area(od, idia),
                "weight_per_length": s[f"{tube}_density"] * np.pi / 4 * (od**2 - idia**2),
            }
        self.bending_rigidity = s["bending_rigidity_scale"] * (
            tubes["catheter"]["EI"] + tubes["wire"]["EI"]
        )
        # Ring 1 (distal, theta1) is turned by the wire, ring 2 (proximal) by the catheter.
        self.torsional_rigidity = ca.vertcat(
            s["wire_torsion_scale"] * tubes["wire"]["GJ"],
            s["catheter_torsion_scale"] * tubes["catheter"]["GJ"],
        )
        self.rod_mass_per_length = (
            tubes["catheter"]["weight_per_length"] + tubes["wire"]["weight_per_length"]
        )
        od, idia, h = s["ring_outer_diameter"], s["ring_inner_diameter"], s["ring_length"]
        self.ring_moment = ring_moment(od, idia, h, s["ring_remanence"])
        self.ring_mass = s["ring_density"] * ring_volume(od, idia, h)
        self.ring_spacing = h + s["ring_gap"]
        axis = ca.vertcat(s["external_axis_x"], s["external_axis_y"], s["external_axis_z"])
        self.external_axis = axis / ca.norm_2(axis)
        self.external_center = ca.vertcat(
            s["external_center_x"], s["external_center_y"], s["external_center_z"]
        )
        self.external_moment = self.external_axis * cylinder_moment(
            s["external_diameter"], s["external_length"], s["external_remanence"]
        )
        self.gravity = ca.vertcat(s["gravity_x"], s["gravity_y"], s["gravity_z"])


@dataclass(frozen=True)
class RingPairModel:
    """The model with a set of effects switched on (empty: the baseline).

    Built once, as CasADi functions:
    ``residual`` (x, command, params) -> (r, dr/dx): r = 0 at equilibrium, in m or rad;
    ``stability`` (x, command, params) -> indicator, all entries > 0 iff stable;
    ``pose`` (x, command, params) -> (position (3), frame (3x3), tip angles (2));
    ``initial`` (command, params) -> x0, the straight robot with tip angles = command;
    ``predictor`` (large_deflection only; else None) (x_linear, command, params) -> x0, a
    start from the equilibrium x_linear of :meth:`linear` (the same effects on the linear
    rod).
    ``command`` are the ring angles set at the base (theta1 distal, theta2 proximal) [rad].
    """

    effects: frozenset[str] = frozenset()
    n_unknowns: int = field(init=False)
    residual: ca.Function = field(init=False, repr=False, compare=False)
    stability: ca.Function = field(init=False, repr=False, compare=False)
    pose: ca.Function = field(init=False, repr=False, compare=False)
    initial: ca.Function = field(init=False, repr=False, compare=False)
    predictor: ca.Function | None = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        effects = frozenset(self.effects)
        object.__setattr__(self, "effects", effects)
        unknown = effects - set(EFFECTS)
        if unknown:
            raise ValueError(
                f"unknown model effect(s) {sorted(unknown)}; expected any of {list(EFFECTS)}"
            )
        large = "large_deflection" in effects
        n_rod = 6 if large else 4
        n = n_rod + (2 if "torsion" in effects else 0)
        object.__setattr__(self, "n_unknowns", n)

        x = ca.SX.sym("x", n)
        command = ca.SX.sym("command", 2)
        prm = ca.SX.sym("params", len(NAMES))
        s = Symbols(prm)
        load = s["load_scale"]
        length, ei = s["free_length"], s.bending_rigidity

        def field_model(p: ca.SX) -> tuple[ca.SX, ca.SX]:
            offset = p - s.external_center
            if "near_field" in effects:
                from design.cylinder_field import cylinder_field

                return cylinder_field(
                    offset,
                    s.external_axis,
                    s["external_diameter"] / 2,
                    s["external_length"],
                    s["external_remanence"],
                )
            return dipole_field(offset, s.external_moment), dipole_field_gradient(
                offset, s.external_moment
            )

        angles = x[n_rod : n_rod + 2] if "torsion" in effects else command
        moment = load * s.ring_moment
        distributed = ca.SX.zeros(3)
        if "gravity" in effects:
            distributed = s.rod_mass_per_length * load * s.gravity

        def tip_loads(position: ca.SX, frame: ca.SX, angles: ca.SX = angles) -> tuple[ca.SX, ca.SX]:
            """Force and moment about the rod tip at this tip pose. [N, N m]"""
            force, torque = tip_wrench(field_model, position, frame, angles, moment, s.ring_spacing)
            if "gravity" in effects:
                g = load * s.gravity
                ring_weight = s.ring_mass * g
                force = force + 2 * ring_weight + s["tip_mass"] * g
                torque = torque + s.ring_spacing * ca.cross(frame[:, 0], ring_weight)  # distal
            return force, torque

        q = x[:n_rod]
        # Rod unknowns of the large-deflection rod: the base wrench (n0, m0), scaled to
        # deflection units (n0 L^3 / EI, m0 L / EI) [m, rad], so that they, the residual and
        # the linear rod's coordinates all share one scale (Newton's tolerance, settling).
        wrench_scale = ca.vertcat(ei / length**3 * ca.DM.ones(3), ei / length * ca.DM.ones(3))
        if large:
            r_dimless, rod_state = rod.boundary_residual(
                q * wrench_scale, length, ei, tip_loads, distributed
            )
            position, frame = rod_state.position, rod_state.frame
            r_rod = r_dimless * ca.vertcat(length * ca.DM.ones(3), ca.DM.ones(3))
        else:
            position, frame = cantilever.tip_pose(q, length)
            force, torque = tip_loads(position, frame)
            bending = cantilever.bending_load(force, torque, frame[:, 0])
            r_rod = (
                q
                - cantilever.compliance(length, ei) @ bending
                - cantilever.distributed_load_response(distributed, length, ei)
            )
        stiffness = [cantilever.stiffness(length, ei)]
        residual = [r_rod]
        if "torsion" in effects:
            axial = self._axial_torques(field_model, position, frame, angles, moment, s, load)
            residual.append(angles - command - axial * length / s.torsional_rigidity)
            stiffness.append(ca.diag(s.torsional_rigidity / length))
        r = ca.vertcat(*residual)
        jac = ca.jacobian(r, x)
        if large:
            # Shooting unknowns have no stiffness form; a fold (snap-through) of the whole
            # system, where one mode loses stability, is where det(dr/dx) changes sign.
            # Unloaded, dr/dx = I, so det > 0 holds on every branch connected to rest
            # without crossing a fold. Symmetric (double) bifurcations are not seen.
            indicator = ca.det(jac)
        else:
            # Stiffness form K_s dr/dx (K_s = blockdiag(K, GJ/L)) is the Hessian of the total
            # potential for these conservative loads; its symmetric part positive definite
            # (Sylvester's criterion after a diagonal congruence scaling) means stable.
            h = ca.diagcat(*stiffness) @ jac
            hs = 0.5 * (h + h.T)
            scale = 1 / ca.sqrt(ca.fmax(ca.fabs(ca.diag(hs)), 1e-300))
            hn = hs * (scale @ scale.T)
            indicator = ca.vertcat(*[ca.det(hn[:k, :k]) for k in range(1, n + 1)])

        rod0 = ca.SX.zeros(n_rod)
        x_start = ca.vertcat(rod0, command) if "torsion" in effects else rod0
        predictor = None
        if large:
            # Newton starts from the base wrench that holds the straight rod, or, better
            # (``predictor``), from the wrench of the linear model's equilibrium x_lin,
            # balanced about its tip: n0 = f + q L, m0 = tau + p x f + L^2/2 e1 x q. A start
            # from the straight rod under a large tip moment would coil the rod (psi = M L/EI)
            # and Newton could settle on a far branch.
            straight = ca.vertcat(length, 0, 0), ca.SX.eye(3)
            base = rod.straight_base_wrench(*tip_loads(*straight), length, distributed)
            rod0 = ca.substitute(base / wrench_scale, x, x_start)
            x_lin = ca.SX.sym("x_linear", 4 + n - n_rod)
            lin_angles = x_lin[4:] if "torsion" in effects else command
            p_lin, frame_lin = cantilever.tip_pose(x_lin[:4], length)
            f, tau = tip_loads(p_lin, frame_lin, lin_angles)
            e1 = ca.DM([1.0, 0.0, 0.0])
            base = ca.vertcat(
                f + distributed * length,
                tau + ca.cross(p_lin, f) + length**2 / 2 * ca.cross(e1, distributed),
            )
            predictor = ca.Function(
                "predictor",
                [x_lin, command, prm],
                [ca.vertcat(base / wrench_scale, x_lin[4:])],
                ["x_linear", "command", "params"],
                ["x0"],
                {"cse": True},
            )
        object.__setattr__(self, "predictor", predictor)
        x0 = ca.vertcat(rod0, command) if "torsion" in effects else rod0
        io = ["x", "command", "params"]
        opts = {"cse": True}
        object.__setattr__(
            self,
            "residual",
            ca.Function("residual", [x, command, prm], [r, jac], io, ["r", "dr_dx"], opts),
        )
        object.__setattr__(
            self,
            "stability",
            ca.Function("stability", [x, command, prm], [indicator], io, ["indicator"], opts),
        )
        object.__setattr__(
            self,
            "pose",
            ca.Function(
                "pose",
                [x, command, prm],
                [position, frame, angles],
                io,
                ["position", "frame", "tip_angles"],
                opts,
            ),
        )
        object.__setattr__(
            self,
            "initial",
            ca.Function("initial", [command, prm], [x0], ["command", "params"], ["x0"], opts),
        )

    @staticmethod
    def _axial_torques(field_model, position, frame, angles, moment, s, load) -> ca.SX:
        """Torque on each ring about the tip tangent: external field plus the other ring.
        [N m], shape (2,) (distal, proximal)."""
        from design.ring_coupling import coupling_coefficient, coupling_torques
        from design.wrench import magnet_torque, ring_moment_vector

        tangent = frame[:, 0]
        out = []
        for i, p in enumerate((position + s.ring_spacing * tangent, position)):
            m_i = ring_moment_vector(angles[i], frame, moment)
            out.append(ca.dot(tangent, magnet_torque(field_model(p)[0], m_i)))
        k12 = load**2 * coupling_coefficient(
            s["ring_outer_diameter"],
            s["ring_inner_diameter"],
            s["ring_length"],
            s.ring_spacing,
            s["ring_remanence"],
        )
        t1, t2 = coupling_torques(angles[0], angles[1], k12)
        return ca.vertcat(out[0] + t1, out[1] + t2)

    def linear(self) -> RingPairModel:
        """The same model on the linear rod (``large_deflection`` switched off)."""
        return model_for(self.effects - {"large_deflection"})

    @property
    def name(self) -> str:
        """'baseline' or the sorted effect names joined by '+'."""
        return "+".join(sorted(self.effects)) or "baseline"

    @staticmethod
    def parameters(design: Design) -> np.ndarray:
        """Parameter vector of ``design``, shape (n,). [SI]"""
        return parameter_vector(design)


@cache
def model_for(effects: frozenset[str] = frozenset()) -> RingPairModel:
    """The model with ``effects``, built once per process (building its CasADi functions
    takes 50-100 ms; models are equal and hash by their effects)."""
    return RingPairModel(frozenset(effects))
