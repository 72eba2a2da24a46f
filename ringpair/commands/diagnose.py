"""``ringpair diagnose``: what the simulation gets wrong on measured data, and why."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path
from typing import TYPE_CHECKING, cast

import click
import numpy as np
from click.core import ParameterSource
from rich.table import Table

from design.atomic import write_text
from ringpair.fit_checks import coordinates, fit_warnings, misses, out_of_reach
from ringpair.options import (
    CSV_DESIGN,
    DATA,
    NO_PRIORS,
    OVERWRITE_POLICY,
    PRIOR,
    UserError,
    bad_input,
    console,
    duration,
    err_console,
    json_text,
    measured_data,
    output_path,
    path_option,
    priors_from,
    progress,
    warn,
)

MAX_ROWS = 20_000
"""Rows diagnosed at most unless --max-rows says more (about seven minutes)."""
SECONDS = (13.0, 0.02)
"""Time of a diagnosis, measured on the development machine (2 cores): a fixed part and
a part per row. [s, s/row]"""
ANNOUNCE = 30.0
"""A diagnosis estimated longer than this is announced with its estimate. [s]"""
if TYPE_CHECKING:
    from optimize.fitting.calibrate import CalibrationResult
    from optimize.fitting.measurements import Measurements

REPORT_FILES = ("residuals.png", "positions.png", "diagnosis.html")
"""What --report writes in its folder."""


@click.command()
@DATA
@CSV_DESIGN
@path_option(
    "--json",
    "json_out",
    help="Write the diagnosis JSON (docs/formats.md) here. " + OVERWRITE_POLICY,
)
@path_option("--report", help="Directory for residual plots before/after and diagnosis.html.")
@click.option("--folds", default=5, show_default=True, help="Cross-validation folds.")
@click.option(
    "--seed",
    type=click.IntRange(0, 2**32 - 1),
    default=0,
    show_default=True,
    help="Seed of the fold assignment.",
)
@click.option(
    "--max-rows",
    type=click.IntRange(1, None),
    default=MAX_ROWS,
    show_default=True,
    help="Refuse data with more rows than this (the time is estimated up front).",
)
@click.option(
    "--workers",
    type=click.IntRange(1, None),
    help="Processes for the independent fits (candidates, folds, intervals) "
    "[default: $RINGPAIR_WORKERS, else one per core].",
)
@PRIOR
@NO_PRIORS
def diagnose(
    data: Path,
    design_path: Path | None,
    json_out: Path | None,
    report: Path | None,
    folds: int,
    seed: int,
    max_rows: int,
    workers: int | None,
    prior_texts: tuple[str, ...],
    no_priors: bool,
) -> None:
    """What the simulation gets wrong on measured DATA, the physical cause, and the gain.

    DATA is a data-set folder (design.toml + measurements.csv) or a CSV with --design.
    Calibrates the paper's baseline, looks for structure in its residuals, adds the model
    effects the data call for (judged by BIC and cross-validated error) and prints the
    causes with their evidence and the fitted physical parameters. Each stage is printed
    on stderr as it starts, with the time so far.
    """
    from optimize.fitting.calibrate import EFFECT_FREE
    from optimize.fitting.diagnose import diagnose as run_diagnosis
    from optimize.fitting.workers import WORKERS_VARIABLE, worker_count
    from ringpair.diagnosis_report import write_report

    if workers is not None:
        os.environ[WORKERS_VARIABLE] = str(workers)
    try:
        worker_count()
    except ValueError as exc:
        raise UserError(str(exc)) from None

    d, m = measured_data(data, design_path)
    priors = priors_from(data, prior_texts, no_priors)
    seconds = SECONDS[0] + SECONDS[1] * len(m)
    if len(m) > max_rows:
        raise UserError(
            f"{m.source} has {len(m):,} rows: a diagnosis would take about {duration(seconds)}; "
            f"at most {max_rows:,} are diagnosed unless --max-rows says more"
        )
    _check_size(m, folds, typed=_typed("folds"), seed=seed)
    inputs = [data, design_path]
    if json_out is not None:
        output_path(json_out, "--json", folder=False, inputs=inputs)
    if report is not None:
        j, r = json_out and json_out.resolve(), report.resolve()
        if j is not None and (j == r or j in r.parents):
            raise UserError(f"--report {report}: a folder where --json writes its file")
        output_path(report, "--report", folder=True, files=REPORT_FILES, inputs=inputs)
    notes = out_of_reach(d, m)
    for note in notes:
        warn(note)
    if seconds > ANNOUNCE:
        err_console.print(f"diagnosing {len(m):,} rows: about {duration(seconds)}")
    t0 = time.perf_counter()
    with progress("diagnosing") as update, bad_input(ValueError, prefix=f"{m.source}: "):

        def say(stage: str) -> None:
            update(description=stage)
            err_console.print(f"{time.perf_counter() - t0:6.1f} s {stage}", style="dim")

        try:
            # Tips beyond the robot's reach are not this robot's (units, another set-up):
            # no effect can bring its tip there, so none is searched.
            searched = () if notes else tuple(EFFECT_FREE)
            result = run_diagnosis(d, m, searched, k=folds, seed=seed, progress=say, priors=priors)
        except (ArithmeticError, RuntimeError, np.linalg.LinAlgError) as exc:
            # the calibrated baseline could not be fitted (a candidate's failure is in
            # the result): one message, exit 1
            text = " ".join(str(exc).split())
            raise click.ClickException(
                f"{m.source}: the diagnosis failed fitting the baseline: "
                f"{type(exc).__name__}: {text}"
            ) from None
    missed = misses(d, m, result.final.calibration)
    later = fit_warnings(d, m, result.final.calibration)
    doc = {**result.to_json(), "warnings": notes + later}
    table = Table(title=f"diagnosis of {m.source} ({m.rows_text()}, {result.time_s:.1f} s)")
    for col in ("model", "RMSE (mm)", "max (mm)", "cross-validated RMSE (mm)"):
        table.add_column(col, justify="right")
    fits = [("baseline", result.baseline)]
    if result.final is not result.baseline:
        fits.append((result.final.name, result.final))
    for name, fit in fits:
        c = fit.calibration
        table.add_row(name, f"{c.rmse_mm:.3f}", f"{c.max_abs_mm:.3f}", f"{fit.cv_rmse_mm:.3f}")
    console.print(table)
    tried = Table(title="every model tried")
    for col in ("model", "on top of", "RMSE (mm)", "CV RMSE (mm)", "BIC change", "verdict"):
        tried.add_column(col, justify="left" if col in ("model", "verdict") else "right")
    for name, row in doc["candidates"].items():
        tried.add_row(
            name,
            row["on_top_of"],
            _number(row["rmse_mm"]),
            _number(row["cv_rmse_mm"]),
            _number(row["bic_change"], "+.1f"),
            row["verdict"],
        )
    if doc["candidates"]:
        console.print(tried)
    for cause in result.causes:
        console.print(f"cause {cause.evidence}")
    for name, power in result.power.items():
        console.print(f"power of the data for {name}: {power['note']}")
    for name, fit in fits:
        console.print(f"{name}: {_pulls(fit.calibration)}")
    if not result.causes and notes:
        console.print(
            "causes: [] (no effect searched: the measured tips lie beyond the robot's "
            "reach, which no effect changes; see the warning)"
        )
    elif not result.causes:
        console.print(
            "causes: [] (the model does not explain the data either: see the warning)"
            if missed
            else "causes: [] (the calibrated baseline does not explain the data either: see "
            "'not explained')"
            if result.unexplained
            else "causes: [] (the calibrated baseline explains the data)"
        )
    if result.unexplained:
        console.print(f"not explained: {result.unexplained}")
    for note in later:
        warn(note)
    if json_out is not None:
        write_text(json_out, json_text(doc))
        console.print(f"wrote {json_out}")
    if report is not None:
        for path in write_report(result, m, report):
            console.print(f"wrote {path}")


def _pulls(cal: CalibrationResult) -> str:
    """Each estimate with its prior and pull, in one line."""
    from optimize.fitting.calibrate import FREE_PARAMETERS, PULL_LIMIT

    parts = []
    beyond = cal.beyond_prior()
    for row in cal.table():
        unit = f" {row['unit']}" if row["unit"] else ""
        width = float(cast(float, row["prior_sigma"]))
        if not math.isfinite(width):
            sigma = "none"
        elif FREE_PARAMETERS[str(row["name"])].kind == "log":
            sigma = f"a factor {math.exp(width):.3g}"
        else:
            sigma = f"{width:.3g}{unit}"
        name = str(row["name"])
        mark = ""
        if name in beyond:
            mark = " (beyond the prior)"
        elif abs(cast(float, row["pull"])) > PULL_LIMIT:
            mark = f" (the data do not pin it there: conflict {cal.conflict():.1f} sigmas)"
        parts.append(
            f"{row['name']} {row['estimate']:.5g}{unit} (nominal {row['nominal']:.5g}, prior "
            f"sigma {sigma}, pull {row['pull']:+.1f}){mark}"
        )
    judged = (
        "the posterior"
        if cal.priors
        else "least squares, judged by the priors"
        if cal.prior_width
        else "no priors given; pulls against the default priors"
    )
    return f"estimates and pulls ({judged}): " + "; ".join(parts)


def _number(value: float | None, spec: str = ".3f") -> str:
    """A table cell: the number, or '-' where the JSON has null."""
    return "-" if value is None else format(value, spec)


def _typed(option: str) -> bool:
    """Whether the user gave ``option`` (rather than its default)."""
    return click.get_current_context().get_parameter_source(option) != ParameterSource.DEFAULT


def _check_size(m: Measurements, folds: int, *, typed: bool, seed: int) -> None:
    """Refuse data too small to diagnose with ``folds``-fold cross-validation: fewer
    distinct configurations than folds, or a training fold with fewer measured numbers
    than the largest model's parameters. The message blames --folds only when ``typed``."""
    from design.model import EFFECTS
    from optimize.fitting.calibrate import configuration_folds, default_free

    if folds < 2:
        raise UserError(f"--folds must be at least 2; got {folds}")
    configurations = len(np.unique(np.round(m.command[m.seen], 12), axis=0))
    if configurations < folds:
        raise UserError(
            f"--folds {folds} needs at least {folds} distinct configurations; {m.source} has "
            f"{configurations}"
            if typed
            else f"{m.source}: {m.rows_text()} with {configurations} distinct seen "
            f"configuration(s) are too few to diagnose: the cross-validation needs at least "
            f"{folds}"
        )
    needed = len(default_free(EFFECTS))
    fold = configuration_folds(m, folds, seed)
    trained = min(coordinates(m.subset(fold != f)) for f in range(folds))
    if trained < needed:
        raise UserError(
            f"{m.source}: too few measurements to diagnose: a cross-validation fold trains "
            f"on {trained} measured numbers, fewer than the {needed} parameters of the "
            "largest model; measure more configurations"
        )
