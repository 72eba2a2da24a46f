"""Exact field of a uniformly magnetised sphere, on CasADi symbols.

Outside a sphere of diameter D and polarisation J = Br m (m the unit magnetisation) the
field is exactly that of the point dipole at its centre with moment
Br / mu0 pi D^3 / 6 m (Jackson, *Classical Electrodynamics*, 3rd ed., section 5.10);
inside it is uniform, B = 2 J / 3, with no gradient. SI units are used for all inputs and
outputs.
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca

from design.constants import MU0
from design.dipole import dipole_field, dipole_field_gradient

__all__ = ["sphere_field", "sphere_field_function", "sphere_moment"]


def sphere_moment(diameter: ca.SX, remanence: ca.SX) -> ca.SX:
    """Magnetic moment of the sphere, Br V / mu0. [A m^2]"""
    return remanence / MU0 * math.pi * diameter**3 / 6


def _build(offset, magnetization, diameter, remanence) -> list[ca.SX]:
    r2 = ca.dot(offset, offset)
    inside = r2 < (diameter / 2) ** 2
    guarded = ca.if_else(inside, ca.vertcat(diameter, 0, 0), offset)  # no 0 / 0 inside
    moment = sphere_moment(diameter, remanence) * magnetization
    flux = ca.if_else(inside, 2 * remanence / 3 * magnetization, dipole_field(guarded, moment))
    grad = ca.if_else(inside, ca.SX.zeros(3, 3), dipole_field_gradient(guarded, moment))
    return [flux, grad]


@lru_cache(maxsize=1)
def sphere_field_function() -> ca.Function:
    """(offset, magnetization, diameter, remanence) -> (B, G) [T, T/m]; arguments as in
    :func:`sphere_field`."""
    args = [ca.SX.sym("offset", 3), ca.SX.sym("magnetization", 3)]
    args += [ca.SX.sym("diameter"), ca.SX.sym("remanence")]
    return ca.Function(
        "sphere_field", args, _build(*args),
        ["offset", "magnetization", "diameter", "remanence"], ["B", "G"],
    )  # fmt: skip


def sphere_field(
    offset: ca.SX, magnetization: ca.SX, diameter: ca.SX, remanence: ca.SX
) -> tuple[ca.SX, ca.SX]:
    """Flux density and gradient of a uniformly magnetised sphere.

    offset : shape (3,), field point minus sphere centre, base frame. [m]
    magnetization : shape (3,), unit magnetisation direction, base frame. [-]
    diameter : sphere diameter. [m]
    remanence : remanent flux density Br. [T]
    Returns B (3,) [T] and G = dB/dp (3, 3), G[i, j] = dB_i / dp_j [T/m].
    """
    flux, grad = sphere_field_function()(offset, magnetization, diameter, remanence)
    return flux, grad
