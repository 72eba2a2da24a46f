"""Rotational stops and pre-twist of the ring pair (the paper's "relative rotational
limits", with the transmissions twisted "enough so that any torsional strain is
compensated").

The mounting pieces' key and notch (:mod:`design.mounting`) hold the rings' relative angle
rho = theta1 - theta2 (at the tip) within [0, S], S the stop angle. In the model the stop is
a contact, written as a stiff, smooth penalty on the rings' angles, so that the equilibrium
stays a root of one residual: the stop potential k (Psi(-rho) + Psi(rho - S)) gives the
torque

    lambda = k (psi(-rho) - psi(rho - S))   on the distal ring (theta1), -lambda on the
                                            proximal one (theta2),

psi(u) = Psi'(u) the ramp max(u, 0) with its corner rounded over a width ``STOP_SMOOTHING``
(u^2 / 2 eps below eps, u - eps / 2 above): C1, exactly zero off contact, so the torsion
model is unchanged wherever the rings are inside their range. The contact stiffness
k = STOP_STIFFNESS / (L / GJ_wire + L / GJ_catheter) is that many times the loop of the two
transmissions in series: a ring held at its stop sits short of it by its contact torque
over k, 1 / STOP_STIFFNESS of the relative twist that torque makes.

The pre-twist p is an offset of the wire's command (theta1) against the catheter's, set when
the robot is assembled; the commanded relative angle is taken within one turn centred on
the stops' range (commands are angles: 350 deg against 0 deg is -10 deg), then the
pre-twist added:

    c1' = c2 + S / 2 + wrap(c1 - c2 - S / 2) + p,    wrap(u) in [-pi, pi).

Closed forms (tests/design/test_stops.py): with no field and no ring coupling, a command
beyond the stop holds the rings at it (rho = 0 or S, less the penetration) with the
contact torque lambda = (rho_c - rho) / C through the transmissions, C = L / GJ_wire + L /
GJ_catheter; off the stops, the pre-twist that holds the rings at rho against their mutual
torque K12 sin(rho) is p = rho - rho_c - C K12 sin(rho).

Every function takes numbers or CasADi expressions alike. SI units are used for all inputs
and outputs.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from design.geometry import is_symbolic

STOP_STIFFNESS = 1e4
"""Contact stiffness of the stops over that of the two transmissions in series. [-]"""
STOP_SMOOTHING = 1e-6
"""Width over which the stop's contact sets in (the ramp's rounded corner). [rad]"""


def _where(condition: Any, yes: Any, no: Any) -> Any:
    if is_symbolic(condition, yes, no):
        return ca.if_else(condition, yes, no)
    return np.where(condition, yes, no)


def _ramp(u: Any) -> Any:
    """max(u, 0) with its corner rounded over :data:`STOP_SMOOTHING` (C1). [rad]"""
    eps = STOP_SMOOTHING
    return _where(u <= 0, 0 * u, _where(u < eps, u**2 / (2 * eps), u - eps / 2))


def stop_stiffness(twist_compliance: Any) -> Any:
    """Contact stiffness k of the stops from the transmissions' compliances L / GJ (wire,
    catheter), shape (2,). [N m / rad]"""
    return STOP_STIFFNESS / (twist_compliance[0] + twist_compliance[1])


def stop_torque(relative: Any, stop_angle: Any, stiffness: Any) -> Any:
    """Torque lambda of the stops on the distal ring (-lambda on the proximal one) at the
    relative angle rho = theta1 - theta2; positive at the lower stop (rho < 0), negative at
    the upper (rho > S). [N m]

    relative : rho. [rad]
    stop_angle : S. [rad]
    stiffness : k (:func:`stop_stiffness`). [N m / rad]
    """
    return stiffness * (_ramp(-relative) - _ramp(relative - stop_angle))


def commanded_angles(command: Any, stop_angle: Any, pretwist: Any) -> tuple[Any, Any]:
    """The commands the transmissions twist from: the relative command within one turn
    centred on the stops' range, the wire's offset by the pre-twist. [rad]

    command : (theta1, theta2) commanded at the base. [rad]
    """
    c1, c2 = command[0], command[1]
    mid = stop_angle / 2
    u = c1 - c2 - mid
    floor = ca.floor if is_symbolic(u) else np.floor
    wrapped = u - 2 * math.pi * floor((u + math.pi) / (2 * math.pi))
    return c2 + mid + wrapped + pretwist, c2


def resting_angles(
    command: Any, stop_angle: Any, pretwist: Any, twist_compliance: Any
) -> tuple[Any, Any]:
    """Tip angles of the unloaded robot (no field, no coupling) against its stops: the
    transmissions, springs of compliance C_i = L / GJ_i, share the contact torque
    lambda = k (penetration - eps / 2) / (1 + k C), C = C_1 + C_2, where a command lies
    beyond a stop (exact once the penetration exceeds :data:`STOP_SMOOTHING`). [rad]"""
    c1, c2 = commanded_angles(command, stop_angle, pretwist)
    k = stop_stiffness(twist_compliance)
    compliance = twist_compliance[0] + twist_compliance[1]
    rho = c1 - c2
    below = k * (-rho - STOP_SMOOTHING / 2) / (1 + k * compliance)
    above = -k * (rho - stop_angle - STOP_SMOOTHING / 2) / (1 + k * compliance)
    eps = STOP_SMOOTHING / 2
    torque = _where(rho < -eps, below, _where(rho > stop_angle + eps, above, 0 * rho))
    return c1 + twist_compliance[0] * torque, c2 - twist_compliance[1] * torque
