"""``ringpair workspace``: CSV, summary and pictures."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image


def test_workspace_writes_csv_summary_and_pictures(tmp_path, run, read_csv):
    result = run("workspace", "--out", str(tmp_path / "ws"), "--step", "15", "--effects", "none")
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "ws" / "summary.json").read_text())
    assert 15 < summary["max_deflection_mm"] < 30
    assert f"{summary['max_deflection_mm']:.2f} mm" in result.output
    # the loop is a circle about the straight tip; the disc about home is its radius less
    # the home's offset in y-z (issue 49), the old measure kept under its own name
    r = summary["max_deflection_mm"]
    assert summary["straight_disc_radius_mm"] == pytest.approx(r, rel=1e-6)
    home = np.array(summary["home_mm"])
    offset = np.hypot(*home[1:])
    assert summary["home_stable"] and 0 < offset <= summary["droop_mm"] < 0.05 * r
    assert summary["disc_radius_mm"] == pytest.approx(r - offset, rel=1e-6)
    assert len(read_csv(tmp_path / "ws" / "workspace.csv")) == 24 * 24
    # The demonstrator's baseline never snaps: all of it is steerable from home, the cells'
    # covered disc is the disc less the 15-deg grid's chord (R (1 - cos 7.5 deg)), and the
    # disc is the workspace's; the old key says the same, with a warning.
    assert summary["controllable_fraction"] == 1.0
    assert summary["disc_radius_mm"] == summary["workspace_disc_radius_mm"]
    chord = r * (1 - np.cos(np.deg2rad(7.5)))
    assert summary["covered_disc_radius_mm"] == pytest.approx(
        summary["disc_radius_mm"] - chord, abs=0.15
    )
    assert summary["controllable_disc_radius_mm"] == summary["disc_radius_mm"]
    assert any("controllable_disc_radius_mm is deprecated" in w for w in summary["warnings"])
    assert "the disc about home" in " ".join(result.output.split())
    for name in ("top", "side", "section", "deflection", "controllable"):
        img = np.asarray(Image.open(tmp_path / "ws" / f"{name}.png").convert("L"))
        assert img.shape[0] > 200 and (img < 128).mean() > 0.005, name  # drawn, not blank
