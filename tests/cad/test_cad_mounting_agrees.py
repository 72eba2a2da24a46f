"""The CAD builds the tip the model simulates: every dimension, for drawn mountings.

Issue 48's regression: a design file's ``[tip.mounting] wall_mm = 1.0`` made the model
simulate a 9.15 mm tip while ``cad`` built a 6.65 mm one from a process table of its own.
Here the model's side is its own symbolic tip (:class:`design.model.Symbols`, evaluated at
the design's parameter vector through the registry), the CAD's side is
:func:`cad.mounting.mounting_dims` and the built CadQuery solids; the mountings are drawn
from the whole range the design-file reader and the CAD accept (seeds printed).
"""

from __future__ import annotations

from dataclasses import fields

import casadi as ca
import numpy as np
import pytest

from cad.mounting import _LENGTHS, build_mounting_pieces, mounting_dims
from design.designfile import design_to_dict, loads_design
from design.model import RingPairModel, Symbols
from design.mounting import MAX_STOP_ANGLE, TipGeometry
from design.process import PROCESSES
from design.records import Design
from design.registry import NAMES

SEEDS = range(4800, 4812)


def model_tip(design: Design) -> dict[str, float]:
    """The tip geometry the model simulates ``design`` with, by field. [SI]"""
    prm = ca.SX.sym("p", len(NAMES))
    tip = Symbols(prm).tip
    names = [f.name for f in fields(TipGeometry)]
    f = ca.Function("tip", [prm], [ca.vertcat(*(ca.SX(getattr(tip, n)) for n in names))])
    values = np.asarray(f(RingPairModel.parameters(design))).ravel()
    return dict(zip(names, values.tolist(), strict=True))


def drawn_design(demonstrator: Design, seed: int) -> tuple[Design, dict[str, object]]:
    """The demonstrator with a ``[tip.mounting]`` drawn from the accepted range, read back
    through its design-file text (the path a user's file takes)."""
    import tomli_w

    rng = np.random.default_rng(seed)
    process = PROCESSES[str(rng.choice(sorted(PROCESSES)))]
    section: dict[str, object] = {
        "process": process.name,
        "wall_mm": float(rng.uniform(1.0, 4.0) * process.min_wall * 1e3),
        "fit_allowance_mm": float(rng.uniform(-0.05, 0.3)),
        "running_clearance_mm": float(rng.uniform(0.0, 0.4)),
        "density_kg_m3": float(rng.uniform(900.0, 2000.0)),
        "stop_angle_deg": float(rng.uniform(10.0, np.degrees(MAX_STOP_ANGLE))),
    }
    if rng.random() < 0.5:  # a narrowed wire passage, from the wire's need to the bore
        robot = demonstrator.robot
        wire, bore = robot.wire.outer_diameter, robot.catheter.inner_diameter
        section["passage_diameter_mm"] = float(rng.uniform(wire * 1e3 + 0.05, bore * 1e3))
    doc = design_to_dict(demonstrator)
    doc["tip"]["mounting"] = section
    return loads_design(tomli_w.dumps(doc), source=f"seed {seed}"), section


@pytest.mark.parametrize("seed", SEEDS)
def test_cad_dimensions_are_the_models_for_drawn_mountings(demonstrator: Design, seed) -> None:
    design, section = drawn_design(demonstrator, seed)
    want = model_tip(design)
    dims = mounting_dims(design)  # the design's own tip.mounting: no process passed
    for name in _LENGTHS:
        got = getattr(dims, name) * 1e-3
        assert got == pytest.approx(want[name], rel=1e-9, abs=1e-15), (
            f"seed {seed} {section}: {name}"
        )
    assert np.radians(dims.stop_angle_deg) == pytest.approx(want["notch_span"] - want["key_angle"])


def test_the_issue_48_wall_builds_the_tip_the_model_simulates(demonstrator: Design) -> None:
    # The issue's case: wall 1.0 mm on the (resin) demonstrator.
    doc = design_to_dict(demonstrator)
    doc["tip"]["mounting"] = {"wall_mm": 1.0}
    import tomli_w

    design = loads_design(tomli_w.dumps(doc), source="wall 1.0")
    want = model_tip(design)
    pieces = build_mounting_pieces(design, with_groove=False)
    assert pieces.dims.wall == pytest.approx(1.0)
    for solid, length in (
        (pieces.proximal, want["proximal_length"]),
        (pieces.distal, want["distal_length"]),
    ):
        bb = solid.BoundingBox()
        assert bb.zlen * 1e-3 == pytest.approx(length, rel=1e-6)
        # the outer cylinder's box (OCC's box of a curved face is loose by a little)
        assert max(bb.xlen, bb.ylen) * 1e-3 == pytest.approx(want["outer_diameter"], rel=2e-3)
    # and the process's default wall would not have made it
    default = build_mounting_pieces(demonstrator, with_groove=False)
    assert default.dims.outer_diameter < pieces.dims.outer_diameter - 0.5
