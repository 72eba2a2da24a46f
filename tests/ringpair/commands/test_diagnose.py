"""``ringpair diagnose``: the spec JSON, the report, bad options."""

from __future__ import annotations

import html
import json

import numpy as np
from click.testing import CliRunner
from PIL import Image

from ringpair.cli import cli


def test_diagnose_writes_the_spec_json_and_report(tmp_path, run):
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
    # every model tried, with its verdict, in the JSON, the table and the page
    tried = doc["candidates"]
    assert tried["gravity"]["verdict"].startswith("accepted: BIC")
    assert all(c["verdict"] for c in tried.values())
    assert {"rmse_mm", "cv_rmse_mm", "bic", "params", "uncertainty"} <= set(tried["gravity"])
    assert set(tried["gravity"]["uncertainty"]) == set(tried["gravity"]["params"])
    assert "every model tried" in result.output
    assert set(doc["power"]) <= {"torsion", "hysteresis", "near_field", "large_deflection"}
    page = (tmp_path / "r" / "diagnosis.html").read_text()
    assert page.count("data:image/png;base64,") == 2 and "gravity" in page
    assert "Every model tried" in page and html.escape(tried["gravity"]["verdict"]) in page
    assert "profile interval" in page and f"{lower:.4g} to {upper:.4g}" in page
    img = np.asarray(Image.open(tmp_path / "r" / "residuals.png").convert("L"))
    assert (img < 128).mean() > 0.005


def test_diagnose_bad_folds_is_a_clear_error(tmp_path, run):
    data = tmp_path / "bench"
    assert run("synth", "--n", "20", "--out", str(data)).exit_code == 0
    result = CliRunner().invoke(cli, ["diagnose", str(data), "--folds", "1"])
    assert result.exit_code == 2 and "--folds" in result.output


def test_diagnose_bad_worker_count_is_a_clear_error(tmp_path, run, monkeypatch):
    data = tmp_path / "bench"
    assert run("synth", "--n", "20", "--out", str(data)).exit_code == 0
    result = CliRunner().invoke(cli, ["diagnose", str(data), "--workers", "0"])
    assert result.exit_code == 2 and "--workers" in result.output
    monkeypatch.setenv("RINGPAIR_WORKERS", "all")
    result = CliRunner().invoke(cli, ["diagnose", str(data)])
    assert result.exit_code != 0 and isinstance(result.exception, SystemExit), result.output
    assert "RINGPAIR_WORKERS must be a whole number" in result.output
    assert "Traceback" not in result.output
