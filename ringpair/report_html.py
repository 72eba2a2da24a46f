"""The study report: one self-contained HTML page (images embedded) and ``results.json``
with every number the page shows. Millimetres, degrees and mm^3 on the page."""

from __future__ import annotations

import html
import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

from design.atomic import atomic_path, write_text
from design.designfile import design_to_dict
from design.model import DEFAULT_EFFECTS
from design.units import MM, MM3
from ringpair.html_page import img, table
from ringpair.pipeline import TOLERANCES, Run
from ringpair.plots import plot_fronts, plot_projection, plot_tolerance, plot_workspaces


def _flat(d: dict[str, Any], prefix: str = "") -> dict[str, float]:
    out: dict[str, float] = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out |= _flat(v, f"{prefix}{k}.")
        elif isinstance(v, int | float) and not isinstance(v, bool):
            out[f"{prefix}{k}"] = float(v)
    return out


def results(run: Run) -> dict[str, Any]:
    """Every number of the report, in report units (mm, mm^3, deg)."""
    best = run.results["optimise"]
    fwd = run.results["forward"]
    tol = run.results["tolerance"]["disc_radius"] / MM
    start_ws, best_ws = fwd["start"], fwd["best"]

    def metrics(m: dict[str, float]) -> dict[str, float]:
        return {
            "disc_radius_mm": m["disc_radius"] / MM,
            "reach_ratio": m["reach_ratio"],
            "neutral_deflection_mm": m["neutral_deflection"] / MM,
            "magnet_volume_mm3": m["magnet_volume"] / MM3,
            "external_distance_mm": m["external_distance"] / MM,
        }

    constraints = {
        c.name: {"value": c.value / c.scale, "limit": c.limit / c.scale, "unit": c.unit}
        for c in best.constraints
    }
    doc: dict[str, Any] = {
        "study": run.study.name,
        "model": sorted(run.study.effects) or ["baseline"],
        "start": metrics(best.base_metrics),
        "best": metrics(best.metrics),
        "materials": list(best.materials),
        "constraints": constraints,
        "forward": {
            "model": sorted(DEFAULT_EFFECTS),
            "start_disc_radius_mm": start_ws.disc_radius / MM,
            "best_disc_radius_mm": best_ws.disc_radius / MM,
        },
        "tolerance": {
            "samples": int(len(tol)),
            "disc_radius_mean_mm": float(np.mean(tol)),
            "disc_radius_std_mm": float(np.std(tol)),
            "disc_radius_p05_mm": float(np.percentile(tol, 5)),
            "disc_radius_p95_mm": float(np.percentile(tol, 95)),
        },
        "effects": run.results["effects"],
        "cad": {
            "passed": run.results["cad"]["passed"],
            "checks": len(run.results["cad"]["checks"]),
        },
        "timings_s": run.seconds,
    }
    if "diagnosis" in run.results:
        doc["diagnosis"] = run.results["diagnosis"]
    return doc


def write_report(run: Run) -> list[Path]:
    """``report.html``, ``results.json``, the figures and, where Chromium is installed,
    ``report.pdf`` (the page printed), in ``run.out``; the paths."""
    out = run.out
    figs = out / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    best = run.results["optimise"]
    fwd = run.results["forward"]
    doc = results(run)
    paths = []
    plot_workspaces(fwd["start"], fwd["best"], figs / "workspace_section.png")
    plot_projection(fwd["start"], run.study.base, figs / "start_top.png", (0, 1), "Start, top")
    plot_projection(fwd["best"], best.design, figs / "best_top.png", (0, 1), "Optimum, top")
    plot_projection(fwd["best"], best.design, figs / "best_side.png", (0, 2), "Optimum, side")
    paths += [figs / n for n in ("workspace_section.png", "start_top.png", "best_top.png")]
    paths.append(figs / "best_side.png")
    if "pareto" in run.results:
        plot_fronts(run.results["pareto"], best, run.study, figs / "pareto.png")
        paths.append(figs / "pareto.png")
    plot_tolerance(
        run.results["tolerance"]["disc_radius"] / MM,
        doc["forward"]["best_disc_radius_mm"],
        figs / "tolerance.png",
    )
    paths.append(figs / "tolerance.png")

    start_d = _flat(design_to_dict(run.study.base))
    best_d = _flat(design_to_dict(best.design))
    param_rows = [
        [k, f"{start_d[k]:.4g}", f"{best_d.get(k, float('nan')):.4g}"]
        for k in start_d
        if not np.isclose(start_d[k], best_d.get(k, np.nan), rtol=1e-9)
    ]
    m_rows = [[k, f"{doc['start'][k]:.3f}", f"{doc['best'][k]:.3f}"] for k in doc["start"]] + [
        [
            f"disc radius, {'+'.join(doc['forward']['model'])} model (mm)",
            f"{doc['forward']['start_disc_radius_mm']:.3f}",
            f"{doc['forward']['best_disc_radius_mm']:.3f}",
        ]
    ]
    c_rows = [
        [k, f"{v['value']:.4g}", f"{v['limit']:.4g}", v["unit"]]
        for k, v in doc["constraints"].items()
    ]
    t = doc["tolerance"]
    tol_rows = [[k, f"{s:g}", kind] for k, (kind, s) in TOLERANCES.items()]
    eff_rows = [
        [r["effect"], f"{r['max_shift_mm']:.2f}", f"{r['rms_shift_mm']:.2f}"]
        for r in doc["effects"]
    ]
    cad = run.results["cad"]
    check_rows = [
        [
            c.get("item", ""),
            c.get("check", ""),
            c.get("value", ""),
            c.get("limit", ""),
            c.get("passed", ""),
        ]
        for c in cad["checks"]
    ]
    pngs = {Path(f).name: Path(f) for f in cad["files"] if f.endswith(".png") and Path(f).exists()}
    renders = [pngs[n] for n in ("assembly.png", "tip_section.png") if n in pngs] or list(
        pngs.values()
    )
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
    images = {p.stem: img(p, p.stem) for p in paths}
    page = f"""<!doctype html>
<html><head><meta charset="utf-8"><title>ringpair study {html.escape(run.study.name)}</title>
<style>body{{font-family:sans-serif;max-width:1150px;margin:2em auto;color:#222}}
table{{border-collapse:collapse;margin:0.5em 0}}td,th{{border:1px solid #bbb;padding:3px 8px}}
th{{background:#eee}}img{{max-width:100%;margin:4px 0}}.row{{display:flex;gap:8px}}
.row img{{max-width:49%;height:auto}}.row{{align-items:flex-start}}</style></head><body>
<h1>Design study: {html.escape(run.study.name)}</h1>
<h2 id="setup">Set-up</h2>
<p>{html.escape(intro)} Study model: {", ".join(doc["model"])}; materials of
the optimum: {", ".join(str(m) for m in doc["materials"])}.</p>
<h2 id="designs">Starting vs optimised design</h2>
{table(["metric", "start", "optimum"], m_rows)}
<h3>Parameters that changed (file units)</h3>
{table(["key", "start", "optimum"], param_rows)}
<h3>Constraints at the optimum</h3>
{table(["constraint", "value", "limit", "unit"], c_rows)}
<div class="row">{images["start_top"]}{images["best_top"]}</div>
<div class="row">{images["best_side"]}{images["workspace_section"]}</div>
<h2 id="pareto">Pareto fronts</h2>
{images.get("pareto", "<p>No sweeps in this study.</p>")}
<h2 id="tolerance">Tolerance spread</h2>
<p>{t["samples"]} samples: disc radius {t["disc_radius_mean_mm"]:.3f} mm mean,
{t["disc_radius_std_mm"]:.3f} mm standard deviation, 5-95 % range
{t["disc_radius_p05_mm"]:.3f}-{t["disc_radius_p95_mm"]:.3f} mm.</p>
{img(figs / "tolerance.png", "tolerance")}
{table(["parameter", "one sigma (SI or relative)", "kind"], tol_rows)}
<h2 id="parts">Parts and printability</h2>
<p>Checks {"all passed" if cad["passed"] else "NOT all passed"} ({len(cad["checks"])}).</p>
<div class="row">{"".join(img(p, p.stem) for p in renders[:2])}</div>
{table(["item", "check", "value", "limit", "passed"], check_rows)}
<h2 id="effects">Model effects (tip shift against the baseline, mm)</h2>
{table(["effect", "max shift", "RMS shift"], eff_rows)}
<h2 id="diagnosis">Diagnosis of measured data</h2>
{diagnosis}
<h2 id="timings">Timings (s)</h2>
{table(["stage", "seconds"], timing_rows)}
</body></html>
"""
    write_text(out / "report.html", page)
    write_text(out / "results.json", json.dumps(doc, indent=2, default=float) + "\n")
    pdf = print_pdf(out / "report.html", out / "report.pdf")
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
