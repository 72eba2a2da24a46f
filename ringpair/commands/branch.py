"""``ringpair branch``: how the state at one command comes about, as a branch diagram."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from design.branches import branches
from design.units import MM
from ringpair.options import (
    DESIGN,
    OVERWRITE_POLICY,
    angle_option,
    console,
    default_out,
    design_from,
    effects_option,
    model_from,
    one_angle,
    output_path,
    path_option,
    progress,
)


@click.command()
@DESIGN
@angle_option("--theta1", "0", "Distal ring angle [deg].")
@angle_option("--theta2", "0", "Proximal ring angle [deg].")
@effects_option("default")
@click.option(
    "--points",
    type=click.IntRange(11, 2001),
    default=201,
    show_default=True,
    help="Load factors from 0 to 1.",
)
@path_option(
    "--out", help="PNG to write. Default: outputs/<design name>/branch.png. " + OVERWRITE_POLICY
)
def branch(
    design: Path | None, theta1: str, theta2: str, effects: str, points: int, out: Path | None
) -> None:
    """Branch diagram of DESIGN at one (theta1, theta2): how the state comes about.

    The state is the stable equilibrium the robot reaches as its loads (the field, gravity,
    the rings' mutual torque) are brought up from zero with the rings held. The picture
    shows it against the load factor, with its snaps (folds), beside the other equilibria
    at the same command (found at full load, followed back down until they end), solid
    where stable and dashed where not.
    """
    from ringpair.plots import plot_branch_diagram

    d = design_from(design)
    model = model_from(effects).for_design(d)
    command = np.deg2rad([one_angle(theta1, "--theta1"), one_angle(theta2, "--theta2")])
    lam = np.linspace(0.0, 1.0, points)
    typed = out is not None
    out = output_path(
        out or default_out(d.name, "branch.png"),
        "--out",
        folder=False,
        typed=typed,
        inputs=[design],
    )
    with progress("following the branches (the first run on a machine compiles)"):
        path_states, others = branches(model, model.parameters(d), command, lam)
    title = (
        f"{d.name}, {model.name} model, theta1 = {np.rad2deg(command[0]):g} deg, "
        f"theta2 = {np.rad2deg(command[1]):g} deg"
    )
    plot_branch_diagram(path_states, others, lam, title, out)
    snaps = np.flatnonzero(np.diff(path_states.snapped.astype(int)) > 0) + 1
    for k in snaps:
        console.print(f"the state snaps at load factor {lam[k]:.3f}")
    end = path_states.position[-1] / MM
    if path_states.stable[-1]:
        console.print(
            f"state at full load: tip ({end[0]:.2f}, {end[1]:.2f}, {end[2]:.2f}) mm; "
            f"{len(others)} other branch(es) of equilibria"
        )
    else:
        console.print(f"no state at full load: {path_states.failure[-1]}")
    console.print(f"wrote {out}")
