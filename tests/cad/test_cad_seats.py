"""The bought catheter and wire sit in their glued seats, measured on the CadQuery solids.

Issue 52: the catheter started at the nose face with no glue engagement (the wire passage
swallowed its socket), and the parts list's length ignored the sockets. Here the assembly
is built with real solids and, for each end of each tube, the holder's material round the
tube is measured slice by slice along the stated engagement (a thin annulus outside the
seat's bore, intersected with the placed holder), the tube must not cut into its holder,
and a floored end must bear on its shoulder (moved 0.05 mm deeper, it would). The cut
lengths are checked against the layout written out independently: socket depths and the
flexible rod, free length less the model's rigid offset (design.mounting).
"""

from __future__ import annotations

import cadquery as cq
import numpy as np
import pytest

from cad.actuator import build_actuator
from cad.assembly import RobotAssembly, build_assembly
from cad.mounting import build_mounting_pieces
from cad.process import FDM
from cad.solids import cylinder, frame
from cad.stock import cuts, fasteners
from design.mounting import design_tip_geometry
from design.records import Design

SLICES = 8
PROBE_MM = 0.45  # radial thickness of the probe annulus outside a seat's bore


@pytest.fixture(scope="module")
def assembly(demonstrator: Design) -> RobotAssembly:
    """The demonstrator's assembly: FDM actuator, the design's own tip pieces. [mm]"""
    act = build_actuator(demonstrator, FDM)
    return build_assembly(demonstrator, act, build_mounting_pieces(demonstrator))


def _instance(assembly: RobotAssembly, name: str):
    return next(i for i in assembly.instances if i.name == name)


def _along_x(solid: cq.Shape) -> cq.Shape:
    """A solid built on +Z, laid along the base frame's +x."""
    return solid.moved(frame((0.0, 0.0, 0.0), (1, 0, 0), (0, 1, 0)))


def _fill(holder: cq.Shape, bore: float, x0: float, x1: float, thick: float = PROBE_MM) -> float:
    """Share of an annulus ``thick`` outside ``bore`` (x0 to x1, on the axis) that the
    holder's material fills. [-]"""
    probe = _along_x(cylinder(bore + 2 * thick, x0, x1).cut(cylinder(bore + 1e-3, x0 - 1, x1 + 1)))
    return holder.intersect(probe).Volume() / probe.Volume()


@pytest.mark.parametrize("tube", ["catheter", "wire"])
def test_each_tube_end_sits_in_its_seat_with_the_stated_engagement(
    demonstrator: Design, assembly: RobotAssembly, tube: str
) -> None:
    cut = cuts(demonstrator, assembly.actuator.layout, assembly.mounting.dims)[tube]
    placed_tube = assembly.placed(_instance(assembly, tube))
    bb = placed_tube.BoundingBox()
    assert (bb.xmin, bb.xmax) == pytest.approx((cut.start, cut.end), abs=1e-6)
    for seat, inward in zip(cut.seats, (+1, -1), strict=True):
        # inward: the direction from the tube's end along its seat
        end = cut.start if inward > 0 else cut.end
        holder = assembly.placed(_instance(assembly, seat.holder))
        assert holder.intersect(placed_tube).Volume() < 1e-3, (tube, seat.holder)
        step = seat.engagement / SLICES
        inside = [
            _fill(
                holder, seat.bore, *sorted((end + inward * k * step, end + inward * (k + 1) * step))
            )
            for k in range(SLICES)
        ]
        mouth = end + inward * seat.engagement
        # just past the mouth the seat's bore ends: a face, a pocket or a lead-in cone
        outside = _fill(
            holder, seat.bore, *sorted((mouth + inward * 0.1, mouth + inward * 0.4)), 0.05
        )
        message = (
            f"{tube} in {seat.holder}: fill {np.round(inside, 2)}, past the mouth {outside:.2f}"
        )
        assert min(inside) > 0.3 and outside < 0.05, message
        if seat.floored:
            deeper = placed_tube.translate(cq.Vector(-inward * 0.05, 0, 0))
            assert holder.intersect(deeper).Volume() > 1e-4, f"{tube} floor in {seat.holder}"


def test_cut_lengths_are_the_layouts(demonstrator: Design, assembly: RobotAssembly) -> None:
    lay, d = assembly.actuator.layout, assembly.mounting.dims
    g = design_tip_geometry(demonstrator)
    rod = (demonstrator.robot.free_length - g.rigid_offset) * 1e3  # nose to the tip piece
    tubes = cuts(demonstrator, lay, d)
    assert tubes["catheter"].length == pytest.approx(
        lay.catheter_socket_depth + rod + g.socket_depth * 1e3, rel=1e-12
    )
    assert tubes["catheter"].seats[0].engagement >= lay.spec.catheter_socket_mm
    for name, c in tubes.items():
        solid = assembly.parts[name].solid
        assert solid.BoundingBox().zlen == pytest.approx(c.length, abs=1e-6), name


def test_every_screw_hole_has_its_listed_screw(assembly: RobotAssembly) -> None:
    lay = assembly.actuator.layout
    listed = {f.name: f for f in fasteners(lay)}
    # four tapped holes in the housing's top under four clearance holes in the lid
    lid = assembly.parts["lid"].solid
    holes = [
        f for f in lid.Faces() if f.geomType() == "CYLINDER"
        and abs(f.BoundingBox().xlen - lay.spec.lid_screw_clearance_mm) < 1e-3
        and abs(f.BoundingBox().ylen - lay.spec.lid_screw_clearance_mm) < 1e-3
    ]  # fmt: skip
    assert listed["lid_screw"].quantity == len(holes) == 4
    screw = listed["lid_screw"]
    assert lay.spec.lid_mm < screw.length <= lay.spec.lid_mm + 8.0  # reaches into the tap
    grub = listed["set_screw"]
    assert grub.quantity == 1 and grub.length <= (lay.spec.wire_mount_mm - lay.spec.hex_mm) / 2
