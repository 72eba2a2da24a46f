"""``ringpair calibrate``: the model's uncertain parameters fitted to measured data."""

from __future__ import annotations

from pathlib import Path
from typing import cast

import click
import numpy as np
from rich.table import Table

from design.atomic import write_text
from design.registry import current
from design.suggest import did_you_mean
from ringpair.fit_checks import coordinates, fit_warnings, out_of_reach
from ringpair.options import (
    CSV_DESIGN,
    DATA,
    OVERWRITE_POLICY,
    UserError,
    bad_input,
    console,
    effects_option,
    json_text,
    measured_data,
    model_from,
    output_path,
    path_option,
    progress,
    warn,
)
from ringpair.tables import estimate_text


@click.command()
@DATA
@CSV_DESIGN
@effects_option("none")
@click.option(
    "--free",
    default=None,
    help="Comma list of the parameters to fit. Default: bending_rigidity_scale and "
    "external_center_x/y/z, plus each effect's own (torsion scales, friction angles, tip mass).",
)
@click.option("--priors", is_flag=True, help="Add Gaussian priors centred on the nominal design.")
@click.option(
    "--profile",
    is_flag=True,
    help="Also give each parameter's 1-sigma profile-likelihood interval (it fixed, the others "
    "refitted): right where parameters trade off nonlinearly, where standard errors are not.",
)
@path_option(
    "--json",
    "json_out",
    help="Also write the estimates, standard errors, correlations and errors as JSON (SI). "
    + OVERWRITE_POLICY,
)
def calibrate(
    data: Path,
    design_path: Path | None,
    effects: str,
    free: str | None,
    priors: bool,
    profile: bool,
    json_out: Path | None,
) -> None:
    """Fit the model's uncertain physical parameters to measured DATA (a data-set folder
    or a CSV, docs/formats.md) by least squares with exact Jacobians; print the estimates
    with their standard errors, and the RMS and largest tip error.

    The fit starts from the nominal design; with torsion also from stiff and from soft
    transmissions (a local fit cannot cross a snap-through of the rings), and the best
    is kept. Data with a sequence are also fitted along their path where driving it ends
    in other states (a multistable robot)."""
    from optimize.fitting.calibrate import FREE_PARAMETERS, calibrate_from_starts, default_free
    from optimize.fitting.likelihood import profile_intervals

    if profile and priors:
        raise UserError("--profile is for fits without --priors (it profiles the data's misfit)")

    d, m = measured_data(data, design_path)
    model = model_from(effects)
    typed = () if free is None else [n.strip() for n in free.split(",") if n.strip()]
    names = None if free is None else tuple(current(n) for n in typed)
    for n in names or ():
        if n not in FREE_PARAMETERS:
            raise UserError(
                f"--free: {n!r} cannot be calibrated{did_you_mean(n, FREE_PARAMETERS)} "
                f"(expected names from {', '.join(FREE_PARAMETERS)})"
            )
    if json_out is not None:
        output_path(json_out, "--json", folder=False, inputs=[data, design_path])
    freed = names or default_free(model.effects)
    if coordinates(m) < len(freed) and not priors:
        raise UserError(
            f"{m.source}: {coordinates(m)} measured number(s) in {m.rows_text()} cannot "
            f"determine {len(freed)} parameters ({', '.join(freed)}); measure more "
            "configurations" + (" or free fewer" if free is not None else "")
        )
    warnings = out_of_reach(d, m)
    for w in warnings:
        warn(w)
    fitting = "fitting (the first run on a machine compiles the model)"
    with progress(fitting), bad_input(ValueError, prefix=f"{m.source}: "):
        res, tried = calibrate_from_starts(d, m, model.effects, names, priors=priors)
    intervals = {}
    if profile:
        with progress("profile likelihood"):
            intervals = profile_intervals(d, m, res, res.names)
    table = Table(title=f"calibration of '{d.name}' ({model.name} model) on {m.rows_text()}")
    columns = ["parameter", "nominal", "estimate", "std. error"]
    for col in columns + (["1-sigma profile interval"] if profile else []) + ["unit"]:
        table.add_column(col, justify="right")
    for row in res.table():
        cells = [
            str(row["name"]),
            f"{row['nominal']:.5g}",
            estimate_text(cast(float, row["estimate"]), cast(float, row["standard_error"])),
            f"{row['standard_error']:.2g}",
        ]
        if profile:
            iv, factor = intervals[str(row["name"])], FREE_PARAMETERS[str(row["name"])].label[1]
            cells.append(f"{iv.lower * factor:.4g} to {iv.upper * factor:.4g}")
        table.add_row(*cells, str(row["unit"]))
    console.print(table)
    console.print(
        f"tip error: RMS {res.rmse_mm:.3f} mm, largest {res.max_abs_mm:.3f} mm; implied noise "
        f"{res.noise_mm:.3f} mm per coordinate; "
        + ("converged" if res.converged else "NOT converged")
        + f" ({res.evaluations} solves, {res.time_s:.2f} s)"
    )
    if len(tried) > 1:
        console.print(
            f"best of {len(tried)} fits (tip error RMS "
            + ", ".join(f"{label} {fit.rmse_mm:.3f} mm" for label, fit in tried.items())
            + (
                "; stiff and soft: the transmissions' torsional rigidity 10x and 0.5x nominal"
                if "stiff" in tried
                else ""
            )
            + ")"
        )
    if res.at_bounds:
        warn(f"at a bound: {', '.join(res.at_bounds)}")
    later = fit_warnings(d, m, res)
    for w in later:
        warn(w)
    warnings += later
    if json_out is not None:
        doc = {
            "design": d.name,
            "model": model.name,
            "rows": len(m),
            "estimate": res.estimate,
            "standard_error": res.standard_error,
            "nominal": res.nominal,
            **(
                {"profile_interval": {k: [v.lower, v.upper] for k, v in intervals.items()}}
                if profile
                else {}
            ),
            "correlation": np.round(res.correlation, 6).tolist(),
            "rmse_mm": res.rmse_mm,
            "max_abs_mm": res.max_abs_mm,
            "noise_mm": res.noise_mm,
            "converged": res.converged,
            "message": res.message,
            "starts_rmse_mm": {label: fit.rmse_mm for label, fit in tried.items()},
            "warnings": warnings,
        }
        write_text(json_out, json_text(doc))
        console.print(f"wrote {json_out}")
