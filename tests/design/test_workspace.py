"""Workspace sweep and metrics: symmetry of symmetric set-ups, metric definitions."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from design.equilibrium import solve_design
from design.workspace import angle_grid, sweep_workspace


def test_axisymmetric_setup_gives_a_round_workspace(demonstrator):
    # Magnet on the robot's axis, magnetised along it: rotating both rings together rotates
    # the tip about x, so the workspace is a disc and its metrics coincide.
    ws = sweep_workspace(demonstrator, np.deg2rad(10))
    assert ws.n_without_state == 0 and ws.n_snapped == 0
    assert ws.y_range[0] == pytest.approx(-ws.y_range[1], rel=1e-9)
    assert ws.z_range == pytest.approx(ws.y_range, rel=1e-9)
    # The loop is a circle about the straight tip: its smooth curve through LOOP_SAMPLES
    # samples follows it to O(720^-4); the home (rings antiparallel) sits off the straight
    # tip (the rings' spacing), so the disc about home is the radius less its offset in y-z
    # (to 1e-6: the arcs' distance is first-order in their bow).
    assert ws.straight_disc_radius == pytest.approx(ws.max_deflection, rel=1e-9)
    offset = np.linalg.norm((ws.home.position - ws.rest_position)[1:])
    assert 0 < offset <= ws.droop < 0.05 * ws.max_deflection
    assert ws.disc_radius == pytest.approx(ws.max_deflection - offset, rel=1e-6)
    r = np.linalg.norm(ws.parallel.position[:, 1:], axis=1)
    assert r.max() - r.min() < 1e-12
    assert ws.boundary_excess < 1e-9
    np.testing.assert_allclose(np.rad2deg(ws.max_angles), [0, 0])


def test_magnet_offset_in_z_gives_a_workspace_mirror_symmetric_in_y(demonstrator):
    # Mirror y -> -y maps a ring angle theta to pi - theta; with the magnet moved to z = 20
    # mm the set-up is mirror symmetric, so tip(pi - t1, pi - t2) = mirror(tip(t1, t2)).
    ext = dataclasses.replace(demonstrator.external_magnet, center=(0.24905, 0.0, 0.02))
    d = dataclasses.replace(demonstrator, external_magnet=ext)
    rng = np.random.default_rng(5)
    t1, t2 = rng.uniform(0, 2 * np.pi, (2, 50))
    a = solve_design(d, t1, t2)
    b = solve_design(d, np.pi - t1, np.pi - t2)
    np.testing.assert_allclose(b.position * [1, -1, 1], a.position, atol=1e-14)
    ws = sweep_workspace(d, np.deg2rad(10))
    assert ws.y_range[0] == pytest.approx(-ws.y_range[1], rel=1e-9)
    assert ws.z_range[0] != pytest.approx(-ws.z_range[1], rel=1e-3)  # not symmetric in z
    assert 0 < ws.disc_radius < ws.max_deflection


def test_neutral_deflection_vanishes_without_spacing(demonstrator):
    # Antiparallel rings at the same place cancel exactly (paper Sec. III-A, delta ~ 0).
    tip = dataclasses.replace(demonstrator.tip, magnet_length=1e-9, magnet_gap=0.0)
    ws = sweep_workspace(dataclasses.replace(demonstrator, tip=tip), np.deg2rad(30))
    assert ws.neutral_deflection < 1e-12
    assert sweep_workspace(demonstrator, np.deg2rad(30)).neutral_deflection > 1e-4


def test_angle_grid_covers_one_turn():
    g = angle_grid(np.deg2rad(5))
    assert len(g) == 72 and g[0] == 0 and g[-1] == pytest.approx(np.deg2rad(355))
