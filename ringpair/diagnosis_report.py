"""The diagnosis as people look at it: residual plots before/after and a short HTML page.

Figures (PNG, also embedded in ``diagnosis.html``):
- ``residuals.png``: the tip error of each row [mm] against the acquisition order, theta1
  and theta1 - theta2, for the calibrated baseline and the selected model;
- ``positions.png``: measured tip positions joined to both models' predictions, seen
  along x (the y-z plane) [mm].
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from design.atomic import write_text  # noqa: E402
from optimize.diagnose import Diagnosis, parameter_values  # noqa: E402
from optimize.measurements import Measurements  # noqa: E402


def _save(fig: plt.Figure, path: Path) -> None:
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=110, bbox_inches="tight")
    plt.close(fig)
    tmp.replace(path)


def plot_residuals(d: Diagnosis, m: Measurements, path: Path) -> None:
    """Error per row [mm] against order, theta1 and theta1 - theta2, baseline vs final."""
    order = np.empty(len(m))
    order[m.order()] = np.arange(len(m))
    t1 = np.rad2deg(m.command[:, 0])
    diff = np.rad2deg((m.command[:, 0] - m.command[:, 1] + np.pi) % (2 * np.pi) - np.pi)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6), sharey=True)
    for ax, x, label in zip(
        axes,
        (order, t1, diff),
        ("acquisition order", "theta1 commanded [deg]", "theta1 - theta2 [deg]"),
        strict=True,
    ):
        for fit, colour, name in (
            (d.baseline, "tab:red", "baseline"),
            (d.final, "tab:blue", d.final.name),
        ):
            ax.plot(x, fit.calibration.errors * 1e3, "o", ms=3.5, color=colour, label=name)
        ax.set_xlabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("tip error [mm]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Calibrated model against the measurements, per row")
    _save(fig, path)


def plot_positions(d: Diagnosis, m: Measurements, path: Path) -> None:
    """Measured tips and both models' tips seen along x (the y-z plane, where the robot
    steers) [mm], each measurement joined to its predictions; for top views (no z), y
    against the acquisition order."""
    fig, ax = plt.subplots(figsize=(6.5, 6))
    meas = m.position * 1e3
    has_z = np.isfinite(meas[:, 2]).mean() > 0.5
    order = np.empty(len(m))
    order[m.order()] = np.arange(len(m))
    for fit, colour, name in (
        (d.baseline, "tab:red", "baseline"),
        (d.final, "tab:blue", d.final.name),
    ):
        model = (m.position - fit.calibration.residuals) * 1e3
        if has_z:
            a, b = model[:, 1], model[:, 2]
            segments_x = np.vstack([meas[:, 1], a, np.full(len(m), np.nan)]).T.ravel()
            segments_y = np.vstack([meas[:, 2], b, np.full(len(m), np.nan)]).T.ravel()
            ax.plot(segments_x, segments_y, "-", color=colour, lw=0.8, alpha=0.6)
        else:
            a, b = order, model[:, 1]
        ax.plot(a, b, "x", ms=5, color=colour, label=name)
    if has_z:
        ax.plot(meas[:, 1], meas[:, 2], "k.", ms=6, label="measured")
        ax.set_xlabel("y [mm]")
        ax.set_ylabel("z [mm]")
        ax.set_aspect("equal", adjustable="datalim")
        title = "Tip positions seen along x (base frame), measured to model"
    else:
        ax.plot(order, meas[:, 1], "k.", ms=6, label="measured")
        ax.set_xlabel("acquisition order")
        ax.set_ylabel("y [mm]")
        title = "Tip y (top view data), measured and model"
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title)
    _save(fig, path)


def _img(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode()
    return f'<img alt="{path.stem}" src="data:image/png;base64,{data}" style="max-width:100%">'


def _row(cells: list[str], tag: str = "td") -> str:
    return "<tr>" + "".join(f"<{tag}>{c}</{tag}>" for c in cells) + "</tr>"


def write_report(d: Diagnosis, m: Measurements, out: Path) -> list[Path]:
    """Residual plots and ``diagnosis.html`` (images embedded) in ``out``; the paths."""
    out.mkdir(parents=True, exist_ok=True)
    residuals, positions = out / "residuals.png", out / "positions.png"
    plot_residuals(d, m, residuals)
    plot_positions(d, m, positions)
    fits = [("baseline", d.baseline), (f"final ({d.final.name})", d.final)]
    table = _row(["model", "RMSE [mm]", "max [mm]", "cross-validated RMSE [mm]"], "th") + "".join(
        _row(
            [
                name,
                f"{f.calibration.rmse_mm:.3f}",
                f"{f.calibration.max_abs_mm:.3f}",
                f"{f.cv_rmse_mm:.3f}",
            ]
        )
        for name, f in fits
    )
    estimate = parameter_values(d.final.calibration)
    error = parameter_values(d.final.calibration, standard_error=True)
    intervals = {k: v for c in d.causes for k, v in c.intervals.items()}

    def interval(key: str) -> str:
        return f"{intervals[key][0]:.4g} to {intervals[key][1]:.4g}" if key in intervals else ""

    params = _row(
        ["parameter", "estimate", "standard error", "1-sigma profile interval"], "th"
    ) + "".join(
        _row([html.escape(k), f"{v:.5g}", f"{error[k]:.2g}", interval(k)])
        for k, v in estimate.items()
    )
    causes = (
        "".join(f"<li>{html.escape(c.evidence)}</li>" for c in d.causes)
        or "<li>none: the calibrated baseline explains the data</li>"
    )
    left = f"<p><b>Not explained:</b> {html.escape(d.unexplained)}</p>" if d.unexplained else ""
    page = f"""<!doctype html>
<html><head><meta charset="utf-8"><title>ringpair diagnosis</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}}
table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:4px 10px;text-align:right}}
th{{background:#eee}}</style></head><body>
<h1>Diagnosis of {html.escape(m.source)}</h1>
<p>{len(m)} measured configurations. Cross-validated error ratio final / baseline:
<b>{d.final.cv_rmse_mm / d.baseline.cv_rmse_mm:.3f}</b>.</p>
<h2>Causes</h2><ul>{causes}</ul>{left}
<h2>Error</h2><table>{table}</table>
<h2>Fitted parameters of the final model</h2><table>{params}</table>
<p>Standard errors are linearised (Gauss-Newton); the profile-likelihood intervals of the
causes' parameters hold where parameters trade off along a curved valley.</p>
<h2>Residuals</h2>{_img(residuals)}{_img(positions)}
</body></html>
"""
    page_path = out / "diagnosis.html"
    write_text(page_path, page)
    return [residuals, positions, page_path]
