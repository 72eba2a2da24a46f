"""The ``ringpair`` command line.

Exit codes: 0 done; 2 bad input (one message naming the key or option, no traceback);
1 an unexpected failure.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click
import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from design.atomic import write_text
from design.branches import branches
from design.designfile import DesignError, default_design, load_design, save_design
from design.equilibrium import solve_design
from design.magnets import cylinder_moment, ring_moment
from design.model import DEFAULT_EFFECTS, EFFECTS, RingPairModel, parse_effects
from design.params import Design
from design.sections import bending_rigidity, tube_torsional_rigidity
from design.workspace import Workspace, sweep_workspace
from ringpair.angles import parse_angles
from ringpair.tables import POSE_COLUMNS, effect_shifts, pose_rows, write_csv

console = Console()
err_console = Console(stderr=True)

DESIGN_HELP = "Design file (TOML, spec/formats.md). Default: the paper's demonstrator."


class UserError(click.ClickException):
    """Bad input: printed as one message, exit code 2."""

    exit_code = 2

    def show(self, file: object = None) -> None:
        err_console.print(
            f"[bold red]error:[/] {escape(self.message)}", highlight=False, soft_wrap=True
        )


def _design(path: Path | None) -> Design:
    if path is None:
        return default_design()
    try:
        return load_design(path)
    except DesignError as exc:
        raise UserError(str(exc)) from None


def _model(effects: str) -> RingPairModel:
    try:
        return RingPairModel(parse_effects(effects))
    except ValueError as exc:
        raise UserError(f"--effects: {exc}") from None


EFFECTS_HELP = (
    "Model effects on top of the paper's baseline: 'none', 'default' ("
    + ",".join(sorted(DEFAULT_EFFECTS))
    + "), 'all' or a comma list of "
    + ", ".join(EFFECTS)
    + " (see the README for what each adds and costs)."
)
EFFECTS_OPTION = click.option("--effects", default="none", show_default=True, help=EFFECTS_HELP)
SIMULATION_EFFECTS_OPTION = click.option(
    "--effects", default="default", show_default=True, help=EFFECTS_HELP
)


def _angles(text: str, option: str) -> np.ndarray:
    try:
        return parse_angles(text, option)
    except ValueError as exc:
        raise UserError(str(exc)) from None


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="ringpair")
def cli() -> None:
    """ringpair: design magnetic continuum robots steered by a rotational ring pair.

    Two diametrically magnetised rings at the tip, each turned by its own coaxial element
    (inner wire: distal ring, theta1; outer catheter: proximal ring, theta2), steer the tip
    in the fixed field of an external magnet. Every command takes a design file
    (spec/formats.md) and defaults to the paper's demonstrator. Angles are in degrees,
    lengths in millimetres; base frame: origin at the clamp, x along the straight robot.
    """


@cli.command()
@click.argument("design", required=False, type=click.Path(path_type=Path))
@click.option(
    "--save",
    type=click.Path(path_type=Path),
    default=None,
    help="Also write the (validated) design to this TOML file, e.g. to start a new one.",
)
def show(design: Path | None, save: Path | None) -> None:
    """Validate DESIGN and print it with its derived quantities."""
    d = _design(design)
    t, r, e = d.tip, d.robot, d.external_magnet
    table = Table(title=f"design '{d.name}'", show_header=True)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    m_ring = ring_moment(
        t.magnet_outer_diameter, t.magnet_inner_diameter, t.magnet_length, t.remanence
    )
    rows = [
        ("free length", f"{r.free_length * 1e3:g} mm"),
        ("bending rigidity EI (catheter + wire)", f"{bending_rigidity(r):.4g} N m^2"),
        ("torsional rigidity GJ catheter", f"{tube_torsional_rigidity(r.catheter):.4g} N m^2"),
        ("torsional rigidity GJ wire", f"{tube_torsional_rigidity(r.wire):.4g} N m^2"),
        ("ring moment (each)", f"{m_ring:.4g} A m^2"),
        ("ring centre spacing", f"{t.spacing * 1e3:g} mm"),
        (
            "external magnet moment",
            f"{cylinder_moment(e.diameter, e.length, e.remanence):.4g} A m^2",
        ),
        ("external magnet centre", "[" + ", ".join(f"{c * 1e3:g}" for c in e.center) + "] mm"),
    ]
    for k, v in rows:
        table.add_row(k, v)
    console.print(table)
    if save is not None:
        save_design(d, save)
        console.print(f"wrote {save}")


@cli.command()
@click.argument("design", required=False, type=click.Path(path_type=Path))
@click.option(
    "--theta1",
    default="0:180:12",
    show_default=True,
    help="Distal ring (wire) angles [deg]: START:STOP:STEP, a comma list or one value.",
)
@click.option(
    "--theta2",
    default="0",
    show_default=True,
    help="Proximal ring (catheter) angles [deg], same forms. Every pair of the two "
    "lists is simulated.",
)
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="CSV to write. Default: outputs/<design name>/simulate.csv.",
)
@SIMULATION_EFFECTS_OPTION
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
    d = _design(design)
    model = _model(effects)
    t1 = _angles(theta1, "--theta1")
    t2 = _angles(theta2, "--theta2")
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
    rest = np.array([d.robot.free_length, 0.0, 0.0])
    rows = pose_rows(eq, rest)
    out = out or Path("outputs") / d.name / "simulate.csv"
    write_csv(
        out, rows, POSE_COLUMNS, header=f"ringpair simulate, design '{d.name}', model {model.name}"
    )
    if not quiet:
        table = Table(title=f"{d.name}: tip poses ({model.name} model)")
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
        shown = rows if len(rows) <= 60 else rows[:30] + rows[-30:]
        for row in shown:
            state = (
                ", ".join(
                    ["stable"] + ["snapped"] * row["snapped"] + ["multistable"] * row["multistable"]
                )
                if row["stable"]
                else "NO STATE"
            )
            table.add_row(
                *(
                    f"{row[k]:.2f}"
                    for k in ("theta1_deg", "theta2_deg", "x_mm", "y_mm", "z_mm", "deflection_mm")
                ),
                state,
            )
        console.print(table)
        if len(rows) > 60:
            console.print(f"({len(rows) - 60} rows not shown)")
    n_bad = int(np.count_nonzero(~eq.converged))
    if n_bad:
        reasons = sorted(set(eq.failure[~eq.converged]))
        err_console.print(
            f"[yellow]warning:[/] {n_bad} configuration(s) have no state: " + "; ".join(reasons)
        )
    console.print(f"wrote {out} ({len(rows)} configurations)")


@cli.command()
@click.argument("design", required=False, type=click.Path(path_type=Path))
@click.option("--theta1", default="0", show_default=True, help="Distal ring angle [deg].")
@click.option("--theta2", default="0", show_default=True, help="Proximal ring angle [deg].")
@SIMULATION_EFFECTS_OPTION
@click.option(
    "--points", type=click.IntRange(11, 2001), default=201, show_default=True,
    help="Load factors from 0 to 1.",
)
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="PNG to write. Default: outputs/<design name>/branch.png.",
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
    d = _design(design)
    model = _model(effects)
    command = np.deg2rad([_one_angle(theta1, "--theta1"), _one_angle(theta2, "--theta2")])
    lam = np.linspace(0.0, 1.0, points)
    with console.status("following the branches (the first run on a machine compiles)"):
        path_states, others = branches(model, model.parameters(d), command, lam)
    out = out or Path("outputs") / d.name / "branch.png"
    title = (
        f"{d.name}, {model.name} model, theta1 = {np.rad2deg(command[0]):g} deg, "
        f"theta2 = {np.rad2deg(command[1]):g} deg"
    )
    from ringpair.plots import plot_branch_diagram  # matplotlib only when plotting

    plot_branch_diagram(path_states, others, lam, title, out)
    snaps = np.flatnonzero(np.diff(path_states.snapped.astype(int)) > 0) + 1
    for k in snaps:
        console.print(f"the state snaps at load factor {lam[k]:.3f}")
    end = path_states.position[-1]
    if path_states.stable[-1]:
        console.print(
            f"state at full load: tip ({end[0] * 1e3:.2f}, {end[1] * 1e3:.2f}, "
            f"{end[2] * 1e3:.2f}) mm; {len(others)} other branch(es) of equilibria"
        )
    else:
        console.print(f"no state at full load: {path_states.failure[-1]}")
    console.print(f"wrote {out}")


def _one_angle(text: str, option: str) -> float:
    values = _angles(text, option)
    if values.size != 1:
        raise UserError(f"{option} takes one angle here; got {values.size}")
    return float(values[0])


@cli.command()
@click.argument("design", required=False, type=click.Path(path_type=Path))
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="Directory for workspace.csv, summary.json and the PNG plots. "
    "Default: outputs/<design name>/workspace.",
)
@click.option(
    "--step",
    type=click.FloatRange(0.1, 90.0),
    default=5.0,
    show_default=True,
    help="Grid spacing of theta1 and theta2 over a full turn [deg].",
)
@SIMULATION_EFFECTS_OPTION
def workspace(design: Path | None, out: Path | None, step: float, effects: str) -> None:
    """Sweep (theta1, theta2) over full turns and map the reachable tip set of DESIGN.

    Prints the deflection range along y and z, the largest deflection and its direction,
    the radius of the largest disc around the rest position inside the reachable set
    (size and symmetry in one number) and the neutral (antiparallel) deflection; writes
    workspace.csv, summary.json, top.png (x-y), side.png (x-z), section.png (y-z) and
    deflection.png (deflection against theta1 with theta2 = 0).
    """
    d = _design(design)
    model = _model(effects)
    out = out or Path("outputs") / d.name / "workspace"
    from ringpair.plots import write_workspace_plots  # matplotlib only when plotting

    with console.status("sweeping the workspace"):
        ws = sweep_workspace(d, np.deg2rad(step), model, multistable=True)
        sweep_deg = np.arange(0.0, 360.0 + 1e-9, 1.0)
        sweep = solve_design(d, np.deg2rad(sweep_deg), 0.0, model)
    rest = ws.rest_position
    write_csv(
        out / "workspace.csv",
        pose_rows(ws.grid, rest),
        POSE_COLUMNS,
        header=f"ringpair workspace, design '{d.name}', grid step {step:g} deg, model {model.name}",
    )
    summary = workspace_summary(ws, d, step, model.name)
    write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    pictures = write_workspace_plots(ws, sweep, d, out)
    _print_summary(summary)
    console.print(
        f"wrote {out}/: workspace.csv, summary.json, " + ", ".join(p.name for p in pictures)
    )


def workspace_summary(ws: Workspace, design: Design, step_deg: float, model: str) -> dict:
    """The workspace metrics in file units (mm, deg)."""
    direction = ws.max_direction
    return {
        "design": design.name,
        "model": model,
        "grid_step_deg": step_deg,
        "configurations": len(ws.grid),
        "without_state": ws.n_without_state,
        "snapped": ws.n_snapped,
        "multistable": ws.n_multistable,
        "free_length_mm": design.robot.free_length * 1e3,
        "y_range_mm": [v * 1e3 for v in ws.y_range],
        "z_range_mm": [v * 1e3 for v in ws.z_range],
        "max_deflection_mm": ws.max_deflection * 1e3,
        "max_deflection_percent_of_length": 100 * ws.max_deflection / design.robot.free_length,
        "max_deflection_direction": [float(c) for c in direction],
        "max_deflection_direction_deg": float(np.rad2deg(np.arctan2(direction[2], direction[1]))),
        "max_deflection_theta_deg": [float(np.rad2deg(a)) for a in ws.max_angles],
        "disc_radius_mm": ws.disc_radius * 1e3,
        "neutral_deflection_mm": ws.neutral_deflection * 1e3,
        "boundary_excess_mm": ws.boundary_excess * 1e3,
    }


def _print_summary(s: dict) -> None:
    table = Table(title=f"workspace of '{s['design']}' ({s['model']} model)")
    table.add_column("metric")
    table.add_column("value", justify="right")
    table.add_row(
        "configurations (without a state / snapped / multistable)",
        f"{s['configurations']} ({s['without_state']} / {s['snapped']} / {s['multistable']})",
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
    table.add_row("largest disc around rest (radius)", f"{s['disc_radius_mm']:.2f} mm")
    table.add_row("neutral (antiparallel) deflection", f"{s['neutral_deflection_mm']:.3f} mm")
    console.print(table)


@cli.command()
@click.argument("design", required=False, type=click.Path(path_type=Path))
@click.option(
    "--theta1",
    default="0:180:12",
    show_default=True,
    help="Distal ring angles [deg] driven in order (the paper's planar experiment).",
)
@click.option("--theta2", default="0", show_default=True, help="Proximal ring angles [deg].")
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="CSV of the comparison. Default: outputs/<design name>/effects.csv.",
)
def effects(design: Path | None, theta1: str, theta2: str, out: Path | None) -> None:
    """How far each model effect moves the tip of DESIGN, against the paper's baseline.

    Drives the rings through every (theta1, theta2) in order (theta2 fastest) with the
    baseline and with each effect on its own, then with all of them, and prints the largest
    and RMS tip shift [mm] and the largest deflection under each model.
    """
    d = _design(design)
    t1 = np.deg2rad(_angles(theta1, "--theta1"))
    t2 = np.deg2rad(_angles(theta2, "--theta2"))
    with console.status("comparing model effects (first use compiles each model)"):
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
    out = out or Path("outputs") / d.name / "effects.csv"
    write_csv(out, rows, tuple(rows[0]), header=f"ringpair effects, design '{d.name}'")
    console.print(f"wrote {out}")


SET_UNITS = {"m": ("mm", 1e-3), "rad": ("deg", np.pi / 180), "Pa": ("MPa", 1e6), "kg": ("g", 1e-3)}
"""Units of --set values: the model's SI unit -> (the unit typed, its SI value)."""


def _overrides(items: tuple[str, ...]) -> dict[str, float]:
    """--set NAME=VALUE pairs in file units (mm, deg, MPa, g) as SI model parameters."""
    from design.parameters import PARAMETERS

    out: dict[str, float] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep:
            raise UserError(f"--set expects NAME=VALUE (e.g. wire_torsion_scale=2); got {item!r}")
        if name not in PARAMETERS:
            import difflib

            close = difflib.get_close_matches(name, list(PARAMETERS), n=1, cutoff=0.6)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise UserError(f"--set: unknown model parameter {name!r}{hint}")
        unit, factor = SET_UNITS.get(PARAMETERS[name].unit, (PARAMETERS[name].unit, 1.0))
        try:
            value = float(text)
        except ValueError:
            raise UserError(
                f"--set {name} expects a number [{unit}]; got {text.strip()!r}"
            ) from None
        if not np.isfinite(value):
            raise UserError(f"--set {name} expects a finite number [{unit}]; got {text.strip()!r}")
        out[name] = value * factor
    return out


@cli.command()
@click.argument("design", required=False, type=click.Path(path_type=Path))
@EFFECTS_OPTION
@click.option(
    "--noise-mm",
    type=click.FloatRange(0.0, 100.0),
    default=0.3,
    show_default=True,
    help="One-sigma Gaussian tracker noise on each measured coordinate [mm].",
)
@click.option("--seed", type=int, default=1, show_default=True, help="Seed of the noise.")
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="Data-set folder to write (design.toml + measurements.csv). "
    "Default: outputs/<design name>/synth.",
)
@click.option(
    "--view",
    type=click.Choice(["3d", "top"]),
    default="3d",
    show_default=True,
    help="3d: x, y and z tracked; top: a camera above the robot sees x and y only.",
)
@click.option(
    "--n",
    "n_points",
    type=click.IntRange(6, 100_000),
    default=60,
    show_default=True,
    help="About this many configurations: theta1 swept from parallel to antiparallel and "
    "back for theta2 = 0, 120, 240 deg, in that order.",
)
@click.option(
    "--set",
    "settings",
    multiple=True,
    metavar="NAME=VALUE",
    help="A true model parameter that differs from DESIGN (repeatable), e.g. "
    "wire_torsion_scale=2, bending_rigidity_scale=0.8, wire_friction_angle=3; lengths in mm, "
    "angles in deg, moduli in MPa, masses in g. design.toml keeps the nominal values.",
)
@click.option("--tip-angles", is_flag=True, help="Also record the ring angles at the tip.")
def synth(
    design: Path | None,
    effects: str,
    noise_mm: float,
    seed: int,
    out: Path | None,
    view: str,
    n_points: int,
    settings: tuple[str, ...],
    tip_angles: bool,
) -> None:
    """Synthetic bench data of DESIGN: a data set (spec/formats.md) to test calibration
    and diagnosis on.

    Drives the rings along a bench path with the chosen model effects (and any --set
    truths), adds Gaussian noise and writes design.toml (nominal) and measurements.csv
    (with a sequence column: the acquisition order). Configurations without a stable
    equilibrium are dropped and counted.
    """
    from optimize.measurements import save_dataset
    from optimize.synth import synthesize_data

    d = _design(design)
    model = _model(effects)
    truth = _overrides(settings)
    out = out or Path("outputs") / d.name / "synth"
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out} exists and is not a folder; expected a data-set folder")
    with console.status("simulating the bench run (the first run on a machine compiles the model)"):
        data = synthesize_data(
            d,
            model.effects,
            n=n_points,
            view=view,
            noise_mm=noise_mm,
            seed=seed,
            params_override=truth,
            tip_angles=tip_angles,
        )
    m = data.measurements
    if len(m) == 0:
        raise UserError(
            "no configuration has a stable equilibrium with these settings; nothing written"
        )
    provenance = (
        f"ringpair synth: design '{d.name}', model {data.model.name}, view {view}, "
        f"noise {noise_mm:g} mm, seed {seed}"
        + "".join(f", true {item.strip()}" for item in settings)
    )
    save_dataset(out, d, m, comment=provenance)
    rest = np.array([d.robot.free_length, 0.0, 0.0])
    deflection = np.linalg.norm(np.nan_to_num(m.position - rest), axis=1) * 1e3
    table = Table(title=f"synthetic data set of '{d.name}' ({data.model.name} model)")
    table.add_column("item")
    table.add_column("value", justify="right")
    table.add_row("configurations written", str(len(m)))
    table.add_row("dropped (no stable equilibrium)", str(data.dropped))
    table.add_row("reached by a snap-through", str(data.snapped))
    table.add_row("view", "x, y (top)" if view == "top" else "x, y, z")
    table.add_row("noise (one sigma, each coordinate)", f"{noise_mm:g} mm, seed {seed}")
    table.add_row("deflection seen", f"{deflection.min():.2f} .. {deflection.max():.2f} mm")
    for k, v in truth.items():
        from design.parameters import PARAMETERS

        unit, factor = SET_UNITS.get(PARAMETERS[k].unit, (PARAMETERS[k].unit, 1.0))
        table.add_row(f"true {k}", f"{v / factor:g} {unit if unit != '-' else ''}".rstrip())
    console.print(table)
    if data.dropped:
        err_console.print(
            f"[yellow]warning:[/] {data.dropped} configuration(s) without a stable equilibrium "
            "were dropped"
        )
    console.print(f"wrote {out}/: design.toml, measurements.csv")


def _measured_data(data: Path, design: Path | None):
    """(Design, Measurements) from a data-set folder, or from a CSV with --design (default
    the demonstrator); every problem with either file becomes a UserError."""
    from optimize.measurements import MeasurementError, load_dataset, load_measurements

    try:
        if data.is_dir():
            if design is not None:
                raise UserError(
                    f"--design is for a CSV; {data} is a data-set folder with its own design.toml"
                )
            return load_dataset(data)
        return _design(design), load_measurements(data)
    except (MeasurementError, DesignError) as exc:
        raise UserError(str(exc)) from None


@cli.command()
@click.argument("data", type=click.Path(path_type=Path))
@click.option(
    "--design",
    "design_path",
    type=click.Path(path_type=Path),
    default=None,
    help="Design file for a CSV DATA (default: the demonstrator); a data-set folder has its own.",
)
@EFFECTS_OPTION
@click.option(
    "--free",
    default=None,
    help="Comma list of the parameters to fit. Default: bending_rigidity_scale and "
    "external_center_x/y/z, plus each effect's own (torsion scales, friction angles, tip mass).",
)
@click.option("--priors", is_flag=True, help="Add Gaussian priors centred on the nominal design.")
@click.option(
    "--profile",
    is_flag=True,
    help="Also give each parameter's 1-sigma profile-likelihood interval (it fixed, the others "
    "refitted): right where parameters trade off nonlinearly, where standard errors are not.",
)
@click.option(
    "--json",
    "json_out",
    type=click.Path(path_type=Path),
    default=None,
    help="Also write the estimates, standard errors, correlations and errors as JSON (SI).",
)
def calibrate(
    data: Path,
    design_path: Path | None,
    effects: str,
    free: str | None,
    priors: bool,
    profile: bool,
    json_out: Path | None,
) -> None:
    """Fit the model's uncertain physical parameters to measured DATA (a data-set folder
    or a CSV, spec/formats.md) by least squares with exact Jacobians; print the estimates
    with their standard errors, and the RMS and largest tip error."""
    from optimize.calibrate import FREE_PARAMETERS
    from optimize.calibrate import calibrate as fit_parameters
    from optimize.profile import profile_intervals

    if profile and priors:
        raise UserError("--profile is for fits without --priors (it profiles the data's misfit)")

    d, m = _measured_data(data, design_path)
    model = _model(effects)
    names = None if free is None else tuple(n.strip() for n in free.split(",") if n.strip())
    for n in names or ():
        if n not in FREE_PARAMETERS:
            import difflib

            close = difflib.get_close_matches(n, list(FREE_PARAMETERS), n=1, cutoff=0.6)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise UserError(
                f"--free: {n!r} cannot be calibrated{hint} (expected names from "
                f"{', '.join(FREE_PARAMETERS)})"
            )
    with console.status("fitting (the first run on a machine compiles the model)"):
        try:
            res = fit_parameters(d, m, model.effects, names, priors=priors)
        except ValueError as exc:
            raise UserError(str(exc)) from None
    intervals = {}
    if profile:
        with console.status("profile likelihood"):
            intervals = profile_intervals(d, m, res, res.names)
    table = Table(title=f"calibration of '{d.name}' ({model.name} model) on {len(m)} rows")
    columns = ["parameter", "nominal", "estimate", "std. error"]
    for col in columns + (["1-sigma profile interval"] if profile else []) + ["unit"]:
        table.add_column(col, justify="right")
    for row in res.table():
        cells = [
            str(row["name"]),
            f"{row['nominal']:.5g}",
            f"{row['estimate']:.5g}",
            f"{row['standard_error']:.2g}",
        ]
        if profile:
            iv, factor = intervals[str(row["name"])], FREE_PARAMETERS[str(row["name"])].label[1]
            cells.append(f"{iv.lower * factor:.4g} to {iv.upper * factor:.4g}")
        table.add_row(*cells, str(row["unit"]))
    console.print(table)
    console.print(
        f"tip error: RMS {res.rmse_mm:.3f} mm, largest {res.max_abs_mm:.3f} mm; implied noise "
        f"{res.noise_mm:.3f} mm per coordinate; "
        + ("converged" if res.converged else "[yellow]NOT converged[/]")
        + f" ({res.evaluations} solves, {res.time_s:.2f} s)"
    )
    if res.at_bounds:
        err_console.print(f"[yellow]warning:[/] at a bound: {', '.join(res.at_bounds)}")
    if "determine only" in res.message:
        err_console.print(f"[yellow]warning:[/] {escape(res.message)}")
    if json_out is not None:

        def finite(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None  # JSON has no inf or NaN

        doc = {
            "design": d.name,
            "model": model.name,
            "rows": len(m),
            "estimate": res.estimate,
            "standard_error": {k: finite(v) for k, v in res.standard_error.items()},
            "nominal": res.nominal,
            **(
                {"profile_interval": {k: [v.lower, v.upper] for k, v in intervals.items()}}
                if profile
                else {}
            ),
            "correlation": [[finite(c) for c in row] for row in np.round(res.correlation, 6)],
            "rmse_mm": res.rmse_mm,
            "max_abs_mm": res.max_abs_mm,
            "noise_mm": res.noise_mm,
            "converged": res.converged,
            "message": res.message,
        }
        write_text(json_out, json.dumps(doc, indent=2) + "\n")
        console.print(f"wrote {json_out}")


@cli.command()
@click.argument("data", type=click.Path(path_type=Path))
@click.option(
    "--design",
    "design_path",
    type=click.Path(path_type=Path),
    default=None,
    help="Design file for a CSV DATA (default: the demonstrator); a data-set folder has its own.",
)
@click.option(
    "--json",
    "json_out",
    type=click.Path(path_type=Path),
    default=None,
    help="Write the diagnosis JSON (spec/formats.md) here.",
)
@click.option(
    "--report",
    type=click.Path(path_type=Path),
    default=None,
    help="Directory for residual plots before/after and diagnosis.html.",
)
@click.option("--folds", default=5, show_default=True, help="Cross-validation folds.")
@click.option("--seed", default=0, show_default=True, help="Seed of the fold assignment.")
def diagnose(
    data: Path,
    design_path: Path | None,
    json_out: Path | None,
    report: Path | None,
    folds: int,
    seed: int,
) -> None:
    """What the simulation gets wrong on measured DATA, the physical cause, and the gain.

    DATA is a data-set folder (design.toml + measurements.csv) or a CSV with --design.
    Calibrates the paper's baseline, looks for structure in its residuals, adds the model
    effects the data call for (judged by BIC and cross-validated error) and prints the
    causes with their evidence and the fitted physical parameters.
    """
    from optimize.diagnose import diagnose as run_diagnosis

    d, m = _measured_data(data, design_path)
    if not 2 <= folds <= len(m):
        raise UserError(f"--folds must be between 2 and the number of rows ({len(m)}); got {folds}")
    with console.status("diagnosing") as status:
        result = run_diagnosis(d, m, k=folds, seed=seed, progress=status.update)
    doc = result.to_json()
    table = Table(title=f"diagnosis of {m.source} ({len(m)} rows, {result.time_s:.1f} s)")
    for col in ("model", "RMSE (mm)", "max (mm)", "cross-validated RMSE (mm)"):
        table.add_column(col, justify="right")
    for name, fit in (("baseline", result.baseline), (result.final.name, result.final)):
        c = fit.calibration
        table.add_row(name, f"{c.rmse_mm:.3f}", f"{c.max_abs_mm:.3f}", f"{fit.cv_rmse_mm:.3f}")
    console.print(table)
    if result.causes:
        for cause in result.causes:
            console.print(f"[bold]cause[/] {escape(cause.evidence)}")
    else:
        console.print("causes: [] (the calibrated baseline explains the data)")
    if result.unexplained:
        console.print(f"[yellow]not explained:[/] {escape(result.unexplained)}")
    if json_out is not None:
        write_text(json_out, json.dumps(doc, indent=2, allow_nan=False) + "\n")
        console.print(f"wrote {json_out}")
    if report is not None:
        from ringpair.diagnosis_report import write_report

        for path in write_report(result, m, report):
            console.print(f"wrote {path}")


@cli.command()
@click.argument("design", required=False, type=click.Path(path_type=Path))
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="Directory for the STEP assembly, STL parts, 3MF plates, check tables and renders. "
    "Default: outputs/<design name>/cad.",
)
@click.option(
    "--process",
    type=click.Choice(["fdm", "resin"]),
    default="fdm",
    show_default=True,
    help="Printing process: sets fit allowances, clearances, minimum wall and build volume.",
)
@click.option("--no-render", is_flag=True, help="Skip the pyvista renders (faster).")
def cad(design: Path | None, out: Path | None, process: str, no_render: bool) -> None:
    """Printable parts of DESIGN: the two mounting pieces with the helical tracking groove
    and the worm-gear actuator, in millimetres.

    Writes ringpair_robot.step (assembly with named parts), stl/<part>.stl, 3MF print
    plates, checks.csv (watertight, volume, minimum wall, build volume, interference, gear
    centre distance), parts.csv, cad_summary.json and renders/*.png. Exits 3 if a
    printability check fails.
    """
    d = _design(design)
    from cad import CadError, build_parts  # CAD libraries only when building parts

    out = out or Path("outputs") / d.name / "cad"
    try:
        with console.status("building, exporting, checking and rendering parts"):
            report = build_parts(d, out, process, render=not no_render)
    except CadError as exc:
        raise UserError(str(exc)) from None
    console.print(report.summary(), highlight=False)
    if not report.passed:
        sys.exit(3)


from ringpair.optimize_cli import optimize as _optimize  # noqa: E402

cli.add_command(_optimize)

from ringpair.study_cli import study as _study  # noqa: E402

cli.add_command(_study)


def main() -> None:
    """Console-script entry point."""
    try:
        cli.main(standalone_mode=True)
    except KeyboardInterrupt:
        err_console.print("interrupted")
        sys.exit(130)


if __name__ == "__main__":
    main()
