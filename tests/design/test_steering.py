"""Steering (design.steering): the inverse of the forward map, on set-ups drawn from the
whole design space (tests/support/setups.py), checked against separate forward solves.

Truths used: a returned angle pair, solved forward on its own (solve_equilibria, the
state's one definition), puts the tip on the target; the angles a target was made from
are among the solutions (completeness); a set-up that is its own mirror image in the x-z
plane steers mirrored targets with mirrored angles (theta -> pi - theta: the rings'
moments point along (cos theta, sin theta) in the y-z plane), and an axisymmetric one
steers a target on the z = 0 axis with solutions closed under theta -> -theta; the
closest point to a target out of reach is no farther than the closest tip on a dense
forward grid; every solution the slower search from the grid's local minima reaches is
among the batch Newton's. The seed of each random case is in its test id.
"""

from __future__ import annotations

import numpy as np
import pytest
from setups import random_design

from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import DEFAULT_EFFECTS, model_for
from design.steering import REACHED, SEED_STEP, SEEDS, steer
from design.steering.grid import _solve_grid, _solved_grid
from design.steering.search import _search

EFFECTS = (frozenset(), DEFAULT_EFFECTS, frozenset({"torsion"}), frozenset({"near_field"}))
"""Effect sets drawn (each costs a compile of its sensitivity once per machine)."""


def _circular(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Largest angle difference of pairs (..., 2), wrapped to [0, pi]. [rad]"""
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b))))).max(axis=-1)


def _forward(model, params, theta: np.ndarray) -> np.ndarray:
    """The tip (y, z) of the state at each row of theta, solved on its own. [m]"""
    eq = solve_equilibria(model, params, theta[:, 0], theta[:, 1])
    return np.where(eq.stable[:, None], eq.position[:, 1:], np.nan)


def _assert_nothing_reached(seed: int, model, params) -> None:
    """Where no drawn configuration has a state (the magnet pulls the robot in over most
    angles), steering still says true things: what it reaches, solved forward, lands on
    the target, and the rest is flagged out of reach with its distance."""
    targets = np.array([[0.01, 0.0], [0.0, -0.005]])
    result = steer(model, params, targets)
    landed = _forward(model, params, result.theta[result.reached])
    error = np.linalg.norm(landed - targets[result.target_index[result.reached]], axis=1)
    assert np.all(error <= REACHED), f"seed {seed}: forward errors {error}"
    assert np.all(~(result.error[~result.reached] <= REACHED)), f"seed {seed}"


def _drawn(seed: int, symmetric: bool = False):
    rng = np.random.default_rng(seed)
    design = random_design(rng, symmetric)
    model = model_for(EFFECTS[rng.integers(len(EFFECTS))])
    return rng, design, model, model.parameters(design)


@pytest.mark.parametrize("seed", range(7500, 7512))
def test_every_solution_lands_on_its_target_and_the_made_from_angles_are_found(seed):
    """Targets made from random angles on a random set-up: every returned pair, solved
    forward on its own, lands on the target to 1e-6 mm, and the pair it was made from is
    among the solutions (where its state is regular: fold margin above 0.05)."""
    rng, design, model, params = _drawn(seed)
    made = rng.uniform(0, 2 * np.pi, (4, 2))
    tips = _forward(model, params, made)
    keep = np.isfinite(tips).all(axis=1)
    if not keep.any():
        _assert_nothing_reached(seed, model, params)
        return
    made, tips = made[keep], tips[keep]
    result = steer(model, params, tips)
    landed = _forward(model, params, result.theta[result.reached])
    error = np.linalg.norm(landed - tips[result.target_index[result.reached]], axis=1)
    assert np.all(error <= REACHED), f"seed {seed} ({model.name}): forward errors {error}"
    for k in range(len(tips)):
        mine = result.target_index == k
        assert result.reached[mine].any(), f"seed {seed}: target {k} made from angles not reached"
        found = _circular(result.theta[mine], made[k]).min()
        margin = result.fold_margin[mine][np.argmin(_circular(result.theta[mine], made[k]))]
        if margin > 0.05:
            assert found < 1e-5, (
                f"seed {seed} ({model.name}): made-from angles {np.rad2deg(made[k])} deg not "
                f"among the solutions {np.rad2deg(result.theta[mine])}"
            )


@pytest.mark.parametrize("seed", range(7520, 7526))
def test_mirror_set_up_steers_mirrored_targets_with_mirrored_angles(seed):
    """A set-up that is its own mirror image in the x-z plane (y -> -y): the solutions for
    (-y, z) are those for (y, z) with each ring angle theta -> pi - theta, all of them."""
    rng, design, model, params = _drawn(seed, symmetric=True)
    made = rng.uniform(0, 2 * np.pi, (6, 2))
    tips = _forward(model, params, made)
    tips = tips[np.isfinite(tips).all(axis=1)][:3]
    if len(tips) == 0:
        _assert_nothing_reached(seed, model, params)
        return
    mirrored = tips * np.array([-1.0, 1.0])
    one, other = steer(model, params, tips), steer(model, params, mirrored)
    for k in range(len(tips)):
        a = one.theta[(one.target_index == k) & one.reached]
        b = other.theta[(other.target_index == k) & other.reached]
        assert len(a) == len(b), (
            f"seed {seed} ({model.name}): {len(a)} solutions for {tips[k] * 1e3} mm, "
            f"{len(b)} for its mirror image"
        )
        for t in np.pi - a:
            assert _circular(b, t).min() < 1e-5, (
                f"seed {seed}: mirrored solution {np.rad2deg(t)} deg missing from {np.rad2deg(b)}"
            )


def test_axisymmetric_target_on_an_axis_has_solutions_in_mirror_pairs():
    """The demonstrator (magnet on the robot's axis, magnetised along it, no gravity) is
    axisymmetric: for a target on the y axis the solutions are closed under theta -> -theta
    (the mirror z -> -z), and a rotated target is steered with every angle rotated too."""
    model = model_for(frozenset())
    params = model.parameters(default_design())
    result = steer(model, params, np.array([[0.01, 0.0], [0.0, 0.01]]))
    on_y = result.theta[(result.target_index == 0) & result.reached]
    on_z = result.theta[(result.target_index == 1) & result.reached]
    assert len(on_y) >= 2 and len(on_y) == len(on_z)
    for t in on_y:
        assert _circular(on_y, -t).min() < 1e-6
        assert _circular(on_z, t + np.pi / 2).min() < 1e-6


@pytest.mark.parametrize("effects", [frozenset(), DEFAULT_EFFECTS])
def test_target_out_of_reach_gets_the_closest_point_of_a_dense_forward_grid(effects):
    """A target beyond the workspace: reached is false, and the closest point returned is
    no farther from it than the closest tip of a 2-deg forward grid (a brute-force search
    of the same map)."""
    model = model_for(effects)
    params = model.parameters(default_design())
    target = np.array([0.004, 0.045])
    result = steer(model, params, target[None])
    assert len(result) == 1 and not result.reached[0] and result.stable[0]
    a = np.deg2rad(np.arange(0.0, 360.0, 2.0))
    g1, g2 = np.meshgrid(a, a, indexing="ij")
    grid = _forward(model, params, np.column_stack([g1.ravel(), g2.ravel()]))
    best = np.nanmin(np.linalg.norm(grid - target, axis=1))
    assert result.error[0] <= best + 1e-9
    assert result.error[0] == pytest.approx(np.linalg.norm(result.position[0, 1:] - target))


@pytest.mark.parametrize("seed", range(7530, 7534))
def test_batch_newton_finds_every_solution_the_local_minima_search_finds(seed):
    """Targets made from random angles on a random set-up: every solution that the search
    (Levenberg-Marquardt on the state from the grid's local minima, the rim and swapped
    solutions: a separate route to the same answers) reaches is among steer's, angles
    within 1e-3 rad (at the rim, where the map folds, a tip within REACHED pins the angles
    only to about 2e-4 rad)."""
    rng, design, model, params = _drawn(seed)
    made = rng.uniform(0, 2 * np.pi, (12, 2))
    tips = _forward(model, params, made)
    tips = tips[np.isfinite(tips).all(axis=1)]
    if len(tips) == 0:
        _assert_nothing_reached(seed, model, params)
        return
    result = steer(model, params, tips)
    search = _search(model, params, tips, _solve_grid(model, params, SEED_STEP), SEEDS)
    for k in range(len(tips)):
        mine = result.theta[(result.target_index == k) & result.reached]
        for t in search.theta[(search.target_index == k) & search.reached]:
            assert len(mine) and _circular(mine, t).min() < 1e-3, (
                f"seed {seed} ({model.name}): target {tips[k] * 1e3} mm, the search's "
                f"solution {np.rad2deg(t)} deg missing from {np.rad2deg(mine)} deg"
            )


def test_a_design_steered_again_reuses_its_seed_grid():
    """Steering the same design twice (a path's trial sizes) solves its seed grid once, and
    answers alike."""
    model = model_for(frozenset())
    params = model.parameters(default_design())
    _solved_grid.cache_clear()
    first = steer(model, params, np.array([[0.01, 0.0]]))
    again = steer(model, params.copy(), np.array([[0.01, 0.0]]))
    assert _solved_grid.cache_info().misses == 1 and _solved_grid.cache_info().hits == 1
    np.testing.assert_array_equal(first.theta, again.theta)
