"""``ringpair optimize``: a design study from its file to the best design, Pareto fronts,
plots and a summary. Millimetres at the edges, SI inside."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import click
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn  # noqa: E402

from design.atomic import atomic_path, write_text  # noqa: E402
from design.designfile import save_design  # noqa: E402
from design.model import RingPairModel  # noqa: E402
from design.workspace import Workspace, sweep_workspace  # noqa: E402
from optimize.nlp import StudyResult, solve_study  # noqa: E402
from optimize.study import Study, StudyError, default_study, load_study  # noqa: E402
from optimize.sweeps import ParetoPoint, ParetoResult, is_monotone, run_sweeps  # noqa: E402

UNITS = {  # Pareto quantity -> (file-unit factor, label)
    "catheter_outer_diameter": (1e3, "catheter outer diameter [mm]"),
    "external_distance": (1e3, "external-magnet distance [mm]"),
    "magnet_volume": (1e9, "magnet volume, both rings [mm^3]"),
}


def _save(fig: plt.Figure, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=120, bbox_inches="tight")
    plt.close(fig)


def _objective_mm(study: Study, value: float) -> float:
    """The objective in report units (mm for a radius; as is otherwise)."""
    single = len(study.objective) == 1 and study.objective[0][0] == "disc_radius"
    return value * 1e3 if single else value


def pareto_rows(points: tuple[ParetoPoint, ...], study: Study) -> list[dict[str, object]]:
    """One CSV row per point, in file units."""
    factor, _ = UNITS[points[0].against] if points else (1.0, "")
    rows = []
    for p in points:
        r = p.result
        row: dict[str, object] = {
            "epsilon": p.epsilon * factor,
            "feasible": p.feasible,
            "objective": _objective_mm(study, p.objective),
            "active": ";".join(r.active) if r is not None else "",
            "error": p.error,
        }
        if r is not None and r.feasible:
            row |= _file_units(r.values)
        rows.append(row)
    return rows


def _file_units(values: dict[str, float]) -> dict[str, float]:
    """Design values in file units: moduli in MPa, lengths in mm."""
    return {
        (f"{k}_mpa" if k.endswith("modulus") else f"{k}_mm"): v
        * (1e-6 if k.endswith("modulus") else 1e3)
        for k, v in values.items()
    }


def write_rows(path: Path, rows: list[dict[str, object]]) -> None:
    columns = list(dict.fromkeys(k for r in rows for k in r))
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_text(path, buf.getvalue())


def plot_fronts(pareto: ParetoResult, best: StudyResult, study: Study, path: Path) -> None:
    """Objective against each swept bound, with the unconstrained optimum marked."""
    sweeps = [(a, pts) for a, pts in pareto.sweeps.items() if pts]
    fig, axes = plt.subplots(1, len(sweeps), figsize=(5 * len(sweeps), 3.8), squeeze=False)
    for ax, (against, pts) in zip(axes[0], sweeps, strict=True):
        factor, label = UNITS[against]
        eps = np.array([p.epsilon for p in pts]) * factor
        obj = np.array([_objective_mm(study, p.objective) for p in pts])
        ax.plot(eps, obj, "o-", color="tab:blue", label="Pareto front")
        if best.feasible:
            ax.plot(
                best.metrics[against] * factor,
                _objective_mm(study, best.objective),
                "r*",
                ms=14,
                label="best design",
            )
        ax.set_xlabel(label)
        ax.set_ylabel("disc radius [mm]" if len(study.objective) == 1 else "objective")
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.set_ylim(bottom=0, top=1.1 * np.nanmax(np.r_[obj, _objective_mm(study, best.objective)]))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Pareto fronts of '{study.name}'")
    _save(fig, path)


def plot_workspaces(start: Workspace, best: Workspace, path: Path) -> None:
    """Starting vs optimised reachable sets seen along x, around each rest position. [mm]"""
    fig, ax = plt.subplots(figsize=(6.5, 6))
    for ws, colour, name in ((start, "tab:gray", "starting design"), (best, "tab:blue", "optimum")):
        pts = (ws.reachable - ws.rest_position) * 1e3
        ax.scatter(pts[:, 1], pts[:, 2], s=2, color=colour, alpha=0.4)
        loop = (ws.parallel.position - ws.rest_position) * 1e3
        ax.plot(loop[:, 1], loop[:, 2], "-", color=colour, lw=1.5, label=name)
        circle = plt.Circle((0, 0), ws.disc_radius * 1e3, fill=False, ls="--", color=colour)
        ax.add_patch(circle)
    ax.set_aspect("equal")
    ax.set_xlabel("y - y_rest [mm]")
    ax.set_ylabel("z - z_rest [mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Workspace seen along x: parallel-ring loop and largest disc")
    _save(fig, path)


def summary(
    study: Study, best: StudyResult, start: Workspace, end: Workspace | None, pareto
) -> dict:
    """The JSON summary (SI plus the forward-simulated radii in mm)."""
    doc: dict[str, object] = {
        "study": study.name,
        "feasible": best.feasible,
        "objective": best.objective,
        "values": best.values,
        "materials": list(best.materials),
        "metrics": best.metrics,
        "base_metrics": best.base_metrics,
        "active": list(best.active),
        "constraints": [c.__dict__ for c in best.constraints],
        "starts": [s.__dict__ for s in best.starts],
        "conflicts": [c.describe() for c in best.conflicts],
        "seconds": best.seconds,
        "forward": {
            "start_disc_radius_mm": start.disc_radius * 1e3,
            "best_disc_radius_mm": None if end is None else end.disc_radius * 1e3,
        },
    }
    if pareto is not None:
        doc["pareto"] = {
            "seconds": pareto.seconds,
            "solved": pareto.solved,
            "resumed": pareto.resumed,
            "workers": pareto.workers,
            "monotone": {a: is_monotone(p) for a, p in pareto.sweeps.items()},
        }
    return json.loads(json.dumps(doc, default=_plain))


def _plain(x: object) -> object:
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, tuple | frozenset | set):
        return list(x)
    return str(x)


@click.command()
@click.argument("study_path", metavar="[STUDY]", required=False, type=click.Path(path_type=Path))
@click.option(
    "--out",
    type=click.Path(path_type=Path),
    default=None,
    help="Output directory. Default: outputs/<study name>/optimize.",
)
@click.option("--scheduler", default=None, help="Address of a running Dask scheduler.")
@click.option(
    "--workers", default=2, show_default=True, help="Local Dask workers (without --scheduler)."
)
@click.option("--no-pareto", is_flag=True, help="Skip the Pareto sweeps.")
def optimize(
    study_path: Path | None, out: Path | None, scheduler: str | None, workers: int, no_pareto: bool
) -> None:
    """Choose the design of STUDY (TOML; default: the embedded demonstrator study).

    Writes best_design.toml, pareto_<quantity>.csv, pareto.png, workspace.png and
    summary.json. Pareto points run on Dask and are kept in OUT/points, so a rerun of the
    same study resumes. Exit 0 also for an infeasible study: the conflict report is
    printed and written to summary.json; exit 2 for a bad study file.
    """
    from ringpair.cli import UserError, console

    try:
        study = default_study() if study_path is None else load_study(study_path)
    except (StudyError, OSError) as exc:
        raise UserError(str(exc)) from None
    if workers < 1:
        raise UserError(f"--workers must be at least 1; got {workers}")
    out = out or Path("outputs") / study.name / "optimize"
    out.mkdir(parents=True, exist_ok=True)
    with console.status(f"solving '{study.name}' ({study.starts} starts per material)"):
        best = solve_study(study)
    console.print(best.report())
    model = RingPairModel(study.effects)
    with console.status("forward simulation of the starting and the best design"):
        start_ws = sweep_workspace(study.base, model=model)
        end_ws = sweep_workspace(best.design, model=model) if best.design is not None else None
    written = []
    if best.design is not None:
        save_design(best.design, out / "best_design.toml")
        written.append(out / "best_design.toml")
        plot_workspaces(start_ws, end_ws, out / "workspace.png")  # type: ignore[arg-type]
        written.append(out / "workspace.png")
        console.print(
            f"disc radius by forward simulation: start {start_ws.disc_radius * 1e3:.2f} mm, "
            f"best {end_ws.disc_radius * 1e3:.2f} mm"  # type: ignore[union-attr]
        )
    pareto = None
    if study.pareto and not no_pareto:
        total = None
        with Progress(
            "[progress.description]{task.description}",
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            console=console,
        ) as bar:
            task = bar.add_task("Pareto points", total=total)

            def step(done: int, n: int) -> None:
                bar.update(task, completed=done, total=n)

            pareto = run_sweeps(study, out, scheduler=scheduler, workers=workers, progress=step)
        for against, points in pareto.sweeps.items():
            path = out / f"pareto_{against}.csv"
            write_rows(path, pareto_rows(points, study))
            written.append(path)
        plot_fronts(pareto, best, study, out / "pareto.png")
        written.append(out / "pareto.png")
        console.print(
            f"Pareto: {pareto.solved} points solved, {pareto.resumed} resumed, "
            f"{pareto.seconds:.1f} s on {pareto.workers or 'no'} workers"
        )
    doc = summary(study, best, start_ws, end_ws, pareto)
    write_text(out / "summary.json", json.dumps(doc, indent=2) + "\n")
    written.append(out / "summary.json")
    for path in written:
        console.print(f"wrote {path}")
