"""Fuzz the command line: many more generated cases than CI's property tests
(tests/ringpair/test_fuzz.py), at random, with the same strategies and checks
(tests/support/fuzzing.py): design files, study files (also valid ones, which run the
optimiser), measurement CSVs, option strings and hostile inputs (file kinds, deep
nesting, integers beyond int64, designs at the corners of the design space), through
``ringpair`` in-process.

Printed per family and in all: cases, exit 0, exit 2, failures (a broken promise: another
exit code, a traceback, a file written on exit 2 or outside the folder, a row that
contradicts itself, a temporary left), the wall time, and each failure's command line and
problems (at most --show of them).

    python benchmarks/fuzz.py [--examples 300] [--seed 0] [--families design,options,...]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from collections import Counter
from pathlib import Path

_HERE = Path(__file__).resolve().parent
# benchmarks/design_optimization.py would shadow the optimize package from this folder.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE]
sys.path.insert(0, str(_HERE.parent / "tests" / "support"))

from fuzzing import (  # noqa: E402
    data_cases,
    design_cases,
    input_cases,
    option_cases,
    run_case,
    study_cases,
)
from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402

FAMILIES = {
    "design": design_cases(),
    "options": option_cases(),
    "data": data_cases(),
    "study": study_cases(hostile=False),
    "inputs": input_cases(),
}


def fuzz(name: str, examples: int, rng_seed: int, show: int) -> Counter:
    """Run ``examples`` cases of family ``name``; print and return the counts."""
    counts: Counter = Counter()
    failures: list[tuple[list[str], list[str]]] = []

    @seed(rng_seed)
    @settings(
        max_examples=examples,
        deadline=None,
        database=None,
        phases=[Phase.generate],  # count every case; no shrinking
        suppress_health_check=list(HealthCheck),
    )
    @given(FAMILIES[name])
    def one(case) -> None:
        outcome = run_case(case)
        counts["cases"] += 1
        counts[f"exit {outcome.exit_code}"] += 1
        if outcome.problems:
            counts["failures"] += 1
            failures.append((case.args, outcome.problems))

    t0 = time.perf_counter()
    one()
    counts["seconds"] = round(time.perf_counter() - t0)
    print(
        f"{name:8s} cases {counts['cases']:5d}  exit 0 {counts['exit 0']:5d}  "
        f"exit 2 {counts['exit 2']:5d}  failures {counts['failures']:3d}  "
        f"({counts['seconds']} s)"
    )
    for args, problems in failures[:show]:
        print(f"    ringpair {' '.join(args)}\n      {'; '.join(problems)[:400]}")
    return counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=int, default=300, help="Cases per family.")
    parser.add_argument("--seed", type=int, default=0, help="Seed of the generator.")
    parser.add_argument("--families", default=",".join(FAMILIES), help="Comma list.")
    parser.add_argument("--show", type=int, default=5, help="Failures printed per family.")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    total: Counter = Counter()
    for name in args.families.split(","):
        total += fuzz(name.strip(), args.examples, args.seed, args.show)
    print(
        f"{'all':8s} cases {total['cases']:5d}  exit 0 {total['exit 0']:5d}  "
        f"exit 2 {total['exit 2']:5d}  failures {total['failures']:3d}  ({total['seconds']} s)"
    )
    sys.exit(1 if total["failures"] else 0)


if __name__ == "__main__":
    main()
