"""The lid's zero marks: a line engraved beside each knob, along the knob's pointer as the
actuator's parts are placed, so the drive's zero can be read and set (the rings' theta = 0
when the transmissions are bonded). Real CadQuery solids probed at the mark, on the
demonstrator and on drawn actuators (tubes, worm drives, knobs and lids of other sizes)."""

from __future__ import annotations

import math
from dataclasses import replace

import cadquery as cq
import numpy as np
import pytest

from cad.drivetrain import placements
from cad.errors import CadError
from cad.gears import WormDriveSpec
from cad.housing import ZERO_MARK_MM, lid, zero_mark_centres
from cad.layout import ActuatorLayout, ActuatorSpec, actuator_layout
from cad.process import get_process
from design.designfile import default_design
from design.units import MM


def _moved(point, loc: cq.Location) -> cq.Vector:
    return cq.Vertex.makeVertex(*point).moved(loc).Center()


NEAR_RIM_MM = 2.0
"""A mark reads as its knob's when it starts at most this far from the knob's rim."""


def assert_marks_beside_knobs_along_pointers(lay: ActuatorLayout, why: str) -> None:
    solid = lid(lay)
    _, length, width, depth = ZERO_MARK_MM
    top = lay.lid_z + lay.spec.lid_mm
    knobs = {k: loc for k, (part, loc) in placements(lay).items() if part == "knob"}
    assert len(knobs) == len(zero_mark_centres(lay)) == 2, why
    for (x, y), (name, loc) in zip(zero_mark_centres(lay), sorted(knobs.items()), strict=True):
        at = f"{why}: {name}"
        # engraved: empty at half its depth, lid beside it and below its floor
        assert not solid.isInside(cq.Vector(x, y, top - depth / 2)), at
        assert solid.isInside(cq.Vector(x + width, y, top - depth / 2)), at
        assert solid.isInside(cq.Vector(x, y, top - depth - 0.3)), at
        # beside the knob (visible), along the pointer (the knob's local +X)
        axis = _moved((0, 0, 0), loc)
        pointer = _moved((1, 0, 0), loc) - axis
        offset = cq.Vector(x - axis.x, y - axis.y, 0)
        rim = offset.Length - length / 2 - lay.spec.knob_mm / 2  # mark's near end to the rim
        assert 0 < rim <= NEAR_RIM_MM, f"{at}: {rim:.3g} mm from the knob's rim"
        assert math.isclose(offset.normalized().dot(pointer.normalized()), 1.0, abs_tol=1e-9), at


@pytest.mark.parametrize("process", ["fdm", "resin"])
def test_each_knob_has_an_engraved_zero_mark_beside_it_along_its_pointer(process):
    lay = actuator_layout(default_design(), get_process(process))
    assert_marks_beside_knobs_along_pointers(lay, process)


def drawn_actuator(seed: int) -> tuple[ActuatorLayout, str]:
    """An actuator the layout accepts, for tubes and a drive, knobs and a lid drawn far
    from the demonstrator's (redrawn where the layout refuses them)."""
    rng = np.random.default_rng(seed)
    d = default_design()
    for _ in range(100):
        catheter = rng.uniform(0.6, 3.0)
        wire = rng.uniform(0.15, 0.8 * catheter - 0.1)
        bore = rng.uniform(wire + 0.05, catheter - 0.1)
        robot = replace(
            d.robot,
            catheter=replace(
                d.robot.catheter, outer_diameter=catheter * MM, inner_diameter=bore * MM
            ),
            wire=replace(d.robot.wire, outer_diameter=wire * MM),
        )
        drive = WormDriveSpec(
            module_mm=rng.uniform(0.8, 2.0),
            wheel_teeth=int(rng.integers(20, 46)),
            worm_starts=int(rng.integers(1, 3)),
            wheel_face_width_mm=rng.uniform(5.0, 10.0),
        )
        spec = ActuatorSpec(
            drive=drive, knob_mm=rng.uniform(14.0, 32.0), lid_mm=rng.uniform(3.0, 6.0)
        )
        process = str(rng.choice(["fdm", "resin"]))
        why = (
            f"seed {seed}: catheter {catheter:.2f}/{bore:.2f} mm, wire {wire:.2f} mm, "
            f"worm drive m {drive.module_mm:.2f} z2 {drive.wheel_teeth} z1 {drive.worm_starts}, "
            f"knob {spec.knob_mm:.1f} mm, lid {spec.lid_mm:.1f} mm, {process}"
        )
        try:
            return actuator_layout(replace(d, robot=robot), get_process(process), spec), why
        except CadError:
            continue
    raise AssertionError(f"seed {seed}: no actuator the layout accepts in 100 draws")


@pytest.mark.parametrize("seed", range(6301, 6307))
def test_drawn_actuators_have_their_zero_marks_beside_each_knob_along_its_pointer(seed):
    lay, why = drawn_actuator(seed)
    assert_marks_beside_knobs_along_pointers(lay, why)
