"""The ring angles that press with a force (design.pressing, ``steer --press``): every
answer, solved forward with contact (design.contact, itself checked against beam theory
and an independent constrained minimisation in test_contact.py), presses with the force
asked for; the answers are where the force map crosses that force on the grid's lines;
a set-up symmetric under z -> -z gives answers symmetric under (theta1, theta2) ->
(-theta1, -theta2) (the ring angle is measured from y towards z)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from setups import random_design

from design.contact import solve_design_in_contact
from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import model_for
from design.obstacles import gaps, tip_body
from design.pressing import PRESS_TOLERANCE, press
from design.records import Obstacle

STEP = np.deg2rad(30.0)


def _walled(design, wall):
    return replace(design, environment=replace(design.environment, obstacles=(wall,)))


def _check_answers(design, model, result, where):
    """Each answer presses with the force forward, lies on a grid line, between grid
    neighbours that press less and more."""
    wanted = result.wanted
    assert len(result.theta) == result.crossings - result.jumps, where
    eq, _, contact = solve_design_in_contact(design, model, *result.theta.T)
    magnitude = np.linalg.norm(contact.force, axis=1)
    assert eq.stable.all() and contact.in_contact.all(), where
    assert np.abs(magnitude - wanted).max() <= PRESS_TOLERANCE, where
    g = result.grid.size
    cell = 2 * np.pi / g
    for theta in result.theta:
        on_line = np.abs(np.round(theta / cell) * cell - theta) < 1e-9
        assert on_line.any(), f"{where}: {np.rad2deg(theta)} on no grid line"
        line = int(np.flatnonzero(on_line)[0])
        fixed = int(np.round(theta[line] / cell)) % g
        below = int(np.floor(theta[1 - line] / cell)) % g
        ends = [(fixed, below), (fixed, (below + 1) % g)]
        if line == 1:
            ends = [(e[1], e[0]) for e in ends]
        f = sorted(result.magnitude[e] for e in ends)
        assert f[0] < wanted < f[1], f"{where}: {np.rad2deg(theta)} not between {f}"


def test_answers_on_the_demonstrator_press_with_the_force_and_mirror_in_z():
    design = _walled(
        default_design(),
        Obstacle("plane", np.array([0.150, 0.010, 0.0]), np.array([0.0, -1.0, 0.0])),
    )
    model = model_for(frozenset())
    result = press(design, model, 4e-3, STEP)
    assert len(result.theta) >= 4
    _check_answers(design, model, result, "demonstrator")
    key = {tuple(np.round(np.mod(t, 2 * np.pi), 6) % round(2 * np.pi, 6)) for t in result.theta}
    mirrored = {
        tuple(np.round(np.mod(-t, 2 * np.pi), 6) % round(2 * np.pi, 6)) for t in result.theta
    }
    assert key == mirrored


@pytest.mark.parametrize(
    "seed, effects", [(5230, ()), (5231, ("near_field", "gravity")), (5232, ("torsion",))]
)
def test_answers_on_drawn_set_ups_press_with_the_force(seed, effects):
    """A wall across the way of a drawn set-up's free tip (as test_contact places it),
    the force asked for halfway along the map's range."""
    rng = np.random.default_rng(seed)
    model = model_for(frozenset(effects))
    for _ in range(20):  # a set-up whose tip has a stable state that moves
        design = random_design(rng)
        command = rng.uniform(0, 2 * np.pi, 2)
        free = solve_equilibria(model, model.parameters(design), *command)
        rest = np.array([design.robot.free_length, 0.0, 0.0])
        move = free.position[0] - rest
        if free.stable[0] and np.linalg.norm(move[1:]) > 0.2e-3:
            break
    else:
        raise AssertionError(f"seed {seed}: 20 set-ups drawn, no stable state moves the tip")
    n = -move / np.linalg.norm(move)
    body = tip_body(design, printed=False)
    gap_free = gaps(Obstacle("plane", rest, n), free.position, free.tangent, body)[0]
    rest_gap = gaps(Obstacle("plane", rest, n), rest[None], np.array([[1.0, 0, 0]]), body)[0]
    design = _walled(design, Obstacle("plane", rest + 0.5 * (gap_free[0] + rest_gap[0]) * n, n))
    grid = press(design, model, 1.0, STEP).magnitude  # (1 N: the map alone, no answer)
    pressing = grid[np.isfinite(grid) & (grid > 0)]
    assert pressing.size, f"seed {seed}: the wall is pressed nowhere"
    wanted = 0.5 * (pressing.min() + pressing.max())
    result = press(design, model, wanted, STEP)
    assert len(result.theta), f"seed {seed}: no answer"
    _check_answers(design, model, result, f"seed {seed}, {effects}")


def test_a_force_beyond_the_map_has_no_answer():
    design = _walled(
        default_design(),
        Obstacle("plane", np.array([0.150, 0.010, 0.0]), np.array([0.0, -1.0, 0.0])),
    )
    result = press(design, model_for(frozenset()), 1.0, STEP)
    assert len(result.theta) == 0 and result.crossings == 0
    assert np.nanmax(result.magnitude) < 1.0
