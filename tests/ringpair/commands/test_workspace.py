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
    assert summary["disc_radius_mm"] == pytest.approx(summary["max_deflection_mm"], rel=1e-4)
    assert len(read_csv(tmp_path / "ws" / "workspace.csv")) == 24 * 24
    for name in ("top", "side", "section", "deflection"):
        img = np.asarray(Image.open(tmp_path / "ws" / f"{name}.png").convert("L"))
        assert img.shape[0] > 200 and (img < 128).mean() > 0.005, name  # drawn, not blank
