"""Rotations on CasADi symbols."""

from __future__ import annotations

import casadi as ca


def skew(v: ca.SX) -> ca.SX:
    """The matrix [v]^ with [v]^ u = v x u."""
    return ca.vertcat(
        ca.horzcat(0, -v[2], v[1]),
        ca.horzcat(v[2], 0, -v[0]),
        ca.horzcat(-v[1], v[0], 0),
    )


def rotation_from_vector(phi: ca.SX) -> ca.SX:
    """Rotation matrix exp([phi]^) of a rotation vector phi (Rodrigues' formula). [-]

    The tiny offset under the square root keeps the expression and its derivatives finite
    at phi = 0, where it reduces to the identity to machine precision.
    """
    theta2 = ca.dot(phi, phi)
    theta = ca.sqrt(theta2 + 1e-300)
    k = skew(phi)
    # sin(t)/t and (1 - cos t)/t^2 in forms that stay accurate at small t.
    a = ca.if_else(theta2 < 1e-12, 1 - theta2 / 6, ca.sin(theta) / theta)
    b = ca.if_else(theta2 < 1e-12, 0.5 - theta2 / 24, (1 - ca.cos(theta)) / (theta2 + 1e-300))
    return ca.SX.eye(3) + a * k + b * (k @ k)
