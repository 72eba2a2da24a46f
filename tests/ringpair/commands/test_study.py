"""``ringpair study``: a small study through every stage, the report, the manifest, reuse,
the hand-off (design file, Pareto CSVs, parts list, --process) and what the console says."""

from __future__ import annotations

import csv
import hashlib
import html
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from PIL import Image

from cad.build import PARTS_COLUMNS
from cad.checks import load_stl
from cad.process import FDM, RESIN
from design.designfile import design_to_dict, load_design
from design.made import made_design, made_value
from optimize.sizing.nlp import optimize_design, pareto_values
from optimize.sizing.studyfile import load_study
from ringpair import report_html
from ringpair.cli import cli
from ringpair.parts_report import model_title


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
        f"{doc['forward']['best_controllable_disc_radius_mm']:.2f} mm",
    ]
    for number in numbers:
        assert number in page, number
    # the disc (steerable from home without a snap) under its old name too (issue 49)
    f = doc["forward"]
    assert f["best_controllable_disc_radius_mm"] == f["best_disc_radius_mm"]
    # the study's NLP improves its own disc; this study designs with another model than the
    # forward check's, about whose home its optimum need not be better (issue 49)
    assert doc["best"]["disc_radius_mm"] > doc["start"]["disc_radius_mm"]
    assert f["best_droop_mm"] >= 0 and f["start_droop_mm"] >= 0
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


def _screenshot(browser: str, page: Path, shot: Path, size: str) -> np.ndarray:
    """Headless Chromium's screenshot of ``page`` in a window of ``size`` ('W,H'), RGB."""
    subprocess.run(
        [
            browser,
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--hide-scrollbars",
            # draw every figure before the shot: on a loaded machine a shot without these
            # once caught the page with a figure not yet painted (CI of eebbbee)
            "--run-all-compositor-stages-before-draw",
            "--virtual-time-budget=10000",
            f"--screenshot={shot}",
            f"--window-size={size}",
            page.resolve().as_uri(),
        ],
        check=True,
        capture_output=True,
        timeout=120,
    )
    return np.asarray(Image.open(shot).convert("RGB"))


def test_report_renders_and_prints_in_headless_chromium(study_run, tmp_path):
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
    # 4000 px: the first figures sit below the cards, limits and design tables (~2700 px)
    img = _screenshot(browser, out / "report.html", tmp_path / "report.png", "1200,4000")
    img = img.astype(float)
    assert img.shape[:2] == (4000, 1200)
    # Text and embedded figures drew: dark pixels and coloured (plot) pixels both present.
    assert (img.mean(axis=2) < 100).mean() > 0.002
    assert (np.ptp(img, axis=2) > 60).mean() > 0.002


def _numbers(doc: dict, prefix: str = "") -> dict[str, float]:
    """Every number of a design-file document, by its dotted key (vectors by index)."""
    out: dict[str, float] = {}
    for k, v in doc.items():
        if isinstance(v, dict):
            out |= _numbers(v, f"{prefix}{k}.")
        elif isinstance(v, list):
            out |= {f"{prefix}{k}.{i}": float(x) for i, x in enumerate(v)}
        elif isinstance(v, int | float) and not isinstance(v, bool):
            out[f"{prefix}{k}"] = float(v)
    return out


def _rows(path):
    """A CSV's rows, its # lines skipped, and those # lines."""
    lines = path.read_text().splitlines()
    notes = [ln for ln in lines if ln.startswith("#")]
    return list(csv.DictReader(ln for ln in lines if not ln.startswith("#"))), notes


def test_best_design_file_reads_back_as_the_rounded_optimum_and_simulates(study_run, tmp_path):
    path, out, first, _ = study_run
    assert first.exit_code == 0, first.output
    optimum = optimize_design(load_study(path)).design  # the same NLP, solved again here
    loaded = load_design(out / "best_design.toml")
    # the optimum rounded to what can be made (design.made), every mounting choice stated
    want = _numbers(design_to_dict(made_design(optimum), explicit=True))
    got = _numbers(design_to_dict(loaded, explicit=True))
    assert got.keys() == want.keys()
    assert got == pytest.approx(want, rel=1e-9, abs=1e-12)
    text = (out / "best_design.toml").read_text()
    assert "[tip.mounting]" in text and "wall_mm" in text and "stop_angle_deg" in text
    assert not re.search(r"_mm = \d+\.\d{6,}", text), text
    doc = json.loads((out / "results.json").read_text())
    assert "Sizes rounded to what can be made" in first.output
    assert doc["forward"]["unrounded_disc_radius_mm"] > 0
    csv_out = tmp_path / "pose.csv"
    args = ["simulate", str(out / "best_design.toml"), "--theta1", "0,90", "--theta2", "0"]
    simulated = CliRunner().invoke(cli, [*args, "--out", str(csv_out)])
    assert simulated.exit_code == 0, simulated.output
    rows, _ = _rows(csv_out)
    assert len(rows) == 2 and all(r["stable"] == "true" for r in rows)


def test_pareto_csv_says_its_units_and_holds_every_point(study_run):
    path, out, _, _ = study_run
    rows, notes = _rows(out / "pareto" / "pareto_external_distance.csv")
    assert any("external-magnet distance [mm]" in n for n in notes)
    assert any("disc radius [mm]" in n for n in notes)
    study = load_study(path)
    bounds_mm = pareto_values(study, study.pareto[0]) * 1e3
    assert [float(r["epsilon"]) for r in rows] == pytest.approx(bounds_mm)
    for r in rows:
        assert r["feasible"] == "True", r
        # a lower bound on the distance: every point keeps its magnet at least that far
        assert float(r["external_distance_mm"]) >= float(r["epsilon"]) - 1e-4
        assert 0 < float(r["objective"]) < 100  # a disc radius in mm, not in m
    radii = [float(r["objective"]) for r in rows]
    assert radii == sorted(radii, reverse=True)  # farther magnet, smaller disc


def test_parts_list_names_material_mass_size_and_file(study_run):
    _, out, _, _ = study_run
    rows, _ = _rows(out / "cad" / "parts.csv")
    assert tuple(rows[0]) == PARTS_COLUMNS
    printed = [r for r in rows if r["printed"] == "True"]
    # the tip pieces as the design (and the model) has them: resin; the rest --process fdm
    tip = {"mounting_piece_proximal", "mounting_piece_distal"}
    assert tip <= {r["part"] for r in printed}
    for r in printed:
        process = RESIN if r["part"] in tip else FDM
        assert r["material"] == f"{process.material}, {process.name} print", r["part"]
        mesh = load_stl(out / "cad" / r["file"])  # the file it names, read back
        assert mesh.volume == pytest.approx(float(r["volume_mm3"]), rel=0.01), r["part"]
        mass = float(r["volume_mm3"]) * 1e-9 * process.material_density_kg_m3 * 1e3
        assert float(r["mass_g"]) == pytest.approx(mass, rel=1e-3), r["part"]
        size = sorted(float(r[f"size_{a}_mm"]) for a in "xyz")
        assert size == pytest.approx(sorted(np.ptp(mesh.vertices, axis=0)), abs=0.05), r["part"]
    ring = next(r for r in rows if r["part"] == "ring_magnet")
    design = load_design(out / "best_design.toml")
    assert float(ring["mass_g"]) == pytest.approx(
        float(ring["volume_mm3"]) * 1e-9 * design.tip.density * 1e3, rel=1e-3
    )
    assert ring["file"] == "ringpair_robot.step" and (out / "cad" / ring["file"]).is_file()


def test_console_says_each_stage_duration_what_the_parts_are_for_and_the_result(study_run):
    _, out, first, second = study_run
    text = first.stdout
    for stage in ("optimisation", "Pareto sweeps", "tolerance Monte Carlo", "report"):
        assert re.search(rf"^{stage}.*: \d+\.\d s$", text, re.M), stage
    assert "CAD of the recommended design (best_design.toml), fdm print" in text
    # the demonstrator's tip pieces are resin (tip.mounting.process): the console says so
    assert "fdm print, tip pieces resin (the design's tip.mounting.process, as modelled)" in text
    handoff = next(ln for ln in text.splitlines() if ln.startswith("hand-off: "))
    for name in ("best_design.toml", "pareto_external_distance.csv", "parts.csv"):
        assert name in handoff, name
    doc = json.loads((out / "results.json").read_text())
    best, start = (doc["forward"][f"{k}_disc_radius_mm"] for k in ("best", "start"))
    last = text.strip().splitlines()[-1]
    assert last.startswith("Recommended design")
    assert f"disc radius {best:.2f} mm" in last and f"against {start:.2f} mm" in last
    assert f"{best - start:+.2f} mm" in last and str(out / "best_design.toml") in last
    assert re.search(r": reused \(it took \d+\.\d s\)$", second.stdout, re.M)
    for output in (first.output, second.output):  # not a terminal: plain text only
        assert "\x1b[" not in output and "X server" not in output


def test_process_resin_builds_resin_parts(study_run, tmp_path):
    _, out, _, _ = study_run
    copy = tmp_path / "out"
    shutil.copytree(out, copy)  # every stage but the CAD is reused
    args = ["study", str(study_run[0]), "--out", str(copy), "--samples", "20", "--seed", "3"]
    result = CliRunner().invoke(cli, [*args, "--process", "resin", "--no-render"])
    assert result.exit_code == 0, result.output
    assert "resin print: parts, checks" in result.stdout  # as modelled: no note
    rows, _ = _rows(copy / "cad" / "parts.csv")
    printed = [r for r in rows if r["printed"] == "True"]
    assert {r["material"] for r in printed} == {f"{RESIN.material}, resin print"}
    assert any((copy / "cad").glob("plate_resin_*.3mf"))
    manifest = json.loads((copy / "manifest.json").read_text())
    assert not manifest["stages"]["cad"]["reused"] and manifest["stages"]["optimise"]["reused"]


def test_unknown_process_is_exit_2_and_writes_nothing(tmp_path, pareto_study):
    path = tmp_path / "s.toml"
    path.write_text(pareto_study)
    result = CliRunner().invoke(
        cli, ["study", str(path), "--out", str(tmp_path / "o"), "--process", "sls"]
    )
    assert result.exit_code == 2
    assert "--process must be one of 'fdm', 'resin'; got 'sls'" in result.output
    assert len(result.output.strip().splitlines()) == 1 and not (tmp_path / "o").exists()


def test_on_a_terminal_each_stage_is_a_live_line_that_ends_in_its_duration(monkeypatch):
    import io

    from rich.console import Console

    from ringpair.commands import study as command

    screen, log = io.StringIO(), io.StringIO()
    monkeypatch.setattr(command, "err_console", Console(file=screen, force_terminal=True))
    monkeypatch.setattr(command, "console", Console(file=log, force_terminal=False))
    with command._stages() as stages:
        stages.start("Pareto sweeps on Dask")
        stages.count(2, 5)
        stages.end("Pareto sweeps on Dask", 12.34, reused=False)
        stages.start("optimisation")
        stages.end("optimisation", 3.0, reused=True)
    assert "Pareto sweeps on Dask" in screen.getvalue()  # the live line, on stderr
    assert log.getvalue().splitlines() == [
        "Pareto sweeps on Dask: 12.3 s",
        "optimisation: reused (it took 3.0 s)",
    ]


def _first_screen(browser: str, page, tmp_path, selectors: tuple[str, ...]) -> dict:
    """Where Chromium lays out each CSS selector's first element in a 1280 x 800 window:
    the page copied with a script that writes the boxes into the DOM, read back with
    --dump-dom. {selector: {"top", "bottom", "left", "right", "text"}} [CSS px]."""
    probe = """<script>
const boxes = {};
for (const s of SELECTORS) {
  const e = document.querySelector(s);
  if (e) { const r = e.getBoundingClientRect();
    boxes[s] = {top: r.top, bottom: r.bottom, left: r.left, right: r.right,
                text: e.innerText}; }
}
const out = document.createElement("pre"); out.id = "probe";
out.textContent = JSON.stringify(boxes); document.body.appendChild(out);
</script></body>""".replace("SELECTORS", json.dumps(list(selectors)))
    copy = tmp_path / "probe.html"
    copy.write_text(page.read_text().replace("</body>", probe))
    dom = subprocess.run(
        [
            browser,
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--hide-scrollbars",
            "--window-size=1280,800",
            "--dump-dom",
            copy.resolve().as_uri(),
        ],
        check=True,
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    found = re.search(r'<pre id="probe">(.*?)</pre>', dom, re.S)
    assert found, "the probe script did not run"
    return json.loads(html.unescape(found.group(1)))


def test_the_first_screen_carries_the_answer_in_headless_chromium(study_run, tmp_path):
    browser = report_html.browser()
    if browser is None:
        pytest.skip("Chromium is not installed (Debian package 'chromium'; .ci/run installs it)")
    _, out, _, _ = study_run
    doc = json.loads((out / "results.json").read_text())
    boxes = _first_screen(
        browser, out / "report.html", tmp_path, ("#headline", "#study", ".question", ".next")
    )
    # the headline is the disc (about home, steerable, the model for design work); this
    # study designs with another model, whose own disc has its card
    headline = boxes["#headline"]
    assert headline["text"].strip() == f"{doc['forward']['best_disc_radius_mm']:.2f} mm"
    assert boxes["#study"]["text"].strip() == f"{doc['best']['disc_radius_mm']:.2f} mm"
    for selector, box in boxes.items():  # on the first screen, without scrolling
        assert 0 <= box["top"] < box["bottom"] <= 800, (selector, box)
        assert 0 <= box["left"] < box["right"] <= 1280, (selector, box)
    # and Chromium drew it there: the headline's blue in the screenshot's headline box
    img = _screenshot(browser, out / "report.html", tmp_path / "first.png", "1280,800")
    img = img.astype(int)
    box = img[int(headline["top"]) : int(headline["bottom"]), int(headline["left"]) :]
    blue = np.abs(box - np.array([0x1F, 0x77, 0xB4])).sum(axis=2) < 60
    assert blue.sum() > 200, "the headline number is not drawn in its box"


def test_report_design_table_has_every_dimension_with_its_bounds(study_run):
    from design.registry import PARAMETERS, file_unit

    path, out, _, _ = study_run
    doc = json.loads((out / "results.json").read_text())
    study = load_study(path)
    rows = {r["key"]: r for r in doc["design"]}
    keyed = [n for n, p in PARAMETERS.items() if p.field is not None and p.key is not None]
    assert len(doc["design"]) == len(keyed) + 1  # and the magnet's distance to its centre
    best = load_design(out / "best_design.toml")
    for name in keyed:
        p = PARAMETERS[name]
        row = next(r for r in doc["design"] if r["quantity"] == p.meaning)
        unit, scale = file_unit(name)
        assert row["unit"] == unit
        assert row["start"] == pytest.approx(p.value(study.base) / scale)
        # the table's optimum is the optimiser's; the hand-off file holds it rounded
        assert made_value(name, row["optimum"] * scale) / scale == pytest.approx(
            p.value(best) / scale, abs=1e-9
        ), name
        b = study.bound(name)
        assert (row["low"], row["high"]) == (
            (pytest.approx(b.low / scale), pytest.approx(b.high / scale)) if b else (None, None)
        ), name
    distance = rows["external_distance_mm (study file)"]
    assert "centre" in distance["quantity"]
    centre = np.asarray(best.external_magnet.center) * 1e3
    # both rounded to 0.5 mm in the hand-off file
    assert distance["optimum"] == pytest.approx(centre[0] - best.robot.free_length * 1e3, abs=0.5)
    page = (out / "report.html").read_text()
    assert "external magnet distance, rest tip to the magnet&#x27;s centre" in page


def test_report_per_material_and_limits_come_from_the_solver(study_run):
    path, out, _, _ = study_run
    doc = json.loads((out / "results.json").read_text())
    study = load_study(path)
    chosen = [m["objective"] for m in doc["per_material"] if m["accepted"]]
    assert max(chosen) == pytest.approx(doc["best"]["disc_radius_mm"], rel=1e-9)
    assert sum(m["starts"] for m in doc["per_material"]) == study.starts * len(
        study.catheter_materials or [None]
    ) * len(study.wire_materials or [None])
    active = {k for k, v in doc["constraints"].items() if v["active"]}
    covered = {g for r in doc["limits"] for g in r["groups"]}
    assert active | {a for a in doc["active"] if a.startswith("bound.")} <= covered
    gains = [r["gain"] for r in doc["limits"] if r["gain"] is not None and np.isfinite(r["gain"])]
    assert gains == sorted(gains, reverse=True)
    # a relaxed limit never makes the re-solved optimum worse (IPOPT from the optimum)
    assert all(g > -1e-6 * doc["best"]["disc_radius_mm"] for g in gains)
    page = (out / "report.html").read_text()
    # each row says in words what it limits; one the stage could not move says why
    for r in doc["limits"]:
        assert r["meaning"].startswith("the ") and r["limit"] not in r["meaning"], r
        if r["old"] is None:
            assert r["reason"].startswith("not moved: ") and r["reason"] in page, r
    if gains and gains[0] > 0:
        top = doc["limits"][0]
        assert f"would add <b>{top['gain']:.2f} mm</b>" in page and top["meaning"] in page


def test_report_fronts_say_whether_their_bound_binds_as_the_csv_shows(study_run):
    path, out, _, _ = study_run
    doc = json.loads((out / "results.json").read_text())
    rows, _ = _rows(out / "pareto" / "pareto_external_distance.csv")
    optimum = doc["best"]["disc_radius_mm"]
    binds = [
        "epsilon.external_distance" in r["active"] and float(r["objective"]) < optimum * 0.999
        for r in rows
    ]
    sentence = doc["pareto"]["external_distance"]
    assert ("It binds" in sentence) == any(binds)
    assert ("does not bind" in sentence) == (not any(binds))
    if any(binds):
        lowest = min(float(r["objective"]) for r, b in zip(rows, binds, strict=True) if b)
        assert f"disc radius is {lowest:.2f} mm" in sentence
    assert sentence in (out / "report.html").read_text().replace("&#x27;", "'")


def test_report_names_the_model_of_each_number_and_collapses_passing_checks(study_run):
    from design.model import DEFAULT_EFFECTS, RingPairModel

    path, out, _, _ = study_run
    page = (out / "report.html").read_text()
    study_model = model_title(load_study(path).effects)
    work_model = model_title(RingPairModel(DEFAULT_EFFECTS).effects)
    assert "+" not in work_model and "printed tip" in work_model  # words, not a log
    assert f"Model of the study: <b>{html.escape(study_model)}</b>" in page
    assert f"Workspaces ({html.escape(work_model)} model)" in page
    assert f"Pareto fronts ({html.escape(study_model)} model)" in page
    checks = json.loads((out / "results.json").read_text())["cad"]["checks"]
    shown = re.search(r"(\d+) checks: (\d+) failed; (\d+) shown below", page)
    hidden = re.search(r"<summary>the other (\d+) checks, all passed</summary>", page)
    assert shown and hidden
    assert int(shown[1]) == checks and int(shown[3]) + int(hidden[1]) == checks
    collapsed = page.split("<summary>the other", 1)[1].split("</details>")[0]
    assert "FAIL" not in collapsed  # failures are never collapsed
    assert collapsed.count("<td>pass</td>") == int(hidden[1])
