"""Exact field of a uniformly, axially magnetised solid cylinder, on CasADi symbols.

The cylinder (radius a, length 2 b, remanence Br, magnetisation M = Br / mu0 along its axis)
is a solenoid sheet carrying the surface current M on its side. Derby & Olbert [1]
(after Bulirsch [2]) give its flux density in cylindrical coordinates
(rho, z) about the centre:

    B_rho = B0 [alpha_+ C(k_+, 1, 1, -1) - alpha_- C(k_-, 1, 1, -1)]
    B_z   = B0 a / (a + rho) [beta_+ C(k_+, g^2, 1, g) - beta_- C(k_-, g^2, 1, g)]

    B0 = Br / pi,  z_+- = z +- b,  alpha_+- = a / d_+-,  beta_+- = z_+- / d_+-,
    d_+- = sqrt(z_+-^2 + (a + rho)^2),  g = (a - rho) / (a + rho),
    k_+- = sqrt(z_+-^2 + (a - rho)^2) / d_+-,

with Bulirsch's complete elliptic integral (its first argument is the complementary modulus)

    C(kc, p, c, s) = int_0^(pi/2) (c cos^2 t + s sin^2 t)
                     / ((cos^2 t + p sin^2 t) sqrt(cos^2 t + kc^2 sin^2 t)) dt.

Caciagli et al. [3] give the same field with Legendre's K, E and Pi. Three steps make it
exact everywhere outside the magnet and twice differentiable by CasADi:

1. ``cel`` is Bulirsch's algorithm [2] with its AGM loop unrolled to CEL_ITERATIONS steps
   (machine precision for kc >= 1e-14, i.e. anywhere but within ~1e-14 a of a rim), so the
   graph is fixed and compiles to C.
2. C(kc, g^2, 1, g) jumps by pi / kc at rho = a (the surface current) and loses its
   precision there; each face term cancels the other's jump outside the magnet. The change
   of parameter n -> k^2 / n of Pi (DLMF section 19.7(iii)), written for cel, gives
   C(kc, g^2, 1, g) = C(kc, beta^2, 1 / (1 + g), beta^2 - g / (1 + g))
   + sign(g) pi / 2 sqrt((1 - g) / ((1 + g) (kc^2 - g^2))), whose last term adds exactly
   Br / 4 sign(a - rho) sign(z_+-) to the face term. A face uses that form only where g^2
   is both below beta^2 and below DERBY_MIN_P (a / 3 < rho < 3 a), so no p is small except
   on a rim, where B itself is singular. Beyond that band the plain form is kept although
   beta^2 may be larger: there 1 + g is small, the other form's weights c and s grow as
   1 / (1 + g), and its value cancels the added Br / 4 to the size of B (a slender magnet
   162 radii off its axis: 1.3e-8 relative error that way, 1.5e-13 this way).
3. B_rho / rho and the Cartesian gradient are 0 / 0 on the axis. Within rho < AXIS_SERIES
   * a the field is the off-axis expansion of the on-axis field b(z) = B_z(0, z)
   = Br / 2 [f(z + b) - f(z - b)], f(u) = u / sqrt(u^2 + a^2), which follows from
   div B = 0 and curl B = 0: B_z = b - rho^2 b'' / 4 + rho^4 b'''' / 64,
   B_rho / rho = -b' / 2 + rho^2 b''' / 16 - rho^4 b^(5) / 384 (next terms ~ (rho / a)^6,
   1e-18 relative). Both branches are evaluated on guarded inputs, so neither produces a
   NaN that could leak into a derivative.

The gradient is closed-form too: dB/dz is the field of two current loops in the face planes
(current M, the loop field of [4] written with cel, sharing the AGM), the radial
derivatives follow from div B = 0 and curl B = 0, and near the axis from the series. It is
exact, finite everywhere off the rims and twice differentiable, and B with G takes 1.7x the
operations of B alone (CasADi's AD of B: 5x). SI units are used for all inputs and outputs.

[1] N. Derby, S. Olbert, "Cylindrical magnets and ideal solenoids", Am. J. Phys. 78(3),
    229-235 (2010), doi:10.1119/1.3256157.
[2] R. Bulirsch, "Numerical calculation of elliptic integrals and elliptic functions. III",
    Numer. Math. 13, 305-315 (1969), doi:10.1007/BF02165405.
[3] A. Caciagli, R. J. Baars, A. P. Philipse, B. W. M. Kuipers, "Exact expression for the
    magnetic field of a finite cylinder with arbitrary uniform magnetization", J. Magn.
    Magn. Mater. 456, 423-432 (2018), doi:10.1016/j.jmmm.2018.02.003.
[4] J. Simpson, J. Lane, C. Immer, R. Youngquist, "Simple analytic expressions for the
    magnetic field of a circular current loop", NASA technical report 20010038494 (2001).
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca

__all__ = [
    "AXIS_SERIES",
    "CEL_ITERATIONS",
    "cel",
    "cylinder_field",
    "cylinder_field_function",
    "cylinder_flux_density",
]

CEL_ITERATIONS = 8
"""AGM steps of ``cel``: relative error below 1e-15 for kc >= 1e-14 (kc ~ distance to the
rim / diameter)."""

DERBY_MIN_P = 0.25
"""Derby & Olbert's face term is kept for g^2 = ((a - rho) / (a + rho))^2 at or above this
(rho <= a / 3 or rho >= 3 a), where it is well conditioned. [-]"""

AXIS_SERIES = 1e-3
"""Points closer to the axis than this fraction of the radius use the off-axis series. [-]"""


def _cel_shared(kc: ca.SX, terms: list[tuple]) -> list[ca.SX]:
    """Bulirsch's cel(kc, p, c, s) for several (p, c, s) with one kc and p > 0, sharing
    the AGM of 1 and kc [2]. A term with p = 1 (the number) uses p_n = em_n, which holds
    for p = 1 and saves its divisions."""
    state = []
    for p, c, s in terms:
        if isinstance(p, (int, float)) and p == 1:
            state.append([None, c, s])
        else:
            root = ca.sqrt(p)
            state.append([root, c, s / root])
    em: float | ca.SX = 1.0
    qc, kk = kc, kc
    for step in range(CEL_ITERATIONS):
        inv_em = 1 / em
        for st in state:
            p, c, s = st
            if p is None:  # p_n = em_n, g = kk / p_n = qc
                st[1], st[2] = c + s * inv_em, 2 * (s + c * qc)
            else:
                inv_p = 1 / p
                g = kk * inv_p
                st[0], st[1], st[2] = p + g, c + s * inv_p, 2 * (s + c * g)
        em = em + qc
        if step < CEL_ITERATIONS - 1:
            qc = 2 * ca.sqrt(kk)
            kk = em * qc
    out = []
    for p, c, s in state:
        p = em if p is None else p
        out.append((math.pi / 2) * (s + c * em) / (em * (em + p)))
    return out


def cel(kc: ca.SX, p: ca.SX, c: ca.SX, s: ca.SX) -> ca.SX:
    """Bulirsch's general complete elliptic integral [2] (see the module docstring).

    kc : complementary modulus, nonzero. [-]
    p : parameter, positive. [-]
    c, s : weights of cos^2 and sin^2 in the numerator. [-]
    K(k) = cel(kc, 1, 1, 1), E(k) = cel(kc, 1, 1, kc^2), Pi(n, k) = cel(kc, 1 - n, 1, 1),
    kc = sqrt(1 - k^2).
    """
    return _cel_shared(kc, [(p, c, s)])[0]


def _derivative_polynomials(order: int) -> list[dict[tuple[int, int], int]]:
    """P_1 .. P_order with f^(n)(u) = a^2 P_n(u) (u^2 + a^2)^-(n + 1/2), f = u / sqrt(u^2 + a^2),
    as {(power of u, power of a^2): integer coefficient}; P_1 = 1 and, by differentiating,
    P_(n+1) = P_n' (u^2 + a^2) - (2 n + 1) u P_n. (Repeated AD would grow the graph ~3x
    per derivative.)"""
    polys = [{(0, 0): 1}]
    for n in range(1, order):
        new: dict[tuple[int, int], int] = {}
        for (i, j), c in polys[-1].items():
            for key, value in (((i + 1, j), i * c - (2 * n + 1) * c), ((i - 1, j + 1), i * c)):
                if value and key[0] >= 0:
                    new[key] = new.get(key, 0) + value
        polys.append(new)
    return polys


_POLYNOMIALS = _derivative_polynomials(6)


def _on_axis_derivatives(z: ca.SX, radius: ca.SX, half_length: ca.SX, remanence: ca.SX):
    """b(z), b'(z), ..., b^(6)(z) of the on-axis field b = Br / 2 [f(z + b) - f(z - b)]."""
    a2 = radius**2
    faces = []
    for u in (z + half_length, z - half_length):
        w = 1 / ca.sqrt(u**2 + a2)
        values, power = [u * w], w
        for poly in _POLYNOMIALS:
            power = power * w**2
            values.append(a2 * power * sum(c * u**i * a2**j for (i, j), c in poly.items()))
        faces.append(values)
    return [remanence / 2 * (up - low) for up, low in zip(*faces, strict=True)]


def _axisymmetric(z, rho2, radius, length, remanence, gradient: bool) -> list[ca.SX]:
    """F = B_rho / rho [T/m] and H = B_z [T] at (rho^2, z), and with ``gradient`` also
    dF/dz, dF/d(rho^2), dH/dz; series or closed form by distance to the axis."""
    a, b = radius, length / 2
    near_axis = rho2 < (AXIS_SERIES * a) ** 2
    rho = ca.sqrt(ca.if_else(near_axis, (AXIS_SERIES * a) ** 2, rho2))  # guarded: rho > 0

    # Derby & Olbert [1] with the jump-free form of each face term (module docstring, 2.).
    # dB/dz is the field of two current loops (current M) in the face planes; the loop
    # field [4] written with cel is  B_z = Br a / (pi d^3) C(kc, 1, (a - rho) / kc^2, a + rho),
    # B_rho / rho = Br a z_f / (pi rho d^3) C(kc, 1, 1 / kc^2, -1).
    g = (a - rho) / (a + rho)
    sums = [0, 0, 0, 0]  # B_rho, B_z (without jump), dB_z/dz, d(B_rho/rho)/dz, all / B0
    jump = 0
    for sign_face, zf in ((1, z + b), (-1, z - b)):
        d = ca.sqrt(zf**2 + (a + rho) ** 2)
        kc2 = (zf**2 + (a - rho) ** 2) / d**2
        kc = ca.sqrt(kc2)
        beta = zf / d
        derby = ca.logic_or(g**2 >= beta**2, g**2 >= DERBY_MIN_P)
        p = ca.if_else(derby, g**2, beta**2)
        c = ca.if_else(derby, 1, 1 / (1 + g))
        s = ca.if_else(derby, g, beta**2 - g / (1 + g))
        terms = [(1, 1, -1), (p, c, s)]
        if gradient:
            terms += [(1, (a - rho) / kc2, a + rho), (1, 1 / kc2, -1)]
        values = _cel_shared(kc, terms)
        factors = [a / d, beta, a / d**3, a * zf / d**3]
        for i, (factor, value) in enumerate(zip(factors, values, strict=False)):
            sums[i] += sign_face * factor * value
        jump += sign_face * ca.if_else(derby, 0, ca.sign(a - rho) * ca.sign(zf))
    b0 = remanence / math.pi
    exact = [
        b0 * sums[0] / rho,
        b0 * a / (a + rho) * sums[1] + remanence / 4 * jump,
    ]
    if gradient:
        f_z, h_z = b0 * sums[3] / rho, b0 * sums[2]
        # div B = 0: 2 F + 2 rho^2 dF/d(rho^2) + dH/dz = 0
        exact += [f_z, -(h_z + 2 * exact[0]) / (2 * rho**2), h_z]

    # Off-axis expansion of the on-axis field (module docstring, 3.).
    d0, d1, d2, d3, d4, d5, d6 = _on_axis_derivatives(z, a, b, remanence)
    series = [
        -d1 / 2 + rho2 / 16 * d3 - rho2**2 / 384 * d5,
        d0 - rho2 / 4 * d2 + rho2**2 / 64 * d4,
    ]
    if gradient:
        series += [
            -d2 / 2 + rho2 / 16 * d4 - rho2**2 / 384 * d6,
            d3 / 16 - rho2 / 192 * d5,
            d1 - rho2 / 4 * d3 + rho2**2 / 64 * d5,
        ]
    return [ca.if_else(near_axis, x, y) for x, y in zip(series, exact, strict=True)]


def cylinder_flux_density(
    offset: ca.SX, axis: ca.SX, radius: ca.SX, length: ca.SX, remanence: ca.SX
) -> ca.SX:
    """Flux density of a uniformly, axially magnetised solid cylinder [1].

    offset : shape (3,), field point minus cylinder centre, base frame. [m]
    axis : shape (3,), unit magnetisation direction (north face side), base frame. [-]
    radius : cylinder radius a. [m]
    length : cylinder length 2 b. [m]
    remanence : remanent flux density Br (polarisation mu0 M). [T]
    Returns B, shape (3,), base frame. [T]

    Exact outside the magnet, including on its faces and on and near its axis; infinite
    on the two rims. Inside it is the flux density B; on the side wall, where B_z jumps
    by Br, it is the mean of both sides.
    """
    return cylinder_field_function(False)(offset, axis, radius, length, remanence)


def _build(offset, axis, radius, length, remanence, *, gradient: bool) -> list[ca.SX]:
    """B (and G) from the axisymmetric parts; see :func:`cylinder_field`."""
    z = ca.dot(offset, axis)
    transverse = offset - z * axis
    rho2 = ca.dot(transverse, transverse)
    out = _axisymmetric(z, rho2, radius, length, remanence, gradient)
    flux = out[0] * transverse + out[1] * axis
    if not gradient:
        return [flux]
    # B = F t + H n with t = offset - z n:  dB/dp = F (I - n n^T) + 2 F_rho2 t t^T
    #   + F_z t n^T + 2 H_rho2 n t^T + H_z n n^T, and curl B = 0 gives 2 H_rho2 = F_z.
    f, _, f_z, f_rho2, h_z = out
    n, t = axis, transverse
    grad = (
        f * (ca.SX.eye(3) - n @ n.T)
        + 2 * f_rho2 * (t @ t.T)
        + f_z * (t @ n.T + n @ t.T)
        + h_z * (n @ n.T)
    )
    return [flux, grad]


def _symbols() -> list[ca.SX]:
    return [
        ca.SX.sym("offset", 3),
        ca.SX.sym("axis", 3),
        ca.SX.sym("radius"),
        ca.SX.sym("length"),
        ca.SX.sym("remanence"),
    ]


_NAMES_IN = ["offset", "axis", "radius", "length", "remanence"]


@lru_cache(maxsize=2)
def cylinder_field_function(gradient: bool = True) -> ca.Function:
    """The field as a ``casadi.Function`` for numeric use: (offset, axis, radius, length,
    remanence) -> (B, G) (or B alone with ``gradient=False``), arguments as in
    :func:`cylinder_flux_density`; G = dB/dp, shape (3, 3), G[i, j] = dB_i / dp_j [T/m].

    Call it with numbers, or compile it with :func:`design.compiled.compile_function`
    and ``.map(n, "thread", k)`` for batches. SI in, SI out.
    """
    args = _symbols()
    if not gradient:
        return ca.Function(
            "cylinder_flux_density", args, _build(*args, gradient=False), _NAMES_IN, ["B"]
        )
    return ca.Function("cylinder_field", args, _build(*args, gradient=True), _NAMES_IN, ["B", "G"])


def cylinder_field(
    offset: ca.SX, axis: ca.SX, radius: ca.SX, length: ca.SX, remanence: ca.SX
) -> tuple[ca.SX, ca.SX]:
    """Flux density and its gradient of an axially magnetised cylinder [1].

    Arguments as in :func:`cylinder_flux_density`; any of them may be CasADi expressions
    (SX inlines the graph, MX makes a call node) or numbers.
    Returns B, shape (3,) [T], and G = dB/dp, shape (3, 3), G[i, j] = dB_i / dp_j, base
    frame [T/m]; G is symmetric and traceless outside the magnet.
    """
    flux, grad = cylinder_field_function(True)(offset, axis, radius, length, remanence)
    return flux, grad
