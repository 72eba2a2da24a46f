"""Exact field of a circular current loop (a coil of thin turns), on CasADi symbols.

A loop of radius a carrying the current N I (N turns of current I) about the axis n gives,
in cylindrical coordinates (rho, z) about its centre, with d^2 = z^2 + (a + rho)^2 and the
complementary modulus kc^2 = (z^2 + (a - rho)^2) / d^2 (Simpson et al. [1] written with
Bulirsch's cel [2], as :mod:`design.cylinder_field` writes its face loops):

    B_z = mu0 N I a / (pi d^3) C(kc, 1, (a - rho) / kc^2, a + rho),
    B_rho = mu0 N I a z / (pi d^3) C(kc, 1, 1 / kc^2, -1),

the direction of B_z given by the right-hand rule about n. On the axis B_rho / rho is
0 / 0; within rho < AXIS_SERIES a the field is the off-axis expansion of the on-axis field
b(z) = mu0 N I a^2 / (2 (z^2 + a^2)^(3/2)) (div B = 0, curl B = 0):
B_z = b - rho^2 b'' / 4 + rho^4 b'''' / 64, B_rho / rho = -b' / 2 + rho^2 b''' / 16
- rho^4 b^(5) / 384. Both branches are evaluated on guarded inputs. The gradient is
CasADi's exact derivative of B. B is singular on the wire only. Helmholtz and Maxwell
pairs are two coils. SI units are used for all inputs and outputs.

[1] J. Simpson, J. Lane, C. Immer, R. Youngquist, "Simple analytic expressions for the
    magnetic field of a circular current loop", NASA technical report 20010038494 (2001).
[2] R. Bulirsch, "Numerical calculation of elliptic integrals and elliptic functions.
    III", Numer. Math. 13, 305-315 (1969), doi:10.1007/BF02165405.
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca

from design.constants import MU0
from design.cylinder_field import _POLYNOMIALS, AXIS_SERIES, _cel_shared
from design.fields.gradient import field_function

__all__ = ["coil_field", "coil_field_function", "coil_flux_density"]


def _on_axis(z: ca.SX, radius: ca.SX, scale: ca.SX) -> list[ca.SX]:
    """b, b', ..., b^(5) of b = scale f'(z), f(u) = u / sqrt(u^2 + a^2)."""
    a2 = radius**2
    w = 1 / ca.sqrt(z**2 + a2)
    out, power = [], w
    for poly in _POLYNOMIALS:
        power = power * w**2
        out.append(scale * a2 * power * sum(c * z**i * a2**j for (i, j), c in poly.items()))
    return out


def coil_flux_density(
    offset: ca.SX, axis: ca.SX, radius: ca.SX, turns: ca.SX, current: ca.SX
) -> ca.SX:
    """Flux density of a circular current loop [1].

    offset : shape (3,), field point minus loop centre, base frame. [m]
    axis : shape (3,), unit normal of the loop (the current turns about it by the
        right-hand rule), base frame. [-]
    radius : loop radius a, > 0. [m]
    turns : number of turns N. [-]
    current : current I in each turn. [A]
    Returns B, shape (3,), base frame. [T]
    """
    a = radius
    z = ca.dot(offset, axis)
    t = offset - z * axis
    rho2 = ca.dot(t, t)
    near_axis = rho2 < (AXIS_SERIES * a) ** 2
    rho = ca.sqrt(ca.if_else(near_axis, (AXIS_SERIES * a) ** 2, rho2))
    d2 = z**2 + (a + rho) ** 2
    kc2 = (z**2 + (a - rho) ** 2) / d2
    c_z, c_rho = _cel_shared(ca.sqrt(kc2), [(1, (a - rho) / kc2, a + rho), (1, 1 / kc2, -1)])
    k = MU0 * turns * current * a / (math.pi * d2 * ca.sqrt(d2))
    exact_f, exact_h = k * z * c_rho / rho, k * c_z
    d0, d1, d2_, d3, d4, d5 = _on_axis(z, a, MU0 * turns * current / 2)
    series_f = -d1 / 2 + rho2 / 16 * d3 - rho2**2 / 384 * d5
    series_h = d0 - rho2 / 4 * d2_ + rho2**2 / 64 * d4
    f = ca.if_else(near_axis, series_f, exact_f)  # B_rho / rho
    h = ca.if_else(near_axis, series_h, exact_h)  # B_z
    return f * t + h * axis


_NAMES = ["offset", "axis", "radius", "turns", "current"]


@lru_cache(maxsize=2)
def coil_field_function(gradient: bool = True) -> ca.Function:
    """(offset, axis, radius, turns, current) -> (B, G) [T, T/m] (B alone with
    ``gradient=False``); arguments as in :func:`coil_flux_density`."""
    return field_function("coil", coil_flux_density, _NAMES, [3, 3, 1, 1, 1], gradient)


def coil_field(
    offset: ca.SX, axis: ca.SX, radius: ca.SX, turns: ca.SX, current: ca.SX
) -> tuple[ca.SX, ca.SX]:
    """B (3,) [T] and G = dB/dp (3, 3) [T/m] of the loop; arguments as in
    :func:`coil_flux_density` (numbers or CasADi expressions)."""
    flux, grad = coil_field_function(True)(offset, axis, radius, turns, current)
    return flux, grad
