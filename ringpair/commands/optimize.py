"""``ringpair optimize``: a design study from its file to the best design, Pareto fronts,
plots and a summary. Millimetres at the edges, SI inside."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import click
import numpy as np

from design.atomic import write_text
from design.designfile import save_design
from design.model import RingPairModel
from design.units import MM
from design.workspace import Workspace, sweep_workspace
from ringpair.options import (
    OVERWRITE_POLICY,
    SCHEDULER,
    STUDY,
    UserError,
    base_file,
    check_study_size,
    console,
    default_out,
    held_run,
    json_text,
    output_path,
    path_option,
    progress,
    scheduler_from,
    study_from,
)
from ringpair.tables import write_pareto_csvs

if TYPE_CHECKING:
    from optimize.sizing.nlp import OptimizationResult
    from optimize.sizing.pareto import ParetoResult
    from optimize.sizing.studyfile import Study


FILES = ("best_design.toml", "workspace.png", "pareto.png", "summary.json", "manifest.json")
"""What ``optimize`` writes in its folder (and pareto_<quantity>.csv, points/)."""


@click.command()
@STUDY
@path_option(
    "--out", help="Output directory. Default: outputs/<study name>/optimize. " + OVERWRITE_POLICY
)
@SCHEDULER
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
    same study resumes. manifest.json lists what the run wrote; an earlier run's files it
    did not write again (a best design after an infeasible rerun, Pareto files after a run
    without Pareto) are removed, the points kept. Exit 0 also for an infeasible study: the
    conflict report is printed and written to summary.json; exit 2 for a bad study file.
    """
    from optimize.sizing.nlp import optimize_design, start_breaks
    from ringpair.plots import plot_fronts, plot_workspaces

    study = study_from(study_path)
    check_study_size(study, pareto=not no_pareto)
    if study.pareto and not no_pareto:
        scheduler = scheduler_from(scheduler)
    if workers < 1:
        raise UserError(f"--workers must be at least 1; got {workers}")
    out = output_path(
        out or default_out(study.name, "optimize"),
        "--out",
        folder=True,
        typed=out is not None,
        files=FILES,
        inputs=[study_path, base_file(study)],
    )
    with held_run(out, "optimize", keep=("points",)):
        with progress(f"solving '{study.name}' ({study.starts} starts per material)"):
            best = optimize_design(study)
        console.print(best.report())
        model = RingPairModel(study.effects)
        with progress("forward simulation of the starting and the best design"):
            start_ws = sweep_workspace(study.base, model=model)
            end_ws = sweep_workspace(best.design, model=model) if best.design is not None else None
        written = []
        if best.design is not None and end_ws is not None:
            save_design(best.design, out / "best_design.toml")
            written.append(out / "best_design.toml")
            plot_workspaces(start_ws, end_ws, out / "workspace.png")
            written.append(out / "workspace.png")
            console.print(
                f"disc radius by forward simulation: start {start_ws.disc_radius / MM:.2f} mm, "
                f"best {end_ws.disc_radius / MM:.2f} mm"
            )
            broken = start_breaks(study)
            if broken:
                console.print("the starting design breaks the study's limits: " + "; ".join(broken))
            if "controllable_disc_radius" in best.metrics:
                console.print(
                    "controllable disc (steerable from rest without a snap, the study's model): "
                    f"start {best.base_metrics['controllable_disc_radius'] / MM:.2f} mm, "
                    f"best {best.metrics['controllable_disc_radius'] / MM:.2f} mm"
                )
        pareto = None
        if study.pareto and not no_pareto:
            pareto = _run_sweeps(study, out, scheduler, workers, best)
            written += write_pareto_csvs(pareto, study, out)
            plot_fronts(pareto, best, study, out / "pareto.png")
            written.append(out / "pareto.png")
            console.print(
                f"Pareto: {pareto.solved} points solved, {pareto.resumed} resumed, "
                f"{pareto.seconds:.1f} s on {pareto.workers or 'no'} workers"
            )
        doc = summary(study, best, start_ws, end_ws, pareto)
        write_text(out / "summary.json", json_text(doc))
        written.append(out / "summary.json")
        for path in written:
            console.print(f"wrote {path}")
    console.print(f"wrote {out / 'manifest.json'}")


def _run_sweeps(
    study: Study, out: Path, scheduler: str | None, workers: int, start: OptimizationResult
) -> ParetoResult:
    """The study's Pareto sweeps on Dask, with a progress bar, each sweep continued from
    the optimum ``start`` (:func:`optimize.sizing.pareto.run_sweeps`)."""
    from optimize.sizing.pareto import run_sweeps

    with progress("Pareto points") as update:

        def step(done: int, n: int) -> None:
            update(completed=done, total=n)

        return run_sweeps(
            study, out, scheduler=scheduler, workers=workers, progress=step, start=start
        )


def summary(
    study: Study,
    best: OptimizationResult,
    start: Workspace,
    end: Workspace | None,
    pareto: ParetoResult | None,
) -> dict:
    """The JSON summary (SI plus the forward-simulated radii in mm)."""
    from optimize.sizing.pareto import is_monotone

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
            "start_disc_radius_mm": start.disc_radius / MM,
            "best_disc_radius_mm": None if end is None else end.disc_radius / MM,
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
    """JSON for what json cannot write: numpy values as numbers and lists, sets as lists,
    anything else as its str."""
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, tuple | frozenset | set):
        return list(x)
    return str(x)
