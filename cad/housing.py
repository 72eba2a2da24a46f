"""The actuator's housing (base, walls, bulkheads with bushing seats) and its lid.

CAD works in millimetres: every length here is in mm.

Both are modelled in the actuator frame of :mod:`cad.layout`. The housing prints as
modelled (base on the bed); the lid prints upside down, its flat top on the bed, so its
print frame is the actuator frame turned over (see :func:`lid_placement`).

Bushing seats: each bulkhead has a U-slot whose round bottom seats a shaft's spool
bushing (slot width = bushing + fit allowance); the lid's tongues drop into the slots and
hold the spools down. Each worm's lower bushing sits in a bored boss on the base, the
upper one in a seat through the lid. Four M3 screws hold the lid on the end bulkheads.
Beside each knob the lid has a zero mark, a line engraved along the knob's pointer as the
parts are placed (the worm's thread towards its wheel): with the pointer on it the ring's
angle is a multiple of 360 / ratio degrees, the zero set when the transmissions are
bonded with the rings at theta = 0 (docs/tutorial.md).
"""

from __future__ import annotations

import math

import cadquery as cq

from cad.layout import ActuatorLayout
from cad.solids import X_AXIS, box, cylinder, frame, single_solid

SCREW_DEPTH_MM = 8.0
ZERO_MARK_MM = (1.0, 3.0, 0.8, 0.6)
"""The lid's zero mark beside each knob: its gap to the knob's rim, length, width and
depth, an engraved line along the knob's pointer at the drive's zero. [mm]"""
SADDLE_HALF_ANGLE_DEG = 60.0
"""Half the arc over which a lid tongue's saddle holds its spool: the saddle meets the
tongue's flat ends at 180 - 60 = 120 deg. [deg]"""


def _screw_positions(lay: ActuatorLayout) -> list[tuple[float, float]]:
    """(x, y) of the four lid screws, on the end bulkheads. [mm]"""
    b0, b3 = lay.bulkheads[0], lay.bulkheads[3]
    y = lay.width / 2 - lay.spec.wall_mm - 4.0
    return [(b.mid, sy * y) for b in (b0, b3) for sy in (1, -1)]


def _slot_width(lay: ActuatorLayout) -> float:
    return lay.spec.spool_outer_mm + lay.fit


def housing(lay: ActuatorLayout) -> cq.Solid:
    """Base plate, side walls, four bulkheads with U-slot bushing seats, worm bosses."""
    s = lay.spec
    x = (lay.bulkheads[3].lo, lay.bulkheads[0].hi)
    half = lay.width / 2
    top = lay.lid_z
    parts = [
        box(x, (-half, half), (0.0, s.base_mm)),
        box(x, (half - s.wall_mm, half), (0.0, top)),
        box(x, (-half, -half + s.wall_mm), (0.0, top)),
    ]
    parts += [box((b.lo, b.hi), (-half, half), (0.0, top)) for b in lay.bulkheads]
    boss_d = s.worm_bushing_outer_mm + 2 * s.wall_mm
    for xw, yw in zip(lay.wheel_x, lay.worm_y, strict=True):
        parts.append(
            cylinder(boss_d, s.base_mm - 0.01, lay.boss_top_z).translate(cq.Vector(xw, yw, 0))
        )
    body = parts[0].fuse(*parts[1:]).clean()

    slot = _slot_width(lay)
    h = lay.shaft_height
    cuts: list[cq.Shape] = []
    for b in lay.bulkheads:
        cuts.append(
            cq.Solid.makeCylinder(slot / 2, b.length + 2, cq.Vector(b.lo - 1, 0, h), X_AXIS)
        )
        cuts.append(box((b.lo - 1, b.hi + 1), (-slot / 2, slot / 2), (h, top + 1)))
    seat = s.worm_bushing_outer_mm + lay.fit
    for xw, yw in zip(lay.wheel_x, lay.worm_y, strict=True):
        z0 = lay.boss_top_z - lay.worm_bushing_length
        cuts.append(cylinder(seat, z0, lay.boss_top_z + 1).translate(cq.Vector(xw, yw, 0)))
    cuts.extend(zero_marks(lay))
    for xs, ys in _screw_positions(lay):
        cuts.append(
            cylinder(s.lid_screw_tap_mm, top - SCREW_DEPTH_MM, top + 1).translate(
                cq.Vector(xs, ys, 0)
            )
        )
    return single_solid(body.cut(*cuts).clean(), "housing")


def lid(lay: ActuatorLayout) -> cq.Solid:
    """Lid in the actuator frame: plate, tongues into the U-slots, worm bushing seats,
    screw holes."""
    s = lay.spec
    x = (lay.bulkheads[3].lo, lay.bulkheads[0].hi)
    half = lay.width / 2
    z0, z1 = lay.lid_z, lay.lid_z + s.lid_mm
    tongue = _slot_width(lay) - lay.fit
    h = lay.shaft_height
    # The tongue's saddle wraps the spool over +-SADDLE_HALF_ANGLE_DEG and ends in flats:
    # a saddle over the tongue's full width would meet its sides in 9 deg knife edges.
    bottom = h + _slot_width(lay) / 2 * math.cos(math.radians(SADDLE_HALF_ANGLE_DEG))
    parts = [box(x, (-half, half), (z0, z1))]
    for b in lay.bulkheads:
        parts.append(box((b.lo, b.hi), (-tongue / 2, tongue / 2), (bottom, z0 + 0.01)))
    body = parts[0].fuse(*parts[1:]).clean()
    cuts: list[cq.Shape] = [
        cq.Solid.makeCylinder(
            (_slot_width(lay)) / 2, lay.length + 2, cq.Vector(x[0] - 1, 0, h), X_AXIS
        )
    ]
    seat = s.worm_bushing_outer_mm + lay.fit
    for xw, yw in zip(lay.wheel_x, lay.worm_y, strict=True):
        cuts.append(cylinder(seat, z0 - 1, z1 + 1).translate(cq.Vector(xw, yw, 0)))
    cuts.extend(zero_marks(lay))
    for xs, ys in _screw_positions(lay):
        cuts.append(
            cylinder(s.lid_screw_clearance_mm, z0 - 1, z1 + 1).translate(cq.Vector(xs, ys, 0))
        )
    return single_solid(body.cut(*cuts).clean(), "lid")


def zero_mark_centres(lay: ActuatorLayout) -> list[tuple[float, float]]:
    """(x, y) of each knob's zero mark's centre on the lid's top, actuator frame: beside
    the knob's rim towards the wheels' axis (y = 0), where its pointer sits at the drive's
    zero (:func:`cad.drivetrain.placements` places the knob so). [mm]"""
    gap, length, _, _ = ZERO_MARK_MM
    out = []
    for xw, yw in zip(lay.wheel_x, lay.worm_y, strict=True):
        out.append((xw, yw - math.copysign(lay.spec.knob_mm / 2 + gap + length / 2, yw)))
    return out


def zero_marks(lay: ActuatorLayout) -> list[cq.Solid]:
    """The engraved zero marks' volumes (cut from the lid's top face), actuator frame."""
    _, length, width, depth = ZERO_MARK_MM
    top = lay.lid_z + lay.spec.lid_mm
    z = (top - depth, top + 1)
    return [
        box((x - width / 2, x + width / 2), (y - length / 2, y + length / 2), z)
        for x, y in zero_mark_centres(lay)
    ]


def lid_placement(lay: ActuatorLayout) -> cq.Location:
    """Print frame of the lid (top face on the bed, tongues up) -> actuator frame."""
    top = lay.lid_z + lay.spec.lid_mm
    return frame((0.0, 0.0, top), (0, 0, -1), (1, 0, 0))


def housing_parts(lay: ActuatorLayout) -> dict[str, tuple[cq.Solid, cq.Location]]:
    """Part name -> (solid in its print frame, print frame to actuator frame)."""
    lid_loc = lid_placement(lay)
    return {
        "housing": (housing(lay), cq.Location()),
        "lid": (lid(lay).moved(lid_loc.inverse), lid_loc),
    }
