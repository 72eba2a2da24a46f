"""docs/tutorial.md runs as written: its shell blocks, in order, in an empty folder, with
the ringpair of this checkout; then the files it promises are there and say what the
text says (the diagnosis names the planted cause)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
BLOCK = re.compile(r"^```bash\n(.*?)^```", re.M | re.S)


def tutorial_commands() -> list[str]:
    """The command lines of the tutorial's bash blocks, in order."""
    text = (DOCS / "tutorial.md").read_text(encoding="utf-8")
    return [ln for block in BLOCK.findall(text) for ln in block.splitlines() if ln.strip()]


def test_the_tutorial_has_a_command_for_every_step():
    commands = [c.split()[1] for c in tutorial_commands() if c.startswith("ringpair ")]
    for step in ("show", "simulate", "workspace", "steer", "cad", "synth", "diagnose"):
        assert step in commands, step


@pytest.mark.slow
def test_every_tutorial_command_runs_as_written(tmp_path):
    script = "set -euo pipefail\n" + "\n".join(tutorial_commands()) + "\n"
    bin_dir = str(Path(sys.executable).parent)  # this environment's ringpair
    env = {**os.environ, "PATH": bin_dir + os.pathsep + os.environ.get("PATH", "")}
    done = subprocess.run(
        ["bash", "-c", script],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert "Traceback" not in done.stderr
    out = tmp_path / "outputs" / "mine"
    sweep = [ln for ln in (out / "sweep.csv").read_text().splitlines() if ln[:1] != "#"]
    assert len(sweep) == 1 + 5  # header + theta1 = 0, 45, ..., 180
    summary = json.loads((out / "workspace" / "summary.json").read_text())
    assert summary["disc_radius_mm"] > 0
    assert "reached" in (out / "steer.csv").read_text()
    assert "part,quantity,printed,material" in (out / "cad" / "parts.csv").read_text()
    assert any((out / "cad" / "stl").glob("*.stl"))
    assert (out / "bench" / "measurements.csv").is_file()
    fit = json.loads((out / "fit.json").read_text())
    assert fit  # strict JSON, read back
    diagnosis = json.loads((out / "diagnosis.json").read_text())
    assert [c["name"] for c in diagnosis["causes"]] == ["torsion"]
    assert diagnosis["gain"]["cv_rmse_ratio"] < 0.5
    assert (out / "diagnosis" / "diagnosis.html").is_file()
