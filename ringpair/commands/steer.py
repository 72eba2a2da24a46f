"""``ringpair steer``: the ring angles that put the tip at given points."""

from __future__ import annotations

import csv
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import click
import numpy as np
from rich.table import Table

from cad.layout import ActuatorSpec
from design.designfile import read_regular
from design.home import solve_home
from design.model import RingPairModel
from design.paths import (
    PathSchedule,
    circle,
    ellipse,
    evaluate,
    follow,
    largest_ellipse,
    line,
)
from design.records import Design
from design.steering import REACHED, Steering, steer
from design.units import MM
from ringpair.moved_magnet import (
    MAGNET_COLUMNS,
    MAGNET_HEADS,
    MagnetPoses,
    MagnetRequest,
    magnet_options,
    magnet_poses,
    pose_words,
    row_poses,
)
from ringpair.options import (
    DESIGN,
    MAX_CONFIGS,
    FloatRange,
    UserError,
    check_request,
    console,
    csv_with_picture,
    default_out,
    design_from,
    effects_option,
    model_from,
    output_path,
    path_option,
    progress,
)
from ringpair.plots import plot_path
from ringpair.pressing import PRESS_STEP, steer_press
from ringpair.tables import write_csv

TARGET_SECONDS = 0.01
"""Time one target takes with the model for design work (its seed grid aside): 0.006 to
0.009 s measured on the development machine (2 cores) by benchmarks/estimates.py, targets
about the demonstrator's home, a tenth of them out of reach. [s]"""
MAX_TARGETS = 30_000
"""Targets per run unless --max-targets says more: about five minutes at TARGET_SECONDS."""

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


PATH_COLUMNS = (
    "step",
    "target_y_mm",
    "target_z_mm",
    "theta1_deg",
    "theta2_deg",
    "knob1_turns",
    "knob2_turns",
    "y_mm",
    "z_mm",
    "error_mm",
    "reached",
    "snapped",
)
PATH_POINTS = {"circle": 72, "ellipse": 72, "line": 25}
"""Points along a path unless --points says otherwise."""
MAX_PATH_POINTS = 2000
LARGEST_POINTS = 48
"""Points along the largest ellipse (each size tried is steered and driven)."""


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
    return _target_file(path)[0]


def _target_file(path: Path) -> tuple[list[tuple[float, float]], list[dict]]:
    """The targets of a CSV (:func:`read_targets`) [mm] and its rows as read (text)."""
    try:
        lines = [line for line in read_regular(path).splitlines() if not line.startswith("#")]
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"--targets: cannot read {path}: {exc}") from None
    reader = csv.DictReader(lines)
    missing = {"y_mm", "z_mm"} - set(reader.fieldnames or ())
    if missing:
        raise UserError(
            f"{path}: expected columns y_mm, z_mm; missing {', '.join(sorted(missing))}"
        )
    rows = list(reader)
    targets = [
        parse_target(f"{row['y_mm']},{row['z_mm']}", f"{path} line {k + 2}")
        for k, row in enumerate(rows)
    ]
    if not targets:
        raise UserError(f"{path}: no targets (expected rows of y_mm, z_mm)")
    return targets, rows


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
@path_option(
    "--targets",
    help="CSV of targets, columns y_mm, z_mm; with any of magnet_x_mm, magnet_y_mm, "
    "magnet_z_mm, magnet_turn_deg, the magnet's pose for each target (the design's where a "
    "column is absent).",
)
@click.option(
    "--path",
    "path_spec",
    metavar="SPEC",
    default=None,
    help="Drive the tip along a path: circle:R, ellipse:A,B (semi-axes along y and z), "
    "line:Y1,Z1,Y2,Z2 (mm), ellipse:largest (the largest ellipse about the workspace's "
    "centre that the tip can be driven around), or a CSV of points (columns y_mm, z_mm, in "
    "order). Writes a schedule of ring angles and knob turns, and its plot.",
)
@click.option(
    "--points",
    type=click.IntRange(2, MAX_PATH_POINTS),
    default=None,
    help="Points along a circle, ellipse or line (default 72, 72, 25).",
)
@click.option(
    "--center",
    metavar="Y,Z",
    default=None,
    help="Centre of a circle or ellipse in mm (default: the robot's home, the tip with the "
    "rings antiparallel, theta1 = 180, theta2 = 0 deg; ellipse:largest is about the "
    "workspace's centre, the mean tip with the rings parallel).",
)
@click.option("--closed", is_flag=True, help="A CSV path returns to its first point.")
@click.option(
    "--press",
    type=FloatRange(0.0, None, min_open=True),
    default=None,
    metavar="MN",
    help="Press the tip on the design's obstacles with this force [mN]: every pair of ring "
    "angles that does, found where the curves of that force cross the ring grid's lines. "
    "Writes simulate's columns per answer and the force map with the answers marked.",
)
@click.option(
    "--step",
    type=FloatRange(0.1, 90.0),
    default=None,
    help=f"Grid step of both rings for --press [deg] (default {PRESS_STEP:g}).",
)
@path_option(
    "--out",
    help="CSV to write. Default: outputs/<design name>/steer.csv (steer_path.csv with "
    "--path, and its plot beside it as .png; with --path the name must end in .csv).",
)
@effects_option("default")
@magnet_options
@click.option(
    "--max-targets",
    type=click.IntRange(1, None),
    default=MAX_TARGETS,
    show_default=True,
    help="Refuse more targets than this (about a tenth of a second each with the model for "
    "design work; the estimate is given); raise it for a long run.",
)
@MAX_CONFIGS
@click.option("--quiet", is_flag=True, help="Do not print the table.")
def steer_command(
    design: Path | None,
    to: tuple[str, ...],
    targets: Path | None,
    path_spec: str | None,
    points: int | None,
    center: str | None,
    closed: bool,
    press: float | None,
    step: float | None,
    out: Path | None,
    effects: str,
    magnet: MagnetRequest,
    max_targets: int,
    max_configs: int,
    quiet: bool,
) -> None:
    """The ring angles that put the tip of DESIGN at each target (y, z), drive it along a
    path, or press it on the design's obstacles with a force.

    Targets (--to, --targets): every pair of ring angles whose state (the stable
    equilibrium the robot reaches with the rings held there) puts the tip on the target, to
    1e-6 mm: the ring pair has several, typically mirror pairs. Each comes with its
    state's flags, its fold margin (1 for the unloaded robot, 0 at a fold where it snaps:
    how far from snapping) and the tip tangent. A target out of reach gets the closest
    reachable point, flagged reached = false, with its distance. CSV columns: target
    (1-based), target_y_mm, target_z_mm, theta1_deg, theta2_deg, x_mm, y_mm, z_mm, the tip
    tangent, error_mm, reached, stable, snapped, multistable, fold_margin. More than
    --max-targets targets are refused with an estimate of their time.

    A path (--path): one solution per point, chosen for the smallest total ring rotation
    without jumps between solution branches, then driven as the robot is (each state
    continued from the one before, 4 commands between points) to confirm that the tip
    follows and nothing snaps. CSV columns: step, target_y_mm, target_z_mm, theta1_deg,
    theta2_deg (continuous along the path), knob1_turns, knob2_turns (turns of the
    actuator's knobs from the first point: the wire's and the catheter's worm drive), y_mm,
    z_mm (the driven tip), error_mm, reached, snapped (the move into this point snapped).

    A force (--press MN): frictionless contact holds the force along the obstacle's
    normal, so the ring angles that press with a magnitude form curves over both ring
    angles; every point where they cross the lines of a --step grid, located to 0.0001 mN.
    One row per answer with simulate's columns (contact force, point, stiffness), the
    force map with the answers marked beside the CSV (.png).

    A moved magnet (--magnet-*, the classical steering combined with the rings'): targets
    are steered at every combination of the typed poses (or each at its own pose, from
    the --targets file's magnet columns), the pose in magnet_x_mm, magnet_y_mm,
    magnet_z_mm, magnet_turn_deg after target_z_mm; --path and --press hold the magnet at
    one pose.
    """
    d = design_from(design)
    model = model_from(effects).for_design(d)
    moves = magnet_poses(d, magnet)
    if press is not None or path_spec is not None:
        d = moves.one("--press" if press is not None else "--path").design(d, 0)
    if press is not None:
        if to or targets is not None or path_spec is not None:
            raise UserError(
                "--press finds angles for a force; give it without --to, --targets or --path"
            )
        if points is not None or center is not None or closed:
            raise UserError("--points, --center and --closed belong to --path")
        steer_press(d, model, design, press, step, out, max_configs)
        return
    if step is not None:
        raise UserError("--step is the grid of --press")
    if path_spec is not None:
        if to or targets is not None:
            raise UserError("--path drives along a path; give it without --to or --targets")
        _steer_path(d, model, design, path_spec, points, center, closed, out, quiet)
        return
    if points is not None or center is not None or closed:
        raise UserError("--points, --center and --closed belong to --path")
    wanted = [parse_target(t, "--to") for t in to]
    file_rows: list[dict] = []
    if targets is not None:
        more, file_rows = _target_file(targets)
        wanted += more
    if not wanted:
        raise UserError("give a target: --to Y,Z (mm), --targets FILE.csv or --path SPEC")
    _within_reach(d, wanted)
    at_pose = _target_poses(d, moves, magnet, targets, file_rows, len(to))
    if at_pose is None:  # every target at every typed pose
        poses = list(range(len(moves.poses)))
        pairs = [np.arange(len(wanted))] * len(poses)
    else:  # each target at its own pose, each distinct pose solved once
        moves = at_pose
        _, first, which = np.unique(moves.poses, axis=0, return_index=True, return_inverse=True)
        poses = [int(k) for k in np.sort(first)]
        pairs = [np.flatnonzero(which == which[k]) for k in poses]
    n = sum(len(p) for p in pairs)
    check_request(
        n,
        max_targets,
        " and ".join(o for o, given in (("--to", to), ("--targets", targets)) if given)
        + " and --magnet-*" * (moves.moving and at_pose is None),
        f"{n:,} targets",
        n * TARGET_SECONDS,
        "--max-targets",
    )
    out = output_path(
        out or default_out(d.name, "steer.csv"),
        "--out",
        folder=False,
        typed=out is not None,
        inputs=[design, targets],
    )
    rows: list[dict] = []
    steering = "steering (the first run on a machine compiles the model)"
    with progress(steering, total=n) as update:
        for pose, chosen in zip(poses, pairs, strict=True):
            params = model.parameters(moves.design(d, pose))
            result = steer(model, params, np.array(wanted)[chosen] * MM)
            for row in steer_rows(result):
                row["target"] = int(chosen[row["target"] - 1]) + 1
                rows.append(row | (moves.columns(pose) if moves.moving else {}))
            update(advance=len(chosen))
    if at_pose is not None:
        rows.sort(key=lambda row: row["target"])
    columns: tuple[str, ...] = STEER_COLUMNS
    if moves.moving:
        columns = STEER_COLUMNS[:3] + MAGNET_COLUMNS + STEER_COLUMNS[3:]
    header = f"ringpair steer, design '{d.name}', model {model.name}"
    write_csv(out, rows, columns, header=header + (f"\n{moves.label()}" if moves.moving else ""))
    if not quiet:
        title = f"{d.name}: ring angles for each target ({model.name} model)"
        _print(rows, title, moves.varied())
    at = f" at {len(poses)} magnet pose(s)" * (moves.moving and at_pose is None)
    console.print(f"wrote {out} ({len(wanted)} target(s){at}, {len(rows)} row(s))")


def _target_poses(
    d: Design,
    moves: MagnetPoses,
    magnet: MagnetRequest,
    targets: Path | None,
    file_rows: list[dict],
    typed: int,
) -> MagnetPoses | None:
    """The pose of each target from the --targets file's magnet columns, or None where it
    has none (the typed --magnet-* poses then apply to every target)."""
    if not file_rows or not set(MAGNET_COLUMNS) & set(file_rows[0]):
        return None
    if typed or moves.moving and replace(magnet, source=None).given:
        raise UserError(
            f"{targets} gives the magnet's pose for each target (columns "
            f"{', '.join(c for c in MAGNET_COLUMNS if c in file_rows[0])}); give its targets "
            "without --to, --magnet-x, --magnet-y, --magnet-z or --magnet-turn"
        )
    return row_poses(d, magnet.source, file_rows, str(targets))


def _within_reach(d: Design, wanted: list[tuple[float, float]]) -> None:
    """Refuse points farther from the robot's axis than its free length (wrong units)."""
    limit = d.robot.free_length / MM
    far = [p for p in wanted if np.hypot(*p) > limit]
    if far:
        raise UserError(
            f"target {far[0][0]:g},{far[0][1]:g} mm is farther from the robot's axis than its "
            f"free length ({limit:g} mm): no tip can get there (are the units mm?)"
        )


def parse_path(
    spec: str, count: int | None, center: tuple[float, float] | None
) -> tuple[np.ndarray, bool]:
    """The points (M, 2) [mm] and closedness of a --path SPEC (circle:R, ellipse:A,B,
    line:Y1,Z1,Y2,Z2); ``center`` [mm] is needed for circles and ellipses."""
    kind, _, numbers = spec.partition(":")
    kind = kind.strip().lower()
    expected = {"circle": 1, "ellipse": 2, "line": 4}
    if kind not in expected:
        raise UserError(
            f"--path: expected circle:R, ellipse:A,B, line:Y1,Z1,Y2,Z2 or a CSV file, got {spec!r}"
        )
    try:
        values = [float(v) for v in numbers.split(",")]
    except ValueError:
        values = []
    n = expected[kind]
    if len(values) != n or not np.isfinite(values).all():
        raise UserError(
            f"--path {kind}: expected {n} number(s) in mm after '{kind}:', got {spec!r}"
        )
    if kind != "line" and min(values) <= 0:
        raise UserError(f"--path {kind}: radii must be positive (mm), got {spec!r}")
    if kind == "line" and values[:2] == values[2:]:
        raise UserError(f"--path line: the two ends are the same point, got {spec!r}")
    count = count or PATH_POINTS[kind]
    assert center is not None or kind == "line"
    if kind == "circle":
        return circle(values[0], count, center or (0.0, 0.0)), True
    if kind == "ellipse":
        return ellipse(values[0], values[1], count, center or (0.0, 0.0)), True
    return line((values[0], values[1]), (values[2], values[3]), count), False


def path_rows(schedule: PathSchedule, ratio: float) -> list[dict]:
    """One row per path point in file units (mm, deg, knob turns at ``ratio`` knob turns
    per ring turn)."""
    knobs = ratio * (schedule.theta - schedule.theta[0]) / (2 * np.pi)
    return [
        {
            "step": k + 1,
            "target_y_mm": schedule.points[k, 0] / MM,
            "target_z_mm": schedule.points[k, 1] / MM,
            "theta1_deg": np.rad2deg(schedule.theta[k, 0]),
            "theta2_deg": np.rad2deg(schedule.theta[k, 1]),
            "knob1_turns": knobs[k, 0],
            "knob2_turns": knobs[k, 1],
            "y_mm": schedule.position[k, 1] / MM,
            "z_mm": schedule.position[k, 2] / MM,
            "error_mm": schedule.error[k] / MM,
            "reached": bool(schedule.reached[k]),
            "snapped": bool(schedule.snapped[k]),
        }
        for k in range(len(schedule.points))
    ]


def _steer_path(
    d: Design,
    model: RingPairModel,
    design: Path | None,
    spec: str,
    count: int | None,
    center_text: str | None,
    closed: bool,
    out: Path | None,
    quiet: bool,
) -> None:
    """``ringpair steer --path``: the schedule, its CSV, its plot and a summary."""
    csv_path = Path(spec) if Path(spec).suffix.lower() == ".csv" else None
    if csv_path is not None and (count is not None or center_text is not None):
        raise UserError("--points and --center shape circles, ellipses and lines, not a CSV path")
    if csv_path is None and closed:
        raise UserError("--closed is for a CSV path (circles and ellipses are closed already)")
    center = parse_target(center_text, "--center") if center_text is not None else None
    out, picture = csv_with_picture(
        out, default_out(d.name, "steer_path.csv"), "--path", "the plot", [design, csv_path]
    )
    params = model.parameters(d)
    schedule: PathSchedule | None = None
    with (
        console.status("steering along the path (the first run on a machine compiles the model)"),
        _as_user_error("--path"),
    ):
        if csv_path is not None:
            wanted = np.array(read_targets(csv_path))
            if len(wanted) < 2:
                raise UserError(f"{csv_path}: a path needs at least two points")
            if len(wanted) > MAX_PATH_POINTS:
                raise UserError(f"{csv_path}: {len(wanted):,} points; at most {MAX_PATH_POINTS:,}")
        elif spec.replace(" ", "").lower() == "ellipse:largest":
            if center is not None:
                raise UserError("--center: the largest ellipse is about the workspace's centre")
            schedule = largest_ellipse(model, params, count or LARGEST_POINTS)
            wanted = schedule.points / MM
        else:
            if center is None and not spec.lower().startswith("line"):
                home = solve_home(model, params, d.robot.free_length)  # issue 49
                if not home.stable:
                    raise UserError(f"--center: the robot has no home ({home.state.failure[0]})")
                center = (home.position[1] / MM, home.position[2] / MM)
            wanted, closed = parse_path(spec, count, center)
        _within_reach(d, [tuple(p) for p in wanted])
        if schedule is None:
            schedule = follow(model, params, wanted * MM, closed=closed)
    ratio = ActuatorSpec().drive.ratio
    rows = path_rows(schedule, ratio)
    write_csv(
        out,
        rows,
        PATH_COLUMNS,
        header=(
            f"ringpair steer --path {spec}, design '{d.name}', model {model.name}; knob turns "
            f"at {ratio:g} knob turns per ring turn (the actuator's worm drives), from step 1"
        ),
    )
    plot_path(schedule, picture, f"{d.name}: {spec} ({model.name} model)")
    if not quiet:
        console.print(_summary(schedule, ratio))
    console.print(f"wrote {out} ({len(rows)} steps) and {picture}")


@contextmanager
def _as_user_error(option: str) -> Iterator[None]:
    """What the solver cannot do with the input (no workspace, no state near a point) is
    said as the option's error."""
    try:
        yield
    except ValueError as exc:
        raise UserError(f"{option}: {exc}") from None


def _summary(schedule: PathSchedule, ratio: float) -> str:
    """What the drive along the path gave, in plain sentences."""
    turns = np.rad2deg(schedule.rotation)
    knobs = ratio * schedule.rotation / (2 * np.pi)
    lines = [
        f"{len(schedule.points)} points; rings turned {turns[0]:.1f} deg (wire) and "
        f"{turns[1]:.1f} deg (catheter) in all: {knobs[0]:.1f} and {knobs[1]:.1f} knob turns."
    ]
    if schedule.closed:
        e = evaluate(schedule)
        lines.append(
            f"Around the path the tip deflects at most {e.max_y / MM:.1f} mm along y and "
            f"{e.max_z / MM:.1f} mm along z, {e.mean_deflection / MM:.1f} mm on average; RMS "
            f"distance to the ellipse fitted to it {e.rms_to_ellipse / MM:.3f} mm."
        )
    if schedule.followed:
        lines.append(
            f"FOLLOWED: the driven tip passes every point (within {np.max(schedule.error) / MM:.1e}"
            f" mm) and strays at most {schedule.deviation / MM:.3f} mm from the path between "
            "them; nothing snaps."
        )
        return "\n".join(lines)
    missed = np.flatnonzero(~schedule.reached)
    if missed.size:
        lines.append(
            f"OUT OF REACH: {missed.size} point(s) (steps {_ranges(missed + 1)}); the schedule "
            f"goes to the closest reachable point instead, up to "
            f"{np.max(schedule.error[missed]) / MM:.3f} mm away."
        )
    snapped = np.flatnonzero(schedule.snapped)
    if snapped.size:
        lines.append(
            f"SNAPS on the way to step(s) {_ranges(snapped + 1)}: no schedule of these "
            "solutions avoids it."
        )
    lines.append(
        f"The driven tip strays at most {schedule.deviation / MM:.3f} mm from the path; the "
        f"largest miss at a point is {np.max(schedule.error) / MM:.3f} mm."
    )
    return "\n".join(lines)


def _ranges(steps: np.ndarray) -> str:
    """1-based steps as '3-7, 12'."""
    parts, start = [], int(steps[0])
    for a, b in zip(steps[:-1], steps[1:], strict=True):
        if b != a + 1:
            parts.append(f"{start}" if start == a else f"{start}-{a}")
            start = int(b)
    last = int(steps[-1])
    parts.append(f"{start}" if start == last else f"{start}-{last}")
    return ", ".join(parts)


def _print(rows: list[dict], title: str, magnet: tuple[str, ...] = ()) -> None:
    """The solutions as a table (with the moved magnet's pose columns ``magnet``, those
    that vary), then a plain sentence for each target out of reach."""
    table = Table(title=title)
    for col in (
        "target [mm]",
        *(MAGNET_HEADS[c] for c in magnet),
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
            *(f"{row[c]:.2f}" for c in magnet),
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
        if magnet:
            where += f" ({pose_words(row, magnet)})"
        if not row["stable"]:
            console.print(f"{where}: no configuration near it has a state.")
        elif not row["reached"]:
            console.print(
                f"{where} is OUT OF REACH: the closest point, ({row['y_mm']:.3f}, "
                f"{row['z_mm']:.3f}) mm, is {row['error_mm']:.3f} mm away."
            )
