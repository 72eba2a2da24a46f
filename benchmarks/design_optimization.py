"""Benchmark: designing with the robot as it will be built. The embedded default study is
optimised twice in one run, with the paper's baseline model (``effects = "none"``) and with
the model for design work, the printed tip included (``near_field``, ``large_deflection``,
``gravity``, ``printed_tip``); both optima are then re-simulated with that faithful model
(the forward workspace sweep, :func:`design.workspace.sweep_workspace`, 10-degree grid and
the 720-sample loops) and checked against the study's limits with it
(:func:`optimize.sizing.nlp.evaluate_design`).

Goal (issue 16): the faithful optimum's re-simulated disc radius at least 1.15x the
baseline optimum's, and the faithful study under 5 minutes on the development machine.

Run: ``python benchmarks/design_optimization.py [--starts N]``. Prints, for each optimum,
the disc radius the optimiser predicted, the re-simulated disc radius, the neutral
deflection and the sag, the printed tip's diameter, the limits it breaks under the
faithful model, and the wall time; then the ratio of the re-simulated disc radii.
The faithful study's time includes building its NLP (and, the first time on a machine,
compiling the model's per-configuration function, printed separately).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

# This script's folder holds optimize-like names: keep it from shadowing the packages.
_HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE]

from design.model import DEFAULT_EFFECTS, model_for  # noqa: E402
from design.mounting import design_tip_geometry  # noqa: E402
from design.workspace import sweep_workspace  # noqa: E402
from optimize.sizing.nlp import _nlp_shape, evaluate_design, optimize_design  # noqa: E402
from optimize.sizing.nlp_problem import core  # noqa: E402
from optimize.sizing.studyfile import default_study  # noqa: E402

FAITHFUL = DEFAULT_EFFECTS
"""The model for design work (the printed tip included)."""
GOAL_RATIO = 1.15
GOAL_SECONDS = 300.0
TOLERANCE = 1e-4
"""A limit counts as broken beyond this, in its file unit (mm, deg, %)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=None, help="starts per material")
    args = parser.parse_args()
    base_study = replace(default_study(), effects=frozenset())
    if args.starts:
        base_study = replace(base_study, starts=args.starts)
    faithful_study = replace(base_study, effects=FAITHFUL)
    model = model_for(FAITHFUL)

    t0 = time.perf_counter()
    core(_nlp_shape(faithful_study))
    t_build = time.perf_counter() - t0
    rows = []
    for label, study in (("baseline model", base_study), ("faithful model", faithful_study)):
        t0 = time.perf_counter()
        result = optimize_design(study)
        seconds = time.perf_counter() - t0
        if not result.feasible or result.design is None:
            print(f"{label}: no feasible optimum\n{result.report()}")
            return
        ws = sweep_workspace(result.design, np.deg2rad(10.0), model)
        check = evaluate_design(faithful_study, result.design, result.materials)
        broken = [s.describe() for s in check.constraints if s.margin / s.scale < -TOLERANCE]
        tip = design_tip_geometry(result.design).outer_diameter
        rows.append((label, result, ws, check, broken, tip, seconds))

    print(f"default study {base_study.name!r}, re-simulated with {model.name}")
    for label, result, ws, check, broken, tip, seconds in rows:
        print(
            f"  {label}: predicted disc {result.metrics['disc_radius'] * 1e3:7.2f} mm, "
            f"re-simulated {ws.disc_radius * 1e3:7.2f} mm; neutral "
            f"{check.metrics['neutral_deflection'] * 1e3:.2f} mm, sag "
            f"{check.metrics['sag'] * 1e3:.2f} mm; printed tip {tip * 1e3:.2f} mm; "
            f"rings {result.values.get('magnet_outer_diameter', np.nan) * 1e3:.2f} mm; "
            f"{result.materials[0]}; {len(result.starts)} solves in {seconds:.1f} s"
        )
        print(f"    faithful model: converged {check.converged}, stable {check.stable}")
        print("    breaks: " + ("; ".join(broken) if broken else "nothing"))
    base_ws, faithful_ws = rows[0][2], rows[1][2]
    with np.errstate(divide="ignore"):
        ratio = np.float64(faithful_ws.disc_radius) / base_ws.disc_radius
    if base_ws.disc_radius == 0:
        print("  the baseline optimum's loop no longer surrounds the straight tip (disc 0)")
    total = rows[1][6] + t_build
    print(f"  re-simulated disc ratio faithful / baseline: {ratio:.3f} (goal >= {GOAL_RATIO})")
    print(
        f"  faithful study {total:.1f} s, of which building its NLP {t_build:.1f} s "
        f"(goal < {GOAL_SECONDS:.0f} s)"
    )


if __name__ == "__main__":
    main()
