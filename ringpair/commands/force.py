"""``ringpair force``: the force map, how hard the tip presses on the design's obstacles
over the ring grid."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from design.atomic import write_text
from design.contact import solve_design_in_contact
from design.geometry import rest_position
from design.workspace import angle_grid
from ringpair.options import (
    DESIGN,
    MAX_CONFIGS,
    OVERWRITE_POLICY,
    UserError,
    check_configurations,
    console,
    default_out,
    design_from,
    effects_option,
    grid_step_option,
    json_text,
    model_from,
    output_path,
    path_option,
    progress,
)
from ringpair.plots import plot_force_map
from ringpair.tables import POSE_COLUMNS, pose_rows, write_csv

FILES = ("force.csv", "summary.json", "force.png")
"""What ``force`` writes in its folder."""


@click.command()
@DESIGN
@path_option(
    "--out",
    help="Directory for force.csv, summary.json and force.png. "
    "Default: outputs/<design name>/force. " + OVERWRITE_POLICY,
)
@grid_step_option(10.0)
@effects_option("default")
@MAX_CONFIGS
def force(
    design: Path | None, out: Path | None, step: float, effects: str, max_configs: int
) -> None:
    """The force map of DESIGN: over a full-turn grid of both rings, the force the tip
    exerts on the design's obstacles ([[environment.obstacles]]), with the tip stiffness.

    Writes force.csv (simulate's columns for every configuration), summary.json (how many
    configurations press, the range of the force's magnitude and of each component, the
    largest force, its direction and ring angles) and force.png (the force's magnitude
    over both ring angles).
    """
    d = design_from(design)
    if not d.environment.obstacles:
        raise UserError(
            f"force: the design '{d.name}' has no [[environment.obstacles]]; add a plane, "
            "sphere or lumen for the tip to press on (docs/formats.md)"
        )
    model = model_from(effects)
    grid = angle_grid(np.deg2rad(step))
    check_configurations(grid.size**2, max_configs, "--step")
    out = output_path(
        out or default_out(d.name, "force"),
        "--out",
        folder=True,
        typed=out is not None,
        files=FILES,
    )
    t1, t2 = (a.ravel() for a in np.meshgrid(grid, grid, indexing="ij"))
    with progress("pressing the tip on the obstacles over the ring grid"):
        eq, stiffness, contact = solve_design_in_contact(d, model, t1, t2)
    rest = rest_position(d.robot.free_length)
    write_csv(
        out / "force.csv",
        pose_rows(eq, rest, stiffness, contact),
        POSE_COLUMNS,
        header=f"ringpair force, design '{d.name}', grid step {step:g} deg, model {model.name}",
    )
    magnitude = np.linalg.norm(contact.force, axis=1) * 1e3
    pressed = contact.in_contact
    summary: dict = {
        "design": d.name,
        "model": model.name,
        "grid_step_deg": step,
        "configurations": int(t1.size),
        "pressing": int(pressed.sum()),
        "without_state": int((~eq.stable).sum()),
    }
    if pressed.any():
        k = int(np.argmax(np.where(pressed, magnitude, -np.inf)))
        f = contact.force[pressed] * 1e3 + 0.0  # (no -0)
        summary.update(
            {
                "force_min_mN": float(magnitude[pressed].min()),
                "force_max_mN": float(magnitude[k]),
                "largest_at_deg": [round(float(np.rad2deg(t)), 9) for t in (t1[k], t2[k])],
                "largest_direction": (contact.force[k] / magnitude[k] * 1e3 + 0.0).tolist(),
                "component_range_mN": {
                    a: [float(f[:, i].min()), float(f[:, i].max())] for i, a in enumerate("xyz")
                },
                "stiffness_min_mN_per_mm": float(np.nanmin(stiffness.lowest[pressed])),
            }
        )
    write_text(out / "summary.json", json_text(summary))
    plot_force_map(
        np.rad2deg(grid),
        np.where(pressed, magnitude, np.nan).reshape(grid.size, grid.size),
        out / "force.png",
        f"{d.name}: force on the obstacles ({model.name} model)",
    )
    said = f"{summary['pressing']} of {summary['configurations']} configurations press"
    if pressed.any():
        at = summary["largest_at_deg"]
        said += (
            f", {summary['force_min_mN']:.3g} to {summary['force_max_mN']:.3g} mN, the largest "
            f"at theta1 = {at[0]:g}, theta2 = {at[1]:g} deg"
        )
    console.print(said)
    console.print(f"wrote {out}/: " + ", ".join(FILES))
