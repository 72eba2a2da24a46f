"""The ring-pair model: one set of CasADi expressions from which every numeric function
(equilibrium residual, its Jacobian, tangent stiffness, tip pose, wrench) is built.

Baseline (the paper's model, derived anew): point-dipole external field, linear
cantilever with a tip wrench, transmissions rigid in torsion, no magnet coupling, no
gravity. Unknowns are the cantilever coordinates q (see :mod:`design.cantilever`); the
equilibrium is r(q) = q - C Q(q) = 0 with Q the bending loads of the magnetic wrench at
the pose q. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from design import cantilever
from design.dipole import dipole_field, dipole_field_gradient
from design.parameters import BASELINE, parameter_vector
from design.params import Design
from design.wrench import tip_wrench

EFFECTS = ("near_field", "large_deflection", "torsion", "gravity", "hysteresis")
"""Model extensions by name (spec/formats.md); none is implemented in the baseline yet."""

N_COORDINATES = 4


@dataclass(frozen=True)
class RingPairModel:
    """The model with a set of effects switched on (empty: the baseline).

    Attributes built once: ``residual`` (q, theta, params) -> (r, dr/dq, H) where H is the
    tangent stiffness K - dQ/dq (its symmetric part positive definite <=> stable);
    ``pose`` (q, params) -> (position, frame); ``wrench`` (q, theta, params) -> (f, tau).
    ``theta`` are the ring angles at the tip (theta1 distal, theta2 proximal) [rad].
    """

    effects: frozenset[str] = frozenset()
    parameter_names: tuple[str, ...] = BASELINE
    residual: ca.Function = field(init=False, repr=False, compare=False)
    pose: ca.Function = field(init=False, repr=False, compare=False)
    wrench: ca.Function = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        unknown = set(self.effects) - set(EFFECTS)
        if unknown:
            raise ValueError(
                f"unknown model effect(s) {sorted(unknown)}; expected any of {list(EFFECTS)}"
            )
        if self.effects:
            raise NotImplementedError(
                f"effects {sorted(self.effects)} are not implemented yet; only the baseline is"
            )
        q = ca.SX.sym("q", N_COORDINATES)
        theta = ca.SX.sym("theta", 2)
        prm = ca.SX.sym("params", len(self.parameter_names))
        s = dict(zip(self.parameter_names, ca.vertsplit(prm), strict=True))
        ext_moment = ca.vertcat(
            s["external_moment_x"], s["external_moment_y"], s["external_moment_z"]
        )
        ext_center = ca.vertcat(
            s["external_center_x"], s["external_center_y"], s["external_center_z"]
        )

        def field_model(p: ca.SX) -> tuple[ca.SX, ca.SX]:
            offset = p - ext_center
            return dipole_field(offset, ext_moment), dipole_field_gradient(offset, ext_moment)

        length, ei = s["free_length"], s["bending_rigidity"]
        position, frame = cantilever.tip_pose(q, length)
        force, torque = tip_wrench(
            field_model, position, frame, theta, s["ring_moment"], s["ring_spacing"]
        )
        load = cantilever.bending_load(force, torque, frame[:, 0])
        r = q - cantilever.compliance(length, ei) @ load
        dload = ca.jacobian(load, q)
        tangent_stiffness = cantilever.stiffness(length, ei) - dload
        object.__setattr__(
            self,
            "residual",
            ca.Function(
                "residual",
                [q, theta, prm],
                [r, ca.jacobian(r, q), tangent_stiffness],
                ["q", "theta", "params"],
                ["r", "dr_dq", "H"],
            ),
        )
        object.__setattr__(
            self,
            "pose",
            ca.Function(
                "pose", [q, prm], [position, frame], ["q", "params"], ["position", "frame"]
            ),
        )
        object.__setattr__(
            self,
            "wrench",
            ca.Function(
                "wrench",
                [q, theta, prm],
                [force, torque],
                ["q", "theta", "params"],
                ["force", "torque"],
            ),
        )

    def parameters(self, design: Design) -> np.ndarray:
        """Parameter vector of ``design`` for this model, shape (n,). [SI]"""
        return parameter_vector(design, self.parameter_names)
