"""The epsilon bounds of the Pareto sweeps, and the answers a tighter bound keeps. SI units."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from design.magnets import ring_volume
from optimize.sizing.materials import material
from optimize.sizing.nlp.evaluation import _nlp_shape, _state, _violation
from optimize.sizing.nlp_designs import group_bounds, study_parameters
from optimize.sizing.nlp_problem import core, design_values
from optimize.sizing.nlp_results import OptimizationResult
from optimize.sizing.studyfile import ParetoSweep, Study


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


def kept_optimum(
    study: Study, against: str, epsilon: float, looser: OptimizationResult
) -> OptimizationResult | None:
    """``looser`` (a feasible answer under a looser bound on ``against``, or none) as the
    answer under the bound ``epsilon``, where its design meets that bound too: the
    feasible set only shrinks as the bound tightens, so a design optimal in the larger set
    and inside the smaller one is optimal there (the epsilon-constraint method); no NLP
    is solved. None where it breaks the bound (beyond FEASIBILITY_TOLERANCE, the NLP's
    own acceptance). The bound's state replaces the looser one's in ``constraints`` and
    ``active``; ``starts`` are the solves that found the design. [SI]"""
    if not looser.feasible or looser.design is None:
        return None
    cat, wire = (material(n) if n else None for n in looser.materials)
    bounds = group_bounds(study, cat, wire, {against: epsilon})
    name = f"epsilon.{against}"
    value = design_values(study_parameters(study, looser.design))[name]
    state = _state(name, np.array([value]), bounds)
    if _violation([state]) > 0:
        return None
    state = replace(state, active=state.active and name in core(_nlp_shape(study)).variable_groups)
    constraints = tuple(s for s in looser.constraints if s.name != name) + (state,)
    active = tuple(a for a in looser.active if a != name) + ((name,) if state.active else ())
    return replace(
        looser,
        constraints=constraints,
        active=active,
        epsilon={**looser.epsilon, against: epsilon},
        seconds=0.0,
    )
