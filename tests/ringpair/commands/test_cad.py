"""``ringpair cad``: parts written and checked."""

from __future__ import annotations


def test_cad_writes_checked_parts(tmp_path, run):
    out = tmp_path / "cad"
    result = run("cad", "--out", str(out), "--no-render")
    assert result.exit_code == 0, result.output
    assert "128/128 passed" in result.output or "passed" in result.output
    assert (out / "ringpair_robot.step").stat().st_size > 10_000
    assert any((out / "stl").glob("*.stl"))
