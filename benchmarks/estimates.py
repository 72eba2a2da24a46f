"""The size estimates ringpair announces before long work, against the work measured.

Each estimate is a rate constant (ringpair/options.py and the commands): configurations
solved per second by ``workspace`` (SOLVE_RATE, also the ``simulate`` grids and the
tolerance stage), seconds per ``steer`` target (TARGET_SECONDS) and seconds per NLP start
and sampled configuration (START_SECONDS_PER_CONFIGURATION). Each command runs through
the command line at two sizes, on the demonstrator, so that the fixed cost (start-up,
the compiled model, the plots) cancels; the rate is the difference of the sizes over the
difference of the wall times. Printed: the constant, the measured rate, and their ratio
(above 1: the estimate is pessimistic, the run ends sooner than announced).

An estimate is a promise of order of magnitude (it decides whether a run is announced or
refused), so a ratio within 0.33-3 is good enough; the first run on a machine compiles the
models (run it twice).

    python benchmarks/estimates.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from optimize.sizing.nlp_designs import START_SECONDS_PER_CONFIGURATION
from ringpair.commands.steer import TARGET_SECONDS
from ringpair.options import SOLVE_RATE

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE.parent / "tests" / "support"))
from studies import SMALL  # noqa: E402


def _timed(args: list[str], cwd: Path, warm: bool = False) -> float:
    """Wall time of ``ringpair args`` [s] (``warm``: after one run to warm the caches, the
    compiled models); a failed run stops the benchmark."""
    if warm:
        _timed(args, cwd)
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "ringpair.cli", *args], cwd=cwd, capture_output=True, text=True
    )
    if done.returncode != 0:
        sys.exit(f"ringpair {' '.join(args)} failed ({done.returncode}):\n{done.stderr}")
    return time.perf_counter() - t0


def _rate(work: tuple[float, float], seconds: tuple[float, float]) -> float:
    """Work per second from two runs of sizes ``work`` and wall times ``seconds``."""
    return (work[1] - work[0]) / (seconds[1] - seconds[0])


def workspace(cwd: Path) -> tuple[str, float, float]:
    steps = (10.0, 4.0)
    n = tuple(float(len(np.arange(0.0, 360.0, s)) ** 2) for s in steps)
    t = tuple(
        _timed(["workspace", "--step", f"{s:g}", "--out", f"ws{s:g}"], cwd, warm=s == steps[0])
        for s in steps
    )
    return "workspace configurations per second (SOLVE_RATE)", SOLVE_RATE, _rate(n, t)


def steer(cwd: Path) -> tuple[str, float, float]:
    rng = np.random.default_rng(0)
    sizes = (100, 1000)
    t = []
    for n in sizes:
        yz = rng.uniform(-8.0, 8.0, size=(n, 2)) + (0.0, -22.0)  # about the demonstrator's home
        (cwd / f"t{n}.csv").write_text("y_mm,z_mm\n" + "".join(f"{y:.3f},{z:.3f}\n" for y, z in yz))
        args = ["steer", "--targets", f"t{n}.csv", "--out", f"s{n}.csv"]
        t.append(_timed(args, cwd, warm=n == sizes[0]))
    seconds = (t[1] - t[0]) / (sizes[1] - sizes[0])
    return "steer seconds per target (TARGET_SECONDS)", TARGET_SECONDS, seconds


def optimize(cwd: Path) -> tuple[str, float, float]:
    starts = (2, 8)
    sampled = 24 + 2 * 8
    t = []
    for s in starts:
        (cwd / f"study{s}.toml").write_text(SMALL.replace("starts = 2", f"starts = {s}"))
        t.append(_timed(["optimize", f"study{s}.toml", "--out", f"o{s}"], cwd, warm=s == starts[0]))
    seconds = (t[1] - t[0]) / ((starts[1] - starts[0]) * sampled)
    return (
        "optimize seconds per NLP start and sampled configuration "
        "(START_SECONDS_PER_CONFIGURATION)",
        START_SECONDS_PER_CONFIGURATION,
        seconds,
    )


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        cwd = Path(tmp)
        rows = [workspace(cwd), steer(cwd), optimize(cwd)]
    print(f"{'estimate':80s} {'constant':>10s} {'measured':>10s} {'ratio':>6s}")
    for what, constant, measured in rows:
        per_second = "per second" in what
        # ratio > 1: the run takes less time than announced
        ratio = measured / constant if per_second else constant / measured
        print(f"{what:80s} {constant:10.4g} {measured:10.4g} {ratio:6.2f}")


if __name__ == "__main__":
    main()
