"""``ringpair diagnose``: what the simulation gets wrong on measured data, and why."""

from __future__ import annotations

import json
from pathlib import Path

import click
from rich.markup import escape
from rich.table import Table

from design.atomic import write_text
from ringpair.options import CSV_DESIGN, DATA, UserError, console, measured_data, path_option


@click.command()
@DATA
@CSV_DESIGN
@path_option("--json", "json_out", help="Write the diagnosis JSON (spec/formats.md) here.")
@path_option("--report", help="Directory for residual plots before/after and diagnosis.html.")
@click.option("--folds", default=5, show_default=True, help="Cross-validation folds.")
@click.option("--seed", default=0, show_default=True, help="Seed of the fold assignment.")
def diagnose(
    data: Path,
    design_path: Path | None,
    json_out: Path | None,
    report: Path | None,
    folds: int,
    seed: int,
) -> None:
    """What the simulation gets wrong on measured DATA, the physical cause, and the gain.

    DATA is a data-set folder (design.toml + measurements.csv) or a CSV with --design.
    Calibrates the paper's baseline, looks for structure in its residuals, adds the model
    effects the data call for (judged by BIC and cross-validated error) and prints the
    causes with their evidence and the fitted physical parameters.
    """
    from optimize.fitting.diagnose import diagnose as run_diagnosis
    from ringpair.diagnosis_report import write_report

    d, m = measured_data(data, design_path)
    if not 2 <= folds <= len(m):
        raise UserError(f"--folds must be between 2 and the number of rows ({len(m)}); got {folds}")
    with console.status("diagnosing") as status:
        result = run_diagnosis(d, m, k=folds, seed=seed, progress=status.update)
    doc = result.to_json()
    table = Table(title=f"diagnosis of {m.source} ({len(m)} rows, {result.time_s:.1f} s)")
    for col in ("model", "RMSE (mm)", "max (mm)", "cross-validated RMSE (mm)"):
        table.add_column(col, justify="right")
    for name, fit in (("baseline", result.baseline), (result.final.name, result.final)):
        c = fit.calibration
        table.add_row(name, f"{c.rmse_mm:.3f}", f"{c.max_abs_mm:.3f}", f"{fit.cv_rmse_mm:.3f}")
    console.print(table)
    if result.causes:
        for cause in result.causes:
            console.print(f"[bold]cause[/] {escape(cause.evidence)}")
    else:
        console.print("causes: [] (the calibrated baseline explains the data)")
    if result.unexplained:
        console.print(f"[yellow]not explained:[/] {escape(result.unexplained)}")
    if json_out is not None:
        write_text(json_out, json.dumps(doc, indent=2, allow_nan=False) + "\n")
        console.print(f"wrote {json_out}")
    if report is not None:
        for path in write_report(result, m, report):
            console.print(f"wrote {path}")
