"""``ringpair simulate --magnet-*``: a moved magnet as a command beside the ring angles.

Each row of a moved-magnet run must be the state of the design with its magnet written at
that pose in the design file (its own file, simulated without --magnet-*: the model's
parameters of that file, not the per-row columns), over set-ups drawn from the whole
design space (optimize.fitting.setups) with an obstacle where drawn; the seed is printed
on failure."""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np
import pytest
import tomli_w
from setups import random_design

from design.designfile import (
    default_design,
    design_to_dict,
    dumps_design,
    loads_design,
    save_design,
)
from design.designfile.keys import DesignError
from design.moving import moved, moved_source
from design.records import Obstacle
from design.units import MM

POSE = ("x_mm", "y_mm", "z_mm", "tangent_x", "tangent_y", "tangent_z", "stiffness_min_mN_per_mm")


def _values(rows, keys):
    return np.array([[float(r[k]) if r[k] else np.nan for k in keys] for r in rows])


@pytest.mark.parametrize("draw", range(3))
def test_each_moved_pose_is_the_design_with_its_magnet_there(tmp_path, run, read_csv, draw):
    seed = int(os.environ.get("RINGPAIR_SEED", np.random.SeedSequence().entropy % 2**32))
    rng = np.random.default_rng(seed)
    d = random_design(rng)
    if draw == 2:  # a wall across the tip's side (contact with per-row parameters)
        wall = Obstacle("plane", (d.robot.free_length, 6 * MM, 0.0), (0.0, -1.0, 0.0))
        d = replace(d, environment=replace(d.environment, obstacles=(wall,)))
    ext = d.external_magnet
    centre = np.array(ext.center) / MM
    source = moved_source(d, None)
    # moves of a few mm to a few cm, redrawn until the magnet clears the robot at every
    # pose (the reader's rule; seed 3488106384 drew one onto the robot's axis)
    for _ in range(50):
        xs = centre[0] + np.array([0.0, rng.uniform(5.0, 40.0)]) * np.sign(centre[0] or 1.0)
        ys = centre[1] + np.array([rng.uniform(-20.0, 20.0)])
        turn = rng.uniform(-30.0, 30.0)
        try:
            for x, t in [(x, t) for x in xs for t in (0.0, turn)]:
                moved(d, source, np.array([x, ys[0], centre[2]]) * MM, np.deg2rad(t))
            break
        except DesignError:
            continue
    else:
        pytest.fail(f"seed {seed}: no pose clear of the robot in 50 draws")
    path = tmp_path / "d.toml"
    save_design(d, path)
    out = tmp_path / "moved.csv"
    args = ["--theta1", "0,120", "--theta2", "0,200", "--effects", "default", "--quiet"]
    result = run(
        "simulate",
        str(path),
        *args,
        "--magnet-x",
        ",".join(f"{x:.6f}" for x in xs),
        "--magnet-y",
        f"{ys[0]:.6f}",
        "--magnet-turn",
        f"0,{turn:.6f}",
        "--out",
        str(out),
    )
    assert result.exit_code == 0, f"seed {seed}: {result.output}"
    rows = read_csv(out)
    assert len(rows) == 4 * 2 * 2, f"seed {seed}"
    for k, (x, t) in enumerate([(x, t) for x in xs for t in (0.0, turn)]):
        mine = rows[4 * k : 4 * (k + 1)]
        pose = _values(mine, ("magnet_x_mm", "magnet_y_mm", "magnet_z_mm", "magnet_turn_deg"))
        np.testing.assert_allclose(pose, [[x, ys[0], centre[2], t]] * 4, atol=1e-5)
        there = tmp_path / f"pose{k}.toml"
        centre_m = np.array([x, ys[0], centre[2]]) * MM
        save_design(moved(d, source, centre_m, np.deg2rad(t)), there)
        alone = tmp_path / f"pose{k}.csv"
        assert run("simulate", str(there), *args, "--out", str(alone)).exit_code == 0
        expected = read_csv(alone)
        assert [r["failure"] for r in mine] == [r["failure"] for r in expected], f"seed {seed}"
        np.testing.assert_allclose(
            _values(mine, POSE),
            _values(expected, POSE),
            rtol=1e-6,
            atol=1e-6,
            err_msg=f"seed {seed}, pose {k}",
        )
        if draw == 2:
            assert [r["in_contact"] for r in mine] == [r["in_contact"] for r in expected]


def test_a_driven_moving_magnet_path_stays_on_the_states_on_their_own(tmp_path, run, read_csv):
    """The magnet moved along a path (--ordered, refined to 1 mm steps), over a drawn
    set-up (whole design space, default model): where the path did not snap, its state is
    the state on its own or, where the two differ, another stable state at that pose
    (checked exactly, :func:`design.equilibrium.stable_states`; the on-its-own run's
    search for other states need not find it: seed 3876101847, a state 58 mm away). Poses
    that put the magnet on the robot are refused and redrawn (seed 374038718)."""
    from design.equilibrium import stable_states
    from design.model import DEFAULT_EFFECTS, RingPairModel
    from design.moving import pose_parameters

    seed = int(os.environ.get("RINGPAIR_SEED", np.random.SeedSequence().entropy % 2**32))
    rng = np.random.default_rng(seed)
    for _ in range(10):  # a set-up with a row to compare (seed 2034476848 drew none)
        d = random_design(rng)
        path = tmp_path / "d.toml"
        save_design(d, path)
        centre = np.array(d.external_magnet.center) / MM
        ys = centre[1] + np.linspace(-1.0, 1.0, 5) * rng.uniform(5.0, 25.0)
        theta1 = rng.uniform(0, 360)
        moves = ["--magnet-y", ",".join(f"{y:.6f}" for y in ys), "--theta1", f"{theta1:.3f}"]
        driven, alone = tmp_path / "driven.csv", tmp_path / "alone.csv"
        ordered = run("simulate", str(path), *moves, "--ordered", "--quiet", "--out", str(driven))
        if ordered.exit_code != 0 and "must clear the robot" in ordered.output:
            continue
        assert ordered.exit_code == 0, f"seed {seed}: {ordered.output}"
        assert run("simulate", str(path), *moves, "--quiet", "--out", str(alone)).exit_code == 0
        a, b = read_csv(driven), read_csv(alone)
        rows = [
            i for i, (x, y) in enumerate(zip(a, b, strict=True))
            if x["snapped"] == "false" and x["stable"] == "true" and y["stable"] == "true"
        ]  # fmt: skip
        if rows:
            break
    assert rows, f"seed {seed}: no row to compare in 10 set-ups"
    mine, theirs = _values([a[i] for i in rows], POSE[:3]), _values([b[i] for i in rows], POSE[:3])
    gaps = np.abs(mine - theirs).max(axis=1)
    differ = [r for r, gap in zip(rows, gaps, strict=True) if gap > 1e-5]
    if differ:  # the path's own states, through the API, checked at their poses
        from ringpair.commands.simulate import _moved_path

        model, source = RingPairModel(DEFAULT_EFFECTS).for_design(d), moved_source(d, None)
        poses = _values(a, ("theta1_deg", "theta2_deg", "magnet_x_mm", "magnet_y_mm",
                            "magnet_z_mm", "magnet_turn_deg"))  # fmt: skip
        poses[:, [0, 1, 5]] = np.deg2rad(poses[:, [0, 1, 5]])
        poses[:, 2:5] *= MM
        eq, _, _ = _moved_path(d, poses, model, source)
        np.testing.assert_allclose(eq.position / MM, _values(a, POSE[:3]), atol=1e-5,
                                   err_msg=f"seed {seed}")  # fmt: skip
        params = pose_parameters(model, d, source, poses[differ, 2:5], poses[differ, 5])
        stable = stable_states(model, params, eq.unknowns[differ].T, poses[differ, :2].T)
        assert stable.all(), f"seed {seed}: rows {differ}"


def test_a_path_of_constant_parameter_columns_is_the_plain_path():
    """solve_sequence with one parameter column per command, all equal, gives the plain
    path's states to the last digit."""
    from design.equilibrium import solve_sequence
    from design.model import DEFAULT_EFFECTS, RingPairModel

    d = default_design()
    model = RingPairModel(DEFAULT_EFFECTS).for_design(d)
    p = model.parameters(d)
    t1 = np.deg2rad(np.arange(0.0, 100.0, 20.0))
    plain = solve_sequence(model, p, t1, 0.0 * t1)
    columns = solve_sequence(model, np.tile(p[:, None], (1, t1.size)), t1, 0.0 * t1)
    np.testing.assert_array_equal(columns.position, plain.position)
    np.testing.assert_array_equal(columns.snapped, plain.snapped)


def test_a_turned_magnet_rotates_the_field_as_a_turned_design_file(tmp_path, run, read_csv):
    """The demonstrator's magnet turned 90 deg about z in the design file (magnetisation
    -x -> -y, the cylinder's axis with it) and by --magnet-turn 90: the same tip."""
    d = default_design()
    turned = replace(d.external_magnet, magnetization=(0.0, -1.0, 0.0))
    path = tmp_path / "turned.toml"
    save_design(replace(d, external_magnet=turned), path)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    args = ["--theta1", "0,90", "--effects", "none", "--quiet"]
    assert run("simulate", *args, "--magnet-turn", "90", "--out", str(a)).exit_code == 0
    assert run("simulate", str(path), *args, "--out", str(b)).exit_code == 0
    np.testing.assert_allclose(
        _values(read_csv(a), POSE[:3]), _values(read_csv(b), POSE[:3]), atol=1e-9
    )


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--magnet-x", "150"], ["external_magnet moved to (150, 0, 0) mm", "straight robot"]),
        (["--magnet-x", "2e5"], ["--magnet-x", "within +-100000 mm"]),
        (["--magnet-y", "a"], ["--magnet-y expects millimetres"]),
        (["--magnet", "3"], ["field.sources number 1..0", "'3'"]),
    ],
)
def test_bad_moved_magnet_input_is_one_message(tmp_path, run, args, words):
    out = tmp_path / "s.csv"
    result = run("simulate", "--theta1", "0", *args, "--out", str(out), "--quiet")
    assert result.exit_code == 2, result.output
    for w in words:
        assert w in result.output, result.output
    assert "Traceback" not in result.output and not out.exists()


def test_a_block_is_not_turned_and_a_uniform_field_not_moved(tmp_path, run):
    doc_block = """
[[field.sources]]
kind = "cuboid"
dimensions_mm = [40.0, 40.0, 20.0]
center_mm = [250.0, 0.0, 0.0]
magnetization = [-1.0, 0.0, 0.0]
remanence_t = 1.3
"""
    doc_uniform = """
[[field.sources]]
kind = "uniform"
b_t = [0.0, 0.02, 0.0]
"""
    base = design_to_dict(default_design())
    del base["external_magnet"]
    for doc, args, words in (
        (doc_block, ["--magnet-turn", "10"], "its pose cannot be turned"),
        (doc_uniform, ["--magnet-x", "300"], "no field source that can be moved"),
    ):
        path = tmp_path / "d.toml"
        path.write_text(dumps_design(loads_design(_joined(base, doc))))
        out = tmp_path / "s.csv"
        result = run("simulate", str(path), "--theta1", "0", *args, "--out", str(out))
        assert result.exit_code == 2 and words in result.output, result.output
        assert not out.exists()


def _joined(base: dict, sources: str) -> str:
    return tomli_w.dumps(base) + sources
