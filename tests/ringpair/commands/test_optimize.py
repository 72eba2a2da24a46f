"""``ringpair optimize``: files written and valid, resumed Pareto points, bad study files."""

from __future__ import annotations

import csv
import json
import re

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from design.designfile import load_design
from design.workspace import sweep_workspace
from ringpair.cli import cli


def test_optimize_writes_the_best_design_fronts_plots_and_summary(tmp_path, pareto_study):
    path = tmp_path / "study.toml"
    path.write_text(pareto_study)
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["optimize", str(path), "--out", str(out)])
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["feasible"] and summary["pareto"]["monotone"]["external_distance"]
    # The saved design, simulated forward, has the disc radius the summary reports.
    best = load_design(out / "best_design.toml")
    radius = sweep_workspace(best).disc_radius * 1e3
    assert radius == pytest.approx(summary["forward"]["best_disc_radius_mm"], rel=1e-9)
    assert abs(radius - summary["objective"] * 1e3) < 1e-2 * radius
    assert radius > summary["forward"]["start_disc_radius_mm"]
    lines = (out / "pareto_external_distance.csv").read_text().splitlines()
    assert lines[0].startswith("# Pareto sweep")  # what the columns mean, in # lines
    rows = list(csv.DictReader(ln for ln in lines if not ln.startswith("#")))
    assert len(rows) == 3 and all(r["feasible"] == "True" for r in rows)
    assert float(rows[-1]["external_distance_mm"]) == pytest.approx(float(rows[-1]["epsilon"]))
    objective = [float(r["objective"]) for r in rows]
    assert objective == sorted(objective, reverse=True)  # farther magnet, smaller disc
    for name in ("pareto.png", "workspace.png"):
        img = np.asarray(Image.open(out / name).convert("L"))
        assert img.shape[0] > 200 and (img < 128).mean() > 0.005, name
    again = CliRunner().invoke(cli, ["optimize", str(path), "--out", str(out)])
    assert again.exit_code == 0 and "0 points solved, 3 resumed" in again.output


def test_bad_study_file_is_one_message_and_exit_2(tmp_path, pareto_study):
    path = tmp_path / "study.toml"
    bad = pareto_study.replace("magnet_gap_mm = [0.0, 1.0]", "magnet_gap_mm = [1.0, 0.0]")
    path.write_text(bad)
    result = CliRunner().invoke(cli, ["optimize", str(path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2 and "magnet_gap_mm" in result.output
    assert "Traceback" not in result.output and not (tmp_path / "o").exists()


def test_optimize_with_the_controllable_objective_says_the_steerable_disc(tmp_path):
    """objective = "controllable_disc_radius" (issue 18): the console gives the disc the
    robot can be steered over from rest without a snap, start and best, in mm, and the
    best is the summary's objective."""
    from studies import SMALL

    path = tmp_path / "s.toml"
    path.write_text(
        SMALL.replace('objective = "disc_radius"', 'objective = "controllable_disc_radius"')
    )
    result = CliRunner().invoke(cli, ["optimize", str(path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    # the demonstrator (the start) twists its wire far past the 20-degree limit: said
    assert "the starting design breaks the study's limits: twist.wire" in text, text
    pattern = r"steerable from rest without a snap.*?start ([\d.]+) mm, best ([\d.]+) mm"
    match = re.search(pattern, text)
    assert match, text
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    best = float(match.group(2))
    assert best == pytest.approx(summary["objective"] * 1e3, abs=0.006)  # SI in the summary
