"""Point-dipole field and its gradient on CasADi symbols.

B(P) = mu0 / (4 pi) (3 P (P . m) / |P|^5 - m / |P|^3),  P = p - p_dipole.

The paper's eq. 9 prints 3 P (P . m) / P^3, which is not dimensionally a field (P is
not normalised); the form above, with unit vector P/|P| or the extra |P|^2, is the
standard one. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

import math

import casadi as ca

from design.constants import MU0

K_DIPOLE = MU0 / (4 * math.pi)  # [T m / A]


def dipole_field(offset: ca.SX, moment: ca.SX) -> ca.SX:
    """Flux density of a point dipole.

    offset : shape (3,), field point minus dipole position. [m]
    moment : shape (3,), dipole moment. [A m^2]
    Returns B, shape (3,). [T]
    """
    r2 = ca.dot(offset, offset)
    r = ca.sqrt(r2)
    pm = ca.dot(offset, moment)
    return K_DIPOLE * (3 * offset * pm / r2 - moment) / (r2 * r)


def dipole_field_gradient(offset: ca.SX, moment: ca.SX) -> ca.SX:
    """Gradient dB_i/dp_j of the point-dipole field (symmetric and traceless).

    dB_i/dP_j = mu0 / (4 pi) 3 / r^5 ((P.m) d_ij + P_i m_j + m_i P_j - 5 (P.m) P_i P_j / r^2)

    Returns shape (3, 3). [T/m]
    """
    r2 = ca.dot(offset, offset)
    r5 = r2 * r2 * ca.sqrt(r2)
    pm = ca.dot(offset, moment)
    outer = offset @ moment.T + moment @ offset.T
    return (3 * K_DIPOLE / r5) * (pm * ca.SX.eye(3) + outer - 5 * pm * (offset @ offset.T) / r2)
