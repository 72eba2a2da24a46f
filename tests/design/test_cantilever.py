"""Linear cantilever against textbook closed forms.

Gere & Goodno, Mechanics of Materials (8th ed.), Appendix G, cases 4 and 6: a cantilever of
length L and rigidity EI under a tip force P deflects by P L^3 / (3 EI) with tip slope
P L^2 / (2 EI); under a tip moment M by M L^2 / (2 EI) with slope M L / EI.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from design import cantilever

L, EI = 0.15, 3.9e-4


def response(force, torque, tangent=(1.0, 0.0, 0.0)):
    load = cantilever.bending_load(ca.DM(force), ca.DM(torque), ca.DM(tangent))
    return np.asarray(ca.evalf(cantilever.compliance(L, EI) @ load)).ravel()


def test_cantilever_tip_force_deflection_and_slope():
    p = 0.01
    dy, dz, phi_y, phi_z = response([0, p, 0], [0, 0, 0])
    assert dy == pytest.approx(p * L**3 / (3 * EI), rel=1e-14)
    assert phi_z == pytest.approx(p * L**2 / (2 * EI), rel=1e-14)  # slope dy/dx
    assert dz == 0 and phi_y == 0


def test_cantilever_tip_moment_deflection_and_slope():
    m = 2e-4  # about +z: bends the tip towards +y
    dy, dz, phi_y, phi_z = response([0, 0, 0], [0, 0, m])
    assert dy == pytest.approx(m * L**2 / (2 * EI), rel=1e-14)
    assert phi_z == pytest.approx(m * L / EI, rel=1e-14)
    assert dz == 0 and phi_y == 0


def test_out_of_plane_loads_by_integrating_the_beam_equation():
    # Independent check of signs in 3-D: integrate kappa = M(s) / EI with
    # M(s) = tau + (L - s) e1 x f along the straight axis (small deflection).
    f, tau = np.array([0.3e-2, -0.7e-2, 1.1e-2]), np.array([0.5e-4, 1.3e-4, -0.8e-4])

    def rhs(s, state):
        phi = state[3:]
        moment = tau + (L - s) * np.cross([1, 0, 0], f)
        kappa = moment / EI
        kappa[0] = 0.0  # the axial part is torsion, not bending
        tangent = np.array([1.0, 0, 0]) + np.cross(phi, [1.0, 0, 0])
        return np.concatenate([tangent, kappa])

    sol = solve_ivp(rhs, (0, L), np.zeros(6), rtol=1e-12, atol=1e-15)
    tip = sol.y[:, -1]
    dy, dz, phi_y, phi_z = response(f, tau)
    np.testing.assert_allclose([dy, dz, phi_y, phi_z], [tip[1], tip[2], tip[4], tip[5]], rtol=1e-9)


def test_axial_torque_does_not_bend():
    tangent = np.array([np.cos(0.3), np.sin(0.3), 0.0])
    np.testing.assert_allclose(response([0, 0, 0], 1e-4 * tangent, tangent), 0, atol=1e-15)


def test_stiffness_is_the_inverse_compliance():
    k = np.asarray(ca.evalf(cantilever.stiffness(L, EI)))
    c = np.asarray(ca.evalf(cantilever.compliance(L, EI)))
    np.testing.assert_allclose(k @ c, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(c, c.T)
    assert np.all(np.linalg.eigvalsh(c) > 0)


def test_base_moment_balances_the_straight_rod():
    # Statics of the straight rod: the tip moment, the tip force at (L, 0, 0) and the
    # distributed load's resultant q L at (L / 2, 0, 0), about the clamp.
    f, tau, q = np.array([1.0, 2.0, 3.0]), np.array([0.1, 0.2, 0.3]), np.array([0.0, -4.0, 5.0])
    expected = tau + np.cross([0.5, 0, 0], f) + np.cross([0.25, 0, 0], 0.5 * q)
    np.testing.assert_allclose(cantilever.base_moment(f, tau, 0.5, q), expected, rtol=1e-15)
    symbolic = cantilever.base_moment(ca.DM(f), ca.DM(tau), 0.5, ca.DM(q))
    np.testing.assert_allclose(np.asarray(symbolic).ravel(), expected, rtol=1e-15)
    np.testing.assert_allclose(
        cantilever.base_moment(f, tau, 0.5), tau + np.cross([0.5, 0, 0], f), rtol=1e-15
    )
