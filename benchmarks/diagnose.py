"""Diagnosis on set-ups it has never seen: right diagnoses, false discoveries, the final
model's held-out error, parameter recovery and the time of a diagnosis.

Draws ``--random N`` bench data sets for each planted effect, each pair of effects and
nothing planted (null sets), across the whole design space with as-built deviations
(:mod:`optimize.fitting.planted`: its module docstring states the ranges and the
detectability criterion), and runs :func:`optimize.fitting.diagnose.diagnose` on each,
given only the nominal design file and the data. Prints, per planted set and overall:

- right: the planted effects named and nothing else (goal >= 95 % where detectable);
- false: null sets with any cause named (goal <= 1 in 20), and the share of named causes
  that were not planted;
- CV/noise: the final model's cross-validated RMS distance over the noise's
  (noise x sqrt(measured axes)) (goal <= 1.3), beside that of the planted effects' own
  model fitted from the truth with the same folds (a reference: on a few
  configurations for many parameters it lies above 1.3 itself);
- recovery: |estimate - truth| / reported 1-sigma (profile-likelihood interval on the
  truth's side) of the named planted effects' parameters: median, share within 2. The
  truth is what the final model finds in the data without their noise
  (:func:`identifiable_truth`): a torsion factor multiplies the nominal GJ while the robot
  has its modulus as built, and where the final model does not fit the field's strength
  the parameters the data fix only relative to it
  (:data:`optimize.fitting.calibrate.FIELD_RELATIVE`) follow the as-built remanences;
- beyond priors: how many baselines (and final models) needed a parameter beyond
  PULL_LIMIT (3) prior sigmas of its nominal value (:mod:`optimize.fitting.calibrate.priors`;
  ``--no-priors`` diagnoses with the plain least squares, as before priors, and judges
  its estimates by the default priors: run both for the before and after);
- time: median seconds per diagnosis (goal <= 30 s) on the worker processes
  :mod:`optimize.fitting.workers` gives it (``RINGPAIR_WORKERS``, default one per core),
  and the CPU seconds of the process and its workers (all threads; less sensitive to a
  shared machine's load than the wall time). ``--serial`` also runs each diagnosis in one
  process, the baseline of that speed-up, prints the ratio and checks that both give the
  same diagnosis. Every
  model a diagnosis can fit is built first (:func:`warm_up`; its time is printed): the
  first use of a model on a machine compiles it to native code (10-20 s each, then cached
  on disk), which is not the diagnosis' cost.

    python benchmarks/diagnose.py --random 2 [--seed 0] [--only torsion,null] [--serial]
        [--on-axis] [--jsonl out.jsonl]
    python benchmarks/diagnose.py --summary out.jsonl   # the figures of earlier rows

The baseline it is judged against is the calibrated paper model the diagnosis starts
from (``baseline`` of each result).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import resource
import sys
import time
import traceback
from pathlib import Path

import numpy as np

# This folder holds scripts only; keep it from shadowing the packages of the project.
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).parent]

from rich.console import Console  # noqa: E402
from rich.progress import Progress  # noqa: E402

from design.units import MM  # noqa: E402
from optimize.fitting.calibrate import (  # noqa: E402
    EFFECT_FREE,
    FIELD_RELATIVE,
    PULL_LIMIT,
    calibrate,
)
from optimize.fitting.diagnose import Diagnosis, Fit, _fit, diagnose, report_key  # noqa: E402
from optimize.fitting.planted import PLANTED_SETS, Planted, draw_planted  # noqa: E402
from optimize.fitting.sensitivity import built_model  # noqa: E402
from optimize.fitting.workers import worker_count  # noqa: E402


def warm_up() -> tuple[int, float]:
    """Build every model a diagnosis can fit (each set of candidate effects), compiling
    its solver and sensitivity functions to native code where the disk cache
    (:mod:`design.compiled`) has none yet. A machine compiles each model once; the
    diagnoses' times then measure the diagnosis. Returns (models, seconds)."""
    t0 = time.perf_counter()
    names = list(EFFECT_FREE)
    sets = [frozenset(c) for r in range(len(names) + 1) for c in itertools.combinations(names, r)]
    for effects in sets:
        built_model(effects)
    return len(sets), time.perf_counter() - t0


PRIORS = True
"""Whether the diagnoses fit with priors (``--no-priors``: the plain least squares, the
diagnosis before priors)."""


def timed(case: Planted, j: int, workers: int | None = None) -> tuple[Diagnosis, float, float]:
    """Diagnose ``case`` (fold seed ``j``) on ``workers`` processes (None: the default,
    :mod:`optimize.fitting.workers`), with priors unless ``--no-priors`` (PRIORS);
    returns it with its wall and CPU seconds (this process and its workers)."""
    saved = os.environ.get("RINGPAIR_WORKERS")
    if workers is not None:
        os.environ["RINGPAIR_WORKERS"] = str(workers)
    try:
        t0, c0 = time.perf_counter(), cpu_seconds()
        result = diagnose(case.design, case.measurements, seed=j, priors=PRIORS)
        return result, time.perf_counter() - t0, cpu_seconds() - c0
    finally:
        if saved is None:
            os.environ.pop("RINGPAIR_WORKERS", None)
        else:
            os.environ["RINGPAIR_WORKERS"] = saved


def cpu_seconds() -> float:
    """CPU seconds of this process (all threads) and of its finished worker processes."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


MODULUS_OF = {
    "wire_torsion_scale": ("wire_youngs_modulus", "wire"),
    "catheter_torsion_scale": ("catheter_youngs_modulus", "catheter"),
}
"""A torsion factor multiplies the tube's nominal GJ (design.model), so its estimate is the
torsional rigidity found over the nominal one; the robot as built has its own modulus, so
the true GJ over the nominal is the planted factor times E as built over E nominal."""


def approximate_truth(case: Planted, name: str, final: Fit) -> float:
    """The true value of parameter ``name`` of ``case`` on the scale the ``final`` model
    estimates it, to first order: MODULUS_OF; relative to the field's strength where that
    model does not fit it (exact where the rings' and the external magnet's remanences are
    off by the same factor, :data:`optimize.fitting.calibrate.FIELD_RELATIVE`). [SI]"""
    truth = case.truth[name]
    if name in MODULUS_OF:
        modulus, tube = MODULUS_OF[name]
        truth *= case.truth[modulus] / getattr(case.design.robot, tube).youngs_modulus
    if name in FIELD_RELATIVE and "external_remanence" not in final.calibration.names:
        truth /= (case.truth["magnet_remanence"] / case.design.tip.magnet_remanence) * (
            case.truth["external_remanence"] / case.design.external_magnet.remanence
        )
    return truth


def identifiable_truth(case: Planted, final: Fit) -> dict[str, float]:
    """The true values of the ``final`` model's free parameters as that model can find
    them: its fit to the data without their noise, from :func:`approximate_truth`.

    The rings' remanence drives their mutual torque (its square) and their torque in the
    external field (times the external remanence): as built +4 % and -7 % (seed [2, 3, 0]),
    no one stiffness scale maps the truth onto the design's field. The product rule put
    the wire's transmission at 0.497, 4.3 standard errors from the estimate 0.439; the fit
    to the noise-free data finds 0.443 (0.35 of them). Where that fit does not reach a
    tenth of the noise (another basin), the first-order values. [SI]"""
    names = final.calibration.names
    start = {n: approximate_truth(case, n, final) for n in names if n in case.truth}
    first_order = {n: start.get(n, math.nan) for n in names}
    try:
        fit = calibrate(
            case.design,
            case.synthetic.noise_free,
            final.effects,
            names,
            initial=start,
            ordered=final.ordered,
            sigma=case.noise_mm * MM,
        )
    except Exception:
        return first_order
    if not fit.rmse_mm < 0.1 * noise_rms(case):
        return first_order
    return dict(fit.estimate)


def recovery(result: Diagnosis, case: Planted, truth: dict[str, float]) -> list[float]:
    """|estimate - truth| / 1-sigma of each named planted effect's own parameters, the
    truth as a right fit can find it (:func:`identifiable_truth`). [-]"""
    out = []
    for cause in result.causes:
        if cause.name not in case.planted:
            continue
        for name in EFFECT_FREE[cause.name]:
            estimate = result.final.calibration.estimate[name]
            key, factor = report_key(name)
            lower, upper = (v / factor for v in cause.intervals[key])
            sigma = (upper - estimate) if truth[name] > estimate else (estimate - lower)
            out.append(abs(estimate - truth[name]) / sigma if sigma > 0 else math.inf)
    return out


def noise_rms(case: Planted) -> float:
    """The RMS distance the noise alone puts between data and truth. [mm]"""
    return case.noise_mm * math.sqrt(3 if case.view == "3d" else 2)


def planted_cv(case: Planted, seed: int) -> float:
    """The cross-validated RMSE over :func:`noise_rms` of the planted effects' own model
    fitted from the truth (its default free parameters), with the diagnosis' folds: a
    reference for the diagnosis' figure, above 1.3 where few configurations fix many
    parameters (seed [2, 13, 0], 15 rows for 7 parameters: 1.39, the diagnosis' too). Not
    a bound: along a multistable path one fit from the truth can end in another basin
    than the diagnosis' search (seed [2, 14, 0]: 8.20 against the diagnosis' 1.07). [-]"""
    try:
        fit = _fit(
            case.design,
            case.measurements,
            case.planted,
            k=5,
            seed=seed,
            cv=True,
            starts=[dict(case.truth)],
            sigma=None,
            priors=PRIORS,
        )
    except Exception:  # the reference is then unknown; the diagnosis' row stands
        return math.nan
    return fit.cv_rmse_mm / noise_rms(case)


def score(
    result: Diagnosis, case: Planted, seconds: float, cpu: float, reference: float
) -> dict[str, object]:
    """One diagnosis' figures (a JSON-able row); ``reference``: :func:`planted_cv`."""
    named = {c.name for c in result.causes}
    truth = identifiable_truth(case, result.final)
    return {
        "planted": case.name,
        "describe": case.describe(),
        "detectable": case.detectable,
        "margin": case.margin,
        "named": sorted(named),
        "right": named == set(case.planted),
        "false": sorted(named - case.planted),
        "cv_over_noise": result.final.cv_rmse_mm / noise_rms(case),
        "planted_cv_over_noise": reference,
        "recovery": recovery(result, case, truth),
        "estimates": {
            n: [result.final.calibration.estimate[n], truth[n]]
            for c in result.causes
            if c.name in case.planted
            for n in EFFECT_FREE[c.name]
        },
        "seconds": seconds,
        "cpu_seconds": cpu,
        "unexplained": result.unexplained,
        # the estimates beyond PULL_LIMIT prior sigmas (judged by the default priors
        # where the diagnosis fitted without them)
        "baseline_beyond_prior": result.baseline.calibration.beyond_prior(),
        "final_beyond_prior": result.final.calibration.beyond_prior(),
        "verdicts": {k: c.verdict for k, c in result.candidates.items()},
    }


def same(a: Diagnosis, b: Diagnosis) -> bool:
    """Whether two diagnoses of the same data say the same (their JSON but the time)."""

    def text(d: Diagnosis) -> str:
        doc = d.to_json()
        doc.pop("time_s", None)
        return json.dumps(doc, sort_keys=True, default=str)

    return text(a) == text(b)


def summary(rows: list[dict], label: str) -> str:
    """One line of figures over ``rows``."""
    ok = [r for r in rows if "error" not in r]
    det = [r for r in ok if r["detectable"]]
    right = sum(r["right"] for r in det)
    nulls = [r for r in ok if r["planted"] == "null"]
    named = sum(len(r["named"]) for r in ok)
    false_named = sum(len(r["false"]) for r in ok)
    cv = [r["cv_over_noise"] for r in ok if np.isfinite(r["cv_over_noise"])]
    rec = [z for r in ok for z in r["recovery"]]
    times = [r["seconds"] for r in ok]
    beyond = [r for r in ok if "baseline_beyond_prior" in r]
    parts = [
        f"right {right}/{len(det)}"
        + (f" ({len(ok) - len(det)} undetectable)" * (len(ok) > len(det))),
    ]
    if nulls:
        parts.append(f"null named {sum(bool(r['named']) for r in nulls)}/{len(nulls)}")
    parts.append(f"false {false_named}/{named} named" if named else "false 0/0 named")
    if cv:
        parts.append(f"CV/noise median {np.median(cv):.2f} max {np.max(cv):.2f}")
    pairs = [
        (r["cv_over_noise"], r["planted_cv_over_noise"])
        for r in ok
        if np.isfinite(r.get("planted_cv_over_noise", math.nan))
    ]
    if pairs:
        refs = np.array(pairs)
        parts.append(
            f"(planted model from the truth: median {np.median(refs[:, 1]):.2f} max "
            f"{np.max(refs[:, 1]):.2f}; within 1.1x of it "
            f"{np.sum(refs[:, 0] <= 1.1 * refs[:, 1])}/{len(refs)})"
        )
    if rec:
        rec_a = np.asarray(rec)
        parts.append(f"recovery median {np.median(rec_a):.2f}, within 2: {np.mean(rec_a <= 2):.0%}")
    if beyond:
        parts.append(
            f"baseline beyond {PULL_LIMIT:g} prior sigmas "
            f"{sum(bool(r['baseline_beyond_prior']) for r in beyond)}/{len(beyond)}, final "
            f"{sum(bool(r['final_beyond_prior']) for r in beyond)}/{len(beyond)}"
        )
    if times:
        parts.append(f"time median {np.median(times):.0f} s")
    cpu = [r["cpu_seconds"] for r in ok if "cpu_seconds" in r]
    if cpu:
        parts.append(f"CPU median {np.median(cpu):.0f} s")
    serial = [
        (r["serial_seconds"], r["seconds"], r["same_as_serial"])
        for r in ok
        if "serial_seconds" in r
    ]
    if serial:
        a = np.array(serial)
        parts.append(
            f"one process: median {np.median(a[:, 0]):.0f} s, speed-up median "
            f"{np.median(a[:, 0] / a[:, 1]):.2f}x, same result {int(a[:, 2].sum())}/{len(a)}"
        )
    if len(ok) < len(rows):
        parts.append(f"FAILED {len(rows) - len(ok)}")
    return f"{label:<28s}" + ", ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--random", type=int, default=2, metavar="N", help="data sets per planted set")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", default="", help="comma-separated planted sets (e.g. torsion,null)")
    ap.add_argument("--jsonl", type=Path, help="append one JSON row per diagnosis here")
    ap.add_argument(
        "--on-axis",
        action="store_true",
        help="every nominal design with its magnet on the robot's axis, magnetised along it "
        "(the paper's arrangement; symmetric set-ups, which the drawn positions almost never are)",
    )
    ap.add_argument(
        "--summary", type=Path, help="only print the figures of the rows of this --jsonl file"
    )
    ap.add_argument(
        "--serial",
        action="store_true",
        help="also run each diagnosis in one process (the baseline of the worker processes' "
        "speed-up) and check it gives the same result",
    )
    ap.add_argument(
        "--no-priors",
        action="store_true",
        help="diagnose with the plain least squares, no priors (the diagnosis before them): "
        "the baseline of the priors' figures",
    )
    args = ap.parse_args()
    global PRIORS
    PRIORS = not args.no_priors
    if args.summary:
        rows_of: dict[str, list[dict]] = {}
        for line in args.summary.read_text().splitlines():
            row = json.loads(line)
            rows_of.setdefault(row["planted"], []).append(row)
        report(rows_of, f"{args.summary}")
        return
    sets = [
        s
        for s in PLANTED_SETS
        if not args.only or ("+".join(sorted(s)) or "null") in args.only.split(",")
    ]
    console = Console()
    with console.status("building the models (compiled once per machine)"):
        count, seconds = warm_up()
    console.print(
        f"{count} models built in {seconds:.0f} s (compiling those new to this machine); "
        f"not counted in the times below; {worker_count()} worker process(es) per diagnosis"
    )
    rows: dict[str, list[dict]] = {}
    with Progress(console=console) as bar:
        task = bar.add_task("diagnosing", total=len(sets) * args.random)
        for planted in sets:
            i = PLANTED_SETS.index(planted)  # the same seeds with or without --only
            for j in range(args.random):
                rng = np.random.default_rng([args.seed, i, j])
                label = "+".join(sorted(planted)) or "null"
                bar.update(task, description=f"{label} #{j + 1}: drawing")
                case = draw_planted(rng, planted, on_axis=args.on_axis)
                bar.update(task, description=f"{label} #{j + 1}: diagnosing")
                try:
                    result, seconds, cpu = timed(case, j)
                    bar.update(task, description=f"{label} #{j + 1}: the planted model")
                    row = score(result, case, seconds, cpu, planted_cv(case, j))
                    if args.serial:
                        bar.update(task, description=f"{label} #{j + 1}: in one process")
                        alone, serial, _ = timed(case, j, workers=1)
                        row["serial_seconds"] = serial
                        row["same_as_serial"] = same(alone, result)
                except Exception as exc:  # the benchmark reports a failure and goes on
                    row = {
                        "planted": label,
                        "describe": case.describe(),
                        "error": repr(exc),
                        "traceback": traceback.format_exc(),
                    }
                row["seed"] = [args.seed, i, j]
                rows.setdefault(label, []).append(row)
                mark = (
                    "ERROR " + row["error"]
                    if "error" in row
                    else (
                        f"named {row['named']} {'right' if row['right'] else 'WRONG'}, CV/noise "
                        f"{row['cv_over_noise']:.2f} (planted model "
                        f"{row['planted_cv_over_noise']:.2f}), {row['seconds']:.0f} s "
                        f"({row['cpu_seconds']:.0f} s CPU)"
                        + (
                            f"; in one process {row['serial_seconds']:.0f} s "
                            f"({row['serial_seconds'] / row['seconds']:.2f}x), "
                            f"{'the same' if row['same_as_serial'] else 'DIFFERENT'} result"
                            if "serial_seconds" in row
                            else ""
                        )
                    )
                )
                bar.console.print(f"{case.describe()}: {mark}")
                if args.jsonl:
                    with args.jsonl.open("a") as f:
                        f.write(json.dumps(row, default=float) + "\n")
                bar.advance(task)
    title = f"--random {args.random} --seed {args.seed}" + " --on-axis" * args.on_axis
    report(rows, title + " --no-priors" * args.no_priors)


def report(rows: dict[str, list[dict]], title: str) -> None:
    """The figures per planted set and overall."""
    print(f"\n{title}:")
    for label, group in rows.items():
        print(summary(group, label))
    print(summary([r for g in rows.values() for r in g], "all"))
    print(
        "goals: right >= 95 % where detectable, null named <= 1 in 20, CV/noise <= 1.3, "
        "time <= 30 s"
    )


if __name__ == "__main__":
    main()
