"""The admissibility rules (design.admissible) against closed forms written here, and the
three places that apply them agreeing on drawn designs: the design-file reader raises,
the CAD refuses and the NLP's constraint rows are negative exactly where a rule says so.
The seed of each random case is in its test id."""

from __future__ import annotations

import copy
from types import SimpleNamespace

import numpy as np
import pytest

from cad.errors import CadError
from cad.mounting import mounting_dims
from design.admissible import FIT_TOLERANCE, RULES, WIRE_CLEARANCE, admits, quantities
from design.designfile import DesignError, default_design, design_from_dict, design_to_dict
from design.mounting import design_tip_geometry
from design.registry import parameter_vector
from design.units import MM
from optimize.sizing.nlp_problem import _design_rows

# --- bore over the wire: inner diameter - wire diameter >= clearance, within FIT_TOLERANCE.


@pytest.mark.parametrize("clearance", [WIRE_CLEARANCE, 0.2 * MM])
@pytest.mark.parametrize("wire", [0.2 * MM, 0.4 * MM, 1.0 * MM])
def test_ring_clears_wire_exactly_at_the_clearance_and_not_a_micrometre_below(wire, clearance):
    rule = RULES["ring_on_wire"]

    def fits(bore, least=None):
        return rule.admits(
            rule.margin({"magnet_inner_diameter": bore, "wire_outer_diameter": wire}), least
        )

    assert fits(wire + clearance, clearance)
    assert fits(wire + clearance - FIT_TOLERANCE / 2, clearance)
    assert not fits(wire + clearance - 1e-6, clearance)
    if clearance == WIRE_CLEARANCE:  # the rule's own least
        assert fits(wire + clearance)
        assert not fits(wire + clearance - 1e-6)


def test_a_study_limit_raises_a_rule_and_never_lowers_it():
    # Studies may ask for more clearance or wall than the rule, never less.
    rule, wall = RULES["ring_on_wire"], RULES["ring_wall"]
    assert rule.bound(SimpleNamespace(wire_clearance=0.2 * MM)) == 0.2 * MM
    assert rule.bound(SimpleNamespace(wire_clearance=0.01 * MM)) == WIRE_CLEARANCE
    assert wall.bound(SimpleNamespace(min_wall=0.3 * MM)) == 0.3 * MM
    assert wall.bound(SimpleNamespace(min_wall=-1.0)) == 0.0


def _drawn(seed: int) -> dict:
    """A demonstrator document with its tubes' and rings' diameters and the seats' fit
    allowance drawn, admissible or not. [mm]"""
    rng = np.random.default_rng(seed)
    doc = copy.deepcopy(design_to_dict(default_design()))
    r, t = doc["robot"], doc["tip"]
    wire = float(rng.uniform(0.1, 1.2))
    r["wire"]["outer_diameter_mm"] = wire
    r["wire"]["inner_diameter_mm"] = float(rng.choice([0.0, rng.uniform(0.0, 1.2)]))
    r["catheter"]["inner_diameter_mm"] = wire + float(rng.uniform(-0.1, 0.6))
    r["catheter"]["outer_diameter_mm"] = float(rng.uniform(0.5, 2.5))
    t["magnet_outer_diameter_mm"] = float(rng.uniform(1.0, 5.0))
    t["magnet_inner_diameter_mm"] = wire + float(rng.uniform(-0.05, 0.8))
    t.setdefault("mounting", {})["fit_allowance_mm"] = float(rng.uniform(0.0, 0.3))
    if rng.random() < 0.5:  # a narrowed passage, sometimes too narrow or wider than the bore
        passage = wire + float(rng.uniform(0.0, 0.7))
        t["mounting"]["passage_diameter_mm"] = passage
    return doc


SEEDS = list(range(60))


@pytest.mark.parametrize("seed", SEEDS)
def test_the_reader_refuses_exactly_the_designs_a_rule_refuses(seed):
    doc = _drawn(seed)
    r, t = doc["robot"], doc["tip"]
    wire, cat = r["wire"], r["catheter"]
    clearance_mm = WIRE_CLEARANCE / MM
    admissible = (
        cat["inner_diameter_mm"] < cat["outer_diameter_mm"]
        and wire["inner_diameter_mm"] < wire["outer_diameter_mm"]
        and wire["outer_diameter_mm"] < cat["inner_diameter_mm"]
        and t["magnet_inner_diameter_mm"] < t["magnet_outer_diameter_mm"]
        # the clearance in mm, the rule in m: decided here away from the threshold
        and t["magnet_inner_diameter_mm"] - wire["outer_diameter_mm"] >= clearance_mm
    )
    passage = t["mounting"].get("passage_diameter_mm", 0.0)
    if passage:  # the wire turns in it; it narrows the catheter's bore, never widens it
        admissible = admissible and (
            wire["outer_diameter_mm"] + clearance_mm <= passage <= cat["inner_diameter_mm"]
        )
    near = abs(t["magnet_inner_diameter_mm"] - wire["outer_diameter_mm"] - clearance_mm) < 1e-9
    near |= bool(passage) and (
        abs(passage - wire["outer_diameter_mm"] - clearance_mm) < 1e-9
        or abs(passage - cat["inner_diameter_mm"]) < 1e-9
    )
    if near:
        pytest.skip(f"seed {seed}: the bore is on the clearance to rounding")
    try:
        design_from_dict(doc)
        refused = ""
    except DesignError as exc:
        refused = str(exc)
    geometric = ("diameter_mm must be smaller", "must be at least robot.wire")
    geometric += ("passage_diameter_mm must be at least",)
    assert admissible == (not refused), f"seed {seed}: {refused}"
    assert not refused or any(g in refused for g in geometric), f"seed {seed}: {refused}"


def test_the_cad_refuses_and_the_nlp_row_is_negative_where_the_rings_do_not_seat():
    names, rows = _design_rows()
    outcomes = set()
    for seed in SEEDS:
        try:
            design = design_from_dict(_drawn(seed))
        except DesignError:
            continue
        tip = design_tip_geometry(design)
        # the ring rests on the pocket floors: its bore over the distal piece's wire bore
        # (wire + fit allowance) and over the proximal piece's passage (the catheter's bore
        # unless the design narrows it)
        bore = design.robot.wire.outer_diameter + design.tip.mounting.fit_allowance
        passage = design.tip.mounting.passage_diameter or design.robot.catheter.inner_diameter
        seat = design.tip.magnet_inner_diameter - max(bore, passage)
        assert float(tip.wire_bore) == pytest.approx(bore, abs=1e-15), f"seed {seed}"
        q = quantities(design, tip)
        assert RULES["ring_seat"].margin(q) == pytest.approx(seat, abs=1e-15), f"seed {seed}"
        nlp = np.asarray(rows(parameter_vector(design))[0]).ravel()
        for name in ("ring_on_wire", "wire_in_catheter", "ring_wall", "catheter_wall", "ring_seat"):
            margin = RULES[name].margin(q)
            assert nlp[names.index(name)] == pytest.approx(margin, abs=1e-15), f"seed {seed}"
        if abs(seat) < 1e-12:
            continue  # on the threshold to rounding
        try:
            mounting_dims(design)
            built = ""
        except CadError as exc:
            built = str(exc)
        refused = "rests on the pocket floor" in built
        assert refused == (seat < 0) == (not admits("ring_seat", q)), f"seed {seed}: {built}"
        outcomes.add(refused)
    assert outcomes == {True, False}, "the draws never reached one side of the seat rule"
