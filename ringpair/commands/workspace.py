"""``ringpair workspace``: the reachable tip set over full turns of both rings."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np
from rich.table import Table

from design.atomic import write_text
from design.controllable import Controllable, steerable
from design.equilibrium import solve_design
from design.records import Design
from design.stiffness import tip_stiffness
from design.units import MM
from design.workspace import NoWorkspace, Workspace, angle_grid, sweep_workspace
from ringpair.moved_magnet import MAGNET_COLUMNS, MagnetRequest, magnet_options, magnet_poses
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
    held_run,
    json_text,
    model_from,
    output_path,
    path_option,
    progress,
)
from ringpair.tables import POSE_COLUMNS, pose_rows, write_csv

FILES = (
    "workspace.csv",
    "summary.json",
    "top.png",
    "side.png",
    "section.png",
    "deflection.png",
    "controllable.png",
    "manifest.json",
)
"""What ``workspace`` writes in its folder."""


@click.command()
@DESIGN
@path_option(
    "--out",
    help="Directory for workspace.csv, summary.json and the PNG plots. "
    "Default: outputs/<design name>/workspace. " + OVERWRITE_POLICY,
)
@grid_step_option(5.0)
@effects_option("default")
@magnet_options
@MAX_CONFIGS
def workspace(
    design: Path | None,
    out: Path | None,
    step: float,
    effects: str,
    magnet: MagnetRequest,
    max_configs: int,
) -> None:
    """Sweep (theta1, theta2) over full turns and map the reachable tip set of DESIGN.

    Prints the robot's home (the rings antiparallel, theta1 = 180, theta2 = 0 deg, in the
    model: gravity and the printed tip included) and its droop from the straight tip, the
    disc (the largest disc about home the robot can be steered over from home without a
    snap: size and symmetry in one number; the controllable workspace drives neighbouring
    configurations into each other), the reach beyond home in each direction, the
    deflection range along y and z and the largest deflection and its direction, the disc
    about the straight tip and the neutral (antiparallel) deflection; writes
    workspace.csv, summary.json, top.png (x-y), side.png (x-z), section.png (y-z),
    deflection.png (deflection against theta1 with theta2 = 0) and controllable.png.
    With --magnet-* (one value each) the magnet is held at that pose: the ring pair's
    workspace there, to compare with the design's (summary.json says the pose).
    """
    from ringpair.plots import plot_controllable, write_workspace_plots

    d = design_from(design)
    moves = magnet_poses(d, magnet).one("workspace")
    d = moves.design(d, 0)
    held = f"\n{moves.label()} at {_pose_text(moves.columns(0))}" if moves.moving else ""
    if d.environment.obstacles:
        raise UserError(
            "workspace: the full-turn map with environment.obstacles is not made yet; "
            "`ringpair simulate` solves configurations pressed on them"
        )
    model = model_from(effects).for_design(d)
    check_configurations(len(angle_grid(np.deg2rad(step))) ** 2, max_configs, "--step")
    out = output_path(
        out or default_out(d.name, "workspace"),
        "--out",
        folder=True,
        typed=out is not None,
        files=FILES,
        inputs=[design],
    )
    with held_run(out, "workspace"):
        with progress("sweeping the workspace"):
            try:
                ws = sweep_workspace(d, np.deg2rad(step), model, multistable=True)
            except NoWorkspace as exc:
                raise UserError(
                    f"design '{d.name}' ({model.name} model) has no workspace to map: {exc}; "
                    "nothing written"
                ) from None
            sweep_deg = np.arange(0.0, 360.0 + 1e-9, 1.0)
            sweep = solve_design(d, np.deg2rad(sweep_deg), 0.0, model)
        with progress("driving between neighbouring configurations (the controllable workspace)"):
            ctl = steerable(ws, model, model.parameters(d))
        write_csv(
            out / "workspace.csv",
            pose_rows(
                ws.grid, ws.rest_position, tip_stiffness(model, model.parameters(d), ws.grid)
            ),
            POSE_COLUMNS,
            header=f"ringpair workspace, design '{d.name}', grid step {step:g} deg, "
            f"model {model.name}{held}",
        )
        summary = workspace_summary(ws, d, step, model.name, ctl)
        if moves.source is not None:
            summary["moved_magnet"] = {"source": moves.source.label} | moves.columns(0)
        write_text(out / "summary.json", json_text(summary))
        pictures = write_workspace_plots(ws, sweep, d, out)
        plot_controllable(ws, ctl, out / "controllable.png", model.name)
        pictures.append(out / "controllable.png")
        _print_summary(summary)
    console.print(
        f"wrote {out}/: workspace.csv, summary.json, "
        + ", ".join(p.name for p in pictures)
        + ", manifest.json"
    )


RENAMED = {
    "controllable_disc_radius_mm": "disc_radius_mm",
}
"""Keys of summary.json kept for readers of earlier versions: old name -> the key it equals
(a warning in ``warnings`` says so)."""
WARNINGS = (
    "disc_radius_mm is the disc about the robot's home (rings antiparallel, in the model) "
    "that it can be steered over from home without a snap (issue 49); before, it was the "
    "disc about the straight, weightless tip, now straight_disc_radius_mm",
    "controllable_disc_radius_mm is deprecated: it equals disc_radius_mm",
)


def workspace_summary(
    ws: Workspace, design: Design, step_deg: float, model: str, ctl: Controllable | None = None
) -> dict:
    """The workspace metrics in file units (mm, deg); with ``ctl``, the controllable
    workspace's too and the disc capped by it."""
    direction = ws.max_direction
    disc = ws.disc_radius if ctl is None else ctl.disc_radius
    out = {
        "design": design.name,
        "model": model,
        "grid_step_deg": step_deg,
        "configurations": len(ws.grid),
        "without_state": ws.n_without_state,
        "snapped": ws.n_snapped,
        "multistable": ws.n_multistable,
        "free_length_mm": design.robot.free_length / MM,
        "disc_radius_mm": disc / MM,
        "home_mm": [float(v) / MM for v in ws.home.position],
        "home_stable": ws.home.stable,
        "droop_mm": ws.droop / MM,
        "reach_mm": dict(zip(("+y", "-y", "+z", "-z"), (r / MM for r in ws.reach), strict=True)),
        "workspace_disc_radius_mm": ws.disc_radius / MM,
        "straight_disc_radius_mm": ws.straight_disc_radius / MM,
        "y_range_mm": [v / MM for v in ws.y_range],
        "z_range_mm": [v / MM for v in ws.z_range],
        "max_deflection_mm": ws.max_deflection / MM,
        "max_deflection_percent_of_length": 100 * ws.max_deflection / design.robot.free_length,
        "max_deflection_direction": [float(c) for c in direction],
        "max_deflection_direction_deg": float(np.rad2deg(np.arctan2(direction[2], direction[1]))),
        "max_deflection_theta_deg": [float(np.rad2deg(a)) for a in ws.max_angles],
        "neutral_deflection_mm": ws.neutral_deflection / MM,
        "boundary_excess_mm": ws.boundary_excess / MM,
    }
    if ctl is not None:
        out |= {
            "covered_disc_radius_mm": ctl.covered_disc_radius / MM,
            "covered_resolution_mm": ctl.resolution / MM,
            "controllable_fraction": ctl.fraction,
        }
        out |= {old: out[new] for old, new in RENAMED.items()}
    out["warnings"] = list(WARNINGS[: 1 + (ctl is not None)])
    return out


def _pose_text(pose: dict) -> str:
    """A held pose (MAGNET_COLUMNS) as 'x, y, z mm, turned T deg'."""
    return "{:g}, {:g}, {:g} mm, turned {:g} deg".format(*(pose[c] for c in MAGNET_COLUMNS))


def _print_summary(s: dict) -> None:
    title = f"workspace of '{s['design']}' ({s['model']} model)"
    if "moved_magnet" in s:
        m = s["moved_magnet"]
        title += f", {m['source']} at {_pose_text(m)}"
    table = Table(title=title)
    table.add_column("metric")
    table.add_column("value", justify="right")
    table.add_row(
        "configurations (without a state / snapped / multistable)",
        f"{s['configurations']} ({s['without_state']} / {s['snapped']} / {s['multistable']})",
    )
    table.add_row(
        "home (rings antiparallel): droop from the straight tip", f"{s['droop_mm']:.2f} mm"
    )
    table.add_row("the disc about home, steerable without a snap", f"{s['disc_radius_mm']:.2f} mm")
    table.add_row(
        "reach beyond home +y / -y / +z / -z",
        " / ".join(f"{v:.2f}" for v in s["reach_mm"].values()) + " mm",
    )
    table.add_row("deflection range along y", "{:.2f} .. {:.2f} mm".format(*s["y_range_mm"]))
    table.add_row("deflection range along z", "{:.2f} .. {:.2f} mm".format(*s["z_range_mm"]))
    table.add_row(
        "largest deflection",
        f"{s['max_deflection_mm']:.2f} mm "
        f"({s['max_deflection_percent_of_length']:.1f} % of the length)",
    )
    table.add_row(
        "  its direction (from +y towards +z)", f"{s['max_deflection_direction_deg']:.1f} deg"
    )
    table.add_row(
        "  at theta1, theta2", "{:.1f}, {:.1f} deg".format(*s["max_deflection_theta_deg"])
    )
    table.add_row(
        "largest disc about the straight tip (radius)", f"{s['straight_disc_radius_mm']:.2f} mm"
    )
    if "controllable_fraction" in s:
        table.add_row(
            "configurations steerable from home", f"{100 * s['controllable_fraction']:.1f} %"
        )
    table.add_row("neutral (antiparallel) deflection", f"{s['neutral_deflection_mm']:.3f} mm")
    console.print(table)
