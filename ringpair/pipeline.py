"""The main job: a study file through every stage to a report, with a manifest.

Stages (each a function of the study and earlier stages' results, timed, stored under
``OUT/.stages/<stage>-<hash>.npz`` (:mod:`design.stored`: JSON and NPZ, never code) so a
rerun with the same inputs (:func:`inputs_key`) reuses it):

1. ``baseline``: workspace of the starting design (the study's model);
2. ``optimise``: the study's NLP (:func:`optimize.sizing.nlp.optimize_design`);
   ``sensitivity``: what each limit holding the optimum costs (:func:`sensitivity`: the
   NLP solved again with that one limit moved by
   :data:`optimize.sizing.limit_costs.RELAX`);
3. ``pareto``: the Pareto sweeps on Dask (:func:`optimize.sizing.pareto.run_sweeps`);
4. ``forward``: the starting and the chosen design re-simulated with the model for design
   work (:data:`design.model.DEFAULT_EFFECTS`, the printed tip included:
   :func:`forward_model`);
5. ``tolerance``: Monte Carlo over manufacturing tolerances
   (:func:`design.tolerances.tolerance_spread`), the spread of the chosen design's disc
   radius (one batch solve of every sample's parallel-ring loop);
6. ``effects``: how far each model effect moves the chosen design's tip;
7. ``cad``: parts, checks and renders of the chosen design (:func:`cad.build_parts`);
0. ``diagnosis``: of measured data, when given; it runs first, and every later stage
   designs with its calibrated model, the robot as built (:func:`calibrated_study`).

Besides each stage's files the run writes the hand-off: ``best_design.toml`` (the
recommended design as a design file, read back by ``ringpair simulate`` and
:func:`design.designfile.load_design`) and ``pareto/pareto_<quantity>.csv`` (each front,
file units, with # lines saying what the columns mean); the CAD stage writes the parts
list ``cad/parts.csv``.

SI units inside; the report and the manifest say their units.
"""

from __future__ import annotations

import json
import platform
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from design import stored
from design.atomic import write_text
from design.designfile import save_design
from design.made import made_design
from design.model import DEFAULT_EFFECTS, RingPairModel
from design.records import Design
from design.registry import PARAMETERS
from design.tolerances import TOLERANCE_LOOP, TOLERANCES, tolerance_spread
from design.units import MM
from design.workspace import Workspace, sweep_workspace
from optimize.sizing.limit_costs import RELAX, limit_costs
from optimize.sizing.studyfile import Study
from ringpair.report_notes import rounding_note
from ringpair.runs import inputs_key, sha256, stage_path, stored_stage, tree_hash
from ringpair.tables import effect_shifts, objective_in_report_units, write_pareto_csvs

if TYPE_CHECKING:
    from optimize.sizing.nlp import OptimizationResult

EFFECTS_PATH = np.deg2rad(np.arange(0.0, 181.0, 12.0))
"""theta1 of the effects stage [rad], driven in order with theta2 = 0: the paper's planar
experiment, as ``ringpair effects`` by default."""

BEST_DESIGN = "best_design.toml"
"""The recommended design's file, in the study's output folder."""


class Watch(Protocol):
    """Who watches the stages run (the command's progress display)."""

    def start(self, what: str) -> None:
        """A stage starts; ``what`` says what it does."""

    def count(self, done: int, total: int) -> None:
        """Of the running stage's ``total`` pieces of work, ``done`` are finished."""

    def end(self, what: str, seconds: float, reused: bool) -> None:
        """The stage ended after ``seconds`` [s] (reused: read back from an earlier run,
        ``seconds`` then being what it took when it ran)."""


class _Unwatched:
    def start(self, what: str) -> None:
        pass

    def count(self, done: int, total: int) -> None:
        pass

    def end(self, what: str, seconds: float, reused: bool) -> None:
        pass


class StageError(RuntimeError):
    """A stage failed; ``stage`` names it, ``run`` holds the stages finished before it."""

    def __init__(self, stage: str, message: str, run: Run | None = None) -> None:
        super().__init__(f"stage '{stage}' failed: {message}")
        self.stage = stage
        self.run = run


@dataclass
class Run:
    """Results of the stages so far, their timings [s], whether each was reused, and the
    hand-off files written so far (design file, Pareto CSVs, parts list)."""

    out: Path
    study: Study
    results: dict[str, Any] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    reused: dict[str, bool] = field(default_factory=dict)
    handoff: list[Path] = field(default_factory=list)
    calibration: dict[str, Any] | None = None
    """With measured data: what the study took from its diagnosis (:func:`calibrated_study`)."""


def _stage(
    run: Run, name: str, what: str, inputs: tuple, work: Callable[[], Any], watch: Watch
) -> Any:
    """Run one stage, or reuse its stored result for the same inputs (``inputs``, whose
    first item is :func:`inputs_key`, and the stage's name); a reused stage reports the
    seconds it took."""
    key = stored.digest(name, *inputs)
    watch.start(what)
    old = stored_stage(run.out, name, key)
    if old is not None:
        result, seconds = old
        run.reused[name] = True
    else:
        t0 = time.perf_counter()
        try:
            result = work()
        except Exception as exc:
            raise StageError(name, f"{type(exc).__name__}: {exc}", run) from exc
        seconds = time.perf_counter() - t0
        stored.save(stage_path(run.out, name, key), {"result": result, "seconds": seconds}, key)
        run.reused[name] = False
    run.results[name] = result
    run.seconds[name] = seconds
    watch.end(what, seconds, run.reused[name])
    return result


def sensitivity(study: Study, best: OptimizationResult) -> list[dict[str, Any]]:
    """What each limit holding the optimum costs
    (:func:`optimize.sizing.limit_costs.limit_costs`), its ``objective`` and ``gain`` in
    report units (:func:`ringpair.tables.objective_in_report_units`). Largest gain first."""
    start = objective_in_report_units(study, best.objective)
    rows = []
    for row in limit_costs(study, best):
        objective = objective_in_report_units(study, row["objective"])
        rows.append(row | {"objective": objective, "gain": objective - start})
    return sorted(rows, key=lambda r: -np.nan_to_num(r["gain"], nan=-np.inf))


@lru_cache(maxsize=1)
def versions() -> dict[str, str]:
    """Python, key packages and the project's git commit (if known)."""
    import casadi
    import scipy

    out = {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "casadi": str(getattr(casadi, "__version__", "unknown")),
    }
    try:
        import cadquery

        out["cadquery"] = str(getattr(cadquery, "__version__", "unknown"))
    except ImportError:  # pragma: no cover - CAD is a dependency
        pass
    try:
        here = Path(__file__).resolve().parent
        commit = subprocess.run(
            ["git", "-C", str(here), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        out["ringpair_commit"] = commit
    except (OSError, subprocess.CalledProcessError):
        out["ringpair_commit"] = "unknown"
    return out


def run_study(
    study: Study,
    out: Path,
    *,
    study_text: str,
    data: Path | None = None,
    workers: int = 2,
    scheduler: str | None = None,
    samples: int = 200,
    seed: int = 0,
    cad_process: str = "fdm",
    render: bool = True,
    watch: Watch | None = None,
) -> Run:
    """Every stage of the main job, and the hand-off files as soon as their stage is done
    (:data:`BEST_DESIGN`, the Pareto CSVs); StageError names a failing stage (earlier
    stages' outputs stay valid on disk).

    cad_process : print process of the parts (:data:`cad.process.PROCESSES`).
    watch : told when each stage starts and ends (default: nobody).
    """
    from cad import build_parts
    from optimize.sizing.nlp import optimize_design
    from optimize.sizing.pareto import run_sweeps

    w = watch or _Unwatched()
    run = Run(out, study)
    key: tuple[Any, ...] = (inputs_key(study, study_text, data),)
    if data is not None:  # the robot as built: design with the calibrated model
        what = "diagnosis of the measured data (the model the study designs with)"
        diagnosis = _stage(run, "diagnosis", what, key, lambda: _diagnose(data), w)
        study, run.calibration = calibrated_study(study, diagnosis["calibration"])
        run.study = study
    model = RingPairModel(study.effects)
    what = "workspace of the starting design"
    _stage(run, "baseline", what, key, lambda: sweep_workspace(study.base, model=model), w)
    what = "optimisation (IPOPT, multi-start)"
    best = _stage(run, "optimise", what, key, lambda: optimize_design(study), w)
    if not best.feasible or best.design is None:
        raise StageError("optimise", "the study is infeasible: " + best.report(), run)
    # The hand-off: the optimum rounded to what can be made (design.made); the forward
    # stage re-runs the model on it and on the raw optimum, and the report states the change.
    chosen: Design = made_design(best.design)
    what = f"what each limit costs (each moved by {RELAX:.0%}, the NLP solved again)"
    _stage(run, "sensitivity", what, key, lambda: sensitivity(study, best), w)
    save_design(chosen, out / BEST_DESIGN, explicit=True)
    run.handoff.append(out / BEST_DESIGN)
    if study.pareto:
        pareto = _stage(
            run,
            "pareto",
            "Pareto sweeps on Dask",
            key,
            lambda: run_sweeps(
                study,
                out / "pareto",
                scheduler=scheduler,
                workers=workers,
                progress=w.count,
                start=best,
            ),
            w,
        )
        run.handoff += write_pareto_csvs(pareto, study, out / "pareto")
    faithful = forward_model(study)
    _stage(
        run,
        "forward",
        "forward re-simulation with the model for design work (and the disc steerable from home)",
        key,
        lambda: (
            _forward_pair(study.base, chosen, faithful)
            | {"optimum": sweep_workspace(best.design, STEERABLE_STEP, faithful)}
        ),
        w,
    )
    _stage(
        run,
        "tolerance",
        f"tolerance Monte Carlo ({samples} samples)",
        (*key, samples, seed),
        lambda: tolerance_spread(chosen, samples, seed, faithful),
        w,
    )
    _stage(
        run,
        "effects",
        "how much each model effect matters",
        key,
        lambda: effect_shifts(chosen, EFFECTS_PATH, np.zeros(1))[0],
        w,
    )
    _stage(
        run,
        "cad",
        f"CAD of the recommended design ({BEST_DESIGN}), {cad_process} print"
        + _tip_note(chosen, cad_process)
        + ": parts, checks"
        + (", renders" if render else ""),
        (*key, cad_process, render),
        lambda: _cad_summary(
            build_parts(
                chosen,
                out / "cad",
                cad_process,
                render=render,
            )
        ),
        w,
    )
    run.handoff.append(out / "cad" / "parts.csv")
    return run


STEERABLE_STEP = np.deg2rad(10.0)
"""Grid step of the ring angles for the controllable disc of the forward stage. [rad]"""


def forward_model(study: Study) -> RingPairModel:
    """The model the forward stage re-simulates with: the model for design work
    (:data:`design.model.DEFAULT_EFFECTS`, the printed tip included), whatever the study's
    own model."""
    return RingPairModel(DEFAULT_EFFECTS)


def steerable_workspace(design: Design, model: RingPairModel) -> tuple[Workspace, Any]:
    """The workspace of ``design`` about its home (STEERABLE_STEP grid) and its
    controllable part (:func:`design.controllable.steerable`), whose ``disc_radius`` is the
    disc: the disc about home the robot can be steered over without a snap."""
    from design.controllable import steerable

    ws = sweep_workspace(design, STEERABLE_STEP, model)
    return ws, steerable(ws, model, model.parameters(design))


def _forward_pair(start: Design, best: Design, model: RingPairModel) -> dict[str, Any]:
    """The forward stage: the start's and the recommended design's workspaces
    (``start``, ``best``) and controllable parts (``start_controllable``,
    ``best_controllable``), :func:`steerable_workspace`; where ``model`` leaves torsion out,
    the recommended design's with it (``best_torsion``: the disc, droop, share steerable
    from home, snaps; the transmissions' twist with the printed pieces' stops and
    pre-twist as the design file has them). [SI]"""
    ws_start, ctl_start = steerable_workspace(start, model)
    ws_best, ctl_best = steerable_workspace(best, model)
    out = {
        "start": ws_start,
        "best": ws_best,
        "start_controllable": ctl_start,
        "best_controllable": ctl_best,
    }
    if "torsion" not in model.effects:
        # what the model leaves out, measured on the recommended design
        twisted = RingPairModel(model.effects | {"torsion"})
        t0 = time.perf_counter()
        ws_t, ctl_t = steerable_workspace(best, twisted)
        out["best_torsion"] = {
            "effects": sorted(twisted.effects),
            "disc_radius": ctl_t.disc_radius,
            "workspace_disc_radius": ws_t.disc_radius,
            "droop": ws_t.droop,
            "home_stable": ws_t.home.stable,
            "controllable_fraction": ctl_t.fraction,
            "snapped": ws_t.n_snapped,
            "configurations": len(ws_t.grid),
            "seconds": time.perf_counter() - t0,
        }
    return out


CARRIED = (
    "bending_rigidity_scale",
    "wire_torsion_scale",
    "catheter_torsion_scale",
    "magnet_remanence",
    "external_remanence",
    "tip_mass",
)
"""Calibrated parameters that carry over from the bench robot to the designs of a study:
properties of the tubes' material, the magnets and the tip as built (not of the bench's
geometry, such as where its external magnet stood)."""


def calibrated_study(study: Study, calibration: dict[str, Any]) -> tuple[Study, dict[str, Any]]:
    """The study with the robot as built: the diagnosed model's effects added to the
    study's (those a study can use: hysteresis needs ordered paths), the calibrated values
    of :data:`CARRIED` set on its base design (the tip's mass, the magnets' remanence) or,
    for the model's stiffness factors, which a design file does not hold, on every
    candidate's parameters (:attr:`Study.calibration`). Returns (that study, what was
    taken: effects, values by name [SI], effects left out)."""
    from design.registry import design_with
    from optimize.sizing.studyfile import STUDY_EFFECTS

    diagnosed = frozenset(calibration["effects"])
    usable = frozenset(e for e in diagnosed if e in STUDY_EFFECTS)
    values = {k: float(v) for k, v in calibration["estimate"].items() if k in CARRIED}
    held = {k: v for k, v in values.items() if PARAMETERS[k].field is not None}
    factors = tuple((k, v) for k, v in values.items() if k not in held)
    taken = {"effects": sorted(usable), "values": values, "left_out": sorted(diagnosed - usable)}
    calibrated = replace(
        study,
        effects=study.effects | usable,
        base=design_with(study.base, held),
        calibration=study.calibration + factors,
    )
    return calibrated, taken


def _tip_note(design: Design, process: str) -> str:
    """Where the tip pieces are printed otherwise than the other parts (always as the
    design file says, the pieces the model carries), say so."""
    designed = design.tip.mounting.process
    if designed == process:
        return ""
    return f", tip pieces {designed} (the design's tip.mounting.process, as modelled)"


def headline(run: Run) -> str:
    """The result in one paragraph: the recommended design's disc (about home, steerable
    without a snap) under the model for design work against the start's, and where its
    design file and parts are."""
    fwd = run.results["forward"]
    start = fwd["start_controllable"].disc_radius / MM
    best = fwd["best_controllable"].disc_radius / MM
    materials = [m for m in run.results["optimise"].materials if m]
    made = f" ({', '.join(materials)})" if materials else ""
    cad = run.results.get("cad")
    parts = f"; parts for it in {Path(cad['out_dir'])} (list: parts.csv)" if cad is not None else ""
    return (
        f"Recommended design{made}: disc radius {best:.2f} mm with the model for design work "
        f"({', '.join(sorted(forward_model(run.study).effects))}), against {start:.2f} mm "
        "for the starting "
        f"design ({best - start:+.2f} mm, {100 * (best / start - 1):+.0f} %). "
        f"{rounding_note(fwd)} Design file: {run.out / BEST_DESIGN}{parts}."
    )


def _cad_summary(report: Any) -> dict[str, Any]:
    """The picklable part of a CAD report (files relative to its folder)."""
    return {
        "out_dir": str(report.out_dir),
        "files": [str(p) for p in report.files],
        "checks": report.checks,
        "parts": report.parts,
        "bom": report.bom,
        "tip": report.tip,
        "passed": report.passed,
        "timings_s": report.timings_s,
    }


def _diagnose(data: Path) -> dict[str, Any]:
    """The diagnosis JSON of the data set (docs/formats.md), and under ``calibration`` its
    final model's effects and estimates by parameter name [SI]."""
    from optimize.fitting.diagnose import diagnose
    from optimize.fitting.measurements import load_dataset

    design, m = load_dataset(data)
    result = diagnose(design, m)
    out = result.to_json()
    out["calibration"] = {
        "effects": sorted(result.final.effects),
        "estimate": dict(result.final.calibration.estimate),
    }
    return out


def write_manifest(
    run: Run,
    study_path: Path | None,
    data: Path | None,
    seed: int,
    failed: str = "",
    folder: dict[str, Any] | None = None,
) -> Path:
    """``manifest.json``: inputs with hashes, versions, seeds, stage timings, every file
    (and the stage that failed, if one did: the files listed are those still valid);
    ``folder``: what :mod:`ringpair.runs` says of the run's folder (an interrupted earlier
    run, the stale files removed), under ``run``."""
    inputs: dict[str, Any] = {
        "study": {
            "path": str(study_path) if study_path else "embedded default study",
            "sha256": sha256(study_path) if study_path else None,
        }
    }
    if data is not None:
        inputs["data"] = {"path": str(data), "sha256": tree_hash(data)}
    files = sorted(
        p
        for p in run.out.rglob("*")
        if p.is_file()
        and ".stages" not in p.parts
        and p.name != "manifest.json"
        and not p.name.startswith(".ringpair")
    )
    doc = {
        "study": run.study.name,
        "inputs": inputs,
        "versions": versions(),
        "seeds": {"tolerance": seed, "study": run.study.seed},
        "failed_stage": failed or None,
        "run": folder or {},
        "stages": {
            name: {"seconds": run.seconds[name], "reused": run.reused[name]} for name in run.seconds
        },
        "files": [
            {"path": str(p.relative_to(run.out)), "bytes": p.stat().st_size, "sha256": sha256(p)}
            for p in files
        ],
    }
    path = run.out / "manifest.json"
    write_text(path, json.dumps(doc, indent=2) + "\n")
    return path


__all__ = [
    "BEST_DESIGN",
    "TOLERANCE_LOOP",
    "TOLERANCES",
    "Run",
    "StageError",
    "Watch",
    "Workspace",
    "headline",
    "run_study",
    "sensitivity",
    "tolerance_spread",
    "write_manifest",
]
