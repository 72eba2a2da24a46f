"""``ringpair study``: a small study through every stage, the report, the manifest, reuse."""

from __future__ import annotations

import hashlib
import json
import re

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from PIL import Image

from ringpair import report_html
from ringpair.cli import cli


@pytest.fixture(scope="module")
def study_run(tmp_path_factory, pareto_study):
    tmp = tmp_path_factory.mktemp("study")
    path = tmp / "small.toml"
    path.write_text(pareto_study)
    out = tmp / "out"
    args = ["study", str(path), "--out", str(out), "--samples", "20", "--seed", "3"]
    first = CliRunner().invoke(cli, args)
    second = CliRunner().invoke(cli, args)
    return path, out, first, second


def test_every_stage_runs_and_the_report_shows_the_json_numbers(study_run):
    _, out, first, _ = study_run
    assert first.exit_code == 0, first.output
    page = (out / "report.html").read_text()
    doc = json.loads((out / "results.json").read_text())
    for section in ("setup", "designs", "pareto", "tolerance", "parts", "effects", "diagnosis"):
        assert f'id="{section}"' in page, section
    numbers = [
        f"{doc['forward']['best_disc_radius_mm']:.3f}",
        f"{doc['forward']['start_disc_radius_mm']:.3f}",
        f"{doc['best']['disc_radius_mm']:.3f}",
        f"{doc['tolerance']['disc_radius_mean_mm']:.3f}",
        f"{doc['tolerance']['disc_radius_std_mm']:.3f}",
    ]
    for number in numbers:
        assert number in page, number
    assert doc["forward"]["best_disc_radius_mm"] > doc["forward"]["start_disc_radius_mm"]
    assert doc["tolerance"]["samples"] == 20 and doc["tolerance"]["disc_radius_std_mm"] > 0
    assert {r["effect"] for r in doc["effects"]} >= {"torsion", "near_field", "all"}
    images = re.findall(r'src="data:image/png;base64,', page)
    assert len(images) >= 7  # workspaces, Pareto, tolerance, renders: self-contained


def test_manifest_lists_every_file_and_each_is_valid(study_run):
    path, out, _, _ = study_run
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["inputs"]["study"]["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    assert manifest["seeds"]["tolerance"] == 3
    assert set(manifest["versions"]) >= {"python", "numpy", "casadi", "ringpair_commit"}
    assert set(manifest["stages"]) >= {"baseline", "optimise", "pareto", "forward", "cad"}
    listed = {f["path"]: f for f in manifest["files"]}
    assert {"report.html", "results.json"} <= set(listed)
    for rel, entry in listed.items():
        data = (out / rel).read_bytes()
        assert len(data) == entry["bytes"] and hashlib.sha256(data).hexdigest() == entry["sha256"]
        if rel.endswith(".png"):
            img = np.asarray(Image.open(out / rel).convert("L"))
            assert img.std() > 5, rel  # drawn, not blank
        elif rel.endswith(".stl"):
            mesh = trimesh.load(out / rel)
            assert mesh.is_watertight and mesh.volume > 0, rel
        elif rel.endswith(".step"):
            assert data.startswith(b"ISO-10303-21"), rel
        elif rel.endswith(".pdf"):
            assert data.startswith(b"%PDF") and data.rstrip().endswith(b"%%EOF"), rel
    assert any(r.endswith(".step") for r in listed) and any(r.endswith(".stl") for r in listed)


def test_rerun_reuses_every_stage(study_run):
    _, out, _, second = study_run
    assert second.exit_code == 0, second.output
    manifest = json.loads((out / "manifest.json").read_text())
    assert all(stage["reused"] for stage in manifest["stages"].values())


def test_bad_study_is_exit_2_and_writes_nothing(tmp_path, pareto_study):
    path = tmp_path / "bad.toml"
    path.write_text(pareto_study.replace("[free]", "[freee]"))
    result = CliRunner().invoke(cli, ["study", str(path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2 and "freee" in result.output
    assert not (tmp_path / "o").exists()


def test_report_renders_and_prints_in_headless_chromium(study_run, tmp_path):
    import subprocess

    browser = report_html.browser()
    if browser is None:
        pytest.skip("Chromium is not installed (Debian package 'chromium'; .ci/run installs it)")
    _, out, _, _ = study_run
    # The printed report: every page's images came along (the figures are ~100 kB each).
    pdf = (out / "report.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and len(pdf) > 200_000
    assert len(re.findall(rb"/Type\s*/Page\b", pdf)) >= 3
    manifest = json.loads((out / "manifest.json").read_text())
    assert "report.pdf" in {f["path"] for f in manifest["files"]}
    shot = tmp_path / "report.png"
    subprocess.run(
        [
            browser,
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--hide-scrollbars",
            f"--screenshot={shot}",
            "--window-size=1200,2600",
            (out / "report.html").resolve().as_uri(),
        ],
        check=True,
        capture_output=True,
        timeout=120,
    )
    img = np.asarray(Image.open(shot).convert("RGB")).astype(float)
    assert img.shape[:2] == (2600, 1200)
    # Text and embedded figures drew: dark pixels and coloured (plot) pixels both present.
    assert (img.mean(axis=2) < 100).mean() > 0.002
    assert (np.ptp(img, axis=2) > 60).mean() > 0.002
