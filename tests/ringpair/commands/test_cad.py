"""``ringpair cad``: parts written and checked."""

from __future__ import annotations

import csv
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def test_cad_writes_checked_parts(tmp_path, run):
    out = tmp_path / "cad"
    result = run("cad", "--out", str(out), "--no-render")
    assert result.exit_code == 0, result.output
    assert "128/128 passed" in result.output or "passed" in result.output
    assert (out / "ringpair_robot.step").stat().st_size > 10_000
    assert any((out / "stl").glob("*.stl"))


def test_cad_builds_a_robot_in_a_field_map_and_lists_the_map(tmp_path, run):
    """A design with no [external_magnet] (here a field map) crashed the bill of materials
    before; its source is listed, with nothing to buy."""
    result = run("cad", str(EXAMPLES / "field_map.toml"), "--out", str(tmp_path), "--no-render")
    assert result.exit_code == 0, result.output
    with open(tmp_path / "bom.csv", newline="", encoding="utf-8") as f:
        rows = {r["item"]: r for r in csv.DictReader(f)}
    assert "external_magnet" not in rows
    assert rows["source_1"]["kind"] == "provided"
    assert "demonstrator_map.csv" in rows["source_1"]["specification"]
