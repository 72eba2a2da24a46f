"""Benchmark: the embedded default study, with the paper's baseline model and 3 starts (as
it was when these figures were taken), solved by ringpair's design NLP (IPOPT, exact
derivatives, equilibria as constraints, multi-start over the catheter materials) and by
``scipy.optimize.differential_evolution`` on the same objective and constraints, in one
run.

The baseline evaluates every candidate by forward simulation (``design.solve_equilibria``
on the study's sampled configurations, via :func:`optimize.sizing.nlp.evaluate_design`, the same
metric and constraint expressions as the NLP) and handles the constraints by a penalty:
minimise -disc_radius / disc_radius(base) + PENALTY x (sum of the constraint violations in
their file units: mm, deg, %), a candidate whose equilibria do not converge or are
unstable scores BAD. The catheter material is an integer variable (``integrality``).
Both optima are re-checked by the forward workspace sweep (``design.workspace``).

Run: ``python benchmarks/design_nlp_vs_de.py [--maxiter 200] [--popsize 15]``. Prints the best
objective of each, their wall times and the ratio. Both objectives are the disc radius of
the polygon of the study's 24 parallel-ring samples (design.geometry.disc_radius), a little
below the forward sweep's 720-sample figure. On the shared 2-core development machine
(2026-11-24): NLP 26.791 mm (forward sweep 27.022 mm; Pebax 7233 catheter) in 1.6 s,
9 solves, including building the NLP; differential evolution 26.262 mm (forward
26.489 mm, feasible) after 200 generations, 27,135 forward evaluations, 223.8 s, not yet
converged; ratio 137x. The demonstrator as built: 20.531 mm (it also breaks the study's
15 deg twist limit).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import differential_evolution

# This script is called optimize.py: keep its folder from shadowing the optimize package.
_HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE]

from design.workspace import sweep_workspace  # noqa: E402
from optimize.sizing.nlp import evaluate_design, optimize_design  # noqa: E402
from optimize.sizing.nlp_designs import candidate_design, material_combinations  # noqa: E402
from optimize.sizing.studyfile import default_study  # noqa: E402

PENALTY = 10.0
BAD = 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maxiter", type=int, default=200, help="DE generations at most")
    parser.add_argument("--popsize", type=int, default=15, help="DE population multiplier")
    parser.add_argument(
        "--no-pareto", dest="pareto", action="store_false", help="skip the Dask worker timing"
    )
    args = parser.parse_args()
    study = replace(default_study(), effects=frozenset(), starts=3)  # the paper's model
    combos = material_combinations(study)
    lo = np.array([b.low for b in study.free])
    hi = np.array([b.high for b in study.free])

    t0 = time.perf_counter()
    result = optimize_design(study)
    t_nlp = time.perf_counter() - t0
    assert result.feasible and result.design is not None, result.report()

    base = evaluate_design(study, study.base)  # warms up the compiled forward solver
    scale = base.metrics["disc_radius"]
    evaluations = 0

    def candidate(x: np.ndarray):
        cat, wire = combos[int(round(x[-1]))]
        values = lo + (hi - lo) * x[:-1]
        names = (cat.name if cat else None, wire.name if wire else None)
        return candidate_design(study, values, cat, wire), names

    def penalised(x: np.ndarray) -> float:
        nonlocal evaluations
        evaluations += 1
        design, names = candidate(x)
        ev = evaluate_design(study, design, names)
        if not (ev.converged and ev.stable):
            return BAD
        return -ev.objective / scale + PENALTY * ev.violation

    bounds = [(0.0, 1.0)] * len(lo) + [(0, len(combos) - 1)]
    t0 = time.perf_counter()
    de = differential_evolution(
        penalised,
        bounds,
        integrality=[False] * len(lo) + [True],
        seed=study.seed,
        maxiter=args.maxiter,
        popsize=args.popsize,
        polish=False,
    )
    t_de = time.perf_counter() - t0
    de_design, de_materials = candidate(de.x)
    de_eval = evaluate_design(study, de_design, de_materials)

    step = np.deg2rad(10.0)
    ws_nlp = sweep_workspace(result.design, step)
    ws_de = sweep_workspace(de_design, step)
    ws_base = sweep_workspace(study.base, step)
    print(f"default study {study.name!r}: {len(lo)} free quantities, {len(combos)} materials")
    print(f"  base design (demonstrator)      disc radius {ws_base.disc_radius * 1e3:8.3f} mm")
    print(
        f"  ringpair NLP (IPOPT)            disc radius {result.objective * 1e3:8.3f} mm "
        f"(forward {ws_nlp.disc_radius * 1e3:.3f} mm), {result.materials[0]}, "
        f"{len(result.starts)} solves, {t_nlp:7.2f} s"
    )
    feasible = "feasible" if de_eval.violation == 0 else f"violation {de_eval.violation:.3g}"
    print(
        f"  differential_evolution          disc radius {de_eval.objective * 1e3:8.3f} mm "
        f"(forward {ws_de.disc_radius * 1e3:.3f} mm), {de_materials[0]}, {feasible}, "
        f"{evaluations} evaluations, {de.nit} generations, {t_de:7.2f} s ({de.message})"
    )
    print(f"  objective ratio NLP / DE: {result.objective / de_eval.objective:.4f}")
    print(f"  wall-time ratio DE / NLP: {t_de / t_nlp:.1f}x")
    if args.pareto:
        pareto_workers(study)


def pareto_workers(study) -> None:
    """Wall time of one Pareto sweep (the external-magnet distance, the default study's
    points) on a local Dask cluster of 1 and of 2 workers, from scratch each time."""
    import dataclasses
    import tempfile
    from pathlib import Path

    from optimize.sizing.pareto import run_sweeps

    sweep = next(s for s in study.pareto if s.against == "external_distance")
    one = dataclasses.replace(study, pareto=(sweep,))
    times = {}
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            result = run_sweeps(one, Path(tmp), workers=workers)
            times[workers] = time.perf_counter() - t0
        print(
            f"  Pareto sweep, {result.solved} points, {workers} Dask worker(s): "
            f"{times[workers]:6.1f} s (cluster start-up included)"
        )
    print(f"  speed-up 2 vs 1 workers: {times[1] / times[2]:.2f}x")


if __name__ == "__main__":
    main()
