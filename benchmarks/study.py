"""Benchmark: ``ringpair study`` on the embedded default study, stage by stage.

Runs the main job (:func:`ringpair.pipeline.run_study`, then the report) into a fresh
output folder and prints each stage's wall time and the total. ``--cold`` compiles into an
empty model cache first (a fresh clone's first run: every model compiled), then runs the
same study again warm into another fresh folder, and prints both and their ratio per stage.
``--reference OUT`` compares the result with an earlier run's folder (``OUT`` written by
``ringpair study`` or this script, e.g. by an earlier commit: the named baseline) and
fails (exit 1) unless the recommended design's disc radius is within 0.1 mm of it and
every Pareto point agrees (same feasibility, objective within FRONT_TOLERANCE).
``--quick`` runs a cheaper variant for iteration (two points per Pareto sweep, 20
Monte Carlo samples, no renders).

Goal (issue 54): at most 180 s from a fresh clone on 2 cores, 90 s warm, the same
recommended design and the same fronts.

Run: ``python benchmarks/study.py [--cold] [--quick] [--reference OUT] [--keep DIR]``.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

# This script's folder holds optimize-like names: keep it from shadowing the packages.
_HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE]

from design.designfile import load_design  # noqa: E402
from optimize.sizing.studyfile import ParetoSweep, default_study  # noqa: E402

DISC_TOLERANCE_MM = 0.1
"""The recommended design's disc radius (forward re-simulation) agrees within this. [mm]"""
FRONT_TOLERANCE_MM = 0.1
"""Each feasible Pareto point's objective (disc radius) agrees within this. [mm]"""
GOAL_COLD, GOAL_WARM = 180.0, 90.0


class _Clock:
    """Records each stage's wall time as the pipeline reports it."""

    def __init__(self) -> None:
        self.stages: dict[str, float] = {}
        self._name = ""
        self._t0 = 0.0

    def start(self, what: str) -> None:
        self._name, self._t0 = what.split(" (")[0].split(":")[0], time.perf_counter()

    def count(self, done: int, total: int) -> None:
        pass

    def end(self, what: str, seconds: float, reused: bool) -> None:
        self.stages[self._name] = time.perf_counter() - self._t0


def run_once(out: Path, quick: bool) -> tuple[dict[str, float], float]:
    """The default study into ``out``; (stage -> seconds, total seconds)."""
    from ringpair.pipeline import run_study
    from ringpair.report_html import write_report

    study = default_study()
    samples = 200
    if quick:
        study = replace(
            study,
            pareto=tuple(ParetoSweep(s.against, 2, s.low, s.high) for s in study.pareto),
        )
        samples = 20
    clock = _Clock()
    t0 = time.perf_counter()
    run = run_study(
        study, out, study_text=repr(study), samples=samples, render=not quick, watch=clock
    )
    t1 = time.perf_counter()
    write_report(run)
    clock.stages["report"] = time.perf_counter() - t1
    return clock.stages, time.perf_counter() - t0


def _front(out: Path) -> dict[str, list[tuple[float, str, str]]]:
    fronts = {}
    for path in sorted((out / "pareto").glob("pareto_*.csv")):
        lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
        rows = list(csv.DictReader(lines))
        fronts[path.stem] = [(float(r["epsilon"]), r["feasible"], r["objective"]) for r in rows]
    return fronts


def compare(out: Path, reference: Path) -> list[str]:
    """What differs between two study folders beyond the tolerances (empty: the same)."""
    from design.workspace import sweep_workspace
    from ringpair.pipeline import BEST_DESIGN, forward_model

    model = forward_model(default_study())
    discs = [
        sweep_workspace(load_design(f / BEST_DESIGN), model=model).disc_radius * 1e3
        for f in (out, reference)
    ]
    faults = []
    print(f"recommended design's disc radius: {discs[0]:.3f} mm, reference {discs[1]:.3f} mm")
    if abs(discs[0] - discs[1]) > DISC_TOLERANCE_MM:
        faults.append(f"disc radius {discs[0]:.3f} mm against {discs[1]:.3f} mm")
    new, old = _front(out), _front(reference)
    for name in sorted(set(new) | set(old)):
        a, b = new.get(name, []), old.get(name, [])
        if [e for e, _, _ in a] != [e for e, _, _ in b]:
            faults.append(f"{name}: other bounds")
            continue
        for (eps, fa, oa), (_, fb, ob) in zip(a, b, strict=True):
            same = fa == fb and (fa != "True" or abs(float(oa) - float(ob)) <= FRONT_TOLERANCE_MM)
            mark = "" if same else "   <-- differs"
            print(f"  {name} at {eps:g}: {fa} {oa or '-'} against {fb} {ob or '-'}{mark}")
            if not same:
                faults.append(f"{name} at {eps:g}: {fa} {oa} against {fb} {ob}")
    return faults


def _table(runs: dict[str, tuple[dict[str, float], float]]) -> None:
    labels = list(runs)
    names = list(dict.fromkeys(n for stages, _ in runs.values() for n in stages))
    head = "".join(f"{label:>12}" for label in labels)
    ratio = "  ratio" if len(labels) == 2 else ""
    print(f"{'stage':<48}{head}{ratio}")
    for n in [*names, "total"]:
        vals = [runs[k][1] if n == "total" else runs[k][0].get(n, float("nan")) for k in labels]
        cells = "".join(f"{v:11.1f}s" for v in vals)
        extra = f"  {vals[0] / vals[1]:5.2f}x" if len(vals) == 2 and vals[1] > 0 else ""
        print(f"{n[:47]:<48}{cells}{extra}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cold", action="store_true", help="empty model cache first")
    parser.add_argument("--quick", action="store_true", help="a cheaper variant")
    parser.add_argument("--reference", type=Path, help="an earlier run's folder to match")
    parser.add_argument("--keep", type=Path, help="write the (last) run here")
    args = parser.parse_args()
    runs: dict[str, tuple[dict[str, float], float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        if args.cold:
            os.environ["RINGPAIR_CACHE"] = str(Path(tmp) / "cache")
            runs["cold"] = run_once(Path(tmp) / "cold", args.quick)
        out = args.keep or Path(tmp) / "warm"
        runs["warm"] = run_once(out, args.quick)
        print(f"default study, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
        _table(runs)
        goals = [("warm", GOAL_WARM), ("cold", GOAL_COLD)]
        for label, goal in goals:
            if label in runs:
                met = "met" if runs[label][1] <= goal else "NOT met"
                print(f"goal {label}: {runs[label][1]:.0f} s against {goal:.0f} s ({met})")
        if args.reference:
            faults = compare(out, args.reference)
            print("same results" if not faults else "DIFFERENT: " + "; ".join(faults))
            if faults:
                sys.exit(1)


if __name__ == "__main__":
    main()
