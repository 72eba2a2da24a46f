"""Linear (small-deflection) cantilever under a tip wrench.

Derivation. Clamp at the origin, tangent e1, bending rigidity EI, free length L; force f
and moment tau at the tip s = L. The internal moment at s (small deflection) is
    M(s) = tau + (L - s) e1 x f,
curvature kappa = M / EI (bending components, perpendicular to e1), tip-frame rotation
phi(s) = int_0^s kappa and tangent t = e1 + phi x e1. Integrating twice:
    phi(L)   = L / EI tau_perp + L^2 / (2 EI) e1 x f,
    delta(L) = L^2 / (2 EI) tau x e1 + L^3 / (3 EI) f_perp.
So a tip force deflects the tip by F L^3 / (3 EI) and turns it by F L^2 / (2 EI); a tip
moment by T L^2 / (2 EI) and T L / EI (Gere & Timoshenko, Mechanics of Materials, table of
cantilever deflections).

Corrections to the paper (shared/seed, Sec. II-B): eq. 6a writes the force term of the
tip position as L/6 (e1 x f) x e1, i.e. F L^3 / (6 EI): the integral of (L s - s^2 / 2)
over [0, L] is L^3 / 3, so the factor is 1/3. Its grouped form eq. 8 writes one factor
L^2 / (2 EI) in front of (f, tau) for the position and L / EI for the tangent, which
drops a length on the force columns (they are not even dimensionally consistent with the
moment columns): the correct blocks are (L^3 / 3EI, L^2 / 2EI) for the position and
(L^2 / 2EI, L / EI) for the tangent, as above.

Generalised coordinates q = (delta_y, delta_z, phi_y, phi_z): tip displacement across the
base axis and the tip-frame rotation vector (no twist: the frame is carried by bending
alone). Their conjugate loads are (f_y, f_z, tau_y, tau_z); the compliance between them
is symmetric positive definite. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from design.frames import rotation_from_vector
from design.geometry import is_symbolic


def tip_pose(coordinates: ca.SX, free_length: Any) -> tuple[ca.SX, ca.SX]:
    """Tip position and frame of the linear rod.

    coordinates : q = (delta_y, delta_z, phi_y, phi_z). [m, m, rad, rad]
    free_length : L. [m]
    Returns (position (3,) base frame [m], frame (3, 3) columns (tangent, y_tip, z_tip)).
    The tip stays at x = L (axial shortening is second order and dropped by the linear
    theory); the frame is exp([phi]^) with phi = (0, phi_y, phi_z), which is orthonormal
    and equals I + [phi]^ to the theory's order.
    """
    position = ca.vertcat(free_length, coordinates[0], coordinates[1])
    frame = rotation_from_vector(ca.vertcat(0, coordinates[2], coordinates[3]))
    return position, frame


def base_moment(
    tip_force: Any, tip_moment: Any, free_length: Any, load_per_length: Any = None
) -> Any:
    """Moment at the clamp of the straight rod (the base moment, M(0) of the derivation)
    under a tip force f and moment tau (about the tip) and a uniform load w per length:
        m0 = tau + e1 x (L f + L^2 / 2 w),
    the tip force's arm L and the load's resultant w L at L / 2. Exact for the straight rod;
    the linear theory's moment wherever the deflection is small.

    tip_force, tip_moment, load_per_length : base frame, shape (3,); ``load_per_length``
        None is zero. [N, N m, N/m]
    free_length : L. [m]
    Returns m0, base frame, shape (3,): CasADi for CasADi inputs, else numpy. [N m]
    """
    symbolic = is_symbolic(tip_force, tip_moment, free_length, load_per_length)
    if symbolic:
        tip_moment = ca.vertcat(tip_moment)
    else:
        tip_force, tip_moment = np.asarray(tip_force, float), np.asarray(tip_moment, float)
    lever = free_length * tip_force
    if load_per_length is not None:
        load = load_per_length if symbolic else np.asarray(load_per_length, float)
        lever = lever + free_length**2 / 2 * load
    if symbolic:
        return tip_moment + ca.vertcat(0, -lever[2], lever[1])
    return tip_moment + np.array([0.0, -lever[2], lever[1]])


def bending_load(force: ca.SX, torque: ca.SX, tangent: ca.SX) -> ca.SX:
    """Loads conjugate to q: (f_y, f_z, tau_y, tau_z), with the torque's component along the
    tip tangent removed: that part twists the transmissions (which hold it) and does not
    bend the rod. [N, N, N m, N m]
    """
    bending_torque = torque - ca.dot(torque, tangent) * tangent
    return ca.vertcat(force[1], force[2], bending_torque[1], bending_torque[2])


def compliance(free_length: Any, bending_rigidity: Any) -> ca.SX:
    """Compliance C with q = C (f_y, f_z, tau_y, tau_z), shape (4, 4). [m/N, m/(N m), 1/(N m)]"""
    a = free_length**3 / (3 * bending_rigidity)
    b = free_length**2 / (2 * bending_rigidity)
    c = free_length / bending_rigidity
    return ca.vertcat(
        ca.horzcat(a, 0, 0, b),
        ca.horzcat(0, a, -b, 0),
        ca.horzcat(0, -b, c, 0),
        ca.horzcat(b, 0, 0, c),
    )


def stiffness(free_length: Any, bending_rigidity: Any) -> ca.SX:
    """Stiffness K = C^-1, closed form (each bending plane is a 2 x 2 block). [N/m, N, N m]"""
    ei, length = bending_rigidity, free_length
    k_ff = 12 * ei / length**3
    k_fm = 6 * ei / length**2
    k_mm = 4 * ei / length
    return ca.vertcat(
        ca.horzcat(k_ff, 0, 0, -k_fm),
        ca.horzcat(0, k_ff, k_fm, 0),
        ca.horzcat(0, k_fm, k_mm, 0),
        ca.horzcat(-k_fm, 0, 0, k_mm),
    )


def distributed_load_response(
    load_per_length: ca.SX, free_length: Any, bending_rigidity: Any
) -> ca.SX:
    """Coordinates q of the linear cantilever under a uniform load w per unit length, fixed in
    the base frame (self-weight). M(s) = (L - s)^2 / 2 e1 x w integrates to
    delta = L^4 / (8 EI) w_perp and phi = L^3 / (6 EI) e1 x w (Gere & Goodno, App. G case 1).
    load_per_length : shape (3,), base frame. [N/m]
    Returns q, shape (4,). [m, m, rad, rad]
    """
    w = load_per_length
    a = free_length**4 / (8 * bending_rigidity)
    b = free_length**3 / (6 * bending_rigidity)
    return ca.vertcat(a * w[1], a * w[2], -b * w[2], b * w[1])
