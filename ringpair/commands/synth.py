"""``ringpair synth``: a synthetic bench data set to test calibration and diagnosis on."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np
from rich.table import Table

from design.designfile import DesignError, revalidated
from design.geometry import rest_position
from design.records import Design
from design.registry import PARAMETERS, current, design_with, file_unit
from design.suggest import did_you_mean
from design.units import MM
from ringpair.options import (
    DESIGN,
    FORCE,
    FloatRange,
    UserError,
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


def _overrides(items: tuple[str, ...]) -> dict[str, float]:
    """--set NAME=VALUE pairs in file units (mm, deg, MPa, g) as SI model parameters."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = current(name.strip())
        if not sep:
            raise UserError(f"--set expects NAME=VALUE (e.g. wire_torsion_scale=2); got {item!r}")
        if name not in PARAMETERS:
            raise UserError(
                f"--set: unknown model parameter {name!r}{did_you_mean(name, PARAMETERS)}"
            )
        unit, size = file_unit(name)
        try:
            value = float(text)
        except ValueError:
            raise UserError(
                f"--set {name} expects a number [{unit}]; got {text.strip()!r}"
            ) from None
        if not np.isfinite(value):
            raise UserError(f"--set {name} expects a finite number [{unit}]; got {text.strip()!r}")
        low, high, low_open = _plausible(name)
        too_low = low is not None and (value <= low if low_open else value < low)
        if too_low or (high is not None and value > high):
            bounds = [f"{'>' if low_open else '>='} {low:g}"] * (low is not None)
            bounds += [f"<= {high:g}"] * (high is not None)
            raise UserError(f"--set {name} must be {' and '.join(bounds)} [{unit}]; got {value:g}")
        out[name] = value * size
    return out


def _check_truth(design: Design, truth: dict[str, float]) -> None:
    """The true robot (``design`` with the --set quantities a design holds) must pass every
    check a design file passes (:func:`design.designfile.revalidated`): walls, bores, a
    flexible rod under the printed tip, a magnet clear of the robot."""
    held = {k: v for k, v in truth.items() if PARAMETERS[k].field is not None}
    if not held:
        return
    try:
        revalidated(design_with(design, held))
    except DesignError as exc:
        given = ", ".join(f"{k}={v / file_unit(k)[1]:g}" for k, v in held.items())
        raise UserError(
            f"--set {given}: the true robot is not one a design admits: {exc}"
        ) from None


def _plausible(name: str) -> tuple[float | None, float | None, bool]:
    """The range --set admits for ``name`` in its file unit: the design file's, or for a
    model factor its calibration range (low, high, whether low is excluded)."""
    p = PARAMETERS[name]
    if p.low is not None or p.high is not None:
        return p.low, p.high, p.low_open
    if p.fit is not None:
        size = file_unit(name)[1]
        return p.fit.lower / size, p.fit.upper / size, False
    return None, None, False


def _measured_elsewhere(path: Path) -> bool:
    """Whether ``path`` is a file whose first line is not synth's provenance comment."""
    if not path.is_file():
        return False
    try:
        with path.open(encoding="utf-8", errors="replace") as f:
            return not f.readline().startswith("# ringpair synth")
    except OSError:
        return True


@click.command()
@DESIGN
@effects_option("none")
@click.option(
    "--noise-mm",
    type=FloatRange(0.0, 100.0),
    default=0.3,
    show_default=True,
    help="One-sigma Gaussian tracker noise on each measured coordinate [mm].",
)
@click.option(
    "--seed",
    type=click.IntRange(0, 2**32 - 1),
    default=1,
    show_default=True,
    help="Seed of the noise.",
)
@path_option(
    "--out",
    help="Data-set folder to write (design.toml + measurements.csv). "
    "Default: outputs/<design name>/synth. Measured data that synth did not write there "
    "are replaced only with --force.",
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
@FORCE
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
    force: bool,
) -> None:
    """Synthetic bench data of DESIGN: a data set (docs/formats.md) to test calibration
    and diagnosis on.

    Drives the rings along a bench path with the chosen model effects (and any --set
    truths), adds Gaussian noise and writes design.toml (nominal) and measurements.csv
    (with a sequence column: the acquisition order). Configurations without a stable
    equilibrium (the robot lost, e.g. pulled onto the magnet) are counted and written
    without a position: driven, not seen.
    """
    from optimize.fitting.measurements import save_dataset
    from optimize.fitting.synth import synthesize_data

    d = design_from(design)
    model = model_from(effects)
    truth = _overrides(settings)
    _check_truth(d, truth)
    typed = out is not None
    out = output_path(
        out or default_out(d.name, "synth"),
        "--out",
        folder=True,
        typed=typed,
        files=("design.toml", "measurements.csv"),
        inputs=[design],
    )
    if not force and _measured_elsewhere(out / "measurements.csv"):
        where = f"--out {out}" if typed else f"the default output folder {out}"
        raise UserError(
            f"{where}: holds measurements.csv that ringpair synth did not write (measured "
            "data?); pass --force to replace it"
        )
    with progress("simulating the bench run (the first run on a machine compiles the model)"):
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
    if not m.seen.any():
        raise UserError(
            "no configuration has a stable equilibrium with these settings; nothing written"
        )
    provenance = (
        f"ringpair synth: design '{d.name}', model {data.model.name}, view {view}, "
        f"noise {noise_mm:g} mm, seed {seed}"
        + "".join(f", true {item.strip()}" for item in settings)
    )
    save_dataset(out, d, m, comment=provenance)
    rest = rest_position(d.robot.free_length)
    deflection = np.linalg.norm(np.nan_to_num(m.position - rest), axis=1)[m.seen] / MM
    table = Table(title=f"synthetic data set of '{d.name}' ({data.model.name} model)")
    table.add_column("item")
    table.add_column("value", justify="right")
    table.add_row("configurations written", str(len(m)))
    table.add_row("not seen (no stable equilibrium)", str(data.dropped))
    table.add_row("reached by a snap-through", str(data.snapped))
    table.add_row("view", "x, y (top)" if view == "top" else "x, y, z")
    table.add_row("noise (one sigma, each coordinate)", f"{noise_mm:g} mm, seed {seed}")
    table.add_row("deflection seen", f"{deflection.min():.2f} .. {deflection.max():.2f} mm")
    for k, v in truth.items():
        unit, size = file_unit(k)
        table.add_row(f"true {k}", f"{v / size:g} {unit if unit != '-' else ''}".rstrip())
    console.print(table)
    if data.dropped:
        warn(
            f"{data.dropped} configuration(s) without a stable equilibrium (the robot lost): "
            "written without a position, as driven but not seen"
        )
    console.print(f"wrote {out}/: design.toml, measurements.csv")
