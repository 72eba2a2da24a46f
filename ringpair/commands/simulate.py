"""``ringpair simulate``: the tip pose for every pair of two lists of ring angles."""

from __future__ import annotations

from collections import Counter, deque
from pathlib import Path

import click
import numpy as np
from rich.table import Table

from design.contact import Contact, solve_design_in_contact
from design.equilibrium import Equilibria, solve_design, solve_sequence
from design.geometry import rest_position
from design.model import RingPairModel
from design.moving import MovedSource, pose_parameters
from design.records import Design
from design.stiffness import TipStiffness, tip_stiffness
from design.units import MM
from ringpair.moved_magnet import (
    MAGNET_COLUMNS,
    MAGNET_HEADS,
    MagnetRequest,
    magnet_options,
    magnet_poses,
)
from ringpair.options import (
    DESIGN,
    MAX_CONFIGS,
    OVERWRITE_POLICY,
    UserError,
    angle_option,
    angles,
    check_configurations,
    console,
    default_out,
    design_from,
    effects_option,
    model_from,
    output_path,
    path_option,
    progress,
    warn,
)
from ringpair.tables import POSE_COLUMNS, csv_writer, pose_rows

SHOWN = 60
"""Rows printed at most: the first and last half of them."""
CHUNK = 4096
"""Configurations solved in one call when each is on its own (a progress step, and the
memory bound: rows go to the CSV chunk by chunk)."""


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
    "Proximal ring (catheter) angles [deg], same forms. Every pair of the two lists is simulated.",
)
@path_option(
    "--out",
    help="CSV to write. Default: outputs/<design name>/simulate.csv. " + OVERWRITE_POLICY,
)
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
@magnet_options
@MAX_CONFIGS
def simulate(
    design: Path | None,
    theta1: str,
    theta2: str,
    out: Path | None,
    effects: str,
    ordered: bool,
    no_multistable: bool,
    quiet: bool,
    magnet: MagnetRequest,
    max_configs: int,
) -> None:
    """Tip pose of DESIGN for every (theta1, theta2): a table and a CSV.

    Each pose is the state the robot reaches: on its own, the stable equilibrium connected
    to the unloaded robot as the field and gravity are brought up with the rings held; with
    --ordered, the state reached by driving the listed path. CSV columns: theta1_deg,
    theta2_deg, the tip ring angles, x_mm, y_mm, z_mm (tip, base frame), the tip tangent,
    deflection_mm (from the straight tip), converged, stable, snapped (the robot jumped to
    another branch on the way), multistable (another stable state found at that command; a
    search from a few starts, so false does not prove the state unique),
    failure (why a row has no state; its pose cells are then empty and converged = false),
    stiffness_min_mN_per_mm and stiffness_max_mN_per_mm (the tip's smallest and largest
    principal stiffness at the tracked point, magnetic stiffness included; an inextensible
    rod's axis, along which the model's tip does not give, is left out). With --magnet-*
    (a moved magnet) the columns magnet_x_mm, magnet_y_mm, magnet_z_mm and magnet_turn_deg
    follow theta2_deg, and the ring angles vary fastest; with --ordered too, the magnet is
    driven from row to row in steps of at most 1 mm and 1 deg.
    """
    d = design_from(design)
    model = model_from(effects).for_design(d)
    if ordered and d.environment.obstacles:
        raise UserError(
            "--ordered: a driven path in contact with environment.obstacles is not followed "
            "yet; simulate the configurations on their own (without --ordered)"
        )
    t1 = angles(theta1, "--theta1")
    t2 = angles(theta2, "--theta2")
    moves = magnet_poses(d, magnet)
    source, poses, moving = moves.source, moves.poses, moves.moving
    n = t1.size * t2.size * len(poses)
    what = "--theta1, --theta2 and --magnet-*" if moving else "--theta1 and --theta2"
    check_configurations(n, max_configs, what, held=ordered)
    out = output_path(
        out or default_out(d.name, "simulate.csv"),
        "--out",
        folder=False,
        typed=out is not None,
        inputs=[design],
    )
    g1, g2 = np.meshgrid(np.deg2rad(t1), np.deg2rad(t2), indexing="ij")
    rings = np.column_stack([g1.ravel(), g2.ravel()])
    # (theta1, theta2, magnet centre [m], turn [rad]): the ring angles fastest
    commanded = np.column_stack(
        [np.tile(rings, (len(poses), 1)), np.repeat(poses, len(rings), axis=0)]
    )
    columns = POSE_COLUMNS[:2] + MAGNET_COLUMNS + POSE_COLUMNS[2:] if moving else POSE_COLUMNS
    rest = rest_position(d.robot.free_length)
    step = n if ordered else CHUNK  # a path is solved in one go, from state to state
    head: list[dict] = []
    tail: deque[dict] = deque(maxlen=SHOWN // 2)
    failures: Counter[str] = Counter()  # why rows have no state
    header = f"ringpair simulate, design '{d.name}', model {model.name}"
    if moving:
        header += "\n" + moves.label()
    solving = "solving equilibria (the first run on a machine compiles the model)"
    with progress(solving, total=n) as update, csv_writer(out, columns, header) as put:
        for start in range(0, n, step):
            chunk = commanded[start : start + step]
            eq, stiffness, contact = _states(d, chunk, model, ordered, not no_multistable, source)
            rows = pose_rows(eq, rest, stiffness, contact)
            if moving:
                for row, pose in zip(rows, chunk[:, 2:], strict=True):
                    row.update(
                        zip(MAGNET_COLUMNS, [*(pose[:3] / MM), np.rad2deg(pose[3])], strict=True)
                    )
            put(rows)
            head += rows[: SHOWN - len(head)]
            tail.extend(rows)
            failures.update(row["failure"] for row in rows if not row["converged"])
            update(advance=len(rows))
    if not quiet:
        shown = head if n <= SHOWN else head[: SHOWN // 2] + list(tail)
        _print_rows(shown, n, f"{d.name}: tip poses ({model.name} model)", moves.varied())
    if failures:
        warn(f"{failures.total()} configuration(s) have no state: " + "; ".join(sorted(failures)))
    console.print(f"wrote {out} ({n} configurations)")


def _states(
    d: Design,
    chunk: np.ndarray,
    model: RingPairModel,
    ordered: bool,
    multistable: bool,
    source: MovedSource | None = None,
) -> tuple[Equilibria, TipStiffness, Contact | None]:
    """The states of the configurations ``chunk`` (M, 2) [rad] (with a moved ``source``:
    (M, 6), its centre [m] and turn [rad] after the ring angles), their tip stiffness and,
    with the design's obstacles, their contact (the stiffness then held on the obstacle)."""
    if ordered and source is not None:
        return _moved_path(d, chunk, model.for_design(d), source)
    if ordered:
        eq = solve_design(d, chunk[:, 0], chunk[:, 1], model, ordered=True)
        return eq, tip_stiffness(model, model.parameters(d), eq), None
    params = None
    if source is not None:
        params = pose_parameters(model.for_design(d), d, source, chunk[:, 2:5], chunk[:, 5])
    return solve_design_in_contact(
        d, model, chunk[:, 0], chunk[:, 1], multistable=multistable, params=params
    )


POSE_STEP = (1.0 * MM, np.deg2rad(1.0))
"""Largest change of the moved magnet's centre [m] and turn [rad] between two states of a
driven path: between listed rows the path is refined to these steps (the solver's
sub-steps follow the ring angles alone)."""


def _moved_path(
    d: Design, rows: np.ndarray, model: RingPairModel, source: MovedSource
) -> tuple[Equilibria, TipStiffness, None]:
    """The states along the listed ``rows`` (M, 6): ring angles [rad], the moved magnet's
    centre [m] and turn [rad], driven in order. Between two rows the magnet moves in steps
    of at most POSE_STEP (the rings' angles with it, linearly); a row is ``snapped``
    where the robot jumped on the way from the row before."""
    pieces, listed = [rows[:1]], [0]
    for a, b in zip(rows[:-1], rows[1:], strict=True):
        moves = np.r_[np.abs(b[2:5] - a[2:5]).max() / POSE_STEP[0], abs(b[5] - a[5]) / POSE_STEP[1]]
        n = max(1, int(np.ceil(moves.max() - 1e-9)))
        pieces.append(a + np.outer(np.arange(1, n + 1) / n, b - a))
        listed.append(listed[-1] + n)
    path = np.vstack(pieces)
    params = pose_parameters(model, d, source, path[:, 2:5], path[:, 5])
    eq = solve_sequence(model, params, path[:, 0], path[:, 1])
    snapped = np.maximum.reduceat(eq.snapped.astype(int), [0, *(np.array(listed[:-1]) + 1)])
    fields = {k: v[listed] for k, v in eq.__dict__.items()}
    fields["snapped"] = snapped.astype(bool)
    kept = Equilibria(**fields)
    return kept, tip_stiffness(model, params[:, listed], kept), None


def _print_rows(shown: list[dict], n: int, title: str, magnet: tuple[str, ...] = ()) -> None:
    """The poses as a table (the ``shown`` rows, at most SHOWN of ``n``), with each row's
    state (and the moved magnet's pose columns ``magnet``, those that vary)."""
    table = Table(title=title)
    for col in (
        "theta1 [deg]",
        "theta2 [deg]",
        *(MAGNET_HEADS[c] for c in magnet),
        "x [mm]",
        "y [mm]",
        "z [mm]",
        "deflection (mm)",
        "state",
    ):
        table.add_column(col, justify="right")
    for row in shown:
        flags = ["snapped"] * row["snapped"] + ["multistable"] * row["multistable"]
        state = ", ".join(["stable", *flags]) if row["stable"] else "NO STATE"
        table.add_row(
            *(
                f"{row[k]:.2f}"
                for k in (
                    "theta1_deg",
                    "theta2_deg",
                    *magnet,
                    "x_mm",
                    "y_mm",
                    "z_mm",
                    "deflection_mm",
                )
            ),
            state,
        )
    console.print(table)
    if n > len(shown):
        console.print(f"({n - len(shown)} rows not shown)")
