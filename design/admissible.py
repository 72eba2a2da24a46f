"""Geometric admissibility of a design: the rules every robot must satisfy to be made,
each written once (walls, the rings' bore over the wire, the wire in the catheter, the
rings' seat on the printed pieces, a flexible rod under the printed tip).

A rule is a *margin*, a function of named quantities (the registry's parameter names,
:data:`design.registry.NAMES`, and of the printed pieces, :class:`design.mounting.TipGeometry`:
``wire_bore``, the distal piece's wire bore, ``passage_diameter``, the proximal piece's wire
passage, and ``rod_length``, the flexible rod under the
rigid tip) that works on numbers and on CasADi symbols alike, and the *least* admissible
margin. Its consumers:

- the design-file reader (:mod:`design.designfile`) raises where a margin is not
  admissible (:meth:`Rule.admits`);
- the CAD (:mod:`cad.mounting`) refuses to build such pieces;
- the NLP (:mod:`optimize.sizing.nlp_problem`) bounds each margin, a constraint row named
  as the rule, from below by :meth:`Rule.bound`: the rule's least, raised to the study's
  own limit (``wire_clearance``, ``min_wall``: a study may ask for more, never less); all
  but ``wire_wall`` and ``rod_length``, not rows yet (a new row moves every optimum at the
  solver's tolerance).

SI units: margins and limits in m.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import casadi as ca

from design.geometry import is_symbolic
from design.mounting import TipGeometry
from design.records import Design
from design.registry import PARAMETERS
from design.units import MM

WIRE_CLEARANCE = 0.05 * MM
"""Least diametral clearance of a ring's bore over the wire. [m]

The wire turns inside the proximal ring (the wire turns the distal ring, the catheter the
proximal one), so the bore is a running fit; catalogue NdFeB rings hold their diameters to
about +-0.05 mm, so a bore drawn 0.05 mm over the wire still passes it at the bore's lower
limit. Studies may ask for more (``wire_clearance_mm``), never less."""
FIT_TOLERANCE = 1e-9
"""A bore short of its clearance by less than this still fits: the NLP's feasibility
tolerance (1e-6 mm), far below any machining, so that an optimum on the bound loads. [m]"""


def _max(a: Any, b: Any) -> Any:
    """The larger of ``a`` and ``b`` (CasADi's fmax for expressions)."""
    return ca.fmax(a, b) if is_symbolic(a, b) else max(a, b)


@dataclass(frozen=True)
class Rule:
    """One admissibility rule: ``margin(q)`` must exceed ``least`` (``strict``) or reach
    it within :data:`FIT_TOLERANCE` (not ``strict``).

    name : the rule's name, also the NLP's constraint group.
    meaning : what the margin measures.
    margin : named quantities (numbers or CasADi symbols) -> the margin. [m]
    least : least admissible margin. [m]
    strict : whether ``least`` itself is inadmissible.
    limit : the study's :class:`~optimize.sizing.studyfile.Constraints` field that may
        raise ``least`` in the NLP; None where no study sets it.
    """

    name: str
    meaning: str
    margin: Callable[[Mapping[str, Any]], Any]
    least: float = 0.0
    strict: bool = True
    limit: str | None = None

    def admits(self, margin: float, least: float | None = None) -> bool:
        """Whether ``margin`` [m] is admissible, against ``least`` (default: the rule's)."""
        lo = self.least if least is None else least
        return margin > lo if self.strict else margin >= lo - FIT_TOLERANCE

    def bound(self, limits: Any) -> float:
        """The NLP's lower bound of the margin: the rule's least, raised to the study's
        limit (``limits``, a :class:`~optimize.sizing.studyfile.Constraints`). [m]"""
        return self.least if self.limit is None else max(self.least, getattr(limits, self.limit))


def _wall(tube: str) -> Callable[[Mapping[str, Any]], Any]:
    return lambda q: (q[f"{tube}_outer_diameter"] - q[f"{tube}_inner_diameter"]) / 2


RULES: dict[str, Rule] = {
    r.name: r
    for r in (
        Rule("catheter_wall", "radial wall of the catheter", _wall("catheter"), limit="min_wall"),
        Rule("wire_wall", "radial wall of the wire (a tube)", _wall("wire")),
        Rule("ring_wall", "radial wall of the rings", _wall("magnet"), limit="min_wall"),
        Rule(
            "wire_in_catheter",
            "catheter bore minus wire OD",
            lambda q: q["catheter_inner_diameter"] - q["wire_outer_diameter"],
            limit="wire_clearance",
        ),
        Rule(
            "ring_on_wire",
            "ring bore minus wire OD",
            lambda q: q["magnet_inner_diameter"] - q["wire_outer_diameter"],
            least=WIRE_CLEARANCE,
            strict=False,
            limit="wire_clearance",
        ),
        Rule(
            "rod_length",
            "flexible rod under the printed tip (free length less the tip's rigid offset)",
            lambda q: q["rod_length"],
        ),
        Rule(
            "ring_seat",
            "ring bore minus the printed pieces' wire bore and passage",
            lambda q: q["magnet_inner_diameter"] - _max(q["wire_bore"], q["passage_diameter"]),
            limit="wire_clearance",
        ),
    )
}
"""The rules by name."""

_NAMES = tuple(
    f"{part}_{d}_diameter" for part in ("catheter", "wire", "magnet") for d in ("outer", "inner")
)


def quantities(design: Design, tip: TipGeometry | None = None) -> dict[str, float]:
    """The quantities of ``design`` the rules read [m]; with ``tip``, its printed pieces
    (:func:`design.mounting.design_tip_geometry`), those of the pieces too."""
    q = {n: PARAMETERS[n].value(design) for n in _NAMES}
    if tip is not None:
        q["wire_bore"] = float(tip.wire_bore)
        q["passage_diameter"] = float(tip.passage_diameter)
        q["rod_length"] = float(tip.rod_length(design.robot.free_length))
    return q


def margin(name: str, q: Mapping[str, Any]) -> Any:
    """The margin of rule ``name`` for the quantities ``q``. [m]"""
    return RULES[name].margin(q)


def admits(name: str, q: Mapping[str, Any], least: float | None = None) -> bool:
    """Whether the quantities ``q`` satisfy rule ``name`` (against ``least``, default the
    rule's own)."""
    rule = RULES[name]
    return rule.admits(rule.margin(q), least)
