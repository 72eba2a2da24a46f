"""Solving the design NLP of a study (:mod:`optimize.sizing.nlp_problem`) with IPOPT, with exact
derivatives through the model's own CasADi expressions; evaluating designs; the results.

Multi-start: start 1 is the base design, the others are drawn uniformly in the bounds
(seeded); a start that fails is recorded with IPOPT's status and does not stop the study.
If no start is feasible, a minimum-violation problem (one slack per constraint group)
tells which constraints conflict and by how much.

SI units are used for all inputs and outputs; file units only in reports.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np

from design.controllable import controllable_disc_radius as controllable_disc
from design.equilibrium import drive, solve_equilibria
from design.geometry import ring_clears_wire
from design.magnets import ring_volume
from design.records import Design
from design.registry import NAMES
from optimize.sizing.materials import Material, material
from optimize.sizing.nlp_designs import (
    candidate_design,
    free_values,
    group_bounds,
    material_combinations,
    study_parameters,
)
from optimize.sizing.nlp_problem import (
    EQUILIBRIUM_TOLERANCE,
    GROUPS,
    METRICS,
    Core,
    NlpShape,
    Problem,
    core,
    problem,
    restoration,
)
from optimize.sizing.nlp_results import (
    Conflict,
    ConstraintState,
    Evaluation,
    OptimizationResult,
    StartResult,
)
from optimize.sizing.studyfile import ParetoSweep, Study

FEASIBILITY_TOLERANCE = 1e-6
"""A constraint row counts as satisfied within this, in its group's file unit, plus this
relative to its limit (IPOPT relaxes bounds by about 1e-8 relative)."""
BRANCH_TOLERANCE = 1e-6
"""An NLP equilibrium is the robot's state when its unknowns are within this of the state
forward simulation reaches (dimensionless: unknowns over their scale, i.e. 1e-6 of the
free length or 1e-6 rad; IPOPT's equilibria are exact to about 1e-8 of that scale)."""
ARRIVAL_TOLERANCE = 1e-4
"""A loop driven from one sample arrives at the next sample's state when the unknowns agree
within this (as BRANCH_TOLERANCE; looser, since a snap moves them by far more and the
driven states carry the path solver's tolerance besides IPOPT's)."""
ACTIVE_TOLERANCE = 1e-5
"""A constraint row is active when within this of its limit (file unit) or its multiplier
is nonzero."""


# ---------------------------------------------------------------------------- evaluation


def _nlp_shape(study: Study) -> NlpShape:
    return NlpShape(
        frozenset(study.effects),
        tuple(b.name for b in study.free),
        study.configurations,
        study.neutral_configurations,
    )


def _states(
    c: Core,
    g: np.ndarray,
    bounds: Mapping[str, tuple[float, float]],
    multipliers: np.ndarray | None = None,
) -> tuple[ConstraintState, ...]:
    rows = np.array(c.rows)
    out = []
    for name in dict.fromkeys(c.rows):
        lo, hi = bounds[name]
        if not (math.isfinite(lo) or math.isfinite(hi)):
            continue
        vals = g[rows == name]
        scale, unit, _ = GROUPS[name]
        margins = np.minimum(vals - lo, hi - vals)
        i = int(np.argmin(margins))
        limit = lo if vals[i] - lo <= hi - vals[i] else hi
        mult = 0.0 if multipliers is None else float(np.max(np.abs(multipliers[rows == name])))
        near = margins[i] / scale < ACTIVE_TOLERANCE or mult > 1e-7
        active = bool(near and name in c.variable_groups)
        out.append(
            ConstraintState(
                name, float(vals[i]), float(limit), float(margins[i]), active, mult, unit, scale
            )
        )
    return tuple(out)


def _violation(states: Sequence[ConstraintState]) -> float:
    """Sum of the groups' violations in file units, each beyond FEASIBILITY_TOLERANCE
    (absolute, plus the same relative to its limit)."""
    return float(
        sum(
            max(0.0, -s.margin / s.scale - FEASIBILITY_TOLERANCE * abs(s.limit) / s.scale)
            for s in states
        )
    )


@dataclass(frozen=True)
class _Norms:
    """Base-design values the objectives are divided by, and scales. [SI]"""

    disc: float
    area: float
    deflection: float
    metrics: dict[str, float]


def _metrics_dict(m: np.ndarray) -> dict[str, float]:
    return {k: float(x) for k, x in zip(METRICS, np.asarray(m).ravel(), strict=True)}


def _objective(study: Study, metrics: Mapping[str, float], norms: _Norms) -> float:
    if len(study.objective) == 1:
        name = study.objective[0][0]
        # the NLP's own measure until the controllable disc is computed (optimize_design)
        return float(metrics[name] if name in metrics else metrics["disc_radius"])
    div = {"disc_radius": norms.disc, "area": norms.area, "reach_ratio": 1.0}
    return float(sum(w * metrics[n] / div[n] for n, w in study.objective))


def _off_branch(c: Core, prm: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Configurations where the NLP's equilibria x (n, K) are not the states the robot
    reaches (:func:`design.solve_equilibria`: stable, connected to the unloaded robot), and
    those states (n, K), NaN where there is none."""
    eq = solve_equilibria(c.model, c.configuration_params(prm), c.commands[0], c.commands[1])
    reached = eq.unknowns.T
    scale = c.model.unknown_scale(prm)[:, None]
    with np.errstate(invalid="ignore"):
        differs = ~(np.max(np.abs(reached - x) / scale, axis=0) <= BRANCH_TOLERANCE)
    return np.flatnonzero(differs), reached


def _loop_faults(c: Core, prm: np.ndarray, x: np.ndarray) -> str:
    """Why the robot could not be driven around the study's loops through its sampled
    states x (n, K'; the states forward simulation reaches, which the NLP's equal), or ''
    when it can: each loop (parallel rings, the workspace's rim;
    antiparallel, the neutral loop; rings at right angles) is driven from every sample to
    the next (:func:`design.equilibrium.drive`, sub-steps of 1 degree, failing where the
    robot would snap) and must arrive at the next sample's state; and no sampled state
    may share its command with another stable state (``multistable``)."""
    k, kn = c.shape.configurations, c.shape.neutral_configurations
    scale = c.model.unknown_scale(prm)[:, None]
    loops = (("parallel", 0, k), ("antiparallel", k, kn), ("right-angle", k + kn, kn))
    for name, first, count in loops:
        idx = first + np.arange(count)
        ahead = np.roll(idx, -1)
        end = c.commands[:, idx] + 2 * np.pi / count  # the next sample, unwrapped
        reached, ok = drive(c.model, prm, x[:, idx], c.commands[:, idx], end)
        expected = x[:, ahead].copy()
        if c.model.n_unknowns > c.model.n_rod:  # tip angles: a turn further at the wrap
            expected[c.model.n_rod :] += end - c.commands[:, ahead]
        with np.errstate(invalid="ignore"):
            same = np.max(np.abs(reached - expected) / scale, axis=0) <= ARRIVAL_TOLERANCE
        bad = np.flatnonzero(~(ok & same))
        if bad.size:
            where = ", ".join(f"{i}-{(i + 1) % count}" for i in bad[:4])
            return f"the {name} loop snaps between samples {where} (of {count})"
    sampled = c.commands[:, :-1]
    eq = solve_equilibria(
        c.model, c.configuration_params(prm)[:, :-1], sampled[0], sampled[1], multistable=True
    )
    if eq.multistable.any():
        return f"multistable at configurations {np.flatnonzero(eq.multistable).tolist()[:6]}"
    return ""


CONTROLLABLE = "controllable_disc_radius"
"""The objective option: the disc about the rest position the robot can be steered over
from rest without a snap (:func:`controllable_disc_radius`)."""
CONTROLLABLE_STEP = np.deg2rad(10.0)
"""Grid step of the ring angles for the controllable workspace. [rad]"""


def controllable_disc_radius(study: Study, design: Design) -> float:
    """The radius of the disc about the rest position that the robot of ``design`` can be
    steered over from rest without a snap (:func:`design.controllable.controllable_disc_radius`
    on a CONTROLLABLE_STEP grid, the study's model). [m]"""
    model = core(_nlp_shape(study)).model
    p = study_parameters(study, design)
    return controllable_disc(model, p, design.robot.free_length, CONTROLLABLE_STEP)


def _forward(study: Study, design: Design) -> tuple[Core, np.ndarray, np.ndarray, Any]:
    """Forward equilibria of ``design`` at the study's configurations: (core, v, X, eq)."""
    c = core(_nlp_shape(study))
    p = study_parameters(study, design)
    eq = solve_equilibria(c.model, c.configuration_params(p), c.commands[0], c.commands[1])
    return c, free_values(study, design), eq.unknowns.T.copy(), eq


@lru_cache(maxsize=32)
def _norms(study: Study) -> _Norms:
    cat, wire = material_combinations(study)[0]
    design = candidate_design(study, free_values(study, study.base), cat, wire)
    c, v, x, _ = _forward(study, design)
    x = np.nan_to_num(x)
    _, m, _, _, _ = c.evaluate(v, x, study_parameters(study, design), 1.0)
    metrics = _metrics_dict(m)
    deflection = metrics["max_deflection"] if metrics["max_deflection"] > 0 else 1e-3
    disc = metrics["disc_radius"] if metrics["disc_radius"] > 1e-6 * deflection else deflection
    area = metrics["area"] if metrics["area"] > 0 else deflection**2
    return _Norms(disc, area, deflection, metrics)


def start_breaks(study: Study) -> list[str]:
    """The limits the study's base design breaks, each described (file units); empty when
    it is feasible. A start whose disc beats the optimum's is not one the study allows."""
    ev = evaluate_design(study, study.base)
    return [
        s.describe()
        for s in ev.constraints
        if -s.margin / s.scale > FEASIBILITY_TOLERANCE * (1 + abs(s.limit) / s.scale)
    ]


def evaluate_design(
    study: Study,
    design: Design,
    materials: tuple[str | None, str | None] | None = None,
    epsilon: Mapping[str, float] | None = None,
) -> Evaluation:
    """Evaluate ``design`` by forward simulation (:func:`design.solve_equilibria`) on the
    study's sampled configurations, with the same metric and constraint expressions as
    the NLP. ``materials`` (catheter, wire) names pick the allowable strains (default:
    the study's first candidates)."""
    cat, wire = material_combinations(study)[0]
    if materials is not None:
        cat = material(materials[0]) if materials[0] else None
        wire = material(materials[1]) if materials[1] else None
    c, v, x, eq = _forward(study, design)
    converged = bool(eq.converged.all())
    norms = _norms(study)
    p = study_parameters(study, design)
    g, m, _, _, _ = c.evaluate(v, np.nan_to_num(x), p, norms.deflection)
    g, metrics = np.asarray(g).ravel(), _metrics_dict(m)
    if any(name == CONTROLLABLE for name, _ in study.objective):
        metrics[CONTROLLABLE] = controllable_disc_radius(study, design)
    bounds = group_bounds(study, cat, wire, epsilon)
    states = _states(c, g, bounds)
    violation = _violation(states)
    if not converged:
        violation = math.inf
    return Evaluation(
        _objective(study, metrics, norms),
        metrics,
        states,
        converged,
        bool(eq.stable.all()),
        violation,
    )


# ------------------------------------------------------------------------------ solving


def _start_points(study: Study, count: int) -> list[np.ndarray]:
    """Start 1: the base design (clipped into the bounds); others uniform in the bounds,
    redrawn (up to 100 times) until the rings fit the wire and the walls are positive."""
    lo = np.array([b.low for b in study.free])
    hi = np.array([b.high for b in study.free])
    base = np.clip(free_values(study, study.base), lo, hi)
    rng = np.random.default_rng(study.seed)
    names = [b.name for b in study.free]
    clearance = study.limits.wire_clearance
    out = [base]
    for _ in range(count - 1):
        for _ in range(100):
            z = lo + (hi - lo) * rng.random(len(lo))
            vals = dict(zip(names, z, strict=True))
            d = candidate_design(study, vals)
            ok = (
                d.tip.magnet_inner_diameter < d.tip.magnet_outer_diameter
                and d.robot.catheter.inner_diameter < d.robot.catheter.outer_diameter
                and d.robot.wire.outer_diameter < d.robot.catheter.inner_diameter
                and ring_clears_wire(
                    d.tip.magnet_inner_diameter, d.robot.wire.outer_diameter, clearance
                )
            )
            if ok:
                break
        out.append(z)
    return out


@dataclass
class _Attempt:
    """One solve's raw outcome (internal)."""

    start: StartResult
    v: np.ndarray | None = None
    x: np.ndarray | None = None
    p: np.ndarray | None = None
    lam_g: np.ndarray | None = None
    lam_x: np.ndarray | None = None
    violation: float = math.inf
    g: np.ndarray | None = None
    metrics: dict[str, float] = field(default_factory=dict)


def _parameters(
    study: Study, start: np.ndarray, cat: Material | None, wire: Material | None, norms: _Norms
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(NLP parameter vector, warm-start z, warm-start x~ (n, K'), area sign)."""
    c = core(_nlp_shape(study))
    design = candidate_design(study, start, cat, wire)
    p = study_parameters(study, design)
    _, _, x, _ = _forward(study, design)
    x = np.nan_to_num(x)
    n = c.model.n_unknowns
    xs = np.ones(n)
    for i in range(min(n, 4)):
        xs[i] = max(np.abs(x[i]).max(), 1e-9 * norms.deflection, 1e-300)
    _, _, _, _, area_signed = c.evaluate(free_values(study, design), x, p, norms.deflection)
    sign = 1.0 if float(area_signed) >= 0 else -1.0
    lo = np.array([b.low for b in study.free])
    hi = np.array([b.high for b in study.free])
    z0 = np.where(hi > lo, (start - lo) / np.where(hi > lo, hi - lo, 1.0), 0.0)
    weights = dict(study.objective)
    disc = weights.get("disc_radius", 0.0) + weights.get(CONTROLLABLE, 0.0)
    w = [disc, weights.get("area", 0.0), weights.get("reach_ratio", 0.0)]
    params = np.concatenate(
        [p, xs, lo, hi, [norms.disc, norms.area, 1.0], [sign], w, [norms.deflection]]
    )
    return params, z0, x / xs[:, None], sign


def _bounds_vectors(
    prob: Problem, bounds: Mapping[str, tuple[float, float]], n_eq: int, n_epi: int
) -> tuple[np.ndarray, np.ndarray]:
    groups = list(prob.core.rows) + ["min_disc_radius", "min_reach_ratio"]
    lo = np.array([bounds[g][0] for g in groups]) / prob.row_scale
    hi = np.array([bounds[g][1] for g in groups]) / prob.row_scale
    lbg = np.concatenate([np.zeros(n_eq), np.zeros(n_epi), lo])
    ubg = np.concatenate([np.zeros(n_eq), np.full(n_epi, np.inf), hi])
    return lbg, ubg


def _reachable_start(
    study: Study,
    start: np.ndarray,
    anchor: np.ndarray,
    cat: Material | None,
    wire: Material | None,
    halvings: int = 5,
) -> np.ndarray:
    """``start``, or the first point on the way to ``anchor`` (halving the distance) whose
    sampled equilibria all converge and are stable by forward simulation (a warm start
    on the branch the NLP should follow)."""
    for _ in range(halvings):
        eq = _forward(study, candidate_design(study, start, cat, wire))[3]
        if eq.stable.all():
            return start
        start = anchor + 0.5 * (start - anchor)
    return start


def _solve_one(
    study: Study,
    index_: int,
    start: np.ndarray,
    cat: Material | None,
    wire: Material | None,
    epsilon: Mapping[str, float] | None,
    norms: _Norms,
) -> _Attempt:
    names = (cat.name if cat else None, wire.name if wire else None)
    t0 = time.perf_counter()
    st = _nlp_shape(study)
    prob = problem(st, study.max_iterations, study.tolerance, study.hessian)
    c = prob.core
    n, nf, k_all = c.model.n_unknowns, len(st.free), c.commands.shape[1]
    params, z0, xt0, _ = _parameters(study, start, cat, wire, norms)
    n_eq, n_epi = n * k_all, st.configurations + 2
    lbg, ubg = _bounds_vectors(prob, group_bounds(study, cat, wire, epsilon), n_eq, n_epi)
    w0 = np.concatenate([z0, xt0.ravel(order="F"), [0.0, 0.0]])
    lbx = np.concatenate([np.zeros(nf), np.full(n * k_all, -np.inf), [0.0, 0.0]])
    ubx = np.concatenate([np.ones(nf), np.full(n * k_all, np.inf), [np.inf, 1.0]])
    xs = params[len(NAMES) : len(NAMES) + n]
    lo, hi = params[len(NAMES) + n : len(NAMES) + n + nf], params[len(NAMES) + n + nf :][:nf]
    p = params[: len(NAMES)]
    for attempt in range(2):
        sol = prob.solver(x0=w0, p=params, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        stats = prob.solver.stats()
        w = np.asarray(sol["x"]).ravel()
        v = lo + (hi - lo) * np.clip(w[:nf], 0.0, 1.0)
        x = w[nf : nf + n * k_all].reshape(n, k_all, order="F") * xs[:, None]
        prm = np.asarray(c.params(v, p)).ravel()
        if not np.isfinite(w).all():
            off = np.arange(k_all)
            break
        off, reached = _off_branch(c, prm, x)
        if attempt or not off.size:
            break
        # IPOPT may follow an equilibrium onto another branch than the robot's: start once
        # more from this design with the states the robot reaches there.
        reached = np.where(np.isfinite(reached), reached, x)
        w0 = np.concatenate([w[:nf], (reached / xs[:, None]).ravel(order="F"), w[-2:]])
    g, m, _, _, _ = c.evaluate(v, x, p, norms.deflection)
    g, metrics = np.asarray(g).ravel(), _metrics_dict(m)
    bounds = group_bounds(study, cat, wire, epsilon)
    states = _states(c, g, bounds)
    violation = _violation(states)
    res = np.asarray(c.column.map(k_all)(x, c.commands, c.configuration_params(prm))[0])
    equilibrium = float(np.abs(res / xs[:, None]).max()) if res.size else 0.0
    success = bool(stats.get("success", False))
    message = ""
    if not np.all(np.isfinite(w)):
        message = "non-finite solution"
    elif equilibrium > EQUILIBRIUM_TOLERANCE:
        message = f"equilibrium not reached (scaled residual {equilibrium:.3g})"
    elif violation > 0:
        worst = max(states, key=lambda s: -s.margin / s.scale)
        message = f"violates {worst.describe()}"
    elif study.limits.stable and off.size:
        message = (
            f"the equilibria at configurations {off.tolist()} are not the states the robot "
            "reaches there (another branch, or unstable)"
        )
    elif study.limits.stable:
        message = _loop_faults(c, prm, reached)
    accepted = success and not message
    lam_g = np.asarray(sol["lam_g"]).ravel()
    result = StartResult(
        index=index_,
        materials=names,
        status=str(stats.get("return_status", "unknown")),
        success=success,
        accepted=accepted,
        objective=_objective(study, metrics, norms) if np.all(np.isfinite(w)) else math.nan,
        values={b.name: float(x_) for b, x_ in zip(study.free, v, strict=True)},
        iterations=int(stats.get("iter_count", 0)),
        seconds=time.perf_counter() - t0,
        message=message,
    )
    return _Attempt(
        result,
        v,
        x,
        p,
        lam_g[n_eq + n_epi : n_eq + n_epi + len(c.rows)],
        np.asarray(sol["lam_x"]).ravel()[:nf],
        violation,
        g,
        metrics,
    )


def _conflicts(
    study: Study,
    start: np.ndarray,
    cat: Material | None,
    wire: Material | None,
    epsilon: Mapping[str, float] | None,
    norms: _Norms,
) -> tuple[float, tuple[Conflict, ...], tuple[str, ...]]:
    """Minimum-violation problem (one slack per group, their sum minimised in the groups'
    file units): the groups whose slack stays > 0, and the free bounds that limit it."""
    st = _nlp_shape(study)
    prob = problem(st, study.max_iterations, study.tolerance, study.hessian)
    solver = restoration(st, max(study.max_iterations, 500), study.hessian)
    c = prob.core
    n, nf, k_all = c.model.n_unknowns, len(st.free), c.commands.shape[1]
    params, z0, xt0, _ = _parameters(study, start, cat, wire, norms)
    n_eq, n_epi = n * k_all, st.configurations + 2
    bounds = group_bounds(study, cat, wire, epsilon)
    lbg, ubg = _bounds_vectors(prob, bounds, n_eq, n_epi)
    n_in = len(lbg) - n_eq - n_epi
    lo_in, hi_in = lbg[n_eq + n_epi :], ubg[n_eq + n_epi :]
    lbg2 = np.concatenate([lbg[: n_eq + n_epi], lo_in, np.full(n_in, -np.inf)])
    ubg2 = np.concatenate([ubg[: n_eq + n_epi], np.full(n_in, np.inf), hi_in])
    n_s = len(GROUPS)
    w0 = np.concatenate([z0, xt0.ravel(order="F"), [0.0, 0.0], np.full(n_s, 1.0)])
    lbx = np.concatenate([np.zeros(nf), np.full(n * k_all, -np.inf), [0.0, 0.0], np.zeros(n_s)])
    ubx = np.concatenate(
        [np.ones(nf), np.full(n * k_all, np.inf), [np.inf, 1.0], np.full(n_s, np.inf)]
    )
    sol = solver(x0=w0, p=params, lbx=lbx, ubx=ubx, lbg=lbg2, ubg=ubg2)
    if not solver.stats().get("success", False):
        raise RuntimeError(f"minimum-violation problem: {solver.stats().get('return_status')}")
    w = np.asarray(sol["x"]).ravel()
    slack = w[-n_s:]
    limiting = []
    for b, z in zip(study.free, w[:nf], strict=True):
        if b.high > b.low and z < 1e-6:
            limiting.append(f"{b.name} at its lower bound")
        elif b.high > b.low and z > 1 - 1e-6:
            limiting.append(f"{b.name} at its upper bound")
    lo_, hi_ = params[len(NAMES) + n : len(NAMES) + n + nf], params[len(NAMES) + n + nf :][:nf]
    v = lo_ + (hi_ - lo_) * np.clip(w[:nf], 0.0, 1.0)
    xs = params[len(NAMES) : len(NAMES) + n]
    x = w[nf : nf + n * k_all].reshape(n, k_all, order="F") * xs[:, None]
    g = np.asarray(c.evaluate(v, x, params[: len(NAMES)], norms.deflection)[0]).ravel()
    violated = {name for name, s in zip(GROUPS, slack, strict=True) if s > 1e-5}
    for state in _states(c, g, bounds):
        if state.name not in violated and state.active:
            limiting.append(
                f"{state.name} at its limit {state.limit / state.scale:.6g} {state.unit}"
            )
    out = []
    for name, s in zip(GROUPS, slack, strict=True):
        if s > 1e-5:
            scale, unit, meaning = GROUPS[name]
            lo, hi = bounds[name]
            limit = lo if math.isfinite(lo) else hi
            out.append(Conflict(name, float(s * scale), float(limit), unit, scale, meaning))
    ranked = tuple(sorted(out, key=lambda c_: -c_.violation / c_.scale))
    return float(slack.sum()), ranked, tuple(limiting)


def optimize_design(
    study: Study,
    *,
    epsilon: Mapping[str, float] | None = None,
    starts: Sequence[Mapping[str, float]] | None = None,
) -> OptimizationResult:
    """Solve the study's design NLP from several starts; return the best accepted design.

    epsilon : Pareto bounds by quantity (PARETO_QUANTITIES: ``catheter_outer_diameter``
        and ``magnet_volume`` bounded above, ``external_distance`` below). [SI: m, m^3]
    starts : explicit start points (free quantities by name, SI; missing ones from the
        base design) instead of the study's seeded ones.
    Every material combination is solved from every start. If no start is accepted the
    result is infeasible and ``conflicts`` lists the constraint groups that stay violated
    at the least-violating design (or is empty if the starts failed for another reason).
    """
    t0 = time.perf_counter()
    norms = _norms(study)
    if starts is None:
        points = _start_points(study, study.starts)
    else:
        base = free_values(study, study.base)
        points = [
            np.array([float(s.get(b.name, base[i])) for i, b in enumerate(study.free)])
            for s in starts
        ]
    attempts: list[_Attempt] = []
    combos = material_combinations(study)
    for cat, wire in combos:
        for i, start in enumerate(points):
            try:
                if not np.all(np.isfinite(start)):
                    bad = [
                        b.name for b, x in zip(study.free, start, strict=True) if not np.isfinite(x)
                    ]
                    raise ValueError(f"start values are not finite: {', '.join(bad)}")
                if i > 0:
                    start = _reachable_start(study, start, points[0], cat, wire)
                attempts.append(_solve_one(study, i + 1, start, cat, wire, epsilon, norms))
            except Exception as exc:  # a failed start is an answer, not the end of the study
                names = (cat.name if cat else None, wire.name if wire else None)
                attempts.append(
                    _Attempt(
                        StartResult(
                            i + 1,
                            names,
                            f"error: {type(exc).__name__}",
                            False,
                            False,
                            math.nan,
                            {},
                            0,
                            0.0,
                            str(exc),
                        )
                    )
                )
    accepted = [a for a in attempts if a.start.accepted]
    if any(name == CONTROLLABLE for name, _ in study.objective):
        for a in accepted:  # the objective: the disc the robot can be steered over
            assert a.v is not None
            cat_name, wire_name = a.start.materials
            design = candidate_design(
                study,
                a.v,
                material(cat_name) if cat_name else None,
                material(wire_name) if wire_name else None,
            )
            a.metrics[CONTROLLABLE] = controllable_disc_radius(study, design)
            a.start = replace(a.start, objective=a.metrics[CONTROLLABLE])
    start_results = tuple(a.start for a in attempts)
    if not accepted:
        conflicts: tuple[Conflict, ...] = ()
        limiting: tuple[str, ...] = ()
        best_total = math.inf
        for cat, wire in combos:
            try:
                total, found, bounds_ = _conflicts(study, points[0], cat, wire, epsilon, norms)
            except Exception:  # noqa: BLE001 - report what the starts said
                continue
            if total < best_total:
                best_total, conflicts, limiting = total, found, bounds_
        return OptimizationResult(
            study=study.name,
            feasible=False,
            objective=math.nan,
            design=None,
            values={},
            materials=(None, None),
            metrics={},
            base_metrics=evaluate_design(study, study.base).metrics,
            constraints=(),
            active=(),
            starts=start_results,
            conflicts=conflicts,
            limiting_bounds=limiting,
            epsilon=dict(epsilon or {}),
            seconds=time.perf_counter() - t0,
        )
    best = max(accepted, key=lambda a: a.start.objective)
    assert best.v is not None and best.g is not None
    cat_name, wire_name = best.start.materials
    cat = material(cat_name) if cat_name else None
    wire = material(wire_name) if wire_name else None
    c = core(_nlp_shape(study))
    states = _states(c, best.g, group_bounds(study, cat, wire, epsilon), best.lam_g)
    active = [s.name for s in states if s.active]
    for b, value in zip(study.free, best.v, strict=True):
        width = b.high - b.low
        if width > 0 and (value - b.low) / width < 1e-6:
            active.append(f"bound.{b.name}.low")
        elif width > 0 and (b.high - value) / width < 1e-6:
            active.append(f"bound.{b.name}.high")
    design = candidate_design(study, best.v, cat, wire, name=f"{study.name}-optimum")
    design = replace(design, description=f"optimum of study {study.name!r} (ringpair optimize)")
    return OptimizationResult(
        study=study.name,
        feasible=True,
        objective=best.start.objective,
        design=design,
        values=dict(best.start.values),
        materials=best.start.materials,
        metrics=best.metrics,
        base_metrics=evaluate_design(study, study.base).metrics,
        constraints=states,
        active=tuple(active),
        starts=start_results,
        epsilon=dict(epsilon or {}),
        seconds=time.perf_counter() - t0,
    )


def pareto_values(study: Study, sweep: ParetoSweep) -> np.ndarray:
    """The epsilon bounds of one Pareto sweep, shape (points,), in increasing order. [SI]

    Without an explicit range, the sweep spans the free bounds of its quantity (for the
    magnet volume: the smallest and largest rings the ring bounds and the minimum wall
    allow, base values for the fixed ones). ValueError if the quantity cannot change in this study.
    """
    low, high = sweep.low, sweep.high
    if low is None or high is None:
        if sweep.against == "magnet_volume":
            tip = study.base.tip
            fixed = {
                "magnet_outer_diameter": tip.magnet_outer_diameter,
                "magnet_inner_diameter": tip.magnet_inner_diameter,
                "magnet_length": tip.magnet_length,
            }
            rng = {}
            for name, value in fixed.items():
                b = study.bound(name)
                rng[name] = (b.low, b.high) if b else (value, value)
            od, idia = rng["magnet_outer_diameter"], rng["magnet_inner_diameter"]
            h = rng["magnet_length"]
            bore = min(idia[1], od[0] - 2 * study.limits.min_wall)
            lo_ = 2 * ring_volume(od[0], max(bore, 0.0), h[0])
            hi_ = 2 * ring_volume(od[1], idia[0], h[1])
        else:
            b = study.bound(sweep.against)
            if b is None:
                raise ValueError(
                    f"pareto sweep against {sweep.against} needs free.{sweep.against}_mm "
                    "or an explicit range_mm"
                )
            lo_, hi_ = b.low, b.high
        low = lo_ if low is None else low
        high = hi_ if high is None else high
    if not high > low:
        raise ValueError(f"pareto sweep against {sweep.against} has an empty range")
    return np.linspace(low, high, sweep.points)
