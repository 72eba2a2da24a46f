"""Magnetic interaction of the two coaxial tip rings (issue 3, item 3: the coupling).

Oracles, all independent of the charge-integral formula in design/ring_coupling.py:
- magpylib's exact field of a diametrically magnetised ring (``CylinderSegment``), integrated
  over the other ring's volume, U = -int M_2 . B_1 dV, by dense graded quadrature;
- magpylib's ``getFT`` (ring cut into dipole cells, force and torque by finite differences);
- the point dipoles side by side, and their next order from averaging the dipole-dipole
  kernel over both volumes.
SI units throughout.
"""

from __future__ import annotations

import math

import casadi as ca
import magpylib as magpy
import numpy as np
import pytest

from design.constants import MU0
from design.ring_coupling import (
    QUADRATURE_NODES,
    coupling_coefficient,
    coupling_energy,
    coupling_torques,
)

# (outer diameter, inner diameter, length, spacing, remanence) [m, m, m, m, T]
DEMONSTRATOR = (4e-3, 2e-3, 0.5e-3, 0.5e-3, 1.45)  # the paper's rings, touching (gap 0)
GAPPED = (3e-3, 1e-3, 1.5e-3, 2.5e-3, 1.2)  # another ring, gap 1 mm
SOLID_DISCS = (3e-3, 0.0, 1e-3, 1.2e-3, 1.3)  # no hole (R_i = 0), gap 0.2 mm
GEOMETRIES = {"demonstrator": DEMONSTRATOR, "gap_1mm": GAPPED, "solid_discs": SOLID_DISCS}


def _moment(outer_diameter, inner_diameter, length, remanence):
    """Ring moment m = M V. [A m^2]"""
    return remanence / MU0 * math.pi * (outer_diameter**2 - inner_diameter**2) / 4 * length


def _point_dipole_coefficient(geometry):
    """Two point dipoles side by side at the centre spacing, both moments perpendicular to
    the line joining them: U = mu0 m^2 / (4 pi delta^3) cos(theta_1 - theta_2). [J]"""
    outer, inner, length, spacing, remanence = geometry
    m = _moment(outer, inner, length, remanence)
    return MU0 * m**2 / (4 * math.pi * spacing**3)


def _ring(geometry, angle, z=0.0):
    outer, inner, length, _, remanence = geometry
    polarization = remanence * np.stack([np.cos(angle), np.sin(angle), 0 * np.asarray(angle)], -1)
    return magpy.magnet.CylinderSegment(
        dimension=(inner / 2, outer / 2, length, 0, 360),
        polarization=polarization,
        position=(0, 0, z),
    )


def _graded_gauss(n, grading=3):
    """Gauss-Legendre on [0, 1] in t with x = t^grading: nodes cluster at x = 0."""
    t, w = np.polynomial.legendre.leggauss(n)
    t, w = (t + 1) / 2, w / 2
    return t**grading, w * grading * t ** (grading - 1)


def _brute_force_energy(geometry, theta1, theta2, n):
    """U = -int_ring2 M_2 . B_1 dV with magpylib's B of ring 1 (centred at the origin).

    B_1 of a diametric ring is a trigonometric polynomial of degree 2 in the azimuth, so the
    trapezoidal rule with 8 azimuths is exact; in r and z, Gauss-Legendre graded towards the
    faces and rims, where B_1 is log-singular when the rings touch. [J]
    """
    outer, inner, length, spacing, remanence = geometry
    r_i, r_o = inner / 2, outer / 2
    s, ws = _graded_gauss(n)
    z = spacing - length / 2 + length * s  # graded towards the face next to ring 1
    wz = length * ws
    half = (r_o - r_i) / 2
    r = np.concatenate([r_i + half * s, r_o - half * s])  # graded towards both rims
    wr = np.concatenate([half * ws, half * ws]) * r
    phi = np.arange(8) * 2 * np.pi / 8
    rr, pp, zz = np.meshgrid(r, phi, z, indexing="ij")
    weights = (wr[:, None, None] * (2 * np.pi / 8) * wz[None, None, :]) * np.ones_like(rr)
    points = np.stack([rr * np.cos(pp), rr * np.sin(pp), zz], -1).reshape(-1, 3)
    field = _ring(geometry, theta1).getB(points)
    magnetization = remanence / MU0 * np.array([math.cos(theta2), math.sin(theta2), 0.0])
    return -float(np.sum(weights.ravel() * (field @ magnetization)))


# --- the oracles --------------------------------------------------------------------------


@pytest.mark.parametrize("name", GEOMETRIES)
def test_coefficient_matches_volume_integral_of_magpylib_field(name):
    """K12 = U(0, 0) = -int M_2 . B_1 dV to 1e-10 relative; the oracle itself converged
    (30 vs 40 nodes per direction) to 1e-11. Touching rings included."""
    geometry = GEOMETRIES[name]
    k12 = coupling_coefficient(*geometry)
    oracle = _brute_force_energy(geometry, 0.0, 0.0, 40)
    assert abs(_brute_force_energy(geometry, 0.0, 0.0, 30) / oracle - 1) < 1e-11
    assert k12 > 0
    assert abs(k12 / oracle - 1) < 1e-10


@pytest.mark.parametrize("name", ["demonstrator", "gap_1mm"])
def test_energy_is_cosine_of_angle_difference(name):
    """U(theta_1, theta_2) = K12 cos(theta_1 - theta_2) at arbitrary angle pairs, against the
    magpylib volume integral (symmetry: only the difference matters, as its cosine)."""
    geometry = GEOMETRIES[name]
    k12 = coupling_coefficient(*geometry)
    pairs_deg = [(30, 0), (90, 0), (150, 0), (180, 0), (200, 65), (-40, 100), (75, 75)]
    for theta1_deg, theta2_deg in pairs_deg:
        theta1, theta2 = math.radians(theta1_deg), math.radians(theta2_deg)
        oracle = _brute_force_energy(geometry, theta1, theta2, 30)
        assert abs(coupling_energy(theta1, theta2, k12) - oracle) < 1e-10 * k12


@pytest.mark.parametrize(
    ("name", "tolerance"),
    # Dipole cells converge slowly next to the touching face (field log-singular at the
    # rims): (60, 4, 4) cells 2.1 %, (120, 8, 8) 0.7 %, (360, 24, 24) 0.1 %. With a gap they
    # converge quadratically: 0.4 %, 0.1 %, (240, 16, 16) 0.03 %.
    [("demonstrator", 1e-2), ("gap_1mm", 3e-3)],
)
def test_axial_torques_match_magpylib_getft(name, tolerance):
    """Axial torque on each ring from magpylib's getFT (cells (120, 8, 8)) at theta_1 -
    theta_2 = 30, 90, 150 deg; and the coarser mesh is farther off (convergence to K12)."""
    geometry = GEOMETRIES[name]
    outer, _, _, spacing, _ = geometry
    angles = np.radians([30.0, 90.0, 150.0])  # theta_1; theta_2 = 0
    k12 = coupling_coefficient(*geometry)
    torque1, torque2 = coupling_torques(angles, 0.0, k12)
    eps = 1e-5 * outer  # getFT's finite-difference step, as its docstring advises [m]

    ring1, ring2 = _ring(geometry, angles), _ring(geometry, 0.0, spacing)
    _, on_ring2 = magpy.getFT(ring1, ring2, meshing=(120, 8, 8), eps=eps)
    _, on_ring1 = magpy.getFT(ring2, ring1, meshing=(120, 8, 8), eps=eps)
    _, coarse = magpy.getFT(ring1, ring2, meshing=(60, 4, 4), eps=eps)

    np.testing.assert_allclose(on_ring2[:, 2], torque2, rtol=tolerance)
    np.testing.assert_allclose(on_ring1[:, 2], torque1, rtol=tolerance)
    fine_error = np.abs(on_ring2[:, 2] / torque2 - 1)
    coarse_error = np.abs(coarse[:, 2] / torque2 - 1)
    assert np.all(coarse_error > fine_error)
    assert np.all(torque1 > 0)  # side by side: the rings pull towards antiparallel


# --- limits and consistency ---------------------------------------------------------------


@pytest.mark.parametrize("name", ["demonstrator", "solid_discs"])
def test_far_limit_is_point_dipoles_side_by_side(name):
    """K12 -> mu0 m^2 / (4 pi delta^3) [1 - 3 (R_o^2 + R_i^2) / delta^2 + h^2 / delta^2].

    Next order from the dipole kernel averaged over both volumes: for parallel moments
    along x, f = 1/r^3 - 3 x^2 / r^5 at r = delta z_hat + s has d2f/dx2 = -9, d2f/dy2 = -3,
    d2f/dz2 = 12 (all / delta^5), and <s_x^2> = <s_y^2> = (R_o^2 + R_i^2) / 2,
    <s_z^2> = h^2 / 6, so <f> = [1 - 3 (R_o^2 + R_i^2) / delta^2 + h^2 / delta^2] / delta^3.
    The remainder is O(delta^-4) (coefficient ~13 (R_o / delta)^4 for the demonstrator).
    """
    outer, inner, length, _, remanence = GEOMETRIES[name]
    r_o, r_i = outer / 2, inner / 2
    for diameters in (5, 10, 20):
        spacing = diameters * outer
        geometry = (outer, inner, length, spacing, remanence)
        k12 = coupling_coefficient(*geometry)
        dipoles = _point_dipole_coefficient(geometry)
        correction = 1 - 3 * (r_o**2 + r_i**2) / spacing**2 + length**2 / spacing**2
        assert abs(k12 / dipoles - 1) < 4 * (r_o / spacing) ** 2
        assert abs(k12 / (dipoles * correction) - 1) < 20 * (r_o / spacing) ** 4


def test_touching_demonstrator_converged_with_quadrature_nodes():
    """At the default 32 nodes K12 is converged to 1e-6 relative (in fact ~1e-14; 16 nodes
    give ~1e-8), for touching rings and for small gaps (hardest: gap ~ 1e-7 .. 1e-5 m);
    dK12/dspacing at gap = 0 (log-singular integrand) to 1e-6."""
    assert QUADRATURE_NODES == 32
    outer, inner, length, _, remanence = DEMONSTRATOR
    for gap in (0.0, 1e-9, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3):
        geometry = (outer, inner, length, length + gap, remanence)
        reference = coupling_coefficient(*geometry, nodes=256)
        assert abs(coupling_coefficient(*geometry) / reference - 1) < 1e-9
    reference = coupling_coefficient(*DEMONSTRATOR, nodes=256)
    assert abs(coupling_coefficient(*DEMONSTRATOR) / reference - 1) < 1e-12
    assert abs(coupling_coefficient(*DEMONSTRATOR, nodes=16) / reference - 1) < 1e-7

    spacing = ca.SX.sym("spacing")
    slopes = []
    for nodes in (QUADRATURE_NODES, 256):
        k12 = coupling_coefficient(outer, inner, length, spacing, remanence, nodes=nodes)
        slope = ca.Function("slope", [spacing], [ca.jacobian(k12, spacing)])
        slopes.append(float(slope(length)))
    assert abs(slopes[0] / slopes[1] - 1) < 1e-6


def test_value_gradient_and_hessian_finite_when_rings_touch():
    """At gap = 0 (and for solid discs, R_i = 0) K12, its gradient in (D_o, D_i, h, delta,
    B_r) and its Hessian are finite; the gradient matches finite differences (central in
    D_o, D_i, B_r; one-sided in the spacing, where K12 has a gap log(gap) term)."""
    x = ca.SX.sym("x", 5)
    k12 = coupling_coefficient(*ca.vertsplit(x))
    assert isinstance(k12, ca.SX)
    function = ca.Function("k12", [x], [k12, ca.jacobian(k12, x), ca.hessian(k12, x)[0]])
    touching_discs = (3e-3, 0.0, 1e-3, 1e-3, 1.3)
    for geometry in (DEMONSTRATOR, touching_discs):
        value, gradient, hessian = (np.array(out) for out in function(geometry))
        assert np.all(np.isfinite(value))
        assert np.all(np.isfinite(gradient))
        assert np.all(np.isfinite(hessian))
        assert abs(value.item() / coupling_coefficient(*geometry) - 1) < 1e-14

    gradient = np.array(function(DEMONSTRATOR)[1]).ravel()
    base = np.array(DEMONSTRATOR)
    for index, step in ((0, 1e-7), (1, 1e-7), (4, 1e-4)):
        up, down = base.copy(), base.copy()
        up[index] += step
        down[index] -= step
        central = (coupling_coefficient(*up) - coupling_coefficient(*down)) / (2 * step)
        assert abs(gradient[index] / central - 1) < 1e-7
    step = 1e-11  # one-sided: error ~ step log(step) K'' / K' ~ 1e-7 relative
    up = base.copy()
    up[3] += step
    one_sided = (coupling_coefficient(*up) - coupling_coefficient(*base)) / step
    assert gradient[3] < 0
    assert abs(gradient[3] / one_sided - 1) < 1e-6


def test_torques_are_minus_energy_gradient_and_opposite():
    """T_i = -dU/dtheta_i (energy consistency), T_2 = -T_1, on CasADi symbols and numbers."""
    theta = ca.SX.sym("theta", 2)
    k12 = coupling_coefficient(*DEMONSTRATOR)
    energy = coupling_energy(theta[0], theta[1], k12)
    torque1, torque2 = coupling_torques(theta[0], theta[1], k12)
    check = ca.Function(
        "check", [theta], [ca.vertcat(torque1, torque2) + ca.gradient(energy, theta)]
    )
    for angles in ([0.3, -1.2], [2.0, 0.1], [np.pi, 0.0]):
        assert np.max(np.abs(np.array(check(angles)))) < 1e-15 * k12
        t1, t2 = coupling_torques(*angles, k12)
        assert t1 == -t2
        assert abs(t1 - k12 * math.sin(angles[0] - angles[1])) < 1e-15 * k12


def test_overlapping_or_impossible_rings_are_rejected():
    outer, inner, length, _, remanence = DEMONSTRATOR
    with pytest.raises(ValueError, match="spacing must be at least the ring length"):
        coupling_coefficient(outer, inner, length, 0.9 * length, remanence)
    with pytest.raises(ValueError, match="inner_diameter must be in"):
        coupling_coefficient(outer, outer, length, length, remanence)
    with pytest.raises(ValueError, match="length must be positive"):
        coupling_coefficient(outer, inner, 0.0, length, remanence)


# --- what it means for the demonstrator ---------------------------------------------------


def test_demonstrator_coupling_report():
    """K12 for the demonstrator vs the point-dipole estimate and the external field's axial
    torque scale (ring moment 5.44e-3 A m^2 in ~35 mT), and the twist it puts in the
    transmissions (twist = T L / (G J), L = 0.15 m)."""
    k12 = coupling_coefficient(*DEMONSTRATOR)
    dipoles = _point_dipole_coefficient(DEMONSTRATOR)
    moment = _moment(*DEMONSTRATOR[:3], DEMONSTRATOR[4])
    external = moment * 35e-3  # [N m]
    length = 0.15  # [m]
    wire, catheter = 5.67e-5, 2.17e-4  # G J [N m^2]
    twist_wire, twist_catheter = k12 * length / wire, k12 * length / catheter
    # Both transmissions give way to the pair torque: the relative tip angle obeys
    # Delta = Delta_cmd + kappa sin(Delta), unstable near parallel when kappa > 1.
    kappa = k12 * (length / wire + length / catheter)
    print(
        f"\nring coupling, demonstrator (D_o 4 mm, D_i 2 mm, h 0.5 mm, gap 0, B_r 1.45 T):\n"
        f"  K12 = {k12:.6e} J (max axial torque {k12:.3e} N m at 90 deg)\n"
        f"  point dipoles at delta = 0.5 mm: {dipoles:.4e} J ({dipoles / k12:.1f}x too large)\n"
        f"  external torque scale m B = {moment:.3e} A m^2 x 35 mT = {external:.2e} N m"
        f" (K12 / that = {k12 / external:.2f})\n"
        f"  twist at K12: wire {twist_wire:.3f} rad ({math.degrees(twist_wire):.1f} deg),"
        f" catheter {twist_catheter:.3f} rad ({math.degrees(twist_catheter):.1f} deg)\n"
        f"  kappa = K12 L (1/GJ_wire + 1/GJ_catheter) = {kappa:.2f}"
    )
    assert abs(moment - 5.4375e-3) < 1e-6
    assert abs(k12 - 5.715956e-4) < 1e-9  # = the magpylib volume integral (test above)
    assert 40 < dipoles / k12 < 42
    assert abs(twist_wire - 1.512) < 1e-3
    assert abs(twist_catheter - 0.395) < 1e-3
