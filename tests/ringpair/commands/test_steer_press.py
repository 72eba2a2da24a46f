"""``ringpair steer --press``: the ring angles that press the tip on a wall with a force,
their CSV (simulate's columns) and the force map with them marked; bad input is one
message, exit 2, nothing written."""

from __future__ import annotations

import numpy as np
import pytest
import tomli_w

WALL = {"kind": "plane", "point_mm": [150.0, 10.0, 0.0], "normal": [0.0, -1.0, 0.0]}


@pytest.fixture()
def walled(tmp_path, demonstrator_doc):
    demonstrator_doc.setdefault("environment", {})["obstacles"] = [WALL]
    path = tmp_path / "wall.toml"
    path.write_bytes(tomli_w.dumps(demonstrator_doc).encode())
    return path


def test_press_writes_angles_that_press_with_the_force(tmp_path, run, read_csv, walled):
    out = tmp_path / "p.csv"
    args = ["steer", str(walled), "--press", "4", "--step", "30", "--effects", "none"]
    result = run(*args, "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    assert len(rows) >= 4 and all(r["in_contact"] == "true" for r in rows)
    force = np.array([[float(r[f"contact_force_{a}_mN"]) for a in "xyz"] for r in rows])
    np.testing.assert_allclose(np.linalg.norm(force, axis=1), 4.0, atol=1e-4)
    np.testing.assert_allclose(force[:, 1], 4.0, atol=1e-4)  # along the wall's normal, -(-y)
    assert out.with_suffix(".png").stat().st_size > 1000
    assert f"{len(rows)} ring-angle pair(s) press with 4 mN" in " ".join(result.output.split())


def test_press_beyond_reach_says_the_range(tmp_path, run, walled):
    out = tmp_path / "p.csv"
    result = run(
        "steer",
        str(walled),
        "--press",
        "500",
        "--step",
        "45",
        "--effects",
        "none",
        "--out",
        str(out),
    )
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "no ring angles press with 500 mN" in text and "to 7.78 mN" in text


@pytest.mark.parametrize(
    "extra, said",
    [
        (["--press", "0"], "--press"),
        (["--press", "4", "--to", "1,2"], "without --to"),
        (["--step", "30", "--to", "1,2"], "--step is the grid of --press"),
        (["--press", "4", "--out", "p.png"], "ending in .csv"),
    ],
)
def test_press_bad_options_are_one_message(tmp_path, run, walled, extra, said):
    result = run("steer", str(walled), "--effects", "none", *extra)
    assert result.exit_code == 2 and said in " ".join(result.output.split()), result.output
    assert not (tmp_path / "p.png").exists()


def test_press_without_obstacles_is_one_message(tmp_path, run):
    out = tmp_path / "p.csv"
    result = run("steer", "--press", "4", "--out", str(out))
    assert result.exit_code == 2 and "environment.obstacles" in result.output
    assert not out.exists()
