"""``ringpair effects``: how far each model effect moves the tip, against the baseline."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np
from rich.table import Table

from design.model import available_effects
from ringpair.options import (
    DESIGN,
    MAX_CONFIGS,
    OVERWRITE_POLICY,
    angle_option,
    angles,
    check_configurations,
    console,
    default_out,
    design_from,
    output_path,
    path_option,
    progress,
)
from ringpair.tables import effect_shifts, write_csv


@click.command()
@DESIGN
@angle_option(
    "--theta1",
    "0:180:12",
    "Distal ring angles [deg] driven in order (the paper's planar experiment).",
)
@angle_option("--theta2", "0", "Proximal ring angles [deg].")
@path_option(
    "--out",
    help="CSV of the comparison. Default: outputs/<design name>/effects.csv. " + OVERWRITE_POLICY,
)
@MAX_CONFIGS
def effects(
    design: Path | None, theta1: str, theta2: str, out: Path | None, max_configs: int
) -> None:
    """How far each model effect moves the tip of DESIGN, against the paper's baseline.

    Drives the rings through every (theta1, theta2) in order (theta2 fastest) with the
    baseline and with each effect on its own, then with all of them, and prints the largest
    and RMS tip shift [mm] and the largest deflection under each model.
    """
    d = design_from(design)
    t1 = np.deg2rad(angles(theta1, "--theta1"))
    t2 = np.deg2rad(angles(theta2, "--theta2"))
    models = len(available_effects()) + 2  # the baseline, each effect, all of them
    check_configurations(t1.size * t2.size, max_configs, "--theta1 and --theta2", solves=models)
    typed = out is not None
    out = output_path(
        out or default_out(d.name, "effects.csv"),
        "--out",
        folder=False,
        typed=typed,
        inputs=[design],
    )
    with progress("comparing model effects (first use compiles each model)"):
        rows, base_max = effect_shifts(d, t1, t2)
    table = Table(
        title=f"'{d.name}': tip shift of each effect against the baseline "
        f"(baseline largest deflection {base_max:.2f} mm)"
    )
    for col in (
        "effect",
        "max shift (mm)",
        "RMS shift (mm)",
        "largest deflection (mm)",
        "no state",
        "snaps",
    ):
        table.add_column(col, justify="right")
    for r in rows:
        table.add_row(
            str(r["effect"]),
            f"{r['max_shift_mm']:.2f}",
            f"{r['rms_shift_mm']:.2f}",
            f"{r['max_deflection_mm']:.2f}",
            str(r["without_state"]),
            str(r["snaps"]),
        )
    console.print(table)
    write_csv(out, rows, tuple(rows[0]), header=f"ringpair effects, design '{d.name}'")
    console.print(f"wrote {out}")
