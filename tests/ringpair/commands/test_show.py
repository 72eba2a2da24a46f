"""``ringpair show``."""

from __future__ import annotations


def test_writing_a_design_and_reading_it_back(tmp_path, run):
    path = tmp_path / "mine.toml"
    assert run("show", "--save", str(path)).exit_code == 0
    result = run("show", str(path))
    assert result.exit_code == 0 and "demonstrator" in result.output
