"""Kirchhoff rod (large deflection) against the elastica literature, closed forms, the linear
cantilever and an independent integration of the same equations.

Sources:
- K. E. Bisshopp and D. C. Drucker, "Large deflection of cantilever beams", Quarterly of
  Applied Mathematics 3 (1945) 272-275, table of the tip under a perpendicular dead load.
- Pure bending: a tip moment M makes a constant curvature M / EI, a circular arc (e.g.
  Timoshenko & Gere, Theory of Elastic Stability, sec. 2.7).
- Gere & Goodno, Mechanics of Materials (8th ed.), Appendix G, cases 1, 4 and 6: uniform
  load w L^4 / (8 EI), slope w L^3 / (6 EI); tip force P L^3 / (3 EI), P L^2 / (2 EI); tip
  moment M L^2 / (2 EI), M L / EI.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from rods import RodSolution, solve_rod, solve_tip_load
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from design import cantilever, rod

L, EI = 0.15, 3.92e-4  # the demonstrator's free length [m] and bending rigidity [N m^2]


def tip_angle(solution: RodSolution) -> float:
    """Angle of the tip tangent from +x towards +y. [rad]"""
    return float(np.arctan2(solution.frame[1, 0], solution.frame[0, 0]))


def rotation_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


# Bisshopp & Drucker (1945), table: q = F L^2 / EI -> (y/L, 1 - x/L, tip angle [rad]).
BISSHOPP_DRUCKER = [
    (1.0, 0.30172, 0.05643, 0.46135),
    (2.0, 0.49346, 0.16064, 0.78175),
    (5.0, 0.71379, 0.38763, 1.21537),
]


@pytest.mark.parametrize(("q", "y_over_l", "shortening", "angle"), BISSHOPP_DRUCKER)
def test_bisshopp_drucker_tip_load(q, y_over_l, shortening, angle):
    sol = solve_tip_load(L, EI, tip_force=[0.0, q * EI / L**2, 0.0])
    assert sol.converged
    assert sol.position[1] / L == pytest.approx(y_over_l, abs=1e-4)
    assert 1 - sol.position[0] / L == pytest.approx(shortening, abs=1e-4)
    assert tip_angle(sol) == pytest.approx(angle, abs=1e-4)
    assert sol.position[2] == 0.0 and sol.frame[2, 0] == 0.0  # stays in its plane


@pytest.mark.parametrize("bend", [1.0, 3.0])
@pytest.mark.parametrize("axis_angle", [0.0, 2.2])
def test_pure_tip_moment_gives_the_circular_arc(bend, axis_angle):
    # Moment M = bend EI / L about an axis a in the cross-section (angle from +z towards -y);
    # the rod bends on a circle of radius EI / M in the plane normal to a, towards a x e1.
    e1 = np.array([1.0, 0, 0])
    axis = np.array([0.0, -np.sin(axis_angle), np.cos(axis_angle)])
    toward = np.cross(axis, e1)
    moment = bend * EI / L
    sol = solve_tip_load(L, EI, tip_moment=moment * axis)
    assert sol.converged
    radius = EI / moment
    s = np.linspace(0, L, len(sol.centreline))
    arc = radius * (np.outer(np.sin(s / radius), e1) + np.outer(1 - np.cos(s / radius), toward))
    # Integration error measured at 8e-7 L for 3 rad of turning (20 RK4 steps).
    np.testing.assert_allclose(sol.centreline, arc, rtol=0, atol=2e-6 * L)
    np.testing.assert_allclose(sol.position, arc[-1], rtol=0, atol=2e-6 * L)
    # The frame turns about the moment's axis by the bending angle.
    turned = Rotation.from_rotvec(bend * axis).as_matrix()
    np.testing.assert_allclose(sol.frame, turned, rtol=0, atol=2e-6)
    np.testing.assert_allclose(
        sol.frame[:, 0], np.cos(bend) * e1 + np.sin(bend) * toward, atol=2e-6
    )
    if bend == 3.0:
        assert np.dot(sol.position, toward) > 0.6 * L  # a large deflection indeed


def test_small_tip_force_matches_linear_cantilever():
    # Gere & Goodno case 4: P L^3 / (3 EI) and slope P L^2 / (2 EI); F L^2 / EI = 0.01.
    force = 0.01 * EI / L**2
    sol = solve_tip_load(L, EI, tip_force=[0.0, force, 0.0])
    assert sol.converged
    assert sol.position[1] == pytest.approx(force * L**3 / (3 * EI), rel=1e-3)
    assert tip_angle(sol) == pytest.approx(force * L**2 / (2 * EI), rel=1e-3)


def test_small_tip_moment_matches_linear_cantilever():
    # Gere & Goodno case 6: M L^2 / (2 EI) and slope M L / EI; M L / EI = 0.01.
    moment = 0.01 * EI / L
    sol = solve_tip_load(L, EI, tip_moment=[0.0, 0.0, moment])
    assert sol.converged
    assert sol.position[1] == pytest.approx(moment * L**2 / (2 * EI), rel=1e-3)
    assert tip_angle(sol) == pytest.approx(moment * L / EI, rel=1e-3)


def test_small_three_dimensional_wrench_matches_the_linear_rod():
    # The baseline's compliance (design.cantilever) maps (f_y, f_z, tau_y, tau_z) to the tip
    # coordinates (dy, dz, phi_y, phi_z), phi the rotation vector of the tip frame; the
    # axial torque bends nothing to first order.
    # Second-order terms are O(load) relative to the first: F L^2 / EI, M L / EI ~ 3e-4.
    force = EI / L**2 * np.array([0.0, 3e-4, -2e-4])
    moment = EI / L * np.array([2e-4, -3e-4, 1e-4])
    sol = solve_tip_load(L, EI, tip_force=force, tip_moment=moment)
    phi = Rotation.from_matrix(sol.frame).as_rotvec()
    got = np.array([sol.position[1], sol.position[2], phi[1], phi[2]])
    load = ca.vertcat(force[1], force[2], moment[1], moment[2])
    linear = np.asarray(ca.evalf(cantilever.compliance(L, EI) @ load)).ravel()
    np.testing.assert_allclose(got, linear, rtol=1e-3)


def test_linearisation_at_the_straight_rod_is_the_cantilever_compliance():
    # Implicit derivative of the shooting solution at zero load: d(tip)/d(load) =
    # -d(tip)/dz (dr/dz)^-1 dr/d(load). The linearised rod has polynomial solutions that
    # RK4 integrates exactly, so this holds to rounding.
    z, load = ca.SX.sym("z", 6), ca.SX.sym("load", 6)
    r, state = rod.boundary_residual(z, L, EI, lambda p, frame: (load[0:3], load[3:6]))
    tip = ca.vertcat(state.position[1], state.position[2], -state.frame[2, 0], state.frame[1, 0])
    jac = ca.Function(
        "derivatives", [z, load], [ca.jacobian(r, z), ca.jacobian(r, load), ca.jacobian(tip, z)]
    )
    r_z, r_load, tip_z = (np.asarray(a) for a in jac(np.zeros(6), np.zeros(6)))
    sensitivity = -tip_z @ np.linalg.solve(r_z, r_load)
    compliance = np.asarray(ca.evalf(cantilever.compliance(L, EI)))
    bending = [1, 2, 4, 5]  # (f_y, f_z, tau_y, tau_z)
    np.testing.assert_allclose(sensitivity[:, bending], compliance, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sensitivity[:, [0, 3]], 0, atol=1e-12)  # f_x, tau_x


def test_uniform_load_matches_linear_cantilever():
    # Gere & Goodno case 1: w L^4 / (8 EI), slope w L^3 / (6 EI); weight along -z,
    # w L^3 / EI = 0.01.
    w = 0.01 * EI / L**3
    sol = solve_tip_load(L, EI, distributed_load=[0.0, 0.0, -w])
    assert sol.converged
    assert -sol.position[2] == pytest.approx(w * L**4 / (8 * EI), rel=1e-3)
    assert -sol.frame[2, 0] == pytest.approx(w * L**3 / (6 * EI), rel=1e-3)
    np.testing.assert_allclose(sol.base_force, [0, 0, -w * L], rtol=1e-12, atol=1e-12 * w * L)


def test_out_of_plane_load_is_the_in_plane_solution_turned_about_the_axis():
    # The clamped rod is symmetric about x: turning the load by R_x(a) turns the
    # centreline by R_x(a) and conjugates the frame, R -> R_x R R_x^T.
    force = EI / L**2 * np.array([0.3, 2.0, 0.0])
    moment = EI / L * np.array([0.4, 0.0, 0.9])
    flat = solve_tip_load(L, EI, tip_force=force, tip_moment=moment)
    turn = rotation_x(0.7)
    sol = solve_tip_load(L, EI, tip_force=turn @ force, tip_moment=turn @ moment)
    assert flat.converged and sol.converged
    np.testing.assert_allclose(sol.centreline, flat.centreline @ turn.T, rtol=0, atol=1e-10 * L)
    np.testing.assert_allclose(sol.frame, turn @ flat.frame @ turn.T, rtol=0, atol=1e-10)
    back = solve_tip_load(L, EI, tip_force=turn.T @ force, tip_moment=turn.T @ moment)
    np.testing.assert_allclose(back.position, turn.T @ flat.position, atol=1e-10 * L)


def oracle_tip(base_force, base_moment, distributed_load):
    """The rod's equations as written in the issue, with a rotation matrix and body
    curvature, integrated by scipy's DOP853: an independent implementation. Returns
    (position, frame, moment) at s = L."""

    def rhs(s, y):
        frame = y[3:12].reshape(3, 3)
        moment = y[12:15]
        force = base_force - distributed_load * s
        body = frame.T @ moment
        u = np.array([0.0, body[1], body[2]]) / EI
        u_hat = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        return np.concatenate([frame[:, 0], (frame @ u_hat).ravel(), -np.cross(frame[:, 0], force)])

    y0 = np.concatenate([np.zeros(3), np.eye(3).ravel(), base_moment])
    sol = solve_ivp(rhs, (0, L), y0, method="DOP853", rtol=1e-12, atol=1e-15)
    y = sol.y[:, -1]
    return y[0:3], y[3:12].reshape(3, 3), y[12:15]


def test_three_dimensional_load_matches_independent_integration():
    force = EI / L**2 * np.array([-1.0, 2.0, -1.5])
    moment = EI / L * np.array([0.5, 0.8, -1.0])
    weight = EI / L**3 * np.array([0.0, 0.0, -2.0])
    sol = solve_tip_load(L, EI, force, moment, weight)
    assert sol.converged
    position, frame, tip_moment = oracle_tip(sol.base_force, sol.base_moment, weight)
    # RK4 with 20 steps: 4e-7 L on this case (module docstring).
    np.testing.assert_allclose(sol.position, position, rtol=0, atol=1e-6 * L)
    np.testing.assert_allclose(sol.frame, frame, rtol=0, atol=3e-6)  # measured 1.2e-6
    np.testing.assert_allclose(tip_moment, moment, rtol=0, atol=1e-5 * EI / L)
    # A space curve: RMS distance from the best-fitting plane 5e-3 L.
    centred = sol.centreline - sol.centreline.mean(axis=0)
    assert np.linalg.svd(centred)[1][-1] / np.sqrt(len(centred)) > 1e-3 * L
    # Balance about the clamp without the distributed load: m0 = tau + p(L) x f.
    no_weight = solve_tip_load(L, EI, force, moment)
    np.testing.assert_allclose(
        no_weight.base_moment, moment + np.cross(no_weight.position, force), rtol=1e-9
    )


def test_frame_is_orthonormal():
    sol = solve_tip_load(
        L, EI, EI / L**2 * np.array([0.5, 4.0, -3.0]), EI / L * np.array([1.0, -1.0, 2.0])
    )
    assert sol.converged
    np.testing.assert_allclose(sol.frame.T @ sol.frame, np.eye(3), rtol=0, atol=1e-12)
    assert np.linalg.det(sol.frame) == pytest.approx(1.0, abs=1e-12)


def test_integration_error_at_default_steps():
    # The docstring's convergence claim: 20 RK4 steps are within 1e-6 L of 80 steps at the
    # largest Bisshopp-Drucker load.
    force = [0.0, 5.0 * EI / L**2, 0.0]
    coarse = solve_tip_load(L, EI, force)
    fine = solve_tip_load(L, EI, force, steps=4 * rod.STEPS)
    error = np.abs(coarse.position - fine.position).max()
    assert 1e-9 * L < error < 1e-6 * L  # converging, and not exact by accident
    half = solve_tip_load(L, EI, force, steps=rod.STEPS // 2)
    assert np.abs(half.position - fine.position).max() / error == pytest.approx(16, rel=0.25)


def test_pose_dependent_wrench_is_applied_at_the_deformed_tip():
    # A follower force along the tip's y axis: at equilibrium it equals a dead load of
    # the same final value, and the same dead load solved on its own gives the same rod.
    def follower(position, frame, load):
        return load[0] * frame[:, 1], ca.SX.zeros(3)

    sol = solve_rod(L, EI, [2.0 * EI / L**2], tip_wrench=follower)
    assert sol.converged
    assert np.dot(sol.tip_force, sol.frame[:, 0]) == pytest.approx(0, abs=1e-12)
    assert tip_angle(sol) > 0.9  # beyond the 0.78 rad of the dead load (F L^2 / EI = 2)
    dead = solve_tip_load(L, EI, tip_force=sol.tip_force)
    np.testing.assert_allclose(dead.position, sol.position, rtol=0, atol=1e-10 * L)


def test_shooting_map_derivatives_match_finite_differences():
    shoot = rod.shooting_function()
    n0, m0 = ca.SX.sym("n0", 3), ca.SX.sym("m0", 3)
    out = shoot(n0, m0, L, EI, ca.DM([0.0, 0.0, -0.5]))
    z = ca.vertcat(n0, m0)
    tip = ca.vertcat(out[0], ca.vec(out[1]), out[3])
    jac = ca.Function("derivatives", [z], [tip, ca.jacobian(tip, z)])
    z0 = np.concatenate(
        [EI / L**2 * np.array([0.5, 3.0, -1.0]), EI / L * np.array([0.2, 1.0, 3.0])]
    )
    exact = np.asarray(jac(z0)[1])
    scale = np.abs(z0).max() * 1e-6
    numeric = np.column_stack(
        [
            (np.asarray(jac(z0 + scale * e)[0]) - np.asarray(jac(z0 - scale * e)[0])).ravel()
            / (2 * scale)
            for e in np.eye(6)
        ]
    )
    np.testing.assert_allclose(numeric, exact, rtol=0, atol=1e-6 * np.abs(exact).max())
