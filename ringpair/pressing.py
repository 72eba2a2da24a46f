"""``ringpair steer --press``: the ring angles that press the tip on the design's
obstacles with a given force (:mod:`design.pressing`), their CSV and picture."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from design.geometry import rest_position
from design.model import RingPairModel
from design.pressing import PRESS_TOLERANCE, press
from design.records import Design
from ringpair.options import (
    UserError,
    check_configurations,
    console,
    csv_with_picture,
    default_out,
    progress,
)
from ringpair.plots import plot_force_map
from ringpair.tables import POSE_COLUMNS, pose_rows, write_csv

PRESS_STEP = 10.0
"""The ring grid's step for --press unless --step says otherwise. [deg]"""


def steer_press(
    d: Design,
    model: RingPairModel,
    design: Path | None,
    wanted_mn: float,
    step_deg: float | None,
    out: Path | None,
    max_configs: int,
) -> None:
    """The answers of ``steer --press wanted_mn`` (mN) for ``d``: CSV (simulate's columns,
    one row per answer) and the force map with the answers marked beside it (.png)."""
    if not d.environment.obstacles:
        raise UserError(
            f"--press: the design '{d.name}' has no [[environment.obstacles]] to press on; "
            "add a plane, sphere or lumen (docs/formats.md)"
        )
    if not np.isfinite(wanted_mn) or wanted_mn <= 0:
        raise UserError(f"--press: expected a force > 0 in mN, got {wanted_mn:g}")
    step = PRESS_STEP if step_deg is None else step_deg
    grid = int(round(360.0 / step))
    check_configurations(grid**2, max_configs, "--step")
    out, picture = csv_with_picture(
        out, default_out(d.name, "steer_press.csv"), "--press", "the force map", [design]
    )
    with progress(f"finding the ring angles that press with {wanted_mn:g} mN"):
        result = press(d, model, wanted_mn * 1e-3, np.deg2rad(step))
    rows = pose_rows(
        result.equilibria, rest_position(d.robot.free_length), result.stiffness, result.contact
    )
    write_csv(
        out,
        rows,
        POSE_COLUMNS,
        header=(
            f"ringpair steer --press {wanted_mn:g} (mN), design '{d.name}', model {model.name}, "
            f"grid step {step:g} deg: each row presses with the force to "
            f"{PRESS_TOLERANCE * 1e3:g} mN"
        ),
    )
    map_mn = np.where(result.magnitude > 0, result.magnitude * 1e3, np.nan)
    plot_force_map(
        np.rad2deg(result.grid),
        map_mn,
        picture,
        f"{d.name}: pressing with {wanted_mn:g} mN ({model.name} model)",
        np.rad2deg(result.theta),
        f"{wanted_mn:g} mN",
    )
    console.print(_said(result, wanted_mn, step))
    console.print(f"wrote {out} ({len(rows)} row(s)) and {picture}")


def _said(result, wanted_mn: float, step: float) -> str:  # noqa: ANN001 - a Pressing
    """What the search found, in a sentence or two."""
    pressing = result.magnitude[np.isfinite(result.magnitude) & (result.magnitude > 0)]
    if not len(result.theta):
        if not len(pressing):
            return "the tip presses on no obstacle at any ring angles of the grid"
        return (
            f"no ring angles press with {wanted_mn:g} mN: over the grid the tip presses with "
            f"{pressing.min() * 1e3:.3g} to {pressing.max() * 1e3:.3g} mN"
        )
    said = (
        f"{len(result.theta)} ring-angle pair(s) press with {wanted_mn:g} mN: where the "
        f"curves of that force cross the {step:g} deg grid's lines (a finer --step samples "
        "them more densely)"
    )
    if result.jumps:
        said += f"; across {result.jumps} grid edge(s) the force jumps past it (no answer there)"
    return said
