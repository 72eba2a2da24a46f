"""Driving the tip along a path (design.paths), on set-ups drawn from the whole design
space (tests/support/setups.py) and checked against separate solves.

Truths used: the schedule's choice is the cheapest chain of solutions, compared with
brute-force enumeration of every chain; every point the schedule reaches, its angles
solved forward on their own (solve_equilibria, the state's one definition), puts the tip
on the point; a followed path is driven without a jump of the tip (a snap would be one)
and the driven state at each point is the configuration's own state; an axisymmetric
set-up steers a circle about its axis by turning both rings together through exactly one
turn (the set-up turned by phi about the axis is the same set-up with both ring angles
plus phi). The seed of each random case is in its test id.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from setups import random_design

from design.designfile import default_design, design_from_dict, design_to_dict
from design.equilibrium import solve_equilibria
from design.model import DEFAULT_EFFECTS, model_for
from design.paths import TIE, _choose, circle, evaluate, follow, largest_ellipse, line
from design.steering import REACHED

EFFECTS = (frozenset(), DEFAULT_EFFECTS, frozenset({"torsion"}), frozenset({"near_field"}))
STRAY = 0.25
"""A followed path's driven tip stays within this fraction of the points' spacing of the
path between points (angles interpolated linearly between neighbouring solutions)."""


def _chain_cost(options, chain, closed, max_turn, struck):
    """Total rotation of one chain, ties broken by TIE x the moves' lengths in the plane
    of the angles (inf if a move is too large or struck)."""
    m, total = len(options), 0.0
    for i in range(m if closed else m - 1):
        j = (i + 1) % m
        turn = np.abs(np.angle(np.exp(1j * (options[j][chain[j]] - options[i][chain[i]]))))
        if turn.max() > max_turn or (i, chain[i], chain[j]) in struck:
            return np.inf
        total += turn.sum() + TIE * np.hypot(*turn)
    return total


@pytest.mark.parametrize("seed", range(8000, 8030))
def test_schedule_is_the_cheapest_chain_found_by_brute_force(seed):
    """_choose against every chain enumerated: the same smallest total rotation, with
    moves above max_turn and struck moves excluded, open and closed paths."""
    rng = np.random.default_rng(seed)
    m = int(rng.integers(2, 6))
    options = [rng.uniform(0, 2 * np.pi, (int(rng.integers(1, 4)), 2)) for _ in range(m)]
    closed = bool(rng.integers(2))
    max_turn = rng.uniform(0.5, np.pi)
    struck = {
        (i, int(rng.integers(len(options[i]))), int(rng.integers(len(options[(i + 1) % m]))))
        for i in rng.integers(0, m, 3)
    }
    chains = list(itertools.product(*[range(len(o)) for o in options]))
    costs = [_chain_cost(options, c, closed, max_turn, struck) for c in chains]
    chosen = _choose(options, closed, max_turn, struck)
    if not np.isfinite(min(costs)):
        assert chosen is None, f"seed {seed}: a chain was chosen where none passes"
        return
    assert chosen is not None, f"seed {seed}: no chain chosen, brute force found {min(costs)}"
    got = _chain_cost(options, chosen, closed, max_turn, struck)
    assert got == pytest.approx(min(costs), abs=1e-12), f"seed {seed}"


def _local_circle(rng, model, params):
    """A circle of 24 points about a reachable tip, small enough to lie in the image of the
    angles within 10 deg of the configuration it comes from (its radius a third of the
    smallest singular value of the tip's derivative times 10 deg), or None."""
    theta = rng.uniform(0, 2 * np.pi, (2, 40))
    eq = solve_equilibria(model, params, theta[0], theta[1])
    if not eq.stable.any():
        return None
    k = int(np.flatnonzero(eq.stable)[0])
    h = 1e-4
    tips = solve_equilibria(
        model,
        params,
        theta[0, k] + np.array([0.0, h, 0.0]),
        theta[1, k] + np.array([0.0, 0.0, h]),
    )
    if not tips.stable.all():
        return None
    jac = (tips.position[1:, 1:] - tips.position[0, 1:]).T / h
    radius = np.linalg.svd(jac, compute_uv=False).min() * np.deg2rad(10.0) / 3
    if radius < 1e-5:
        return None
    return circle(radius, 24, tuple(eq.position[k, 1:]))


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(8100, 8106))
def test_circle_about_a_reachable_tip_is_followed_and_lands_forward(seed):
    """On a drawn set-up, a small circle about a reachable tip: every point the schedule
    reaches lands forward on its own; if followed, the driven state at each point is the
    configuration's own, the tip never jumps between driven commands (at most a point
    spacing: a snap would move it far more) and strays at most STRAY x spacing from the
    path."""
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    model = model_for(EFFECTS[rng.integers(len(EFFECTS))])
    params = model.parameters(design)
    points = _local_circle(rng, model, params)
    if points is None:
        pytest.skip(f"seed {seed}: no configuration with a regular state drawn")
    schedule = follow(model, params, points, closed=True)
    alone = solve_equilibria(model, params, *np.mod(schedule.theta, 2 * np.pi).T)
    hit = schedule.reached
    landed = np.linalg.norm(alone.position[hit, 1:] - points[hit], axis=1)
    assert np.all(landed <= REACHED), f"seed {seed}: forward misses {landed.max()}"
    spacing = np.linalg.norm(points[1] - points[0])
    assert schedule.followed, f"seed {seed}: {model.name}, radius {spacing * 24 / 2 / np.pi}"
    assert np.allclose(schedule.position, alone.position, atol=1e-9), f"seed {seed}"
    jumps = np.linalg.norm(np.diff(schedule.driven[:, 1:], axis=0), axis=1)
    assert jumps.max() <= spacing, f"seed {seed}: the tip jumped {jumps.max() / spacing} spacings"
    assert schedule.deviation <= STRAY * spacing, f"seed {seed}: {schedule.deviation / spacing}"


def _axisymmetric(seed: int):
    """A drawn robot before an external magnet on its axis, magnetised along it, no
    gravity."""
    rng = np.random.default_rng(seed)
    doc = design_to_dict(random_design(rng))
    ext = doc["external_magnet"]
    ext["magnetization"] = [1.0 if rng.random() < 0.5 else -1.0, 0.0, 0.0]
    length = doc["robot"]["free_length_mm"]
    ext["center_mm"] = [length + ext["length_mm"] / 2 + rng.uniform(10.0, 60.0), 0.0, 0.0]
    doc.pop("environment", None)
    return rng, design_from_dict(doc)


@pytest.mark.parametrize("seed", range(8200, 8203))
def test_axisymmetric_circle_about_the_axis_costs_one_turn_of_each_ring(seed):
    """Axisymmetric set-up: the circle about the axis through a reachable tip is driven by
    turning both rings together, through exactly one turn (symmetry: the state at angles
    theta + phi is the state at theta turned by phi about the axis)."""
    rng, design = _axisymmetric(seed)
    model = model_for(frozenset({"near_field"}) if rng.random() < 0.5 else frozenset())
    params = model.parameters(design)
    eq = solve_equilibria(model, params, np.array([0.0]), np.array([np.pi / 3]))
    assert eq.stable[0], f"seed {seed}"
    radius = float(np.hypot(*eq.position[0, 1:]))
    points = circle(radius, 36)
    schedule = follow(model, params, points, closed=True)
    assert schedule.followed, f"seed {seed}"
    np.testing.assert_allclose(schedule.rotation, 2 * np.pi, atol=1e-6, err_msg=f"seed {seed}")
    # Between points the tip stays on the circle: off the path's chords by the sagitta.
    sagitta = radius * (1 - np.cos(np.pi / 36))
    assert schedule.deviation <= sagitta + 1e-9, f"seed {seed}: the drive left the circle"
    turned = schedule.theta - schedule.theta[0]
    np.testing.assert_allclose(turned[:, 0], turned[:, 1], atol=1e-6, err_msg=f"seed {seed}")
    np.testing.assert_allclose(
        np.abs(turned[:, 0]), 2 * np.pi * np.arange(36) / 36, atol=1e-6, err_msg=f"seed {seed}"
    )


def test_line_beyond_the_workspace_flags_the_points_out_of_reach():
    """The demonstrator (baseline model, workspace radius about 23 mm): a line from 1 mm
    off the centre to 40 mm. Points inside are reached and land forward; those beyond get the
    closest reachable point, reached = false, the tip at most on the rim."""
    model = model_for(frozenset())
    params = model.parameters(default_design())
    points = line((0.001, 0.0), (0.04, 0.0), 14)
    schedule = follow(model, params, points)
    rim = solve_equilibria(model, params, np.array([0.0]), np.array([0.0])).position[0, 1:]
    inside = np.linalg.norm(points, axis=1) < np.hypot(*rim) - 1e-4
    assert schedule.reached[inside].all() and not schedule.reached[~inside].any()
    assert np.all(schedule.error[inside] <= 1e-6)
    assert np.all(
        schedule.error[~inside] >= np.linalg.norm(points[~inside], axis=1) - np.hypot(*rim) - 1e-6
    )
    assert not schedule.followed


def test_path_input_is_checked():
    model = model_for(frozenset())
    params = model.parameters(default_design())
    with pytest.raises(ValueError, match="at least two"):
        follow(model, params, np.array([[0.0, 0.0]]))
    with pytest.raises(ValueError, match="finite"):
        follow(model, params, np.array([[0.0, 0.0], [np.nan, 0.0]]))


def test_largest_ellipse_of_an_axisymmetric_set_up_is_its_rim_circle():
    """The demonstrator with the baseline model is axisymmetric: its rim (parallel rings)
    is a circle about the axis, the largest ellipse it is driven around is that circle,
    and the paper's numbers follow: deflection along y = along z = mean deflection = the
    rim's radius, RMS distance to the fitted ellipse zero."""
    model = model_for(frozenset())
    params = model.parameters(default_design())
    rim = solve_equilibria(model, params, np.array([0.0]), np.array([0.0])).position[0, 1:]
    radius = float(np.hypot(*rim))
    schedule = largest_ellipse(model, params, count=24)
    assert schedule.followed
    np.testing.assert_allclose(np.linalg.norm(schedule.points, axis=1), radius, rtol=1e-3)
    e = evaluate(schedule)
    np.testing.assert_allclose([e.max_y, e.max_z, e.mean_deflection], radius, rtol=1e-3)
    assert e.rms_to_ellipse < 1e-9
