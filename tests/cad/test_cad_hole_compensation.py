"""Hole compensation (issue 52): with ``[tip.mounting] compensate_holes = true`` the CAD
draws every bore that must fit (ring seats, the catheter socket and the wire bore of the
tip pieces; the actuator's catheter socket and wire seat) wider by the process's hole
shrink, so that it prints at the size the model takes; the model's robot does not change.

Measured on the real solids: the diameters of their cylindrical faces, with and without
compensation, for both processes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from cad.actuator import build_actuator
from cad.mounting import build_mounting_pieces
from cad.process import get_process
from design.designfile import DesignError, design_to_dict, dumps_design, loads_design
from design.mounting import design_tip_geometry
from design.records import Design, Mounting


def _diameters(solid) -> np.ndarray:
    """Diameters of the full cylindrical faces of ``solid`` (the larger bounding-box side
    across the axis of each), rounded to 1 um. [mm]"""
    out = []
    for f in solid.Faces():
        if f.geomType() != "CYLINDER":
            continue
        bb = f.BoundingBox()
        sides = sorted([bb.xlen, bb.ylen, bb.zlen])
        if abs(sides[1] - sides[2]) < 1e-4 or abs(sides[0] - sides[1]) < 1e-4:
            across = sides[1] if abs(sides[1] - sides[2]) < 1e-4 else sides[0]
            out.append(round(across, 3))
    return np.unique(out)


def _compensated(design: Design, process: str, on: bool) -> Design:
    mounting = Mounting.printed_by(process, compensate_holes=on)
    return replace(design, tip=replace(design.tip, mounting=mounting))


@pytest.mark.parametrize("process", ["resin", "fdm"])
def test_fit_bores_are_drawn_wider_by_the_hole_shrink(demonstrator: Design, process: str):
    shrink = get_process(process).hole_shrink_mm
    plain = build_mounting_pieces(_compensated(demonstrator, process, False))
    wide = build_mounting_pieces(_compensated(demonstrator, process, True))
    d = plain.dims
    assert wide.dims.hole_compensation == pytest.approx(shrink) and d.hole_compensation == 0
    fits = {
        "proximal": (d.seat_diameter, d.socket_diameter),
        "distal": (d.seat_diameter, d.wire_bore),
    }
    for piece, bores in fits.items():
        before = _diameters(getattr(plain, piece))
        after = _diameters(getattr(wide, piece))
        for bore in bores:
            assert np.isclose(before, bore, atol=2e-3).any(), (piece, bore, before)
            assert np.isclose(after, bore + shrink, atol=2e-3).any(), (piece, bore, after)
            assert not np.isclose(after, bore, atol=2e-3).any(), (piece, bore, after)
    # the robot the model simulates is the printed one: the same either way
    assert design_tip_geometry(_compensated(demonstrator, process, True)) == design_tip_geometry(
        _compensated(demonstrator, process, False)
    )


def test_actuator_seats_are_drawn_wider_by_the_hole_shrink(demonstrator: Design):
    fdm = get_process("fdm")
    plain = build_actuator(_compensated(demonstrator, "resin", False), fdm)
    wide = build_actuator(_compensated(demonstrator, "resin", True), fdm)
    lay = plain.layout
    assert wide.layout.hole_compensation == pytest.approx(fdm.hole_shrink_mm)
    for part, bore in (
        ("gear_shaft_front", lay.catheter_socket_diameter),
        ("wire_mount", lay.wire_seat_diameter),
    ):
        before = _diameters(plain.parts[part])
        after = _diameters(wide.parts[part])
        assert np.isclose(before, bore, atol=2e-3).any(), (part, bore, before)
        assert np.isclose(after, bore + fdm.hole_shrink_mm, atol=2e-3).any(), (part, after)


def test_compensate_holes_is_read_written_and_checked(demonstrator: Design):
    doc = design_to_dict(_compensated(demonstrator, "fdm", True))
    assert doc["tip"]["mounting"]["compensate_holes"] is True
    assert loads_design(dumps_design(loads_design(_toml(doc)))).tip.mounting.compensate_holes
    assert "compensate_holes" not in design_to_dict(demonstrator).get("tip", {}).get("mounting", {})
    doc["tip"]["mounting"]["compensate_holes"] = "yes"
    with pytest.raises(DesignError, match="tip.mounting.compensate_holes must be true or false"):
        loads_design(_toml(doc))


def _toml(doc: dict) -> str:
    import tomli_w

    return tomli_w.dumps(doc)
