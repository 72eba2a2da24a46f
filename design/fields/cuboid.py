"""Exact field of a uniformly magnetised cuboid whose edges lie along the base axes, on
CasADi symbols.

A body of uniform polarisation J (remanence Br times the unit magnetisation) is, outside,
the field of the surface charge J . n / mu0 on its faces; inside B = mu0 H + J. For the
cuboid [-a, a] x [-b, b] x [-c, c] and J along z the charged faces z = +-c give, with
u = x - x_i, v = y - y_j, w = z - z_k for the eight corners (x_i = +-a, ...),
R = sqrt(u^2 + v^2 + w^2) and the corner sign s = (-1)^(i + j + k) (+ at (a, b, c)),
(Akoun & Yonnet [1]; Engel-Herbert & Hesjedal [2]):

    B_x = -J / (4 pi) sum s ln(v + R),   B_y = -J / (4 pi) sum s ln(u + R),
    B_z =  J / (4 pi) sum s atan2(u v, w R),

and the other two components of J by cyclic permutation of the axes. atan2 (rather than
atan(u v / (w R))) adds J inside the body, so the result is B everywhere, as magpylib's.
ln(v + R) cancels where v < 0 and u, w are small; there it is written
ln(u^2 + w^2) - ln(R - v), which is exact. B is singular on the edges only.

The gradient G = dB/dp is CasADi's exact derivative of B (no differences). SI units are
used for all inputs and outputs.

[1] G. Akoun, J.-P. Yonnet, "3D analytical calculation of the forces exerted between two
    cuboidal magnets", IEEE Trans. Magn. 20(5), 1962-1964 (1984),
    doi:10.1109/TMAG.1984.1063554.
[2] R. Engel-Herbert, T. Hesjedal, "Calculation of the magnetic stray field of a uniaxial
    magnetic domain", J. Appl. Phys. 97, 074504 (2005), doi:10.1063/1.1883308.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import casadi as ca

from design.fields.gradient import field_function

__all__ = ["cuboid_field", "cuboid_field_function", "cuboid_flux_density"]

_TINY = 1e-300


def _log_plus(v: ca.SX, r: ca.SX, rest2: ca.SX) -> ca.SX:
    """ln(v + R), R = sqrt(v^2 + rest2), without cancellation for v < 0."""
    return ca.if_else(v >= 0, ca.log(v + r), ca.log(ca.fmax(rest2, _TINY)) - ca.log(r - v))


def _z_polarised(offset, half, polarisation: ca.SX) -> list[ca.SX]:
    """(B_x, B_y, B_z) of the cuboid with half sides ``half`` = (a, b, c) polarised along z
    with ``polarisation`` J [T], at ``offset`` (3) from its centre [m]."""
    x, y, z = offset[0], offset[1], offset[2]
    bx: Any = 0
    by: Any = 0
    bz: Any = 0
    for si, xi in ((1, half[0]), (-1, -half[0])):
        u = x - xi
        for sj, yj in ((1, half[1]), (-1, -half[1])):
            v = y - yj
            for sk, zk in ((1, half[2]), (-1, -half[2])):
                w = z - zk
                s = si * sj * sk
                r = ca.sqrt(u**2 + v**2 + w**2)
                bx -= s * _log_plus(v, r, u**2 + w**2)
                by -= s * _log_plus(u, r, v**2 + w**2)
                bz += s * ca.atan2(u * v, w * r)
    k = polarisation / (4 * math.pi)
    return [k * bx, k * by, k * bz]


def cuboid_flux_density(
    offset: ca.SX, dimensions: ca.SX, magnetization: ca.SX, remanence: ca.SX
) -> ca.SX:
    """Flux density of a uniformly magnetised cuboid [1, 2].

    offset : shape (3,), field point minus cuboid centre, base frame. [m]
    dimensions : shape (3,), side lengths along the base axes x, y, z. [m]
    magnetization : shape (3,), unit magnetisation direction, base frame. [-]
    remanence : remanent flux density Br. [T]
    Returns B, shape (3,), base frame. [T]; exact outside and inside, singular on edges.
    """
    half = [dimensions[i] / 2 for i in range(3)]
    flux: list[Any] = [0, 0, 0]
    for axis in range(3):  # J along axis: rotate the axes so that it is the third one
        order = [(axis + 1) % 3, (axis + 2) % 3, axis]
        local = ca.vertcat(*(offset[i] for i in order))
        part = _z_polarised(local, [half[i] for i in order], remanence * magnetization[axis])
        for j, i in enumerate(order):
            flux[i] = flux[i] + part[j]
    return ca.vertcat(*flux)


_NAMES = ["offset", "dimensions", "magnetization", "remanence"]


@lru_cache(maxsize=2)
def cuboid_field_function(gradient: bool = True) -> ca.Function:
    """(offset, dimensions, magnetization, remanence) -> (B, G) [T, T/m] (B alone with
    ``gradient=False``) as a ``casadi.Function``; arguments as in
    :func:`cuboid_flux_density`."""
    return field_function("cuboid", cuboid_flux_density, _NAMES, [3, 3, 3, 1], gradient)


def cuboid_field(
    offset: ca.SX, dimensions: ca.SX, magnetization: ca.SX, remanence: ca.SX
) -> tuple[ca.SX, ca.SX]:
    """B (3,) [T] and G = dB/dp (3, 3), G[i, j] = dB_i / dp_j [T/m] of the cuboid;
    arguments as in :func:`cuboid_flux_density` (numbers or CasADi expressions)."""
    flux, grad = cuboid_field_function(True)(offset, dimensions, magnetization, remanence)
    return flux, grad
