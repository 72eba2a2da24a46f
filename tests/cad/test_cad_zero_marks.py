"""The lid's zero marks: a line engraved beside each knob, along the knob's pointer as the
actuator's parts are placed, so the drive's zero can be read and set (the rings' theta = 0
when the transmissions are bonded). Real CadQuery solids probed at the mark."""

from __future__ import annotations

import math

import cadquery as cq
import pytest

from cad.drivetrain import placements
from cad.housing import ZERO_MARK_MM, lid, zero_mark_centres
from cad.layout import actuator_layout
from cad.process import get_process
from design.designfile import default_design


def _moved(point, loc: cq.Location) -> cq.Vector:
    return cq.Vertex.makeVertex(*point).moved(loc).Center()


@pytest.mark.parametrize("process", ["fdm", "resin"])
def test_each_knob_has_an_engraved_zero_mark_beside_it_along_its_pointer(process):
    lay = actuator_layout(default_design(), get_process(process))
    solid = lid(lay)
    _, length, width, depth = ZERO_MARK_MM
    top = lay.lid_z + lay.spec.lid_mm
    knobs = {k: loc for k, (part, loc) in placements(lay).items() if part == "knob"}
    assert len(knobs) == len(zero_mark_centres(lay)) == 2
    for (x, y), (name, loc) in zip(zero_mark_centres(lay), sorted(knobs.items()), strict=True):
        # engraved: empty at half its depth, lid beside it and below its floor
        assert not solid.isInside(cq.Vector(x, y, top - depth / 2)), name
        assert solid.isInside(cq.Vector(x + width, y, top - depth / 2)), name
        assert solid.isInside(cq.Vector(x, y, top - depth - 0.3)), name
        # beside the knob (visible), along the pointer (the knob's local +X)
        axis = _moved((0, 0, 0), loc)
        pointer = _moved((1, 0, 0), loc) - axis
        offset = cq.Vector(x - axis.x, y - axis.y, 0)
        assert offset.Length - length / 2 > lay.spec.knob_mm / 2, name
        assert math.isclose(offset.normalized().dot(pointer.normalized()), 1.0, abs_tol=1e-9), name
