"""The diagnosis as people look at it: residual plots before/after and a short HTML page.

Figures (PNG, also embedded in ``diagnosis.html``):
- ``residuals.png``: the tip error of each row [mm] against the acquisition order, theta1
  and theta1 - theta2, for the calibrated baseline and the selected model;
- ``positions.png``: measured tip positions joined to both models' predictions, seen
  along x (the y-z plane) [mm].
"""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

from design.atomic import write_text
from optimize.fitting.diagnose import Diagnosis, parameter_values
from optimize.fitting.measurements import Measurements
from ringpair.html_page import img, table
from ringpair.plots import plot_positions, plot_residuals
from ringpair.tables import estimate_text


def write_report(d: Diagnosis, m: Measurements, out: Path) -> list[Path]:
    """Residual plots and ``diagnosis.html`` (images embedded) in ``out``; the paths."""
    out.mkdir(parents=True, exist_ok=True)
    residuals, positions = out / "residuals.png", out / "positions.png"
    plot_residuals(d, m, residuals)
    plot_positions(d, m, positions)
    fits = [("baseline", d.baseline), (f"final ({d.final.name})", d.final)]
    errors = table(
        ["model", "RMSE [mm]", "max [mm]", "cross-validated RMSE [mm]"],
        [
            [
                name,
                f"{f.calibration.rmse_mm:.3f}",
                f"{f.calibration.max_abs_mm:.3f}",
                f"{f.cv_rmse_mm:.3f}",
            ]
            for name, f in fits
        ],
    )
    estimate = parameter_values(d.final.calibration)
    error = parameter_values(d.final.calibration, standard_error=True)
    intervals = {k: v for c in d.causes for k, v in c.intervals.items()}

    def interval(key: str) -> str:
        return f"{intervals[key][0]:.4g} to {intervals[key][1]:.4g}" if key in intervals else ""

    params = table(
        ["parameter", "estimate", "standard error", "1-sigma profile interval"],
        [
            [k, estimate_text(v, error[k]), f"{error[k]:.2g}", interval(k)]
            for k, v in estimate.items()
        ],
    )
    causes = (
        "".join(f"<li>{html.escape(c.evidence)}</li>" for c in d.causes)
        or "<li>none: the calibrated baseline explains the data</li>"
    )
    doc = d.to_json()

    def number(value: object, spec: str = ".3f") -> str:
        return "-" if value is None else format(value, spec)

    tried = table(
        [
            "model",
            "on top of",
            "RMSE [mm]",
            "CV RMSE [mm]",
            "BIC",
            "BIC change",
            "params",
            "verdict",
        ],
        [
            [
                name,
                c["on_top_of"],
                number(c["rmse_mm"]),
                number(c["cv_rmse_mm"]),
                number(c["bic"], ".1f"),
                number(c["bic_change"], "+.1f"),
                ", ".join(
                    f"{k} {estimate_text(v, c['uncertainty'].get(k) or math.nan)}"
                    for k, v in c["params"].items()
                ),
                c["verdict"],
            ]
            for name, c in doc["candidates"].items()
        ],
    )
    power = "".join(
        f"<li>{html.escape(name)}: {html.escape(str(p['note']))}</li>"
        for name, p in d.power.items()
    )
    power = f"<h2>Power of the data</h2><ul>{power}</ul>" if power else ""
    left = f"<p><b>Not explained:</b> {html.escape(d.unexplained)}</p>" if d.unexplained else ""
    lost = int(np.count_nonzero(~m.seen))
    unseen = f" ({lost} more driven along the path but not seen)" if lost else ""
    page = f"""<!doctype html>
<html><head><meta charset="utf-8"><title>ringpair diagnosis</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}}
table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:4px 10px;text-align:right}}
th{{background:#eee}}img{{max-width:100%}}</style></head><body>
<h1>Diagnosis of {html.escape(m.source)}</h1>
<p>{int(m.seen.sum())} measured configurations{unseen}.
Cross-validated error ratio final / baseline:
<b>{number(doc["gain"]["cv_rmse_ratio"])}</b>.</p>
<h2>Causes</h2><ul>{causes}</ul>{left}
<h2>Every model tried</h2>{tried}
{power}
<h2>Error</h2>{errors}
<h2>Fitted parameters of the final model</h2>{params}
<p>Standard errors are linearised (Gauss-Newton); the profile-likelihood intervals of the
causes' parameters hold where parameters trade off along a curved valley.</p>
<h2>Residuals</h2>{img(residuals, "residuals")}{img(positions, "positions")}
</body></html>
"""
    page_path = out / "diagnosis.html"
    write_text(page_path, page)
    return [residuals, positions, page_path]
