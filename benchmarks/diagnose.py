"""Diagnosis: false discoveries on baseline-only data, and the time of a full diagnosis.

Runs ``--cases`` random baseline-only data sets (as-built stiffness and magnet placement
drawn at random, noise 0.1-0.4 mm, the 63-point bench path of ``optimize.fitting.synth``) through
:func:`optimize.fitting.diagnose.diagnose`, counts the cases where any cause is named (goal: at
most 1 in 20), and times each diagnosis (goal: a 60-point data set in under 30 s). Then
one torsion data set for comparison. ``--setup`` draws each case's nominal design from one
of ``optimize.fitting.synth.SETUPS`` (e.g. ``near``: the magnet's face 15-22 mm from the tip, where
the robot is multistable and the diagnosis fits along the bench's path) instead of using
the demonstrator as it is.

    python benchmarks/diagnose.py [--cases 20] [--seed 0] [--setup near]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

# This folder holds scripts only; keep it from shadowing the packages of the project.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).parent]

from design.designfile import default_design  # noqa: E402
from optimize.fitting.diagnose import diagnose  # noqa: E402
from optimize.fitting.synth import SETUPS, setup_variant, synthesize_data  # noqa: E402


def truth(rng: np.random.Generator, design) -> dict[str, float]:
    return {
        "bending_rigidity_scale": rng.uniform(0.7, 1.3),
        "external_center_x": design.external_magnet.center[0] + rng.uniform(-3e-3, 3e-3),
        "external_center_y": rng.uniform(-3e-3, 3e-3),
        "external_center_z": rng.uniform(-3e-3, 3e-3),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--setup", choices=["demonstrator", *SETUPS], default="demonstrator")
    args = ap.parse_args()
    demonstrator = design = default_design()
    rng = np.random.default_rng(args.seed)
    diagnose(design, synthesize_data(design, seed=0).measurements)  # compile / load once
    named, times = 0, []
    for case in range(args.cases):
        seed = int(rng.integers(2**31))
        if args.setup != "demonstrator":
            gap, stiffness = SETUPS[args.setup]
            design = setup_variant(demonstrator, rng.uniform(*gap), rng.uniform(*stiffness))
        noise = rng.uniform(0.1, 0.4)
        data = synthesize_data(
            design, noise_mm=noise, seed=seed, params_override=truth(rng, design)
        ).measurements
        t0 = time.perf_counter()
        result = diagnose(design, data, seed=seed)
        times.append(time.perf_counter() - t0)
        causes = [c.name for c in result.causes]
        named += bool(causes)
        print(
            f"case {case + 1:2d}: {len(data)} rows, noise {noise:.2f} mm, causes {causes}, "
            f"CV RMSE {result.baseline.cv_rmse_mm:.3f} mm, {times[-1]:.1f} s"
        )
    print(
        f"{args.setup} set-up: false discoveries: {named} of {args.cases} "
        f"(goal <= {args.cases // 20}); "
        f"diagnosis time median {np.median(times):.1f} s, max {np.max(times):.1f} s "
        "(goal < 30 s)"
    )
    over = {"wire_torsion_scale": 3.0, "catheter_torsion_scale": 3.0}
    design = demonstrator
    data = synthesize_data(
        design, ("torsion",), noise_mm=0.3, seed=1, params_override=over
    ).measurements
    t0 = time.perf_counter()
    result = diagnose(design, data)
    print(
        f"torsion data set ({len(data)} rows): causes {[c.name for c in result.causes]}, "
        f"CV RMSE {result.baseline.cv_rmse_mm:.2f} -> {result.final.cv_rmse_mm:.2f} mm, "
        f"{time.perf_counter() - t0:.1f} s"
    )


if __name__ == "__main__":
    main()
