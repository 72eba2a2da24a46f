"""Magnetic interaction of the two coaxial, diametrically magnetised tip rings.

Two equal rings (outer radius R_o, inner radius R_i, length h, remanence B_r, magnetisation
M = B_r / mu0) share one axis; their centres are a spacing delta = h + gap apart (gap >= 0).
Ring i is magnetised in its cross-section at the angle theta_i about the common axis.

Symmetry fixes the angular dependence: turning both rings together changes nothing, and
each ring's magnetisation is a vector in the cross-section, so the interaction energy is
bilinear in (cos theta_i, sin theta_i) and invariant under a common rotation:

    U(theta_1, theta_2) = K12 cos(theta_1 - theta_2),
    T_1 = -dU/dtheta_1 = K12 sin(theta_1 - theta_2),   T_2 = -dU/dtheta_2 = -T_1,

T_i being the axial torque on ring i about the common axis, positive in the sense of
increasing theta_i. For rings side by side K12 > 0: antiparallel is preferred.

Coefficient from the real geometry (not point dipoles). A uniform magnetisation has no
volume charge; its surface charge sigma = M . n_hat lives on the curved surfaces only
(zero on the end faces): sigma = +M cos(phi - theta) on the outer cylinder, -M cos(phi -
theta) on the inner one. With the scalar potential of ring 1, H_1 = -grad phi_1, and no
overlap of the rings, U = -mu0 int M_2 . H_1 dV = mu0 int sigma_2 phi_1 dA, i.e.

    U = mu0 / (4 pi) sum_(a, b) s_a s_b M^2 R_a R_b int int int int
        cos(phi_1 - theta_1) cos(phi_2 - theta_2) / |r_1 - r_2| dphi_1 dphi_2 dz_1 dz_2,

over the surface pairs a of ring 1 and b of ring 2 (a, b in {outer, inner}, s = +1 outer,
-1 inner). The distance depends on psi = phi_1 - phi_2 and z_1 - z_2 only, with the
in-plane part rho^2 = R_a^2 + R_b^2 - 2 R_a R_b cos psi = (R_a - R_b)^2 + 4 R_a R_b
sin^2(psi / 2) (the second form has no cancellation). Integrating over phi_1 at fixed psi
gives pi cos(theta_1 - theta_2 - psi); the kernel is even in psi, so only
pi cos(theta_1 - theta_2) cos psi survives. The z integrals over ring 1 (-h/2..h/2) and
ring 2 (delta - h/2..delta + h/2) have the closed form

    G(psi) = int int dz_1 dz_2 / sqrt((z_1 - z_2)^2 + rho^2)
           = F(delta - h) + F(delta + h) - 2 F(delta),
    F(u) = u asinh(u / rho) - sqrt(u^2 + rho^2)   (F'' = 1 / sqrt(u^2 + rho^2)).

Since asinh(u / rho) = log(u + sqrt(u^2 + rho^2)) - log rho and the weights (1, 1, -2) of
the three arguments cancel in u ((delta - h) + (delta + h) - 2 delta = 0), the log rho
terms drop out exactly and G uses the safe form

    F~(u) = u log(u + sqrt(u^2 + rho^2)) - sqrt(u^2 + rho^2),

finite at rho -> 0 for every u >= 0 (F~(0) = -rho; F~' = log(u + sqrt(u^2 + rho^2))). So

    K12 = mu0 M^2 / 4 [R_o^2 I(R_o, R_o) + R_i^2 I(R_i, R_i) - 2 R_o R_i I(R_o, R_i)],
    I(R_a, R_b) = int_0^(2 pi) cos psi G(psi) dpsi = 2 int_0^pi cos psi G(psi) dpsi.

The last integral is a fixed Gauss-Legendre rule in t on [0, 1] with psi = pi t^3
(QUADRATURE_NODES nodes, NODE_GRADING = 3), which clusters nodes at psi = 0. There, for
equal radii, rho -> 0: at gap = 0 the integrand is smooth on [0, pi] (F~(0) = -2 R
sin(psi / 2)), but for a small gap it has a feature of width ~gap / R at psi = 0 and its
derivative with respect to the gap (or the length) has the integrable singularity
log rho; the grading makes both converge fast (at 32 nodes, K12 to ~1e-11 relative for
any gap, dK12/dgap at gap = 0 to ~1e-8; see the tests). The second derivative in the gap
is truly infinite at gap = 0 (K12 has a gap log(gap) term); the rule returns a large,
finite value there. A floor (RHO_FLOOR R_o)^2 in rho^2 keeps a solid disc (R_i = 0)
finite too; it changes K12 by ~1e-12 relative.

Far apart the rings are point dipoles side by side (m = M pi (R_o^2 - R_i^2) h):
K12 -> mu0 m^2 / (4 pi delta^3) [1 - 3 (R_o^2 + R_i^2) / delta^2 + h^2 / delta^2 + ...].
Close together they are far weaker than that: the touching demonstrator's K12 is ~2.4 %
of the point-dipole value. Far apart the second difference in u and the cos psi projection
cancel to ~(h / delta)^2 (R_o / delta)^2, so round-off grows to ~1e-8 relative at
delta = 20 D_o and ~1e-6 at 80 D_o (irrelevant for tip rings, delta ~ h).

Everything is on CasADi SX with a fixed graph, so the geometry and remanence may be NLP
variables and the function compiles to C. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from design.constants import MU0

__all__ = [
    "NODE_GRADING",
    "QUADRATURE_NODES",
    "RHO_FLOOR",
    "coupling_coefficient",
    "coupling_coefficient_function",
    "coupling_energy",
    "coupling_torques",
]

QUADRATURE_NODES = 32
"""Gauss-Legendre nodes of the psi integral. [-]"""

NODE_GRADING = 3
"""Exponent p of the node map psi = pi t^p, t in [0, 1]. [-]"""

RHO_FLOOR = 1e-12
"""Floor of the in-plane distance rho, as a fraction of the outer radius. [-]"""

_SYMBOLIC = (ca.SX, ca.MX)


def _psi_rule(nodes: int, grading: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes psi_k in (0, pi) and weights w_k with sum_k w_k f(psi_k) ~ int_0^pi f dpsi."""
    t, w = np.polynomial.legendre.leggauss(nodes)
    t, w = (t + 1) / 2, w / 2
    return math.pi * t**grading, w * math.pi * grading * t ** (grading - 1)


def _f_tilde(u: Any, rho2: Any) -> Any:
    """F~(u) = u log(u + sqrt(u^2 + rho^2)) - sqrt(u^2 + rho^2), u >= 0, rho^2 > 0. [m]"""
    root = ca.sqrt(u**2 + rho2)
    return u * ca.log(u + root) - root


def _angular_integral(
    radius_a: Any, radius_b: Any, length: Any, spacing: Any, floor2: Any, rule: tuple
) -> Any:
    """I(R_a, R_b) = int_0^(2 pi) cos psi G(psi) dpsi (module docstring). [m^2]"""
    total = 0
    gap = spacing - length
    for psi, weight in zip(*rule, strict=True):
        rho2 = (radius_a - radius_b) ** 2 + 4 * radius_a * radius_b * math.sin(psi / 2) ** 2
        rho2 = rho2 + floor2
        g = _f_tilde(gap, rho2) + _f_tilde(spacing + length, rho2) - 2 * _f_tilde(spacing, rho2)
        total = total + (2 * weight * math.cos(psi)) * g
    return total


def _coupling_expression(
    outer_diameter: Any, inner_diameter: Any, length: Any, spacing: Any, remanence: Any, nodes: int
) -> Any:
    """K12 on CasADi symbols or numbers (module docstring). [J]"""
    rule = _psi_rule(nodes, NODE_GRADING)
    r_o, r_i = outer_diameter / 2, inner_diameter / 2
    floor2 = (RHO_FLOOR * r_o) ** 2
    m = remanence / MU0  # magnetisation [A/m]
    i_oo = _angular_integral(r_o, r_o, length, spacing, floor2, rule)
    i_ii = _angular_integral(r_i, r_i, length, spacing, floor2, rule)
    i_oi = _angular_integral(r_o, r_i, length, spacing, floor2, rule)
    return MU0 * m**2 / 4 * (r_o**2 * i_oo + r_i**2 * i_ii - 2 * r_o * r_i * i_oi)


@lru_cache(maxsize=4)
def coupling_coefficient_function(nodes: int = QUADRATURE_NODES) -> ca.Function:
    """K12 as a ``casadi.Function`` (outer_diameter, inner_diameter, length, spacing,
    remanence) -> K12, arguments as in :func:`coupling_coefficient`.

    For batches: compile it with :func:`design.compiled.compile_function` and ``.map``.
    """
    if nodes < 2:
        raise ValueError(f"nodes must be an integer >= 2; got {nodes}")
    names = ["outer_diameter", "inner_diameter", "length", "spacing", "remanence"]
    args = [ca.SX.sym(name) for name in names]
    outer, inner, length, spacing, remanence = args
    k12 = _coupling_expression(outer, inner, length, spacing, remanence, nodes)
    return ca.Function("ring_coupling", args, [k12], names, ["K12"])


def _check_numeric(outer_diameter, inner_diameter, length, spacing, remanence) -> None:
    values = {
        "outer_diameter": outer_diameter,
        "inner_diameter": inner_diameter,
        "length": length,
        "spacing": spacing,
        "remanence": remanence,
    }
    for name, value in values.items():
        if not math.isfinite(value):
            raise ValueError(f"{name} must be a finite number; got {value}")
    if not 0 <= inner_diameter < outer_diameter:
        raise ValueError(
            f"inner_diameter must be in [0, outer_diameter ({outer_diameter} m)); "
            f"got {inner_diameter} m"
        )
    if length <= 0:
        raise ValueError(f"length must be positive; got {length} m")
    if spacing < length:
        raise ValueError(
            f"spacing must be at least the ring length ({length} m), or the rings overlap; "
            f"got {spacing} m"
        )


def coupling_coefficient(
    outer_diameter: Any,
    inner_diameter: Any,
    length: Any,
    spacing: Any,
    remanence: Any,
    *,
    nodes: int = QUADRATURE_NODES,
) -> Any:
    """Coefficient K12 of the ring-ring interaction energy U = K12 cos(theta_1 - theta_2).

    outer_diameter : ring outer diameter D_o. [m]
    inner_diameter : ring inner diameter D_i, 0 <= D_i < D_o (0: solid disc). [m]
    length : ring length h along the axis, > 0. [m]
    spacing : distance delta between the two ring centres along the axis, delta >= h
        (delta = h + gap; delta = h: the rings touch). [m]
    remanence : remanent flux density B_r of both rings (polarisation mu0 M). [T]
    nodes : Gauss-Legendre nodes of the angular integral (for convergence studies). [-]
    Returns K12 [J]: a float for numbers (checked; ValueError names a bad argument), a
    CasADi expression when any argument is SX (inlined graph) or MX (call node).

    The charge-integral formula and its quadrature are in the module docstring.
    """
    args = (outer_diameter, inner_diameter, length, spacing, remanence)
    if any(isinstance(a, _SYMBOLIC) for a in args):
        return coupling_coefficient_function(nodes)(*args)
    values = [float(a) for a in args]
    _check_numeric(*values)
    return float(coupling_coefficient_function(nodes)(*values))


def _sin_cos(angle: Any) -> tuple[Any, Any]:
    if isinstance(angle, (*_SYMBOLIC, ca.DM)):
        return ca.sin(angle), ca.cos(angle)
    return np.sin(angle), np.cos(angle)


def coupling_energy(theta1: Any, theta2: Any, k12: Any) -> Any:
    """Interaction energy of the two rings, U = K12 cos(theta_1 - theta_2).

    theta1, theta2 : magnetisation angles of rings 1 and 2 about the common axis (floats,
        numpy arrays or CasADi expressions). [rad]
    k12 : coupling coefficient from :func:`coupling_coefficient`. [J]
    Returns U. [J]
    """
    return k12 * _sin_cos(theta1 - theta2)[1]


def coupling_torques(theta1: Any, theta2: Any, k12: Any) -> tuple[Any, Any]:
    """Axial torques of the rings on each other, T_i = -dU/dtheta_i.

    theta1, theta2 : magnetisation angles of rings 1 and 2 about the common axis. [rad]
    k12 : coupling coefficient from :func:`coupling_coefficient`. [J]
    Returns (T1, T2) = (K12 sin(theta_1 - theta_2), -K12 sin(theta_1 - theta_2)), each
    about the common axis, positive in the sense of increasing theta_i. [N m]
    """
    torque = k12 * _sin_cos(theta1 - theta2)[0]
    return torque, -torque
