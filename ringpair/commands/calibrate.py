"""``ringpair calibrate``: the model's uncertain parameters fitted to measured data."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, cast

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
    NO_PRIORS,
    OVERWRITE_POLICY,
    PRIOR,
    UserError,
    bad_input,
    console,
    effects_option,
    json_text,
    measured_data,
    model_from,
    output_path,
    path_option,
    priors_from,
    progress,
    warn,
)
from ringpair.tables import estimate_text

if TYPE_CHECKING:
    from design.records import Design
    from optimize.fitting.measurements import Measurements


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
@click.option(
    "--priors",
    is_flag=True,
    hidden=True,
    help="Gaussian priors centred on the nominal design (the default; kept for old scripts).",
)
@PRIOR
@NO_PRIORS
@click.option(
    "--paper",
    is_flag=True,
    help="Also fit the paper's own two-factor model (stiffness scale K_E, field scale K_B, "
    "exhaustive grid minimising the largest tip error) and judge both fits by the priors.",
)
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
    prior_texts: tuple[str, ...],
    no_priors: bool,
    paper: bool,
    profile: bool,
    json_out: Path | None,
) -> None:
    """Fit the model's uncertain physical parameters to measured DATA (a data-set folder
    or a CSV, docs/formats.md) by least squares with exact Jacobians; print the estimates
    with their standard errors, and the RMS and largest tip error.

    The fit maximises the posterior: every free parameter has a prior about its nominal
    value (defaults from the registry; a data-set folder's priors.toml and --prior override
    them; --no-priors: plain least squares), and each estimate is printed with its pull,
    how many prior sigmas it moved; one beyond 3 is not physical.

    The fit starts from the nominal design; with torsion also from stiff and from soft
    transmissions (a local fit cannot cross a snap-through of the rings), and the best
    is kept. Data with a sequence are also fitted along their path where driving it ends
    in other states (a multistable robot)."""
    from optimize.fitting.calibrate import (
        FREE_PARAMETERS,
        PULL_LIMIT,
        calibrate_from_starts,
        default_free,
    )
    from optimize.fitting.likelihood import profile_intervals

    d, m = measured_data(data, design_path)
    if priors and no_priors:
        raise UserError("--priors and --no-priors contradict each other")
    fit_priors = priors_from(data, prior_texts, no_priors)
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
    if coordinates(m) < len(freed):  # (priors are no data: calibrate refuses it too)
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
        res, tried = calibrate_from_starts(d, m, model.effects, names, priors=fit_priors)
    intervals = {}
    if profile:
        with progress("profile likelihood"):
            intervals = profile_intervals(d, m, res, res.names)
    table = Table(title=f"calibration of '{d.name}' ({model.name} model) on {m.rows_text()}")
    columns = ["parameter", "nominal", "estimate", "std. error"]
    pulled = ["prior sigma", "pull"]
    for col in columns + (["1-sigma profile interval"] if profile else []) + ["unit", *pulled]:
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
        table.add_row(*cells, str(row["unit"]), *_prior_cells(row))
    console.print(table)
    beyond = res.beyond_prior()
    if beyond:
        warn(
            "not physical: "
            + ", ".join(f"{n} moved {p:+.1f} prior sigmas" for n, p in beyond.items())
            + f" (beyond {PULL_LIMIT:g}); the set-up is not as the design file says, or the "
            "model lacks an effect these parameters absorb"
        )
    paper_doc = _paper(d, m, model.effects) if paper else None
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
            "priors": bool(res.priors),
            "prior_width": {n: res.width(n) for n in res.names},
            "pull": res.pulls(),
            "beyond_prior": beyond,
            **({"paper": paper_doc} if paper_doc is not None else {}),
            "warnings": warnings,
        }
        write_text(json_out, json_text(doc))
        console.print(f"wrote {json_out}")


def _prior_cells(row: dict[str, object]) -> list[str]:
    """A parameter's prior width (a factor for a log-fitted one) and pull, as cells."""
    width, pull = cast(float, row["prior_sigma"]), cast(float, row["pull"])
    if not math.isfinite(width):
        return ["none", "-"]
    if row["unit"] == "" and str(row["name"]) in _log_fitted():
        return [f"x/ {math.exp(width):.3g}", f"{pull:+.1f}"]
    return [f"{width:.3g}", f"{pull:+.1f}"]


def _log_fitted() -> set[str]:
    from optimize.fitting.calibrate import FREE_PARAMETERS

    return {n for n, s in FREE_PARAMETERS.items() if s.kind == "log"}


def _paper(d: Design, m: Measurements, effects: frozenset[str]) -> dict[str, object]:
    """The paper's two-factor fit (an exhaustive grid over K_E and K_B minimising the
    largest tip error, :func:`optimize.fitting.paper_grid.grid_search_two_factors`),
    printed with what it needs of the physical parameters and their pulls against the
    default priors; its JSON block."""
    from optimize.fitting.calibrate import PULL_LIMIT, grid_search_two_factors
    from optimize.fitting.paper_grid import paper_pulls

    with progress("the paper's two-factor grid (10 x 101 points)"):
        grid = grid_search_two_factors(d, m, effects)
    pulls = paper_pulls(d, grid.stiffness_scale, grid.field_scale)
    beyond = {n: p for n, p in pulls.items() if abs(p) > PULL_LIMIT}
    console.print(
        f"the paper's fit: K_E = {grid.stiffness_scale:.4g} (bending rigidity), K_B = "
        f"{grid.field_scale:.4g} (the external dipole's moment and its position from the "
        f"base), tip error RMS {grid.rmse_mm:.3f} mm, largest {grid.max_abs_mm:.3f} mm; pulls "
        + ", ".join(f"{n} {p:+.1f}" for n, p in pulls.items())
        + (
            f": not physical ({', '.join(beyond)} beyond {PULL_LIMIT:g} prior sigmas)"
            if beyond
            else ": physical (every pull within the priors)"
        )
    )
    return {
        "stiffness_scale": grid.stiffness_scale,
        "field_scale": grid.field_scale,
        "rmse_mm": grid.rmse_mm,
        "max_abs_mm": grid.max_abs_mm,
        "pull": pulls,
        "beyond_prior": beyond,
        "physical": not beyond,
    }
