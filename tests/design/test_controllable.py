"""The controllable workspace (design.controllable), on set-ups drawn from the whole design
space (tests/support/setups.py), against separately written solves.

Truths used: a link between neighbouring configurations holds exactly when the driven-path
solver (solve_sequence, written separately: one configuration at a time, with falls and
snap detection) drives the robot from one to the other without a snap into the other's
own state; the controllable set is what a plain graph search from the antiparallel rings
reaches along the links; where nothing snaps (the demonstrator's axisymmetric baseline)
every configuration is controllable and the controllable disc is the workspace's disc (to
the grid's chord and the raster's pixel). The seed of each random case is in its test id.
"""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest
from setups import random_design

from design.controllable import MOVES, _reached, controllable_workspace, steerable
from design.designfile import default_design
from design.equilibrium import solve_sequence
from design.model import model_for
from design.workspace import angle_grid, sweep_workspace

STEP = np.deg2rad(10.0)


def _graph_search(linked: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Breadth-first search node by node over the links (a plain queue)."""
    g = start.shape[0]
    seen = start.copy()
    queue = deque(zip(*np.nonzero(start), strict=True))
    while queue:
        i, j = queue.popleft()
        for k, (di, dj) in enumerate(MOVES):
            n = ((i + di) % g, (j + dj) % g)
            if linked[k, i, j] and not seen[n]:
                seen[n] = True
                queue.append(n)
    return seen


@pytest.mark.parametrize("seed", range(8400, 8410))
def test_reached_is_what_a_graph_search_reaches(seed):
    rng = np.random.default_rng(seed)
    g = int(rng.integers(3, 12))
    linked = rng.random((4, g, g)) < rng.uniform(0.2, 0.9)
    start = rng.random((g, g)) < 0.1
    np.testing.assert_array_equal(_reached(linked, start), _graph_search(linked, start))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("seed", "effects"),
    [(8302, {"torsion"}), (8308, {"torsion"}), (8309, {"near_field"}), (8306, {"near_field"})],
)
def test_links_are_the_driven_path_solvers_snap_free_moves(seed, effects):
    """Drawn set-ups with snaps (seeds chosen where links fail): up to 12 links that hold
    and 12 that fail, each driven separately by solve_sequence from the node's state to
    the neighbour's command; a link holds iff that drive does not snap and ends in the
    neighbour's own state."""
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    model = model_for(frozenset(effects))
    params = model.parameters(design)
    ws = sweep_workspace(design, STEP, model)
    angles = angle_grid(STEP)
    ctl = controllable_workspace(model, params, ws.grid, angles, ws.rest_position)
    g = len(angles)
    stable = ws.grid.stable.reshape(g, g)
    pick = np.random.default_rng(seed + 1)
    checked = {True: 0, False: 0}
    for k, i, j in pick.permutation(np.argwhere(np.ones((4, g, g), bool))):
        di, dj = MOVES[k]
        ti, tj = (i + di) % g, (j + dj) % g
        holds = bool(ctl.linked[k, i, j])
        if not (stable[i, j] and stable[ti, tj]) or checked[holds] >= 12:
            continue
        start = np.array([angles[i], angles[j]])
        end = start + np.array([di, dj]) * STEP
        eq = solve_sequence(model, params, [start[0], end[0]], [start[1], end[1]])
        own = ws.grid.position.reshape(g, g, 3)[ti, tj]
        lands = (
            eq.stable[1] and np.linalg.norm(eq.position[1] - own) < 1e-6 * design.robot.free_length
        )
        assert holds == (lands and not eq.snapped[1]), (
            f"seed {seed}: link {k} from ({i}, {j}) says {holds}; solve_sequence "
            f"snapped={eq.snapped[1]}, lands={lands}"
        )
        checked[holds] += 1
        if min(checked.values()) >= 12:
            break
    assert checked[True] > 0 and checked[False] > 0, f"seed {seed}: {checked}"


def test_demonstrator_baseline_is_all_controllable_and_its_disc_is_the_workspace_disc():
    """Nothing snaps on the demonstrator's axisymmetric baseline: every configuration is
    controllable, the cells' covered disc about home is the workspace's disc less at most
    the 5-deg grid's chord (R (1 - cos 2.5 deg)) and two raster pixels, and so the disc is
    the workspace's."""
    design = default_design()
    model = model_for(frozenset())
    step = np.deg2rad(5.0)
    ws = sweep_workspace(design, step, model)
    ctl = steerable(ws, model, model.parameters(design))
    assert ctl.fraction == 1.0 and ctl.linked.all()
    chord = ws.max_deflection * (1 - np.cos(step / 2))
    pixel = 2 * 1.05 * (ws.max_deflection + ws.droop) / 400
    assert ws.disc_radius - chord - 2 * pixel <= ctl.covered_disc_radius <= ws.disc_radius
    assert ctl.disc_radius == ws.disc_radius


def test_a_home_outside_every_covered_cell_has_a_disc_of_exactly_zero():
    """Cells that cover a C-shaped band 5..10 mm about home (a 36 x 4 grid of tip
    positions, the last twenty degrees open) and not home itself, which is open to the
    outside: the disc is 0, not the rounding of the home pixel's distance (4e-20 m read as
    a disc in the study's torsion check); a filled disc of 10 mm reads 10 mm to the
    polygon's chord and the raster's pixel."""
    from design.controllable import _covered_disc

    angle = np.linspace(0, 2 * np.pi, 36, endpoint=False)
    rest = np.array([0.15, 0.0, 0.0])

    def grid(radii):
        y = radii[None, :] * np.cos(angle)[:, None]
        z = radii[None, :] * np.sin(angle)[:, None]
        return np.stack([np.full_like(y, 0.15), y, z], axis=2)

    ring = grid(np.linspace(5e-3, 10e-3, 4))
    ok = np.ones(ring.shape[:2], bool)
    ok[-1] = False  # no cell joins the last angle to the first: the band is open there
    disc, pixel, _ = _covered_disc(ring, ok, rest)
    assert disc == 0.0
    filled = grid(np.linspace(0.0, 10e-3, 5))
    ok = np.ones(filled.shape[:2], bool)
    disc, pixel, _ = _covered_disc(filled, ok, rest)
    chord = 10e-3 * (1 - np.cos(np.pi / 36))  # the polygon's inset from the circle
    assert 10e-3 - chord - 2 * pixel <= disc <= 10e-3
