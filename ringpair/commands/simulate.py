"""``ringpair simulate``: the tip pose for every pair of two lists of ring angles."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np
from rich.table import Table

from design.equilibrium import solve_design
from design.geometry import rest_position
from ringpair.options import (
    DESIGN,
    angle_option,
    angles,
    console,
    default_out,
    design_from,
    effects_option,
    err_console,
    model_from,
    path_option,
)
from ringpair.tables import POSE_COLUMNS, pose_rows, write_csv

SHOWN = 60
"""Rows printed at most: the first and last half of them."""


@click.command()
@DESIGN
@angle_option(
    "--theta1",
    "0:180:12",
    "Distal ring (wire) angles [deg]: START:STOP:STEP, a comma list or one value.",
)
@angle_option(
    "--theta2",
    "0",
    "Proximal ring (catheter) angles [deg], same forms. Every pair of the two "
    "lists is simulated.",
)
@path_option("--out", help="CSV to write. Default: outputs/<design name>/simulate.csv.")
@effects_option("default")
@click.option(
    "--ordered",
    is_flag=True,
    help="Drive the rings through the configurations in the listed order (theta2 varying "
    "fastest), each state starting from the previous one: needed for hysteresis and to see "
    "snap-through along a path. Default: each configuration on its own, the state the robot "
    "reaches when its loads are brought up with the rings held.",
)
@click.option(
    "--no-multistable",
    is_flag=True,
    help="Skip the search for other stable states at each command (faster).",
)
@click.option("--quiet", is_flag=True, help="Do not print the table.")
def simulate(
    design: Path | None,
    theta1: str,
    theta2: str,
    out: Path | None,
    effects: str,
    ordered: bool,
    no_multistable: bool,
    quiet: bool,
) -> None:
    """Tip pose of DESIGN for every (theta1, theta2): a table and a CSV.

    Each pose is the state the robot reaches: on its own, the stable equilibrium connected
    to the unloaded robot as the field and gravity are brought up with the rings held; with
    --ordered, the state reached by driving the listed path. CSV columns: theta1_deg,
    theta2_deg, the tip ring angles, x_mm, y_mm, z_mm (tip, base frame), the tip tangent,
    deflection_mm (from the straight tip), converged, stable, snapped (the robot jumped to
    another branch on the way), multistable (another stable state exists at that command),
    failure (why a row has no state; its pose cells are then empty and converged = false).
    """
    d = design_from(design)
    model = model_from(effects)
    t1 = angles(theta1, "--theta1")
    t2 = angles(theta2, "--theta2")
    g1, g2 = np.meshgrid(t1, t2, indexing="ij")
    commanded = np.column_stack([g1.ravel(), g2.ravel()])
    with console.status("solving equilibria (the first run on a machine compiles the model)"):
        eq = solve_design(
            d,
            np.deg2rad(commanded[:, 0]),
            np.deg2rad(commanded[:, 1]),
            model,
            ordered,
            multistable=not (ordered or no_multistable),
        )
    rest = rest_position(d.robot.free_length)
    rows = pose_rows(eq, rest)
    out = out or default_out(d.name, "simulate.csv")
    write_csv(
        out, rows, POSE_COLUMNS, header=f"ringpair simulate, design '{d.name}', model {model.name}"
    )
    if not quiet:
        _print_rows(rows, f"{d.name}: tip poses ({model.name} model)")
    n_bad = int(np.count_nonzero(~eq.converged))
    if n_bad:
        reasons = sorted(set(eq.failure[~eq.converged]))
        err_console.print(
            f"[yellow]warning:[/] {n_bad} configuration(s) have no state: " + "; ".join(reasons)
        )
    console.print(f"wrote {out} ({len(rows)} configurations)")


def _print_rows(rows: list[dict], title: str) -> None:
    """The poses as a table (at most SHOWN rows), with each row's state."""
    table = Table(title=title)
    for col in (
        "theta1 [deg]",
        "theta2 [deg]",
        "x [mm]",
        "y [mm]",
        "z [mm]",
        "deflection (mm)",
        "state",
    ):
        table.add_column(col, justify="right")
    half = SHOWN // 2
    shown = rows if len(rows) <= SHOWN else rows[:half] + rows[-half:]
    for row in shown:
        flags = ["snapped"] * row["snapped"] + ["multistable"] * row["multistable"]
        state = ", ".join(["stable", *flags]) if row["stable"] else "NO STATE"
        table.add_row(
            *(
                f"{row[k]:.2f}"
                for k in ("theta1_deg", "theta2_deg", "x_mm", "y_mm", "z_mm", "deflection_mm")
            ),
            state,
        )
    console.print(table)
    if len(rows) > SHOWN:
        console.print(f"({len(rows) - SHOWN} rows not shown)")
