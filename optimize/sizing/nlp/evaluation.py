"""Evaluating designs of a study by forward simulation with the NLP's own metric and
constraint expressions; the constraint states, violations and objective norms the solver
reports with. SI units."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np

from design.controllable import controllable_disc_radius as controllable_disc
from design.equilibrium import solve_equilibria
from design.records import Design
from optimize.sizing.materials import material
from optimize.sizing.nlp_designs import (
    candidate_design,
    free_values,
    group_bounds,
    material_combinations,
    study_parameters,
)
from optimize.sizing.nlp_problem import (
    GROUPS,
    METRICS,
    Core,
    NlpShape,
    core,
)
from optimize.sizing.nlp_results import (
    ConstraintState,
    Evaluation,
)
from optimize.sizing.studyfile import Study

FEASIBILITY_TOLERANCE = 1e-6
"""A constraint row counts as satisfied within this, in its group's file unit, plus this
relative to its limit (IPOPT relaxes bounds by about 1e-8 relative)."""
ACTIVE_TOLERANCE = 1e-5
"""A constraint row is active when within this of its limit (file unit) or its multiplier
is nonzero."""


def _nlp_shape(study: Study) -> NlpShape:
    return NlpShape(
        frozenset(study.effects),
        tuple(b.name for b in study.free),
        study.configurations,
        study.neutral_configurations,
    )


def _state(
    name: str, vals: np.ndarray, bounds: Mapping[str, tuple[float, float]], mult: float = 0.0
) -> ConstraintState:
    """The state of constraint group ``name`` from its rows' values ``vals`` (SI) and the
    largest |multiplier| of its rows (scaled problem): its worst row against its limits."""
    lo, hi = bounds[name]
    scale, unit, _ = GROUPS[name]
    margins = np.minimum(vals - lo, hi - vals)
    i = int(np.argmin(margins))
    limit = lo if vals[i] - lo <= hi - vals[i] else hi
    active = margins[i] / scale < ACTIVE_TOLERANCE or mult > 1e-7
    return ConstraintState(
        name, float(vals[i]), float(limit), float(margins[i]), bool(active), mult, unit, scale
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
        mult = 0.0 if multipliers is None else float(np.max(np.abs(multipliers[rows == name])))
        state = _state(name, g[rows == name], bounds, mult)
        out.append(replace(state, active=state.active and name in c.variable_groups))
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
