"""Force and torque on the rings: consistency with the magnetic energy U = -sum m_i . B."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from design.dipole import dipole_field, dipole_field_gradient
from design.frames import rotation_from_vector
from design.wrench import magnet_force, magnet_torque, ring_moment_vector, tip_wrench

P = ca.SX.sym("p", 3)
M = ca.SX.sym("m", 3)
EXT_M = ca.DM([-200.0, 10.0, -5.0])
EXT_C = ca.DM([0.25, 0.01, -0.02])


def dipole_model(p):
    off = p - EXT_C
    return dipole_field(off, EXT_M), dipole_field_gradient(off, EXT_M)


ENERGY = ca.Function("U", [P, M], [-ca.dot(M, dipole_model(P)[0])])
FORCE = ca.Function("f", [P, M], [magnet_force(dipole_model(P)[1], M)])
TORQUE = ca.Function("t", [P, M], [magnet_torque(dipole_model(P)[0], M)])


def test_force_is_minus_gradient_of_energy():
    # f = grad(m . B) = -grad U (Jackson eq. 5.69), by central finite differences of U.
    p, m = np.array([0.15, 0.01, 0.005]), np.array([0.0, 4e-3, 3e-3])
    h = 1e-6
    fd = [-(float(ENERGY(p + h * e, m)) - float(ENERGY(p - h * e, m))) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(np.asarray(FORCE(p, m)).ravel(), fd, rtol=1e-7)


def test_axial_torque_is_minus_derivative_of_energy_by_ring_angle():
    # Turning a ring by d theta about the tip tangent n changes U by -tau . n d theta.
    theta, mag, spacing = ca.SX.sym("theta", 2), 5.4e-3, 0.0
    frame = ca.evalf(rotation_from_vector(ca.DM([0.0, 0.1, -0.2])))
    p = ca.DM([0.15, 0.01, 0.004])
    m1 = ring_moment_vector(theta[0], frame, mag)
    energy = ca.Function("U", [theta], [-ca.dot(m1, dipole_model(p + spacing)[0])])
    torque = ca.Function("tau", [theta], [magnet_torque(dipole_model(p)[0], m1)])
    n = np.asarray(frame[:, 0]).ravel()
    for angle in np.linspace(0, 2 * np.pi, 7):
        th = np.array([angle, 0.0])
        h = 1e-6
        du = (float(energy(th + [h, 0])) - float(energy(th - [h, 0]))) / (2 * h)
        assert float(np.asarray(torque(th)).ravel() @ n) == pytest.approx(-du, rel=1e-7, abs=1e-16)


def _wrench(angles, spacing, field_model, frame_vec=(0.0, 0.0, 0.0)):
    frame = rotation_from_vector(ca.DM(frame_vec))
    f, t = tip_wrench(field_model, ca.DM([0.15, 0.0, 0.0]), frame, ca.DM(angles), 5.4e-3, spacing)
    return np.asarray(ca.evalf(f)).ravel(), np.asarray(ca.evalf(t)).ravel()


def uniform_field(p):
    return ca.DM([-0.03, 0.004, 0.01]), ca.DM.zeros(3, 3)


def test_antiparallel_rings_at_zero_spacing_cancel_in_uniform_field():
    # Symmetry (paper Sec. III-A): equal antiparallel moments feel no net wrench.
    for th in np.linspace(0, 2 * np.pi, 9):
        f, t = _wrench([th + np.pi, th], 0.0, uniform_field, (0.0, 0.2, -0.1))
        assert np.abs(f).max() == 0
        assert np.abs(t).max() < 1e-18


def test_parallel_rings_double_the_torque_in_uniform_field():
    f1, t1 = _wrench([0.3, 0.3], 0.0, uniform_field)
    m = 5.4e-3 * np.array([0.0, np.cos(0.3), np.sin(0.3)])
    np.testing.assert_allclose(t1, 2 * np.cross(m, [-0.03, 0.004, 0.01]), rtol=1e-14)


def test_spacing_lever_is_the_moment_of_the_distal_force_about_the_tip():
    # tau = sum_i m_i x B(p_i) + (p_1 - p) x f_1, computed here ring by ring.
    angles, spacing, tilt = [0.7, 2.1], 2e-3, (0.0, 0.15, 0.1)
    f, t = _wrench(angles, spacing, dipole_model, tilt)
    frame = np.asarray(ca.evalf(rotation_from_vector(ca.DM(tilt))))
    p2 = np.array([0.15, 0.0, 0.0])
    p1 = p2 + spacing * frame[:, 0]
    total_f, total_t = np.zeros(3), np.zeros(3)
    for p_i, th in ((p1, angles[0]), (p2, angles[1])):
        m_i = 5.4e-3 * (np.cos(th) * frame[:, 1] + np.sin(th) * frame[:, 2])
        f_i = np.asarray(FORCE(p_i, m_i)).ravel()
        total_f += f_i
        total_t += np.asarray(TORQUE(p_i, m_i)).ravel() + np.cross(p_i - p2, f_i)
    np.testing.assert_allclose(f, total_f, rtol=1e-12)
    np.testing.assert_allclose(t, total_t, rtol=1e-12)


def test_ring_angle_convention_follows_spec():
    # docs/formats.md: on the straight robot theta = 0 is +y and theta = 90 deg is +z.
    frame = ca.DM.eye(3)
    m0 = np.asarray(ca.evalf(ring_moment_vector(0.0, frame, 1.0))).ravel()
    m90 = np.asarray(ca.evalf(ring_moment_vector(np.pi / 2, frame, 1.0))).ravel()
    np.testing.assert_allclose(m0, [0, 1, 0], atol=1e-16)
    np.testing.assert_allclose(m90, [0, 0, 1], atol=1e-16)
