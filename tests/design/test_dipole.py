"""Point-dipole field and gradient against closed forms and magpylib's Dipole."""

from __future__ import annotations

import casadi as ca
import magpylib as magpy
import numpy as np
import pytest

from design.dipole import dipole_field, dipole_field_gradient

P = ca.SX.sym("P", 3)
M = ca.SX.sym("m", 3)
FIELD = ca.Function("B", [P, M], [dipole_field(P, M)])
GRADIENT = ca.Function("G", [P, M], [dipole_field_gradient(P, M)])
MU0_4PI = 1.25663706127e-6 / (4 * np.pi)


def field(p, m):
    return np.asarray(FIELD(p, m)).ravel()


def test_on_axis_field_closed_form():
    # Jackson, Classical Electrodynamics 3rd ed., eq. 5.56: on the axis B = mu0/(4 pi) 2 m / r^3.
    m, r = 2.5, 0.13
    assert field([0, 0, r], [0, 0, m]) == pytest.approx([0, 0, MU0_4PI * 2 * m / r**3], rel=1e-14)


def test_equatorial_field_closed_form():
    # Jackson eq. 5.56 in the equatorial plane: B = -mu0/(4 pi) m / r^3.
    m, r = 2.5, 0.13
    assert field([r, 0, 0], [0, 0, m]) == pytest.approx([0, 0, -MU0_4PI * m / r**3], rel=1e-14)


def test_field_matches_magpylib_dipole():
    rng = np.random.default_rng(1)
    moment = np.array([-120.0, 30.0, 45.0])
    src = magpy.misc.Dipole(moment=moment, position=(0.2, -0.01, 0.03))
    points = rng.uniform(-0.3, 0.3, (200, 3)) + np.array([0.2, 0, 0])
    points = points[np.linalg.norm(points - src.position, axis=1) > 0.02]
    ours = np.array([field(p - src.position, moment) for p in points])
    np.testing.assert_allclose(ours, src.getB(points), rtol=1e-12, atol=0)


def test_gradient_is_the_derivative_of_the_field():
    # Closed-form gradient against CasADi's exact derivative of the field expression.
    exact = ca.Function("J", [P, M], [ca.jacobian(dipole_field(P, M), P)])
    rng = np.random.default_rng(2)
    for _ in range(20):
        p, m = rng.normal(size=3) * 0.1, rng.normal(size=3) * 50
        np.testing.assert_allclose(
            np.asarray(GRADIENT(p, m)),
            np.asarray(exact(p, m)),
            rtol=1e-11,
            atol=1e-12 * np.abs(np.asarray(exact(p, m))).max(),
        )


def test_gradient_is_symmetric_and_traceless():
    # Outside sources B is curl-free (symmetric gradient) and divergence-free (zero trace).
    g = np.asarray(GRADIENT([0.05, -0.02, 0.07], [3.0, -1.0, 2.0]))
    np.testing.assert_allclose(g, g.T, atol=1e-15 * np.abs(g).max())
    assert abs(np.trace(g)) < 1e-13 * np.abs(g).max()
