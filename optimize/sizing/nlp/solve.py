"""Solving the design NLP with IPOPT from several starts; the minimum-violation problem
when none is feasible. SI units."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from design.admissible import admits, quantities
from design.processes import raise_if_interrupted
from design.registry import NAMES
from optimize.sizing.materials import Material, material
from optimize.sizing.nlp.branches import _loop_faults, _off_branch
from optimize.sizing.nlp.evaluation import (
    CONTROLLABLE,
    _forward,
    _metrics_dict,
    _nlp_shape,
    _Norms,
    _norms,
    _objective,
    _states,
    _violation,
    controllable_disc_radius,
    evaluate_design,
)
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
    Problem,
    core,
    problem,
    restoration,
)
from optimize.sizing.nlp_results import (
    Conflict,
    OptimizationResult,
    StartResult,
)
from optimize.sizing.studyfile import Study


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
            q = quantities(candidate_design(study, vals))
            ok = all(admits(r, q) for r in ("ring_wall", "catheter_wall", "wire_in_catheter"))
            ok = ok and admits("ring_on_wire", q, clearance)
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
        prob.best.reset(lbg, ubg)
        sol = prob.solver(x0=w0, p=params, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        raise_if_interrupted()  # IPOPT's interface stops the solve on Ctrl-C, and goes on
        stats = prob.solver.stats()
        w = np.asarray(sol["x"]).ravel()
        lam_g, lam_x = np.asarray(sol["lam_g"]).ravel(), np.asarray(sol["lam_x"]).ravel()
        status = str(stats.get("return_status", "unknown"))
        success = bool(stats.get("success", False))
        if not success and prob.best.best is not None:
            # IPOPT stalled at, or wandered off, a feasible optimum it could not certify:
            # its best feasible iterate, judged below like any answer (nlp_iterates). An
            # interior-point iterate's multipliers are the barrier's, nonzero on every row,
            # not KKT multipliers: unknown (NaN), so its active rows are read from margins.
            w = prob.best.best[0]
            lam_g, lam_x = np.full_like(lam_g, np.nan), np.full_like(lam_x, np.nan)
            why = "stalled" if prob.best.stalled else status
            status, success = f"Best_Feasible_Iterate ({why})", True
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
    result = StartResult(
        index=index_,
        materials=names,
        status=status,
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
        lam_x[:nf],
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
    raise_if_interrupted()
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
    conflicts: bool = True,
) -> OptimizationResult:
    """Solve the study's design NLP from several starts; return the best accepted design.

    epsilon : Pareto bounds by quantity (PARETO_QUANTITIES: ``catheter_outer_diameter``
        and ``magnet_volume`` bounded above, ``external_distance`` below). [SI: m, m^3]
    starts : explicit start points (free quantities by name, SI; missing ones from the
        base design) instead of the study's seeded ones.
    conflicts : when no start is accepted, solve the minimum-violation problem (False:
        skip it, ``conflicts`` empty; for a trial whose infeasible answer is discarded).
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
        violated: tuple[Conflict, ...] = ()
        limiting: tuple[str, ...] = ()
        best_total = math.inf
        for cat, wire in combos if conflicts else ():
            try:
                total, found, bounds_ = _conflicts(study, points[0], cat, wire, epsilon, norms)
            except Exception:  # noqa: BLE001 - report what the starts said
                continue
            if total < best_total:
                best_total, violated, limiting = total, found, bounds_
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
            conflicts=violated,
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
