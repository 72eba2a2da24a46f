"""Pareto studies: epsilon-constraint sweeps, one design NLP per point, on Dask.

Each point of a sweep bounds one quantity (catheter outer diameter and magnet volume from
above, external-magnet distance from below, :data:`optimize.sizing.studyfile.PARETO_QUANTITIES`) and
maximises the study's objective with :func:`optimize.sizing.nlp.optimize_design`. Points run as Dask
tasks: on a local cluster (processes, one thread each) by default, or on an existing
cluster given its scheduler address. By default each sweep is a continuation in its
bound: its loosest points start from the study's optimum (when given), each further
point from the design of the point :data:`CHAINS` places looser (:func:`run_sweeps`), so
each sweep is :data:`CHAINS` interleaved chains of tasks the workers share (one chain a
sweep left the magnet-volume sweep, 6 points of up to 150 s, the critical path: 481 of
the default study's 490 s); ``continuation=False`` solves every point from the study's
own starts (the cold path, the baseline of ``benchmarks/study.py``). Each finished point
is stored under ``out_dir/points/`` (:mod:`design.stored`: JSON and NPZ, never code) keyed
by a hash of the study, the point and the code, so a rerun of the same inputs skips what
is already solved (a foreign, truncated or altered file is solved again, with a warning);
a point whose solve raises is stored as a failure with its message and does not stop the
sweep.

SI units are used for all inputs and outputs.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from design import stored
from design.processes import die_with_parent
from optimize.sizing.nlp import OptimizationResult, kept_optimum, optimize_design, pareto_values
from optimize.sizing.studyfile import Study

Progress = Callable[[int, int], None]
"""progress(done, total), called as points finish (resumed ones count at once)."""
POINTS = "points"
CHAINS = 2
"""Interleaved continuation chains per sweep: point i starts from point i - CHAINS's
answer (the next looser bound of its chain), the first CHAINS from the optimum."""


@dataclass(frozen=True)
class ParetoPoint:
    """One point of a sweep: the bound imposed and the NLP's answer.

    against : the bounded quantity. epsilon : its bound. [m or m^3]
    result : the study result, or None if the solve raised (``error`` says why).
    resumed : read back from an earlier run instead of solved now.
    """

    against: str
    epsilon: float
    result: OptimizationResult | None
    error: str = ""
    resumed: bool = False

    @property
    def feasible(self) -> bool:
        return self.result is not None and self.result.feasible

    @property
    def objective(self) -> float:
        """The study's objective, NaN where infeasible or failed. [SI]"""
        return self.result.objective if self.feasible else float("nan")  # type: ignore[union-attr]


@dataclass(frozen=True)
class ParetoResult:
    """Every sweep of a study, points in increasing epsilon. seconds : wall time. [s]"""

    sweeps: dict[str, tuple[ParetoPoint, ...]]
    solved: int
    resumed: int
    seconds: float
    workers: int


PACKAGES = ("design", "optimize", "cad", "ringpair")
"""The project's packages: a stored result may rebuild their dataclasses, and their source
is part of every stored result's key (:func:`design.stored.source_digest`)."""


def code_digest() -> str:
    """Identity of the code that computes: the project's version and source. [-]"""
    return stored.source_digest(PACKAGES, "ringpair")


def point_key(study: Study, against: str, epsilon: float, how: tuple[object, ...] = ()) -> str:
    """Identity of one point's inputs: the study (every field, the resolved base design
    included), the bound, the code (:func:`code_digest`) and how its start is chosen
    (``how``: empty for the study's own starts). [-]"""
    return stored.digest(study, against, round(float(epsilon), 15), code_digest(), *how)


def _solve_point(
    study: Study,
    against: str,
    epsilon: float,
    start: Mapping[str, float] | None = None,
    previous: tuple[OptimizationResult | None, str] | None = None,
) -> tuple[OptimizationResult | None, str]:
    """One point: (result, '') or (None, why it raised). ``previous`` is the answer at its
    chain's next looser bound (:func:`predecessor`; for a sweep's loosest points, the
    study's optimum):
    where its design meets this bound too it is this point's answer, no NLP solved
    (:func:`optimize.sizing.nlp.kept_optimum`). Else the NLP starts from that
    design if it was feasible, else from ``start`` (free quantities, SI); if that finds
    no feasible design the point is solved again from the study's own starts (which alone
    look for the conflicting constraints), so a warm start never loses a point the cold
    path finds."""
    try:
        if previous is not None and previous[0] is not None and previous[0].feasible:
            kept = kept_optimum(study, against, epsilon, previous[0])
            if kept is not None:
                return kept, ""
            start = previous[0].values
        if start is not None:
            warm = optimize_design(
                study, epsilon={against: epsilon}, starts=[start], conflicts=False
            )
            if warm.feasible:
                return warm, ""
        return optimize_design(study, epsilon={against: epsilon}), ""
    except Exception as exc:  # a failed point is an answer, not the end of the sweep
        return None, f"{type(exc).__name__}: {exc}"


def _loose_first(against: str, values: np.ndarray) -> list[float]:
    """A sweep's bounds from the loosest to the tightest: upper bounds (diameter, volume)
    from the largest, the distance's lower bound from the smallest. [SI]"""
    ordered = [float(e) for e in np.sort(values)]
    return ordered if against == "external_distance" else ordered[::-1]


def _store(path: Path, point: ParetoPoint, key: str) -> None:
    """Write one finished point atomically (:func:`design.stored.save`: data, no pickle)."""
    stored.save(path, point, key)


def _load(path: Path, key: str) -> ParetoPoint | None:
    """The point stored at ``path`` for ``key``; None (with a warning when a file is there
    but foreign, truncated or altered: the point is then solved again)."""
    point: ParetoPoint | None = stored.reuse(
        path,
        key,
        PACKAGES,
        lambda v: isinstance(v, ParetoPoint),
        "a Pareto point",
        "the point is solved again",
    )
    return point


def run_sweeps(
    study: Study,
    out_dir: Path,
    *,
    scheduler: str | None = None,
    workers: int = 2,
    progress: Progress | None = None,
    start: OptimizationResult | Mapping[str, float] | None = None,
    continuation: bool = True,
) -> ParetoResult:
    """Solve every Pareto sweep of ``study`` (``study.pareto``), resuming from ``out_dir``.

    scheduler : address of a running Dask scheduler (e.g. ``tcp://host:8786``); None starts
        a local cluster of ``workers`` processes for the duration of the call.
    progress : called with (points done, points in all).
    start : the study's optimum (its result; or its free quantities, SI, by name,
        :attr:`OptimizationResult.values`): each sweep's :data:`CHAINS` loosest points
        start there, and are the optimum itself where that meets their bound (None: from
        the study's own starts).
    continuation : each further point is the answer of the point CHAINS places looser
        (:func:`predecessor`) where that meets its bound, else starts from that design
        (:func:`_solve_point`; a point the warm start finds infeasible is solved again
        cold). False: every point from the study's own starts, independent (the cold
        path; ``start`` unused).
    """
    from dask.distributed import Client, LocalCluster, as_completed

    t0 = time.perf_counter()
    store = Path(out_dir) / POINTS
    how: tuple[object, ...] = ()
    optimum = start if isinstance(start, OptimizationResult) and continuation else None
    if isinstance(start, OptimizationResult):
        start = start.values if start.feasible else None
    if continuation:
        start_items = sorted((k, round(float(v), 15)) for k, v in (start or {}).items())
        how = ("continuation", CHAINS, start_items)
    else:
        start = None
    keys = {
        (s.against, e): point_key(study, s.against, e, how)
        for s in study.pareto
        for e in _loose_first(s.against, pareto_values(study, s))
    }
    plan = [(a, e, store / f"{k[:24]}.npz") for (a, e), k in keys.items()]
    done: dict[Path, ParetoPoint] = {}
    for a, e, path in plan:
        old = _load(path, keys[a, e])
        if old is not None:
            done[path] = ParetoPoint(old.against, old.epsilon, old.result, old.error, True)
    total, resumed = len(plan), len(done)
    if progress:
        progress(resumed, total)
    todo = [(a, e, p) for a, e, p in plan if p not in done]
    used = 0
    if todo:
        logging.getLogger("distributed").setLevel(logging.ERROR)
        cluster = None
        if scheduler is None:
            cluster = LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                # the scheduler's HTTP server (metrics) starts even without a dashboard;
                # a free port, not 8787, so a second cluster on the machine does not warn
                scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                # a worker whose heartbeat meets the scheduler already closed (Ctrl-C, a
                # busy machine) logs an ERROR on its way out; a point's own failure comes
                # back as its answer, a lost worker as its future's exception
                silence_logs=logging.CRITICAL,
            )
        try:
            with Client(cluster if cluster is not None else scheduler) as client:
                used = len(client.scheduler_info()["workers"])
                if cluster is not None:  # our workers die with this process (kill -9)
                    client.run(die_with_parent, os.getpid())
                futures = {}
                answers: dict[Path, Any] = {}  # each point's answer, or its future
                for i, (a, e, p) in enumerate(plan):
                    j = predecessor(plan, i) if continuation else None
                    if j is not None:
                        previous = answers[plan[j][2]]
                    else:
                        previous = (optimum, "") if optimum is not None else None
                    if p in done:
                        answers[p] = (done[p].result, done[p].error)
                        continue
                    future = client.submit(_solve_point, study, a, e, start, previous, pure=False)
                    futures[future] = (a, e, p)
                    answers[p] = future
                for future in as_completed(futures):
                    a, e, path = futures[future]
                    result, error = future.result()
                    point = ParetoPoint(a, e, result, error)
                    _store(path, point, keys[a, e])
                    done[path] = point
                    if progress:
                        progress(len(done), total)
        finally:
            if cluster is not None:
                cluster.close()
    sweeps = {
        s.against: tuple(done[p] for _, p in sorted((e, p) for a, e, p in plan if a == s.against))
        for s in study.pareto
    }
    return ParetoResult(sweeps, len(todo), resumed, time.perf_counter() - t0, used)


def predecessor(plan: list[tuple[str, float, Any]], i: int) -> int | None:
    """Index in ``plan`` (sweeps one after the other, each loosest bound first) of the
    point whose answer point ``i`` continues from: :data:`CHAINS` places looser in its
    sweep; None for a sweep's first CHAINS points (they start from the optimum)."""
    j = i - CHAINS
    return j if j >= 0 and plan[j][0] == plan[i][0] else None


def is_monotone(points: tuple[ParetoPoint, ...], tolerance: float = 1e-6) -> bool:
    """The front never improves as the bound tightens: objective non-decreasing in epsilon
    for upper bounds (diameter, volume), non-increasing for the distance's lower bound,
    over the feasible points, within ``tolerance`` relative."""
    feasible = [p for p in points if p.feasible]
    if len(feasible) < 2:
        return True
    values = np.array([p.objective for p in feasible])
    if feasible[0].against == "external_distance":
        values = values[::-1]
    scale = np.abs(values).max()
    return bool(np.all(np.diff(values) >= -tolerance * scale))
