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
Monte Carlo samples, no renders). ``--baseline`` runs the same study a second time with
the named baseline, the cold-start Pareto sweeps (every point from the study's own
starts, independent: the code path before continuation in the bound,
``run_sweeps(continuation=False)``), and prints both and their ratio per stage.
``--pareto`` times the Pareto stage alone (the optimum solved once, then the sweeps
with the baseline and with continuation, ``--points`` per sweep) and compares the fronts.

Every stage is timed in wall seconds and in CPU seconds (this process and the Dask
workers it started and reaped): on a shared machine the CPU time is the measure of work,
the wall time depends on the load (printed).

Goal (issue 54): at most 180 s from a fresh clone on 2 cores, 90 s warm, the same
recommended design and the same fronts.

Run: ``python benchmarks/study.py [--cold] [--quick] [--baseline] [--reference OUT]
[--keep DIR]`` or ``python benchmarks/study.py --pareto [--points N]``.
"""

from __future__ import annotations

import argparse
import csv
import os
import resource
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


def cpu_seconds() -> float:
    """CPU time of this process and of its reaped children (the Dask workers). [s]"""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


Times = dict[str, tuple[float, float]]
"""stage -> (wall, CPU) seconds."""


class _Clock:
    """Records each stage's wall and CPU time as the pipeline reports it."""

    def __init__(self) -> None:
        self.stages: Times = {}
        self._name = ""
        self._t0 = self._c0 = 0.0

    def start(self, what: str) -> None:
        self._name = what.split(" (")[0].split(":")[0]
        self._t0, self._c0 = time.perf_counter(), cpu_seconds()

    def count(self, done: int, total: int) -> None:
        pass

    def end(self, what: str, seconds: float, reused: bool) -> None:
        self.stages[self._name] = (time.perf_counter() - self._t0, cpu_seconds() - self._c0)


def cold_sweeps() -> None:
    """Make the pipeline run the named baseline: the cold-start Pareto sweeps."""
    import optimize.sizing.pareto as pareto

    plain = pareto.run_sweeps

    def run_sweeps(*args: object, **kwargs: object) -> pareto.ParetoResult:
        return plain(*args, **{**kwargs, "continuation": False})  # type: ignore[arg-type]

    pareto.run_sweeps = run_sweeps  # type: ignore[assignment]
    pareto.run_sweeps_continued = plain  # type: ignore[attr-defined]


def continued_sweeps() -> None:
    """Undo :func:`cold_sweeps`."""
    import optimize.sizing.pareto as pareto

    pareto.run_sweeps = getattr(pareto, "run_sweeps_continued", pareto.run_sweeps)


def _quick(study: object, points: int) -> object:
    return replace(
        study,  # type: ignore[type-var]
        pareto=tuple(ParetoSweep(s.against, points, s.low, s.high) for s in study.pareto),  # type: ignore[attr-defined]
    )


def run_once(out: Path, quick: bool) -> tuple[Times, tuple[float, float]]:
    """The default study into ``out``; (stage -> (wall, CPU) s, total (wall, CPU) s)."""
    from ringpair.pipeline import run_study
    from ringpair.report_html import write_report

    study = default_study()
    samples = 200
    if quick:
        study = _quick(study, 2)  # type: ignore[assignment]
        samples = 20
    clock = _Clock()
    t0, c0 = time.perf_counter(), cpu_seconds()
    run = run_study(
        study, out, study_text=repr(study), samples=samples, render=not quick, watch=clock
    )
    t1, c1 = time.perf_counter(), cpu_seconds()
    write_report(run)
    clock.stages["report"] = (time.perf_counter() - t1, cpu_seconds() - c1)
    return clock.stages, (time.perf_counter() - t0, cpu_seconds() - c0)


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


def _table(runs: dict[str, tuple[Times, tuple[float, float]]]) -> None:
    """Wall and CPU seconds per stage; with two runs, their ratio (first over second)."""
    labels = list(runs)
    names = list(dict.fromkeys(n for stages, _ in runs.values() for n in stages))
    head = "".join(f"{label + ' wall':>14}{'CPU':>9}" for label in labels)
    ratio = "  wall ratio  CPU ratio" if len(labels) == 2 else ""
    print(f"{'stage':<44}{head}{ratio}")
    nan = (float("nan"), float("nan"))
    for n in [*names, "total"]:
        vals = [runs[k][1] if n == "total" else runs[k][0].get(n, nan) for k in labels]
        cells = "".join(f"{w:13.1f}s{c:8.1f}s" for w, c in vals)
        extra = ""
        if len(vals) == 2 and vals[1][0] > 0 and vals[1][1] > 0:
            extra = f"  {vals[0][0] / vals[1][0]:9.2f}x {vals[0][1] / vals[1][1]:9.2f}x"
        print(f"{n[:43]:<44}{cells}{extra}")


def pareto_only(points: int | None) -> list[str]:
    """The Pareto stage alone, baseline (cold starts) and continuation, fronts compared;
    what differs beyond FRONT_TOLERANCE_MM (empty: the same)."""
    from optimize.sizing.nlp import optimize_design
    from optimize.sizing.pareto import run_sweeps

    study = default_study()
    if points:
        study = _quick(study, points)  # type: ignore[assignment]
    t0, c0 = time.perf_counter(), cpu_seconds()
    best = optimize_design(study)
    runs: dict[str, tuple[Times, tuple[float, float]]] = {}
    fronts = {}
    timed = {"optimum (once)": (time.perf_counter() - t0, cpu_seconds() - c0)}
    with tempfile.TemporaryDirectory() as tmp:
        for label, continuation in (("baseline", False), ("continued", True)):
            t0, c0 = time.perf_counter(), cpu_seconds()
            res = run_sweeps(study, Path(tmp) / label, continuation=continuation, start=best)
            took = (time.perf_counter() - t0, cpu_seconds() - c0)
            runs[label] = ({"pareto sweeps": took}, took)
            fronts[label] = res.sweeps
    wall, cpu = timed["optimum (once)"]
    print(f"optimum (once): {wall:.1f} s wall, {cpu:.1f} s CPU")
    print(f"Pareto stage, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    _table({"continued": runs["continued"], "baseline": runs["baseline"]})
    faults = []
    for name, old in fronts["baseline"].items():
        for a, b in zip(fronts["continued"][name], old, strict=True):
            same = a.feasible == b.feasible and (
                not a.feasible or abs(a.objective - b.objective) * 1e3 <= FRONT_TOLERANCE_MM
            )
            iters = [sum(x.iterations for x in p.result.starts) if p.result else 0 for p in (a, b)]
            print(
                f"  {name} at {a.epsilon:.4g}: {a.feasible} {a.objective * 1e3:.3f} mm "
                f"({iters[0]} it) against {b.feasible} {b.objective * 1e3:.3f} mm ({iters[1]} it)"
                + ("" if same else "   <-- differs")
            )
            if not same:
                faults.append(f"{name} at {a.epsilon:g}")
    return faults


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cold", action="store_true", help="empty model cache first")
    parser.add_argument("--quick", action="store_true", help="a cheaper variant")
    parser.add_argument("--reference", type=Path, help="an earlier run's folder to match")
    parser.add_argument("--keep", type=Path, help="write the (last) run here")
    parser.add_argument("--baseline", action="store_true", help="also the cold-start sweeps")
    parser.add_argument("--pareto", action="store_true", help="the Pareto stage alone")
    parser.add_argument("--points", type=int, help="points per sweep (with --pareto)")
    args = parser.parse_args()
    if args.pareto:
        faults = pareto_only(args.points)
        print("same fronts" if not faults else "DIFFERENT: " + "; ".join(faults))
        sys.exit(1 if faults else 0)
    runs: dict[str, tuple[Times, tuple[float, float]]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        if args.cold:
            os.environ["RINGPAIR_CACHE"] = str(Path(tmp) / "cache")
            runs["cold"] = run_once(Path(tmp) / "cold", args.quick)
        out = args.keep or Path(tmp) / "warm"
        runs["warm"] = run_once(out, args.quick)
        if args.baseline:
            cold_sweeps()
            try:
                runs["baseline"] = run_once(Path(tmp) / "baseline", args.quick)
            finally:
                continued_sweeps()
        print(f"default study, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
        if args.baseline:
            _table({"warm": runs["warm"], "baseline": runs["baseline"]})
            faults = compare(out, Path(tmp) / "baseline")
            print("same as the baseline" if not faults else "DIFFERENT: " + "; ".join(faults))
        else:
            _table(runs)
        goals = [("warm", GOAL_WARM), ("cold", GOAL_COLD)]
        for label, goal in goals:
            if label in runs:
                total = runs[label][1][0]
                met = "met" if total <= goal else "NOT met"
                print(f"goal {label}: {total:.0f} s wall against {goal:.0f} s ({met})")
        if args.reference:
            faults = compare(out, args.reference)
            print("same results" if not faults else "DIFFERENT: " + "; ".join(faults))
            if faults:
                sys.exit(1)


if __name__ == "__main__":
    main()
