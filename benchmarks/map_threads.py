"""Threaded against serial CasADi maps of the solver's Newton step, by batch size: the
evidence for :data:`design.compiled.THREADED_FROM`.

For each batch size, the Newton step of the large-deflection rod with torsion on the
default design (the heaviest kernel a fit's load ramps run) is evaluated on that many
columns through ``function.map(n, "thread", THREADS)`` and through ``function.map(n)``
(serial), interleaved, best of ``--repeat`` runs of ``--calls`` calls each; prints the
microseconds per call of both and the ratio serial / threaded (above 1: threads pay).
What :func:`design.compiled.mapped` chooses for each size is marked. ``--busy``: with
another process spinning on each other core meanwhile, as the workers of a diagnosis
keep them busy (:mod:`optimize.fitting.workers`, whose maps are serial:
:func:`design.compiled.use_threads`).

    python benchmarks/map_threads.py [--repeat 5] [--calls 200] [--busy]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import sys
import time
from pathlib import Path

import numpy as np

# This folder holds scripts only; keep it from shadowing the packages of the project.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).parent]

from design.compiled import THREADED_FROM, THREADS, ColumnEvaluator  # noqa: E402
from design.designfile import default_design  # noqa: E402
from design.equilibrium.kernels import _initial, kernels  # noqa: E402
from design.model import model_for  # noqa: E402

SIZES = (1, 2, 4, 8, 16, 32, 64, 256, 1024, 4096)


def per_call(evaluate: ColumnEvaluator, args: list[np.ndarray], calls: int) -> float:
    """Seconds per call of ``evaluate`` on ``args``."""
    t0 = time.perf_counter()
    for _ in range(calls):
        evaluate(args)
    return (time.perf_counter() - t0) / calls


def spin() -> None:
    """Keep one core busy (until terminated)."""
    while True:
        pass


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--calls", type=int, default=200, help="calls per run at one column")
    ap.add_argument("--busy", action="store_true", help="the other cores kept busy meanwhile")
    args = ap.parse_args()
    spinners = [
        multiprocessing.Process(target=spin, daemon=True)
        for _ in range((os.cpu_count() or 1) - 1 if args.busy else 0)
    ]
    for s in spinners:
        s.start()
    try:
        measure(args.repeat, args.calls, args.busy)
    finally:
        for s in spinners:
            s.terminate()


def measure(repeat: int, calls_one: int, busy: bool) -> None:
    """Print the table (module docstring)."""
    model = model_for(frozenset({"large_deflection", "torsion"}))
    params = model.parameters(default_design())
    newton = kernels(model).newton
    rng = np.random.default_rng(0)
    print(
        f"CPUs: {os.cpu_count()}, threads: {THREADS}, threaded from {THREADED_FROM} columns"
        + (" in the parent; the other cores busy (a worker's case: serial)" if busy else "")
    )
    print(f"{'columns':>8s} {'threaded us':>12s} {'serial us':>10s} {'serial/threaded':>16s}")
    for size in SIZES:
        command = rng.uniform(-np.pi, np.pi, (2, size))
        x = _initial(model, params, command)
        inputs = [x, command, np.ones((1, size)), np.tile(params, size).reshape(size, -1).T]
        threaded = ColumnEvaluator(newton.map(size, "thread", THREADS))
        serial = ColumnEvaluator(newton.map(size))
        calls = max(3, calls_one // size)
        best = [np.inf, np.inf]
        for _ in range(repeat):
            for j, evaluate in enumerate((threaded, serial)):
                evaluate(inputs)  # the first call on a map allocates its buffers
                best[j] = min(best[j], per_call(evaluate, inputs, calls))
        chosen = "threaded" if size >= THREADED_FROM and not busy else "serial"
        print(
            f"{size:8d} {best[0] * 1e6:12.0f} {best[1] * 1e6:10.0f} "
            f"{best[1] / best[0]:16.2f}   ringpair: {chosen}"
        )


if __name__ == "__main__":
    main()
