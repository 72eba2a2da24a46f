"""Synthetic bench data: seeded, equal to a forward simulation of the truth along the
bench path, top views without z, unstable configurations dropped and counted."""

from __future__ import annotations

import numpy as np
import pytest

from design.equilibrium import solve_design, solve_equilibria, solve_sequence
from design.model import RingPairModel
from design.parameters import index
from optimize.synth import default_commands, synthesize, synthesize_data


def test_default_path_is_a_bench_sweep_both_ways():
    cmd = np.rad2deg(default_commands())
    assert 55 <= len(cmd) <= 65
    first = cmd[cmd[:, 1] == 0, 0]
    assert first[0] == 0 and first.max() == 180 and first[-1] == 0  # parallel -> anti -> back
    np.testing.assert_allclose(np.unique(cmd[:, 1].round(9)), [0, 120, 240])


def test_same_seed_same_data_other_seed_other_noise(demonstrator):
    a = synthesize(demonstrator, n=12, noise_mm=0.3, seed=5)
    b = synthesize(demonstrator, n=12, noise_mm=0.3, seed=5)
    c = synthesize(demonstrator, n=12, noise_mm=0.3, seed=6)
    np.testing.assert_array_equal(a.position, b.position)
    assert not np.allclose(a.position, c.position)
    noise = (a.position - c.position) * 1e3
    assert 0.1 < np.std(noise) / np.sqrt(2) < 0.6  # 0.3 mm per coordinate


def test_noise_free_data_equal_the_forward_simulation(demonstrator):
    truth = {"bending_rigidity_scale": 0.8, "external_center_y": 0.002}
    m = synthesize(demonstrator, n=12, noise_mm=0.0, params_override=truth)
    params = RingPairModel.parameters(demonstrator)
    params[index("bending_rigidity_scale")] = 0.8
    params[index("external_center_y")] = 0.002
    cmd = default_commands(12)
    eq = solve_sequence(RingPairModel(), params, cmd[:, 0], cmd[:, 1])
    np.testing.assert_allclose(m.position, eq.position, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(m.sequence, np.arange(len(cmd)))
    np.testing.assert_allclose(m.command, cmd)
    # without overrides: the design's own (ordered) simulation
    plain = synthesize(demonstrator, n=12, noise_mm=0.0)
    ref = solve_design(demonstrator, cmd[:, 0], cmd[:, 1], ordered=True)
    np.testing.assert_allclose(plain.position, ref.position, atol=1e-15)


def test_top_view_keeps_x_and_y_and_tip_angles_on_request(demonstrator):
    m = synthesize(demonstrator, n=6, view="top", tip_angles=True, angle_noise_deg=0.0)
    assert np.isnan(m.position[:, 2]).all() and np.isfinite(m.position[:, :2]).all()
    np.testing.assert_allclose(m.tip_angles, m.command, atol=1e-12)  # rigid transmissions


def test_the_robot_enters_its_loads_on_the_branch_of_the_straight_rod(demonstrator):
    """A soft rod (1/10 the bending rigidity) at the first bench command: Newton from the
    straight robot at full load lands on an unstable equilibrium on the far side; the
    driven robot, brought into the field by ramping the loads, starts stable on the side
    its small-load deflection points to."""
    params = RingPairModel.parameters(demonstrator)
    params[index("bending_rigidity_scale")] = 0.1
    cmd = default_commands(12)
    alone = solve_equilibria(RingPairModel(), params, cmd[:1, 0], cmd[:1, 1])
    assert alone.converged[0] and not alone.stable[0]
    weak = params.copy()
    weak[index("load_scale")] = 1e-3
    side = np.sign(solve_equilibria(RingPairModel(), weak, cmd[:1, 0], cmd[:1, 1]).position[0, 1])
    driven = solve_sequence(RingPairModel(), params, cmd[:, 0], cmd[:, 1])
    assert driven.stable.all()
    assert np.sign(driven.position[0, 1]) == side != np.sign(alone.position[0, 1])


def test_unstable_configurations_are_dropped_and_counted(demonstrator):
    """A soft rod 30 mm from a strong magnet's centre: some states have no stable
    neighbour to fall into."""
    close = {
        "bending_rigidity_scale": 0.3,
        "external_center_x": demonstrator.robot.free_length + 0.03,
    }
    data = synthesize_data(demonstrator, n=12, params_override=close)
    assert data.dropped >= 1
    assert len(data.measurements) + data.dropped == len(default_commands(12))
    kept = data.measurements.sequence
    assert not data.equilibria.stable[np.setdiff1d(np.arange(len(data.equilibria)), kept)].any()


def test_bad_arguments_are_named(demonstrator):
    with pytest.raises(ValueError, match="did you mean 'wire_torsion_scale'"):
        synthesize(demonstrator, params_override={"wire_torsion_scal": 2.0})
    with pytest.raises(ValueError, match="view must be one of"):
        synthesize(demonstrator, view="side")
    with pytest.raises(ValueError, match="noise_mm"):
        synthesize(demonstrator, noise_mm=-1)
