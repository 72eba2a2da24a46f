"""The command line: outputs of simulate and workspace, and bad input (exit 2, one message
naming the key, no traceback, nothing written)."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
import pytest
import tomli_w
from bad_designs import BAD_VALUES, edited
from click.testing import CliRunner
from PIL import Image

from design.equilibrium import solve_design
from design.model import DEFAULT_EFFECTS, RingPairModel
from ringpair.cli import cli


def run(*args: str):
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


def read_csv(path):
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def test_simulate_writes_the_paper_sweep(tmp_path, demonstrator):
    out = tmp_path / "sim.csv"
    result = run("simulate", "--theta1", "0:180:12", "--theta2", "0", "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    assert [float(r["theta1_deg"]) for r in rows] == list(range(0, 181, 12))  # 16 like the paper
    # The default model for design work (DEFAULT_EFFECTS), configuration by configuration.
    model = RingPairModel(DEFAULT_EFFECTS)
    eq = solve_design(demonstrator, np.deg2rad(np.arange(0, 181, 12)), 0.0, model)
    np.testing.assert_allclose([float(r["y_mm"]) for r in rows], eq.position[:, 1] * 1e3, rtol=1e-8)
    assert all(r["converged"] == "true" and r["stable"] == "true" for r in rows)
    assert "180.00" in result.output and "stable" in result.output


def test_simulate_takes_every_pair_of_two_lists(tmp_path):
    out = tmp_path / "s.csv"
    assert (
        run(
            "simulate", "--theta1", "0,90", "--theta2", "0:20:10", "--out", str(out), "--quiet"
        ).exit_code
        == 0
    )
    rows = read_csv(out)
    assert [(float(r["theta1_deg"]), float(r["theta2_deg"])) for r in rows] == [
        (0, 0),
        (0, 10),
        (0, 20),
        (90, 0),
        (90, 10),
        (90, 20),
    ]


def test_workspace_writes_csv_summary_and_pictures(tmp_path):
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


def test_writing_a_design_and_reading_it_back(tmp_path):
    path = tmp_path / "mine.toml"
    assert run("show", "--save", str(path)).exit_code == 0
    result = run("show", str(path))
    assert result.exit_code == 0 and "demonstrator" in result.output


@pytest.mark.parametrize(
    ("key", "value", "words"), BAD_VALUES, ids=[f"{k}={v!r}"[:60] for k, v, _ in BAD_VALUES]
)
def test_bad_design_exits_2_with_one_message(tmp_path, demonstrator_doc, key, value, words):
    path = tmp_path / "bad.toml"
    path.write_text(tomli_w.dumps(edited(demonstrator_doc, key, value)))
    out = tmp_path / "out.csv"
    result = CliRunner().invoke(cli, ["simulate", str(path), "--out", str(out)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    for w in words:
        assert w in result.output
    assert not out.exists()


@pytest.mark.parametrize(
    ("option", "value"),
    [("--theta1", "0:abc:5"), ("--theta2", "5:0:1"), ("--theta1", "0:10:0"), ("--theta1", "")],
)
def test_bad_angles_exit_2_naming_the_option(option, value):
    result = CliRunner().invoke(cli, ["simulate", option, value])
    assert result.exit_code == 2 and option in result.output
    assert "Traceback" not in result.output


def test_console_script_reports_missing_file_without_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "ringpair.cli", "simulate", str(tmp_path / "none.toml")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert "does not exist" in proc.stderr and "Traceback" not in proc.stderr


def test_help_documents_every_command():
    result = run("--help")
    for command in ("simulate", "workspace", "show"):
        assert command in result.output
        sub = run(command, "--help")
        assert sub.exit_code == 0 and "DESIGN" in sub.output


def test_bracketed_section_names_survive_the_terminal(tmp_path, demonstrator_doc):
    del demonstrator_doc["robot"]["wire"]
    path = tmp_path / "bad.toml"
    path.write_text(tomli_w.dumps(demonstrator_doc))
    result = CliRunner().invoke(cli, ["show", str(path)])
    assert result.exit_code == 2 and "missing section [robot.wire]" in result.output


def test_simulate_with_effects_and_an_ordered_path(tmp_path):
    out = tmp_path / "g.csv"
    result = run(
        "simulate",
        "--effects",
        "gravity,hysteresis",
        "--ordered",
        "--theta1",
        "0:60:30",
        "--out",
        str(out),
        "--quiet",
    )
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    assert [r["snapped"] for r in rows] == ["false"] * 3
    assert float(rows[1]["theta1_tip_deg"]) == pytest.approx(30.0)  # no play in the demonstrator


def test_unknown_effect_exits_2_naming_the_option():
    result = CliRunner().invoke(cli, ["simulate", "--effects", "torsion,twist"])
    assert result.exit_code == 2 and "--effects" in result.output and "'twist'" in result.output


def test_effects_table_compares_every_available_effect(tmp_path):
    out = tmp_path / "effects.csv"
    result = run("effects", "--theta1", "0:24:12", "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = {r["effect"]: r for r in read_csv(out)}
    assert set(rows) == {
        "near_field",
        "large_deflection",
        "torsion",
        "gravity",
        "hysteresis",
        "all",
    }
    assert float(rows["hysteresis"]["max_shift_mm"]) == 0.0  # the demonstrator has no play
    assert float(rows["gravity"]["max_shift_mm"]) > 5.0  # it droops by millimetres
    assert 0.5 < float(rows["near_field"]["max_shift_mm"]) < 5.0


def test_diagnose_writes_the_spec_json_and_report(tmp_path):
    data = tmp_path / "bench"
    synth = run(
        "synth", "--effects", "gravity", "--noise-mm", "0.2", "--seed", "4", "--out", str(data)
    )
    assert synth.exit_code == 0, synth.output
    out = tmp_path / "d.json"
    result = run("diagnose", str(data), "--json", str(out), "--report", str(tmp_path / "r"))
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    assert set(doc) >= {"baseline", "causes", "final", "gain"}
    assert [c["name"] for c in doc["causes"]] == ["gravity"]
    for block in ("baseline", "final"):
        assert set(doc[block]) >= {"rmse_mm", "max_abs_mm", "cv_rmse_mm", "params"}
    assert doc["gain"]["cv_rmse_ratio"] < 0.5
    lower, upper = doc["causes"][0]["interval"]["tip_mass_g"]
    assert lower <= doc["causes"][0]["params"]["tip_mass_g"] <= upper
    assert doc["final"]["interval"]["tip_mass_g"] == [lower, upper]
    assert "gravity" in result.output
    page = (tmp_path / "r" / "diagnosis.html").read_text()
    assert page.count("data:image/png;base64,") == 2 and "gravity" in page
    assert "profile interval" in page and f"{lower:.4g} to {upper:.4g}" in page
    img = np.asarray(Image.open(tmp_path / "r" / "residuals.png").convert("L"))
    assert (img < 128).mean() > 0.005


def test_diagnose_bad_folds_is_a_clear_error(tmp_path):
    data = tmp_path / "bench"
    assert run("synth", "--n", "20", "--out", str(data)).exit_code == 0
    result = CliRunner().invoke(cli, ["diagnose", str(data), "--folds", "1"])
    assert result.exit_code == 2 and "--folds" in result.output


def test_cad_writes_checked_parts(tmp_path):
    out = tmp_path / "cad"
    result = run("cad", "--out", str(out), "--no-render")
    assert result.exit_code == 0, result.output
    assert "128/128 passed" in result.output or "passed" in result.output
    assert (out / "ringpair_robot.step").stat().st_size > 10_000
    assert any((out / "stl").glob("*.stl"))


def test_branch_draws_the_diagram_and_names_the_snap(tmp_path):
    out = tmp_path / "branch.png"
    result = run(
        "branch", "--effects", "near_field,torsion", "--theta1", "30", "--theta2", "30",
        "--points", "81", "--out", str(out),
    )
    assert result.exit_code == 0, result.output
    # The demonstrator's touching rings (kappa = 1.9) snap apart part way up the ramp.
    snap = float(result.output.split("snaps at load factor")[1].split()[0])
    assert 0.6 < snap < 0.9
    with Image.open(out) as image:
        assert image.format == "PNG" and image.size[0] > 1000


def test_branch_refuses_a_list_of_angles(tmp_path):
    out = tmp_path / "b.png"
    result = CliRunner().invoke(cli, ["branch", "--theta1", "0,10", "--out", str(out)])
    assert result.exit_code == 2
    assert "--theta1 takes one angle" in result.output and not out.exists()
