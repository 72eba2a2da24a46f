"""What each limit holding a study's optimum costs: the study's NLP solved again with that
one limit (a constraint's limit, an active free bound) moved by :data:`RELAX` towards a
larger design space. SI units, the objective in its own."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from design.registry import PARAMETERS, file_key
from optimize.sizing.studyfile import FREE_KEYS, Bound, Study

if TYPE_CHECKING:
    from optimize.sizing.nlp import OptimizationResult

RELAX = 0.1
"""Step of the sensitivity stage: an active constraint's limit moved by this fraction of
its value, an active free bound by this fraction of its range (within what the quantity
admits), each towards a larger design space."""

CONSTRAINT_LIMITS = {
    "twist.wire": ("twist_limit", 1),
    "twist.catheter": ("twist_limit", 1),
    "neutral": ("neutral_tolerance", 1),
    "magnet_clearance": ("magnet_clearance", -1),
    "ring_wall": ("min_wall", -1),
    "catheter_wall": ("min_wall", -1),
    "ring_on_wire": ("wire_clearance", -1),
    "wire_in_catheter": ("wire_clearance", -1),
    "ring_seat": ("wire_clearance", -1),
    "ring_diameter": ("max_outer_diameter", 1),
    "catheter_diameter": ("max_outer_diameter", 1),
    "strain.catheter": ("catheter_max_strain", 1),
    "strain.wire": ("wire_max_strain", 1),
}
"""Constraint group of the NLP -> (the study's limit that sets it, :class:`Constraints`
field; +1 where raising the limit relaxes it, -1 where lowering it does)."""


def limit_costs(study: Study, best: OptimizationResult) -> list[dict[str, Any]]:
    """What each limit holding the optimum costs: the study's NLP solved again, from the
    optimum and with its materials, with that one limit moved by :data:`RELAX`.

    One row per limit (constraint groups that share a limit, as the two twist limits do,
    in one row): ``limit`` (a :class:`Constraints` field or ``bound.<name>.low/high``),
    ``groups`` (the active items it covers), ``meaning``, ``unit``, ``old`` and ``new``
    (file units), ``multiplier`` (the largest |Lagrange multiplier| of its groups, scaled
    problem; NaN for a bound, whose multiplier the result does not keep), ``objective``
    (the objective so re-solved, in the objective's own unit; NaN when that NLP found no
    design) and ``gain`` (its change against the optimum). Largest gain first.
    """
    from optimize.sizing.nlp import optimize_design

    cat, wire = best.materials
    fixed = replace(
        study,
        catheter_materials=(cat,) if cat and study.catheter_materials else (),
        wire_materials=(wire,) if wire and study.wire_materials else (),
    )
    limits: dict[str, list[str]] = {}
    for item in best.active:
        name = item if item.startswith("bound.") else CONSTRAINT_LIMITS.get(item, ("", 0))[0]
        if name:
            limits.setdefault(name, []).append(item)
    multipliers = {c.name: c.multiplier for c in best.constraints}
    start = best.objective
    rows = []
    for limit, groups in limits.items():
        moved = _moved(fixed, limit, groups)
        if moved is None:
            continue
        relaxed, row = moved
        result = optimize_design(relaxed, starts=[best.values])
        objective = result.objective if result.feasible else np.nan
        mult = [multipliers[g] for g in groups if g in multipliers]
        rows.append(
            row
            | {
                "limit": limit,
                "groups": groups,
                "multiplier": max(mult) if mult else np.nan,
                "objective": objective,
                "gain": objective - start,
            }
        )
    return sorted(rows, key=lambda r: -np.nan_to_num(r["gain"], nan=-np.inf))


def limit_meaning(item: str) -> str:
    """What an active item of a result (a constraint group, ``bound.<name>.low/high``)
    limits, in words: "the lower bound of the ring length", "the limit on the ..."."""
    from optimize.sizing.nlp_problem import GROUPS

    if item.startswith("bound."):
        _, name, side = item.split(".")
        key = next((k for k in FREE_KEYS.values() if k.name == name), None)
        what = key.meaning if key is not None else name
        return f"the {'lower' if side == 'low' else 'upper'} bound of the {what}"
    return f"the limit on the {GROUPS[item][2]}" if item in GROUPS else item


def _moved(study: Study, limit: str, groups: list[str]) -> tuple[Study, dict[str, Any]] | None:
    """``study`` with ``limit`` moved by RELAX towards a larger design space, and what moved
    (meaning, unit, old and new value in file units); None where it cannot move."""
    from optimize.sizing.nlp_problem import GROUPS

    if limit.startswith("bound."):
        _, name, side = limit.split(".")
        b = study.bound(name)
        key = next(k for k in FREE_KEYS.values() if k.name == name)
        if b is None:
            return None
        step = RELAX * (b.high - b.low)
        if side == "low":
            floor = key.low * key.scale
            low = b.low - step if b.low - step > floor else (b.low + floor) / 2
            low = low if key.low_open else max(low, floor)
            new = Bound(name, low, b.high)
        else:
            new = Bound(name, b.low, min(b.high + step, key.high * key.scale))
        old_v, new_v = (b.low, new.low) if side == "low" else (b.high, new.high)
        if new_v == old_v:
            return None
        free = tuple(new if f.name == name else f for f in study.free)
        unit = file_key(name).rsplit("_", 1)[-1] if name in PARAMETERS else "mm"
        what = {
            "meaning": limit_meaning(limit),
            "unit": unit,
            "old": old_v / key.scale,
            "new": new_v / key.scale,
        }
        return replace(study, free=free), what
    field_name, sign = CONSTRAINT_LIMITS[groups[0]]
    old = getattr(study.limits, field_name)
    if old is None:
        return None
    scale, unit, _ = GROUPS[groups[0]]
    new_limit = old * (1 + sign * RELAX)
    constraints = replace(study.limits, **{field_name: new_limit})
    meaning = "the limit on the " + " and the ".join(GROUPS[g][2] for g in groups)
    what = {"meaning": meaning, "unit": unit, "old": old / scale, "new": new_limit / scale}
    return replace(study, constraints=constraints), what
