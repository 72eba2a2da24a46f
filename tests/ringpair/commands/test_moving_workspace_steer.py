"""``ringpair workspace --magnet-*`` and ``ringpair steer --magnet-*``: the ring pair's
workspace and steering with the magnet held at a moved pose, the classical steering
combined with the rings'.

Each is checked against a second route that does not use the options: the design file
with its magnet written at that pose (``design.moving.moved``, saved and read back),
mapped or simulated on its own; set-ups drawn from the whole design space
(optimize.fitting.setups), the seed printed on failure."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from setups import random_design

from design.designfile import save_design
from design.designfile.keys import DesignError
from design.moving import moved, moved_source
from design.units import MM

NUMBERS = ("x_mm", "y_mm", "z_mm", "tangent_x", "tangent_y", "tangent_z", "deflection_mm")


def _seed() -> int:
    return int(os.environ.get("RINGPAIR_SEED", np.random.SeedSequence().entropy % 2**32))


def _clear_poses(d, rng, seed):
    """Moves of the design's magnet by a few mm to a few cm: one centre x, two y and two
    turns, every combination clear of the robot; as (x, (y1, y2), z) [mm] and (t1, t2)
    [deg]."""
    source = moved_source(d, None)
    centre = np.array(d.external_magnet.center) / MM
    for _ in range(50):
        x = centre[0] + rng.uniform(0.0, 30.0) * np.sign(centre[0] or 1.0)
        ys = centre[1] + rng.uniform(-25.0, 25.0, 2)
        turns = rng.uniform(-30.0, 30.0, 2)
        try:
            for y in ys:
                for t in turns:
                    moved(d, source, np.array([x, y, centre[2]]) * MM, np.deg2rad(t))
        except DesignError:
            continue
        # To the digits the options are typed with, so that both routes hold one pose
        # (states near a fold move by 1e-5 mm with a pose 1e-6 mm away).
        typed = [round(float(v), 6) for v in (x, *ys, centre[2], *turns)]
        return (typed[0], tuple(typed[1:3]), typed[3]), tuple(typed[4:])
    pytest.fail(f"seed {seed}: no poses clear of the robot in 50 draws")


def _clear_pose(d, rng, seed):
    """One pose of :func:`_clear_poses`: (x, y, z) [mm] and a turn [deg]."""
    (x, ys, z), turns = _clear_poses(d, rng, seed)
    return np.array([x, ys[0], z]), turns[0]


def _options(pose, turn) -> list[str]:
    return [
        *(f"--magnet-{a}={v:.6f}" for a, v in zip("xyz", pose, strict=True)),
        f"--magnet-turn={turn:.6f}",
    ]


def _there(d, pose, turn, path):
    """The design file with the magnet written at the pose."""
    save_design(moved(d, moved_source(d, None), np.array(pose) * MM, np.deg2rad(turn)), path)
    return path


def _numbers(rows, keys):
    return np.array([[float(r[k]) if r[k] else np.nan for k in keys] for r in rows])


def test_the_workspace_at_a_moved_pose_is_the_design_file_with_its_magnet_there(
    tmp_path, run, read_csv
):
    seed = _seed()
    rng = np.random.default_rng(seed)
    for _ in range(10):  # a set-up with a workspace to map (a drawn one may have no home)
        d = random_design(rng)
        pose, turn = _clear_pose(d, rng, seed)
        save_design(d, tmp_path / "d.toml")
        a, b = tmp_path / "moved", tmp_path / "file"
        step = ["--step", "15", "--effects", "default"]
        typed = run("workspace", str(tmp_path / "d.toml"), *step, *_options(pose, turn),
                    "--out", str(a))  # fmt: skip
        there = _there(d, pose, turn, tmp_path / "there.toml")
        alone = run("workspace", str(there), *step, "--out", str(b))
        assert typed.exit_code == alone.exit_code, f"seed {seed}: {typed.output}{alone.output}"
        if typed.exit_code == 0:
            break
        assert "has no workspace" in typed.output, f"seed {seed}: {typed.output}"
    else:
        pytest.fail(f"seed {seed}: no drawn set-up has a workspace in 10 draws")
    np.testing.assert_allclose(
        _numbers(read_csv(a / "workspace.csv"), NUMBERS),
        _numbers(read_csv(b / "workspace.csv"), NUMBERS),
        rtol=1e-6,  # the design file holds the pose to its printed digits
        atol=1e-6,
        err_msg=f"seed {seed}",
    )
    mine, theirs = (json.loads((p / "summary.json").read_text()) for p in (a, b))
    held = mine.pop("moved_magnet")
    assert mine.keys() == theirs.keys(), f"seed {seed}"
    for key, value in theirs.items():
        if isinstance(value, str | list) and value and isinstance(value[0], str):
            assert mine[key] == value, f"seed {seed}: {key}"
            continue
        numbers = np.ravel(list(value.values()) if isinstance(value, dict) else value)
        if value is None or isinstance(value, int):  # nulls and counts: exactly
            assert mine[key] == value, f"seed {seed}: {key}"
            continue
        np.testing.assert_allclose(
            np.ravel(list(mine[key].values()) if isinstance(value, dict) else mine[key]),
            numbers.astype(float),
            rtol=1e-6,
            atol=1e-6,
            err_msg=f"seed {seed}: {key}",
        )
    assert held["source"] == "external_magnet"
    got = [held[k] for k in ("magnet_x_mm", "magnet_y_mm", "magnet_z_mm", "magnet_turn_deg")]
    np.testing.assert_allclose(got, [*pose, turn], atol=1e-5)
    assert "moved magnet: external_magnet" in (a / "workspace.csv").read_text()


@pytest.mark.parametrize("per_row", [False, True], ids=["typed poses", "poses per row"])
def test_steered_angles_at_moved_poses_put_the_design_files_tip_on_target(
    tmp_path, run, read_csv, per_row
):
    """Targets are tips simulated at drawn ring angles at each pose (so within reach);
    every answer steer gives at a pose, simulated with the design file of that pose (no
    --magnet-*), puts its tip on the target (steer's 1e-6 mm, checked to 1e-4 mm), and
    every target is reached at its pose."""
    seed = _seed()
    rng = np.random.default_rng(seed)
    for _ in range(10):  # a set-up with states at its drawn angles (a drawn one may have none)
        d = random_design(rng)
        save_design(d, tmp_path / "d.toml")
        (x, ys, z), turns = _clear_poses(d, rng, seed)
        poses = [(np.array([x, ys[k], z]), turns[k]) for k in range(2)]
        angles = rng.uniform(0.0, 360.0, (2, 2))
        wanted = []  # (pose, y, z) per target
        for k, (pose, turn) in enumerate(poses):
            out = tmp_path / f"sim{k}.csv"
            there = _there(d, pose, turn, tmp_path / f"pose{k}.toml")
            theta1 = ",".join(f"{t:.4f}" for t in angles[0])
            result = run("simulate", str(there), "--theta1", theta1, "--theta2",
                         f"{angles[1, k]:.4f}", "--quiet", "--out", str(out))  # fmt: skip
            assert result.exit_code == 0, f"seed {seed}: {result.output}"
            wanted += [(k, float(r["y_mm"]), float(r["z_mm"])) for r in read_csv(out) if r["y_mm"]]
        if wanted:
            break
    else:
        pytest.fail(f"seed {seed}: no drawn configuration has a state in 10 set-ups")
    base = tmp_path / "d.toml"
    out = tmp_path / "steer.csv"
    if per_row:
        rows = ["y_mm,z_mm,magnet_x_mm,magnet_y_mm,magnet_turn_deg"]
        rows += [f"{y!r},{z!r},{x!r},{ys[k]!r},{turns[k]!r}" for k, y, z in wanted]
        (tmp_path / "targets.csv").write_text("\n".join(rows) + "\n")
        args = ["--targets", str(tmp_path / "targets.csv")]
    else:  # every target at every combination of the typed y and turn: 4 poses
        args = [*(f"--to={y!r},{z!r}" for _, y, z in wanted), f"--magnet-x={x!r}",
                "--magnet-y={!r},{!r}".format(*ys),
                "--magnet-turn={!r},{!r}".format(*turns)]  # fmt: skip
    result = run("steer", str(base), *args, "--quiet", "--out", str(out))
    assert result.exit_code == 0, f"seed {seed}: {result.output}"
    answers = read_csv(out)
    checked = 0
    for k, turn in enumerate(turns):
        at_pose = (ys[k], turn)
        own = [
            r for r in answers
            if np.allclose([float(r["magnet_y_mm"]), float(r["magnet_turn_deg"])], at_pose)
        ]  # fmt: skip
        mine = {i + 1 for i, w in enumerate(wanted) if w[0] == k}
        targets = {int(r["target"]) for r in own if r["reached"] == "true"}
        assert mine <= targets, f"seed {seed}: pose {k} reached {targets}, made at {mine}"
        if per_row:
            assert {int(r["target"]) for r in own} == mine, f"seed {seed}"
        good = [r for r in own if r["reached"] == "true" and r["multistable"] == "false"]
        if not good:
            continue
        there = tmp_path / f"pose{k}.toml"
        for r in good:
            sim = tmp_path / "check.csv"
            check = run("simulate", str(there), "--theta1", r["theta1_deg"], "--theta2",
                        r["theta2_deg"], "--quiet", "--out", str(sim))  # fmt: skip
            assert check.exit_code == 0, f"seed {seed}: {check.output}"
            tip = read_csv(sim)[0]
            got = [float(tip["y_mm"]), float(tip["z_mm"])]
            aim = [float(r["target_y_mm"]), float(r["target_z_mm"])]
            np.testing.assert_allclose(got, aim, atol=1e-4, err_msg=f"seed {seed}, pose {k}")
            checked += 1
    assert checked, f"seed {seed}: no answer to check"


def test_a_path_with_the_magnet_held_at_a_moved_pose_is_the_design_files_path(
    tmp_path, run, read_csv
):
    """steer --path circle with --magnet-* and the design file of that pose: the same
    schedule (the demonstrator's magnet moved, drawn)."""
    from design.designfile import default_design

    seed = _seed()
    rng = np.random.default_rng(seed)
    d = default_design()
    pose, turn = _clear_pose(d, rng, seed)
    there = _there(d, pose, turn, tmp_path / "there.toml")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    path = ["--path", "circle:1.5", "--points", "12", "--quiet"]
    typed = run("steer", *path, *_options(pose, turn), "--out", str(a))
    alone = run("steer", str(there), *path, "--out", str(b))
    assert typed.exit_code == alone.exit_code == 0, f"seed {seed}: {typed.output}{alone.output}"
    keys = ("target_y_mm", "target_z_mm", "theta1_deg", "theta2_deg", "y_mm", "z_mm")
    np.testing.assert_allclose(
        _numbers(read_csv(a), keys), _numbers(read_csv(b), keys), atol=1e-9, err_msg=f"seed {seed}"
    )


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["workspace", "--magnet-y", "10,20"], ["workspace holds the magnet at one pose", "2"]),
        (["steer", "--path", "circle:2", "--magnet-turn", "0,5"], ["--path holds the magnet"]),
        (["steer", "--to", "3,0", "--magnet-x", "150"], ["moved to (150, 0, 0) mm"]),
        (["steer", "--targets", "{posed}", "--magnet-y", "3"], ["gives the magnet's pose"]),
        (["steer", "--targets", "{posed}", "--to", "1,1"], ["without --to"]),
        (["steer", "--targets", "{bad}"], ["line 3: magnet_turn_deg expects a number", "'ten'"]),
        (["steer", "--targets", "{inside}"], ["line 2:", "straight robot"]),
    ],
)
def test_bad_moved_magnet_input_to_workspace_and_steer_is_one_message(tmp_path, run, args, words):
    files = {
        "posed": "y_mm,z_mm,magnet_y_mm\n2,0,10\n",
        "bad": "y_mm,z_mm,magnet_turn_deg\n2,0,10\n2,1,ten\n",
        "inside": "y_mm,z_mm,magnet_x_mm\n2,0,100\n",
    }
    for name, text in files.items():
        (tmp_path / f"{name}.csv").write_text(text)
    out = tmp_path / "out"
    args = [a.format(**{n: tmp_path / f"{n}.csv" for n in files}) for a in args]
    result = run(*args, "--out", str(out if args[0] == "workspace" else out.with_suffix(".csv")))
    assert result.exit_code == 2, result.output
    for w in words:
        assert w in result.output, result.output
    assert "Traceback" not in result.output
    assert not out.exists() and not out.with_suffix(".csv").exists()
