"""Calibration, diagnosis, the study and the design NLP model the [external_magnet]
alone: a design with [[field.sources]] is refused at once, in one message naming the file
and the sources, exit 2, nothing written (issue 50: 'refuse clearly' until they take
sources)."""

from __future__ import annotations

from pathlib import Path

import pytest
from studies import SMALL

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CSV = "theta1_deg,theta2_deg,x_mm,y_mm,z_mm\n0,0,150,1,1\n90,0,150,2,1\n"


def one_message(result, *words):
    text = " ".join(result.output.split())
    assert result.exit_code == 2, result.output
    assert result.output.count("rror:") == 1, result.output
    assert "Traceback" not in result.output
    for w in words:
        assert w in text, (w, text)


@pytest.mark.parametrize("command", ["calibrate", "diagnose"])
def test_fits_refuse_a_design_with_field_sources(run, tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.csv").write_text(CSV)
    design = EXAMPLES / "helmholtz_pair.toml"
    result = run(command, "m.csv", "--design", str(design))
    one_message(
        result, "helmholtz_pair.toml", "[[field.sources]] (coil, coil)", "[external_magnet]"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.csv"]


@pytest.mark.parametrize("command", ["study", "optimize"])
def test_the_study_and_the_nlp_refuse_a_base_design_with_field_sources(
    run, tmp_path, monkeypatch, command
):
    monkeypatch.chdir(tmp_path)
    base = (EXAMPLES / "mri_bore.toml").resolve()
    (tmp_path / "s.toml").write_text(f'base_design = "{base}"\n' + SMALL)
    result = run(command, "s.toml")
    one_message(result, "mri_bore.toml", "[[field.sources]] (uniform)", "[external_magnet]")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
