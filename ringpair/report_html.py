"""The study report: one self-contained HTML page (images embedded) and ``results.json``
with every number the page shows. Millimetres, degrees and mm^3 on the page.

The first screen answers the study: the question (objective, set-up, what was free within
which bounds, the limits, the model), the answer (the recommended design, its disc radius
under the study's model and re-simulated with the model for design work, the gain over the
start), what limits it (the active constraints and bounds, in words, with their multipliers)
and the next decision (the limit whose move gains most, from the pipeline's sensitivity
stage). The sections below it hold the full design table, the results per material, the
constraints, the figures (each naming its model), the Pareto fronts with a sentence each,
the tolerance spread, the parts list with masses and renders, and the CAD checks (only the
failed or tight ones expanded)."""

from __future__ import annotations

import html
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

from design.atomic import atomic_path, write_text
from design.made import made_design
from design.registry import PARAMETERS, file_key, file_unit
from design.strict_json import dumps_strict
from design.units import DEG, MM
from ringpair.html_page import details, img, table, thumb
from ringpair.parts_report import bom_section, tip_card
from ringpair.pipeline import (
    BEST_DESIGN,
    RELAX,
    TOLERANCES,
    Run,
)
from ringpair.plots import (
    plot_fronts,
    plot_tip_views,
    plot_tolerance,
    plot_workspaces,
)
from ringpair.report_notes import PDF_MARK, pdf_note, tolerance_words
from ringpair.report_results import number_text, results
from ringpair.tables import (
    TIGHT,
    check_rows,
    check_value_text,
    page_number,
)

OBJECTIVE_WORDS = {
    "disc_radius": "the largest disc of tip positions about the robot's home (rings "
    "antiparallel) that it can be steered over without a snap (the disc)",
    "area": "the area of the reachable set seen along x",
    "reach_ratio": "the roundness of the reachable set (smaller over larger reach)",
}
"""What each objective of a study makes as large as possible, in words."""

LIMIT_WORDS = {
    "max_outer_diameter": ("tip and catheter outer diameter at most", MM, "mm"),
    "wire_clearance": ("bores at least the wire plus", MM, "mm"),
    "min_wall": ("ring and catheter walls at least", MM, "mm"),
    "magnet_clearance": ("rings at least this far from the external magnet:", MM, "mm"),
    "twist_limit": ("twist of each transmission at most", DEG, "deg"),
    "neutral_tolerance": ("tip deflection with antiparallel rings at most", MM, "mm"),
    "catheter_max_strain": ("catheter bending strain at most", 1e-2, "%"),
    "wire_max_strain": ("wire bending strain at most", 1e-2, "%"),
    "min_disc_radius": ("disc radius at least", MM, "mm"),
    "min_reach_ratio": ("reach ratio at least", 1.0, ""),
}
"""A study's limits (:class:`optimize.sizing.studyfile.Constraints` fields) in words, with
the unit the report gives them in (SI per unit, label)."""


def _mm(x: float) -> str:
    return f"{x / MM:.3g}"


def _left_out(f: dict[str, Any]) -> str:
    """What the model for design work leaves out (torsion), and how much it moves the
    recommended design's disc."""
    t = f.get("best_torsion")
    if t is None:
        return ""
    moved = t["disc_radius_mm"] - f["best_disc_radius_mm"]
    return (
        f"<br><b>Left out of the design model: torsion</b> (the transmissions' twist with "
        f"the printed pieces' stops and pre-twist). With it the recommended design's disc "
        f"is <b>{t['disc_radius_mm']:.2f} mm</b> ({moved:+.2f} mm), "
        f"{100 * t['controllable_fraction']:.0f} % of the configurations steerable from home, "
        f"{t['snapped']} of {t['configurations']} snapping, droop {t['droop_mm']:.1f} mm."
    )


def _question(run: Run, doc: dict[str, Any]) -> str:
    """The study's question in a paragraph: objective, set-up, free bounds, limits, model."""
    study, base = run.study, run.study.base
    ext = base.external_magnet
    assert ext is not None, "a study designs for the external magnet"
    words = " and ".join(OBJECTIVE_WORDS.get(n, n) for n, _ in study.objective)
    free = [
        f"{r['quantity']} {r['low']:.3g}–{r['high']:.3g} {r['unit']}"
        for r in doc["design"]
        if r["low"] is not None
    ]
    mats = [
        f"{what} {' or '.join(names)}"
        for what, names in (("catheter", study.catheter_materials), ("wire", study.wire_materials))
        if names
    ]
    limits = []
    for name, (text, scale, unit) in LIMIT_WORDS.items():
        value = getattr(study.limits, name)
        if value is not None:
            limits.append(f"{text} {value / scale:.3g} {unit}".strip())
    if study.limits.stable:
        limits.append("every sampled pose stable")
    start_d = doc["start"]["external_distance_to_centre_mm"]
    return (
        f"<p class=question><b>Question.</b> Which design makes {html.escape(words)} as "
        f"large as possible, for a robot of free length {_mm(base.robot.free_length)} mm "
        f"steered by a {ext.shape} magnet Ø{_mm(ext.diameter)} × {_mm(ext.length)} mm "
        f"({ext.remanence:.3g} T), its centre {start_d:.2f} mm from the rest tip in the start "
        f"design? Model of the study: <b>{html.escape(doc['model'])}</b>"
        f"{_calibration_words(run)}.</p>"
        f"<ul class=setup><li><b>Free</b> (bounds): {html.escape('; '.join(free + mats))}</li>"
        f"<li><b>Limits</b>: {html.escape('; '.join(limits))}</li></ul>"
    )


def _calibration_words(run: Run) -> str:
    """With measured data: that the study designed with the robot as built, and how."""
    cal = run.calibration
    if not cal:
        return ""
    values = "; ".join(
        f"{file_key(name)} {page_number(value / file_unit(name)[1])}"
        for name, value in cal["values"].items()
    )
    out = (
        ", calibrated on the measured data (the robot as built: the diagnosis's effects "
        f"{html.escape(', '.join(cal['effects']) or 'none')}"
        + (f", and {html.escape(values)} on the start design" if values else "")
        + ")"
    )
    if cal["left_out"]:
        out += f"; left out of the optimisation: {html.escape(', '.join(cal['left_out']))}"
    return out


def _answer(run: Run, doc: dict[str, Any]) -> str:
    """The answer cards: the disc (about the robot's home, steerable without a snap) under
    the model for design work, against the start, with the study's NLP's own measure of it
    (and, where the study designed with another model, that model's disc on its own card);
    the recommended design in one line."""
    s, b = doc["start"]["disc_radius_mm"], doc["best"]["disc_radius_mm"]
    f = doc["forward"]
    fs, fb = f["start_disc_radius_mm"], f["best_disc_radius_mm"]
    same = f["model"] == doc["model"]
    cards = [
        f'<div class="card main"><div class=big id=headline>{fb:.2f} mm</div>'
        "the disc of the recommended design: the largest disc about its home that it can "
        f"be steered over without a snap ({html.escape(f['model'])} model)<br>start "
        f"{fs:.2f} mm: <b>{fb - fs:+.2f} mm ({100 * (fb / fs - 1):+.0f} %)</b>"
        + (f"; the study's NLP: {b:.2f} mm (start {s:.2f} mm)" if same else "")
        + _steerable(f)
        + _left_out(f)
        + "</div>"
    ]
    if not same:
        cards.append(
            f"<div class=card><div class=big id=study>{b:.2f} mm</div>disc about home in the "
            f"study's own model ({html.escape(doc['model'])})<br>start {s:.2f} mm: "
            f"<b>{b - s:+.2f} mm ({100 * (b / s - 1):+.0f} %)</b></div>"
        )
    d = made_design(run.results["optimise"].design)  # the hand-off, as best_design.toml
    cat, wire = doc["materials"]
    dims = (
        f"catheter{' ' + cat if cat else ''} Ø{_mm(d.robot.catheter.outer_diameter)}/"
        f"{_mm(d.robot.catheter.inner_diameter)} mm, wire{' ' + wire if wire else ''} "
        f"Ø{_mm(d.robot.wire.outer_diameter)} mm, rings Ø{_mm(d.tip.magnet_outer_diameter)}/"
        f"{_mm(d.tip.magnet_inner_diameter)} × {_mm(d.tip.magnet_length)} mm with "
        f"{_mm(d.tip.magnet_gap)} mm gap, magnet centre "
        f"{doc['best']['external_distance_to_centre_mm']:.1f} mm from the rest tip"
    )
    cards.append(
        f"<div class=card><b>Recommended design</b>: {html.escape(dims)}. "
        f"{html.escape(f['rounding'])} "
        f"Design file <code>{BEST_DESIGN}</code>; parts in <code>cad/</code> "
        f"(<code>parts.csv</code>, <code>bom.csv</code>).</div>"
    )
    cards.append(tip_card(run.results.get("cad")))
    return f"<div class=cards>{''.join(cards)}</div>"


def _steerable(f: dict[str, Any]) -> str:
    """The home's droop and the controllable share under the model for design work."""
    r = f["best_reach_mm"]
    return (
        f"<br>about the robot's home (rings antiparallel), {f['best_droop_mm']:.1f} mm from "
        f"the straight tip (start {f['start_droop_mm']:.1f} mm); reach beyond home "
        f"+y {r['+y']:.1f}, −y {r['-y']:.1f}, +z {r['+z']:.1f}, −z {r['-z']:.1f} mm; "
        f"{100 * f['best_controllable_fraction']:.0f} % of the configurations steerable "
        "from home without a snap"
    )


def _limits(doc: dict[str, Any]) -> str:
    """What limits the design (a table) and the next decision (a sentence)."""
    rows, gains = [], []
    for r in doc["limits"]:
        moved = f"{r['old']:.3g} → {r['new']:.3g} {r['unit']}" if np.isfinite(r["old"]) else "—"
        unknown = r.get("reason", "no design found")
        gain = f"{r['gain']:+.2f} mm" if np.isfinite(r["gain"]) else unknown
        unknown_multiplier = "— (bound)" if r["limit"].startswith("bound.") else "—"
        rows.append([r["meaning"], number_text(r["multiplier"]) or unknown_multiplier, moved, gain])
        gains.append(False)
    if not rows:
        return "<p><b>What limits it.</b> Nothing is active: the optimum is interior.</p>"
    best = next((r for r in doc["limits"] if np.isfinite(r["gain"]) and r["gain"] > 0), None)
    if best is not None:
        gains[doc["limits"].index(best)] = True
    if best is not None:
        nxt = (
            f"<b>Next decision.</b> Moving {html.escape(best['meaning'])} from {best['old']:.3g}"
            f" to {best['new']:.3g} {html.escape(best['unit'])} would add "
            f"<b>{best['gain']:.2f} mm</b> of disc radius ({html.escape(doc['model'])} model)."
        )
    else:
        nxt = "<b>Next decision.</b> No limit moved by the step gains disc radius."
    return (
        f"<p><b>What limits it</b>, most costly first (multiplier: the largest |Lagrange "
        f"multiplier| of the scaled NLP, kept for constraints only; gain: the study's NLP "
        f"solved again from the optimum, with its materials, with only that limit moved by "
        f"{RELAX:.0%} of its value, of its range for a bound):</p>"
        f"{table(['limit', 'multiplier', 'moved', 'disc radius gain'], rows, gains)}"
        f"<p class=next>{nxt}</p>"
    )


def _design_section(doc: dict[str, Any]) -> str:
    rows = [
        [
            r["quantity"],
            r["key"],
            r["unit"],
            page_number(r["start"]),
            page_number(r["optimum"]),
            r["set_by"]
            if r["low"] is None
            else f"{page_number(r['low'])} – {page_number(r['high'])}",
        ]
        for r in doc["design"]
    ]
    marked = [r["changed"] for r in doc["design"]]
    m = [
        [
            "disc radius (mm)",
            f"{doc['start']['disc_radius_mm']:.3f}",
            f"{doc['best']['disc_radius_mm']:.3f}",
            doc["model"],
        ],
        [
            "disc radius (mm)",
            f"{doc['forward']['start_disc_radius_mm']:.3f}",
            f"{doc['forward']['best_disc_radius_mm']:.3f}",
            doc["forward"]["model"],
        ],
    ] + [
        [k, f"{doc['start'][k]:.3f}", f"{doc['best'][k]:.3f}", doc["model"]]
        for k in doc["start"]
        if k != "disc_radius_mm"
    ]
    mats = [
        [
            r["catheter"],
            r["wire"],
            number_text(r["objective"], ".2f"),
            f"{r['accepted']}/{r['starts']}",
        ]
        for r in doc["per_material"]
    ]
    chosen = [
        [r["catheter"], r["wire"]] == [m or "as in the base design" for m in doc["materials"]]
        for r in doc["per_material"]
    ]
    c_rows = [
        [
            k,
            page_number(v["value"]),
            page_number(v["limit"]),
            v["unit"],
            "active" if v["active"] else "",
            page_number(v["multiplier"], 2),
        ]
        for k, v in doc["constraints"].items()
    ]
    return f"""<h2 id="designs">The design, start and optimum</h2>
<p>Every dimension in file units; the changed ones highlighted; bounds where the study
frees a quantity, the material where the study's choice of material sets it, fixed
otherwise.</p>
{table(["quantity", "design-file key", "unit", "start", "optimum", "bounds"], rows, marked)}
<h3>Metrics</h3>
{table(["metric", "start", "optimum", "model"], m)}
<p>reach_ratio is the smaller over the larger reach (y against z); 1 is round.</p>
<h3>Per material (best accepted start, {html.escape(doc["model"])} model)</h3>
{table(["catheter", "wire", "disc radius (mm)", "starts accepted"], mats, chosen)}
<h3>Constraints at the optimum</h3>
{
        table(
            ["constraint", "value", "limit", "unit", "active", "multiplier"],
            c_rows,
            [v["active"] for v in doc["constraints"].values()],
        )
    }"""


def _parts_section(run: Run) -> str:
    cad = run.results["cad"]
    parts = cad["parts"]
    p_rows = [
        [
            p["name"],
            p["quantity"],
            p["material"],
            f"{p['mass_g']:.3g}",
            " × ".join(f"{x:.3g}" for x in p["size_mm"]),
            p["description"],
        ]
        for p in parts
    ]
    total = sum(p["mass_g"] * p["quantity"] for p in parts)
    pngs = [Path(f) for f in cad["files"] if f.endswith(".png") and Path(f).exists()]
    main = [p for p in pngs if p.parent.name != "parts"]
    renders = "".join(thumb(p, p.stem.replace("_", " "), 390) for p in main)
    renders += "".join(thumb(p, p.stem.replace("_", " "), 190) for p in pngs if p not in main)
    shown, rest = check_rows(cad["checks"])

    def rows(cs: list[dict]) -> list[list[object]]:
        return [
            [
                c.get("item", ""),
                c.get("check", ""),
                check_value_text(c.get("value"), str(c.get("unit", ""))),
                "%" if c.get("unit") in ("relative", "fraction") else c.get("unit", ""),
                c.get("limit", ""),
                "pass" if c.get("passed") else "FAIL",
                c.get("note", ""),
            ]
            for c in cs
        ]

    header = ["item", "check", "value", "unit", "limit", "result", "note"]
    failed = sum(not c.get("passed", True) for c in cad["checks"])
    tight = table(header, rows(shown), [not c.get("passed", True) for c in shown]) if shown else ""
    return f"""<h2 id="parts">Parts of the recommended design</h2>
<p>Built from <code>{BEST_DESIGN}</code> (<code>cad/parts.csv</code>, STL and STEP in
<code>cad/</code>); total mass {total:.1f} g.</p>
{table(["part", "qty", "material", "mass (g)", "size (mm)", "what it is"], p_rows)}
<div class=renders>{renders}</div>
<h3>Printability and fit checks</h3>
<p>{len(cad["checks"])} checks: {failed} failed; {len(shown)} shown below (failed, or within
{TIGHT:.0%} of their limit).</p>
{tight}
{details(f"the other {len(rest)} checks, all passed", table(header, rows(rest)))}
{bom_section(cad)}"""


STYLE = """body{font-family:sans-serif;max-width:1200px;margin:0.6em auto;color:#222;
font-size:15px;line-height:1.35}h1{font-size:1.5em;margin:0.2em 0}
table{border-collapse:collapse;margin:0.4em 0;font-size:13px}
td,th{border:1px solid #bbb;padding:2px 7px}th{background:#eee}tr.mark td{background:#fff3c4}
img{max-width:100%;margin:4px 0}.row{display:flex;gap:8px;align-items:flex-start}
.row img{max-width:49%;height:auto}.cards{display:flex;gap:10px;margin:0.5em 0}
.card{border:1px solid #bbb;border-radius:6px;padding:6px 10px;flex:1;font-size:13px}
.card.main{border:2px solid #1f77b4;background:#eef5fb}
.big{font-size:2.1em;font-weight:bold;color:#1f77b4}.question{margin:0.3em 0}
.next{background:#eef8ee;padding:4px 8px;border-left:4px solid #2ca02c}
.renders{display:flex;flex-wrap:wrap;gap:6px}figure{margin:0;font-size:12px}
.setup{margin:0.2em 0;font-size:13px;color:#333}
.first{border-bottom:2px solid #888;padding-bottom:0.3em}"""


def write_report(run: Run) -> list[Path]:
    """``report.html``, ``results.json``, the figures and, where Chromium is installed,
    ``report.pdf`` (the page printed), in ``run.out``; the paths."""
    out = run.out
    figs = out / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    best = run.results["optimise"]
    fwd = run.results["forward"]
    doc = results(run)
    work = doc["forward"]["model"]
    paths = [figs / "workspace_section.png", figs / "tip_views.png"]
    plot_workspaces(fwd["start"], fwd["best"], paths[0], work)
    plot_tip_views(fwd["start"], fwd["best"], paths[1], work)
    if "pareto" in run.results:
        plot_fronts(run.results["pareto"], best, run.study, figs / "pareto.png")
        paths.append(figs / "pareto.png")
    plot_tolerance(
        run.results["tolerance"]["disc_radius"] / MM,
        doc["forward"]["best_disc_radius_mm"],
        figs / "tolerance.png",
    )
    paths.append(figs / "tolerance.png")
    images = {p.stem: img(p, p.stem) for p in paths}

    t = doc["tolerance"]
    tol_rows = [
        [PARAMETERS[k].meaning, tolerance_words(k, kind, sigma)]
        for k, (kind, sigma) in TOLERANCES.items()
    ]
    eff_rows = [
        [r["effect"], f"{r['max_shift_mm']:.2f}", f"{r['rms_shift_mm']:.2f}"]
        for r in doc["effects"]
    ]
    fronts = "".join(f"<p>{html.escape(n)}</p>" for n in doc["pareto"].values())
    if "diagnosis" in run.results:
        dg = run.results["diagnosis"]
        causes = "".join(f"<li>{html.escape(c['evidence'])}</li>" for c in dg["causes"]) or (
            "<li>none: the calibrated baseline explains the data</li>"
        )
        diagnosis = (
            f"<ul>{causes}</ul><p>Cross-validated RMSE {dg['baseline']['cv_rmse_mm']:.3f} mm "
            f"(baseline) to {dg['final']['cv_rmse_mm']:.3f} mm (final).</p>"
        )
    else:
        diagnosis = "<p>No measured data were given (<code>ringpair study --data DIR</code>).</p>"
    timing_rows = [[k, f"{v:.1f}"] for k, v in run.seconds.items()]
    intro = run.study.description.strip()
    intro = intro if not intro or intro.endswith((".", "!", "?")) else intro + "."
    page = f"""<!doctype html>
<html><head><meta charset="utf-8"><title>ringpair study {html.escape(run.study.name)}</title>
<style>{STYLE}</style></head><body>
<section class=first id=answer>
<h1>Design study: {html.escape(run.study.name)}</h1>
{_question(run, doc)}
{_answer(run, doc)}
{_limits(doc)}
<!--pdf-->
</section>
<h2 id="setup">Set-up</h2>
<p>{html.escape(intro)} The study optimised with the {html.escape(doc["model"])} model;
the figures, the tolerance spread and the headline's second number re-simulate the start
and the optimum with the model for design work ({html.escape(work)}).</p>
{_design_section(doc)}
<h2 id="figures">Workspaces ({html.escape(work)} model)</h2>
<div class="row">{images["workspace_section"]}</div>
{images["tip_views"]}
<h2 id="pareto">Pareto fronts ({html.escape(doc["model"])} model)</h2>
{images.get("pareto", "<p>No sweeps in this study.</p>")}
{fronts}
<h2 id="tolerance">Tolerance spread ({html.escape(work)} model)</h2>
<p>{t["samples"]} samples: disc radius {t["disc_radius_mean_mm"]:.3f} mm mean,
{t["disc_radius_std_mm"]:.3f} mm standard deviation, 5-95 % range
{t["disc_radius_p05_mm"]:.3f}-{t["disc_radius_p95_mm"]:.3f} mm.</p>
{images["tolerance"]}
{table(["parameter", "one sigma"], tol_rows)}
{_parts_section(run)}
<h2 id="effects">Model effects (tip shift against the baseline, mm)</h2>
{table(["effect", "max shift", "RMS shift"], eff_rows)}
<h2 id="diagnosis">Diagnosis of measured data</h2>
{diagnosis}
<h2 id="timings">Timings (s)</h2>
{table(["stage", "seconds"], timing_rows)}
</body></html>
"""
    write_text(out / "report.html", page.replace(PDF_MARK, pdf_note(browser() is not None)))
    write_text(out / "results.json", dumps_strict(doc))
    pdf = print_pdf(out / "report.html", out / "report.pdf")
    if pdf is None and browser() is not None:  # Chromium is there but printed nothing
        write_text(out / "report.html", page.replace(PDF_MARK, pdf_note(True, failed=True)))
    return [*paths, *([pdf] if pdf else []), out / "report.html", out / "results.json"]


def browser() -> str | None:
    """Path of a Chromium that can run headless (Debian package ``chromium``), or None."""
    return shutil.which("chromium") or shutil.which("chromium-browser")


def print_pdf(page: Path, pdf: Path) -> Path | None:
    """Print ``page`` to ``pdf`` with headless Chromium; None (nothing written) when
    Chromium is not installed or fails."""
    exe = browser()
    if exe is None:
        return None
    try:
        with atomic_path(pdf) as tmp:
            subprocess.run(
                [
                    exe,
                    "--headless",
                    "--disable-gpu",
                    "--no-sandbox",
                    "--no-pdf-header-footer",
                    f"--print-to-pdf={tmp}",
                    page.resolve().as_uri(),
                ],
                check=True,
                capture_output=True,
                timeout=180,
            )
            if not tmp.read_bytes().startswith(b"%PDF"):
                raise ValueError("Chromium wrote no PDF")  # atomic_path keeps nothing
    except (OSError, subprocess.SubprocessError, ValueError):
        return None
    return pdf
