"""The state with contact (design.contact, design.obstacles): a cantilever pushed against
a wall against beam theory, the same state from an independent energy minimisation with
the wall as a hard constraint (scipy SLSQP, written here), mirror set-ups, and in the
field of random set-ups complementarity and the wrench balance (the contact force applied
as a plain tip load gives the same state by the load ramp)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq, minimize
from setups import random_design

from design.contact import CONTACT_TOLERANCE, solve_in_contact
from design.equilibrium import solve_equilibria
from design.model import model_for
from design.obstacles import gaps, tip_body
from design.records import Obstacle
from design.registry import index

FORCE, MOMENT = index("applied_force_x"), index("applied_moment_x")


def _ei(design) -> float:
    """E pi (D^4 - d^4) / 64 summed over catheter and wire. [N m^2]"""
    return sum(
        t.youngs_modulus * np.pi * (t.outer_diameter**4 - t.inner_diameter**4) / 64
        for t in (design.robot.catheter, design.robot.wire)
    )


def _pushed(design, force):
    """The baseline model's parameters with the field off and ``force`` at the tip. [N]"""
    model = model_for(frozenset())
    p = model.parameters(design)
    p[index("external_remanence")] = 0.0
    p[FORCE : FORCE + 3] = force
    return model, p


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_cantilever_pushed_against_a_wall_gives_the_beam_theory_reaction(side):
    """A cantilever (field off) pushed along y by F0 at its tip, stopped by a wall
    parallel to it: its tip body (the rings' cylinder, radius R, reaching ``front`` ahead
    of the tracked point) touches with the rim of its far end. Beam theory (Gere &
    Timoshenko, *Mechanics of Materials*, the cantilever's tip deflection and slope under
    a tip force and moment), with the reaction lambda at the rim (arm ``front``, moment
    -lambda front): v = (F0 - lambda) L^3 / 3EI - lambda front L^2 / 2EI, theta =
    (F0 - lambda) L^2 / 2EI - lambda front L / EI, and the rim on the wall:
    v + front sin(theta) + R cos(theta) = w. The mirror set-up (side -1) mirrors the
    force."""
    design = random_design(np.random.default_rng(5110))
    length, ei = design.robot.free_length, _ei(design)
    f0 = side * 3.0 * ei / length**3 * 4e-3  # a 4 mm free deflection
    model, p = _pushed(design, [0.0, f0, 0.0])
    body = tip_body(design, printed=False)
    w = side * (2e-3 + body.radius)  # the wall 2 mm beyond the body's rest
    wall = Obstacle("plane", np.array([0.0, w, 0.0]), np.array([0.0, -side, 0.0]))
    eq, contact = solve_in_contact(model, p, [0.0], [0.0], [wall], body)

    def rim(reaction: float) -> float:
        """The rim's height over the wall for a reaction (the y force on the wall): the
        reaction acts at the rim point, arm front cos(theta) - side R sin(theta) ahead of
        the tracked point (theta by fixed point: the arm changes little)."""
        theta = 0.0
        for _ in range(60):
            moment = -reaction * (body.front * np.cos(theta) - side * body.radius * np.sin(theta))
            theta = (f0 - reaction) * length**2 / (2 * ei) + moment * length / ei
        v = (f0 - reaction) * length**3 / (3 * ei) + moment * length**2 / (2 * ei)
        return v + body.front * np.sin(theta) + side * body.radius * np.cos(theta) - w

    reaction = brentq(rim, 0.0, f0) if side > 0 else brentq(rim, f0, 0.0)
    assert contact.in_contact[0] and eq.stable[0]
    # (the gap to CONTACT_TOLERANCE, 1e-9 m of a 2 mm push: the force to ~1e-6)
    np.testing.assert_allclose(contact.force[0], [0.0, reaction, 0.0], rtol=1e-5, atol=1e-12)
    assert abs(contact.gap[0]) <= CONTACT_TOLERANCE


def _rotation(phi: np.ndarray) -> np.ndarray:
    """exp([phi]^) by Rodrigues' formula."""
    angle = np.linalg.norm(phi)
    k = np.array([[0, -phi[2], phi[1]], [phi[2], 0, -phi[0]], [-phi[1], phi[0], 0]])
    if angle < 1e-15:
        return np.eye(3) + k
    return np.eye(3) + np.sin(angle) / angle * k + (1 - np.cos(angle)) / angle**2 * k @ k


@pytest.mark.parametrize("seed", [5120, 5121, 5122])
def test_contact_state_is_the_constrained_energy_minimum(seed):
    """An independent solve: the linear cantilever's energy 1/2 Q^T C^-1 Q ... written as
    1/2 q^T K q - F0 . P(q) (K the inverse of the tip compliance of beam theory, in
    q = (dy, dz, phi_y, phi_z)), minimised by SLSQP with the wall as a hard constraint on
    both end rims of the tip body (sampled), against the contact solve: tip within
    0.01 mm, force within 0.01 mN. Random design, push direction and oblique wall."""
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    length, ei = design.robot.free_length, _ei(design)
    k_lat = 3 * ei / length**3
    direction = np.array([0.0, *rng.normal(size=2)])
    direction /= np.linalg.norm(direction)
    f0 = k_lat * rng.uniform(3e-3, 8e-3) * direction
    model, p = _pushed(design, f0)
    body = tip_body(design, printed=False)
    tilt = rng.uniform(-0.3, 0.3)
    n = -(direction + np.array([tilt, 0.0, 0.0]))
    n /= np.linalg.norm(n)
    point = np.array([length, 0.0, 0.0]) + (body.radius + rng.uniform(1e-3, 2e-3)) * direction
    wall = Obstacle("plane", point, n)
    eq, contact = solve_in_contact(model, p, [0.0], [0.0], [wall], body)
    assert contact.in_contact[0], f"seed {seed}"

    a, b, c = length**3 / (3 * ei), length**2 / (2 * ei), length / ei
    compliance = np.array([[a, 0, 0, b], [0, a, -b, 0], [0, -b, c, 0], [b, 0, 0, c]])
    stiffness = np.linalg.inv(compliance)
    phi = np.linspace(0, 2 * np.pi, 360, endpoint=False)

    def energy(q):
        return 0.5 * q @ stiffness @ q - f0[1] * q[0] - f0[2] * q[1]

    def rims(q):
        frame = _rotation(np.array([0.0, q[2], q[3]]))
        tip = np.array([length, q[0], q[1]])
        out = []
        for s in (-body.back, body.front):
            centre = tip + s * frame[:, 0]
            ring = centre[:, None] + body.radius * (
                np.outer(frame[:, 1], np.cos(phi)) + np.outer(frame[:, 2], np.sin(phi))
            )
            out.append(n @ (ring - point[:, None]))
        return np.concatenate(out) * 1e3  # mm

    unit = np.array([1e-3, 1e-3, 1e-2, 1e-2])  # mm and centiradians: a scaled problem
    res = minimize(
        lambda u: energy(u * unit) / (k_lat * 1e-6),
        np.zeros(4),
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": lambda u: rims(u * unit)}],
        options={"ftol": 1e-12, "maxiter": 500},
    )
    assert res.success, f"seed {seed}: {res.message}"
    q = res.x * unit
    tip = np.array([length, q[0], q[1]])
    np.testing.assert_allclose(eq.position[0], tip, atol=1e-5, err_msg=f"seed {seed}")
    # The reaction from the minimum: the elastic force the rod holds at the tip, minus
    # the push, is the obstacle's force on the tip (its y, z components).
    elastic = stiffness @ q
    reaction_on_tip = -(f0[1:] - elastic[:2])
    np.testing.assert_allclose(
        -contact.force[0, 1:], reaction_on_tip, atol=1e-5, err_msg=f"seed {seed}"
    )


@pytest.mark.parametrize(
    "seed, effects", [(5130, ()), (5131, ("near_field", "torsion")), (5132, ("gravity",))]
)
def test_contact_in_the_field_is_complementary_and_balances_the_wrench(seed, effects):
    """In the field of a random set-up, a wall placed across the free tip's way: the
    pressed state has gap 0, the tip pushes into the wall (force along -n, frictionless)
    and the contact force, applied as a plain load at the contact point, gives the same
    state by the load ramp (the wrench balance magnetic + elastic + contact = 0)."""
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    model = model_for(frozenset(effects))
    params = model.parameters(design)
    command = rng.uniform(0, 2 * np.pi, 2)
    free = solve_equilibria(model, params, command[0], command[1])
    if not free.stable[0]:
        pytest.skip(f"seed {seed}: no stable state drawn")
    body = tip_body(design, printed=False)
    rest = np.array([design.robot.free_length, 0.0, 0.0])
    move = free.position[0] - rest
    if np.linalg.norm(move[1:]) < 0.2e-3:
        pytest.skip(f"seed {seed}: the tip hardly moves")
    n = -move / np.linalg.norm(move)
    gap_free, nearest, _ = gaps(Obstacle("plane", rest, n), free.position, free.tangent, body)
    # the wall halfway between the body at rest and at its free state
    rest_gap = gaps(Obstacle("plane", rest, n), rest[None], np.array([[1.0, 0, 0]]), body)[0]
    wall = Obstacle("plane", rest + 0.5 * (gap_free[0] + rest_gap[0]) * n, n)
    eq, contact = solve_in_contact(model, params, command[0], command[1], [wall], body)
    assert contact.in_contact[0] and eq.stable[0], f"seed {seed}: {eq.failure[0]}"
    g, q, _ = gaps(wall, eq.position, eq.tangent, body)
    assert abs(g[0]) <= CONTACT_TOLERANCE, f"seed {seed}"
    force = contact.force[0]
    lam = -force @ n
    assert lam > 0 and np.linalg.norm(force + lam * n) <= 1e-12 * lam, f"seed {seed}"
    loaded = params.copy()
    loaded[FORCE : FORCE + 3] += -force
    loaded[MOMENT : MOMENT + 3] += np.cross(q[0] - eq.position[0], -force)
    again = solve_equilibria(model, loaded, command[0], command[1])
    np.testing.assert_allclose(again.position[0], eq.position[0], atol=1e-9, err_msg=f"{seed}")
