"""Force and torque of the external field on the two tip rings (paper eqs. 1-2).

Geometry (docs/formats.md): the proximal ring (angle theta2, turned by the catheter) is
centred on the rod tip p; the distal ring (theta1, turned by the wire) one centre spacing
delta further along the tip tangent n. Each ring's moment lies in the tip cross-section:
m_i = |m| (cos theta_i y_tip + sin theta_i z_tip).

On each ring (point dipole in the field B, eq. 1):
    f_i = (dB/dp)^T m_i = grad(m_i . B),   tau_i = m_i x B.
The wrench about the rod tip (eq. 2) adds the lever of the distal ring's force only:
    f = f_1 + f_2,   tau = tau_1 + tau_2 + delta n x f_1.
The paper's eq. 2b puts delta n x (f_1 + f_2), a lever on the proximal ring too, which sits
on the tip itself; with the paper's delta ~ 0 the two agree.

SI units are used for all inputs and outputs.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca

from design.geometry import ring_centres

FieldModel = Callable[[ca.SX], tuple[ca.SX, ca.SX]]
"""p (3,) base frame [m] -> (B (3,) [T], dB/dp (3, 3) [T/m])."""


def ring_moment_vector(angle: ca.SX, frame: ca.SX, magnitude: ca.SX) -> ca.SX:
    """Moment of a diametric ring turned by ``angle`` about the tip tangent.

    angle : from the tip frame's y axis towards its z axis. [rad]
    frame : tip frame, columns (tangent, y_tip, z_tip) in the base frame, shape (3, 3). [-]
    magnitude : moment magnitude. [A m^2]
    Returns the moment, base frame, shape (3,). [A m^2]
    """
    return magnitude * (ca.cos(angle) * frame[:, 1] + ca.sin(angle) * frame[:, 2])


def magnet_force(field_gradient: ca.SX, moment: ca.SX) -> ca.SX:
    """Force on a point dipole, f = (dB/dp)^T m (eq. 1a). [N]"""
    return field_gradient.T @ moment


def magnet_torque(field: ca.SX, moment: ca.SX) -> ca.SX:
    """Torque on a point dipole, tau = m x B (eq. 1b). [N m]"""
    return ca.cross(moment, field)


def tip_wrench(
    field_model: FieldModel,
    tip_position: ca.SX,
    tip_frame: ca.SX,
    angles: ca.SX,
    ring_moment: ca.SX,
    magnet_spacing: ca.SX,
) -> tuple[ca.SX, ca.SX]:
    """Total force and torque (about the rod tip) of the field on the ring pair.

    tip_position : rod tip = proximal ring centre, base frame, shape (3,). [m]
    tip_frame : shape (3, 3), columns (tangent, y_tip, z_tip). [-]
    angles : (theta1 distal, theta2 proximal) tip angles. [rad]
    ring_moment : moment magnitude of each ring. [A m^2]
    magnet_spacing : centre spacing delta. [m]
    Returns (force (3,) [N], torque (3,) [N m]), base frame.
    """
    tangent = tip_frame[:, 0]
    proximal, distal = ring_centres(tip_position, tangent, magnet_spacing)
    m1 = ring_moment_vector(angles[0], tip_frame, ring_moment)
    m2 = ring_moment_vector(angles[1], tip_frame, ring_moment)
    b1, g1 = field_model(distal)
    b2, g2 = field_model(proximal)
    f1 = magnet_force(g1, m1)
    f2 = magnet_force(g2, m2)
    torque = magnet_torque(b1, m1) + magnet_torque(b2, m2) + magnet_spacing * ca.cross(tangent, f1)
    return f1 + f2, torque
