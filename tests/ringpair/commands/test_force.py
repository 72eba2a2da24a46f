"""``ringpair force``: the force map over the ring grid, its summary and picture."""

from __future__ import annotations

import json

import numpy as np
import tomli_w

WALL = {"kind": "plane", "point_mm": [150.0, 10.0, 0.0], "normal": [0.0, -1.0, 0.0]}


def test_force_maps_the_push_on_a_wall(tmp_path, run, read_csv, demonstrator_doc):
    """The summary is the CSV's: the configurations that press, the largest force and
    where; the wall's normal is -y, so the tip pushes along +y only."""
    demonstrator_doc.setdefault("environment", {})["obstacles"] = [WALL]
    path = tmp_path / "wall.toml"
    path.write_bytes(tomli_w.dumps(demonstrator_doc).encode())
    out = tmp_path / "map"
    result = run("force", str(path), "--step", "45", "--effects", "none", "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = read_csv(out / "force.csv")
    summary = json.loads((out / "summary.json").read_text())
    assert len(rows) == summary["configurations"] == 64
    pressing = [r for r in rows if r["in_contact"] == "true"]
    assert len(pressing) == summary["pressing"] > 0
    y = np.array([float(r["contact_force_y_mN"]) for r in pressing])
    # (the CSV's 9 significant digits)
    assert np.isclose(summary["force_max_mN"], y.max(), rtol=1e-8)
    assert np.isclose(summary["force_min_mN"], y.min(), rtol=1e-8)
    best = pressing[int(np.argmax(y))]
    assert summary["largest_at_deg"] == [float(best["theta1_deg"]), float(best["theta2_deg"])]
    assert summary["largest_direction"] == [0.0, 1.0, 0.0]
    assert (out / "force.png").stat().st_size > 1000


def test_force_without_obstacles_is_one_message(tmp_path, run):
    out = tmp_path / "map"
    result = run("force", "--out", str(out))
    assert result.exit_code == 2 and "environment.obstacles" in result.output
    assert not out.exists()
