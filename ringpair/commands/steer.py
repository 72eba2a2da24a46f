"""``ringpair steer``: the ring angles that put the tip at given points."""

from __future__ import annotations

import csv
from pathlib import Path

import click
import numpy as np
from rich.table import Table

from design.steering import REACHED, Steering, steer
from design.units import MM
from ringpair.options import (
    DESIGN,
    UserError,
    console,
    default_out,
    design_from,
    effects_option,
    model_from,
    output_path,
    path_option,
)
from ringpair.tables import write_csv

MAX_TARGETS = 100_000
"""Targets per run at most (about a minute with the baseline model, far more with the
model for design work)."""

STEER_COLUMNS = (
    "target",
    "target_y_mm",
    "target_z_mm",
    "theta1_deg",
    "theta2_deg",
    "x_mm",
    "y_mm",
    "z_mm",
    "tangent_x",
    "tangent_y",
    "tangent_z",
    "error_mm",
    "reached",
    "stable",
    "snapped",
    "multistable",
    "fold_margin",
)


def parse_target(text: str, where: str) -> tuple[float, float]:
    """'Y,Z' in mm as (y, z) [mm]; ``where`` names the option or file row in errors."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise UserError(f"{where}: expected Y,Z in mm (two numbers), got {text!r}") from None
    if len(values) != 2 or not np.isfinite(values).all():
        raise UserError(f"{where}: expected Y,Z in mm (two finite numbers), got {text!r}")
    return values[0], values[1]


def read_targets(path: Path) -> list[tuple[float, float]]:
    """Targets from a CSV with columns y_mm, z_mm (lines starting with # are comments). [mm]"""
    try:
        lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"--targets: cannot read {path}: {exc}") from None
    reader = csv.DictReader(lines)
    missing = {"y_mm", "z_mm"} - set(reader.fieldnames or ())
    if missing:
        raise UserError(
            f"{path}: expected columns y_mm, z_mm; missing {', '.join(sorted(missing))}"
        )
    targets = [
        parse_target(f"{row['y_mm']},{row['z_mm']}", f"{path} line {k + 2}")
        for k, row in enumerate(reader)
    ]
    if not targets:
        raise UserError(f"{path}: no targets (expected rows of y_mm, z_mm)")
    return targets


def steer_rows(result: Steering) -> list[dict]:
    """One row per solution (or closest point) in file units (mm, deg)."""
    rows = []
    for k in range(len(result)):
        p, t = result.position[k] / MM, result.tangent[k]
        rows.append(
            {
                "target": int(result.target_index[k]) + 1,
                "target_y_mm": result.target[k, 0] / MM,
                "target_z_mm": result.target[k, 1] / MM,
                "theta1_deg": np.rad2deg(result.theta[k, 0]),
                "theta2_deg": np.rad2deg(result.theta[k, 1]),
                "x_mm": p[0],
                "y_mm": p[1],
                "z_mm": p[2],
                "tangent_x": t[0],
                "tangent_y": t[1],
                "tangent_z": t[2],
                "error_mm": result.error[k] / MM,
                "reached": bool(result.reached[k]),
                "stable": bool(result.stable[k]),
                "snapped": bool(result.snapped[k]),
                "multistable": bool(result.multistable[k]),
                "fold_margin": result.fold_margin[k],
            }
        )
    return rows


@click.command("steer")
@DESIGN
@click.option(
    "--to",
    "to",
    multiple=True,
    metavar="Y,Z",
    help="A target for the tip: its y and z in mm, base frame (repeat for more).",
)
@path_option("--targets", help="CSV of targets, columns y_mm, z_mm.")
@path_option("--out", help="CSV to write. Default: outputs/<design name>/steer.csv.")
@effects_option("default")
@click.option("--quiet", is_flag=True, help="Do not print the table.")
def steer_command(
    design: Path | None,
    to: tuple[str, ...],
    targets: Path | None,
    out: Path | None,
    effects: str,
    quiet: bool,
) -> None:
    """The ring angles that put the tip of DESIGN at each target (y, z).

    Every pair of ring angles whose state (the stable equilibrium the robot reaches with
    the rings held there) puts the tip on the target, to 1e-6 mm: the ring pair has
    several, typically mirror pairs. Each comes with its state's flags, its fold margin
    (1 for the unloaded robot, 0 at a fold where it snaps: how far from snapping) and the
    tip tangent. A target out of reach gets the closest reachable point, flagged
    reached = false, with its distance. CSV columns: target (1-based), target_y_mm,
    target_z_mm, theta1_deg, theta2_deg, x_mm, y_mm, z_mm, the tip tangent, error_mm,
    reached, stable, snapped, multistable, fold_margin.
    """
    d = design_from(design)
    model = model_from(effects)
    points = [parse_target(t, "--to") for t in to]
    if targets is not None:
        points += read_targets(targets)
    if not points:
        raise UserError("give a target: --to Y,Z (mm) or --targets FILE.csv")
    limit = d.robot.free_length / MM
    far = [p for p in points if np.hypot(*p) > limit]
    if far:
        raise UserError(
            f"target {far[0][0]:g},{far[0][1]:g} mm is farther from the robot's axis than its "
            f"free length ({limit:g} mm): no tip can get there (are the units mm?)"
        )
    if len(points) > MAX_TARGETS:
        raise UserError(
            f"{len(points):,} targets; at most {MAX_TARGETS:,} per run (split the file)"
        )
    out = output_path(
        out or default_out(d.name, "steer.csv"),
        "--out",
        folder=False,
        typed=out is not None,
        inputs=[design, targets],
    )
    with console.status(
        f"steering to {len(points)} target(s) (the first run on a machine compiles the model)"
    ):
        result = steer(model, model.parameters(d), np.array(points) * MM)
    rows = steer_rows(result)
    write_csv(
        out, rows, STEER_COLUMNS, header=f"ringpair steer, design '{d.name}', model {model.name}"
    )
    if not quiet:
        _print(rows, f"{d.name}: ring angles for each target ({model.name} model)")
    console.print(f"wrote {out} ({len(points)} target(s), {len(rows)} row(s))")


def _print(rows: list[dict], title: str) -> None:
    """The solutions as a table, then a plain sentence for each target out of reach."""
    table = Table(title=title)
    for col in (
        "target [mm]",
        "theta1 [deg]",
        "theta2 [deg]",
        "tip y, z [mm]",
        "fold margin",
        "state",
    ):
        table.add_column(col, justify="right")
    for row in rows:
        if not row["stable"]:
            state = "no state"
        elif row["reached"]:
            state = ", ".join(
                ["reached"] + ["snapped"] * row["snapped"] + ["multistable"] * row["multistable"]
            )
        else:
            state = "out of reach"
        table.add_row(
            f"{row['target_y_mm']:.2f}, {row['target_z_mm']:.2f}",
            f"{row['theta1_deg']:.3f}",
            f"{row['theta2_deg']:.3f}",
            f"{row['y_mm']:.3f}, {row['z_mm']:.3f}",
            f"{row['fold_margin']:.3f}",
            state,
        )
    console.print(table)
    console.print(f"reached: the tip within {REACHED / MM:g} mm of the target.")
    for row in rows:
        where = f"target {row['target']} ({row['target_y_mm']:g}, {row['target_z_mm']:g}) mm"
        if not row["stable"]:
            console.print(f"{where}: no configuration near it has a state.")
        elif not row["reached"]:
            console.print(
                f"{where} is OUT OF REACH: the closest point, ({row['y_mm']:.3f}, "
                f"{row['z_mm']:.3f}) mm, is {row['error_mm']:.3f} mm away."
            )
