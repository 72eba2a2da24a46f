"""The turning parts of the actuator: gear shafts, worms, bushings, clips, knobs, wire mount.

CAD works in millimetres: every length here is in mm, angles in degrees.

Every function returns a solid in its *print frame* (flat face on the bed at z = 0, +Z
up); :func:`placements` gives the :class:`cadquery.Location` that carries each print
frame into the actuator frame of :mod:`cad.layout`.
"""

from __future__ import annotations

import math

import cadquery as cq

from cad.gears import wheel_teeth, worm_thread
from cad.layout import CAP_MM, HEX_ENGAGEMENT_MM, WIRE_LEAD_IN_MM, ActuatorLayout
from cad.solids import (
    X_AXIS,
    Z_AXIS,
    annular_sector,
    box,
    cylinder,
    frame,
    hexagon_prism,
    radial_port,
    single_solid,
    tube,
)

COLLAR_MM = 2.0
KNOB_FLUTES = 18


def _front_u(lay: ActuatorLayout, x: float) -> float:
    """Front gear shaft: print-frame z of actuator x (z runs forward from the wheel)."""
    return x - (lay.wheel_x[0] - lay.drive.spec.wheel_face_width_mm / 2)


def _rear_u(lay: ActuatorLayout, x: float) -> float:
    """Rear gear shaft: print-frame z of actuator x (z runs backwards from the wheel)."""
    return (lay.wheel_x[1] + lay.drive.spec.wheel_face_width_mm / 2) - x


def _wheel_with_hub(lay: ActuatorLayout, hub_end: float) -> cq.Shape:
    b2 = lay.drive.spec.wheel_face_width_mm
    return wheel_teeth(lay.drive).fuse(cylinder(lay.spec.hub_mm, b2 - 0.01, hub_end))


def gear_shaft_front(lay: ActuatorLayout) -> cq.Solid:
    """Front hollow gear shaft: wheel, hub, journals through B1 and B0, clip groove, and
    a nose with the catheter's glued socket (:attr:`ActuatorLayout.catheter_socket_depth`
    deep, the catheter bottoming on the shoulder of the narrower bore behind it) and a
    radial glue port between the bulkheads."""
    s, ax = lay.spec, lay.spec.axial_clearance_mm
    b0, b1 = lay.bulkheads[0], lay.bulkheads[1]
    u = lambda x: _front_u(lay, x)  # noqa: E731
    hub_end = u(b1.lo - s.flange_mm - 2 * ax)
    clip = lay.clip_groove_x[0]
    nose = u(lay.nose_x)
    body = _wheel_with_hub(lay, hub_end).fuse(
        cylinder(s.shaft_journal_mm, hub_end - 0.01, u(clip.lo)),
        cylinder(lay.clip_groove_mm, u(clip.lo) - 0.01, u(clip.hi) + 0.01),
        cylinder(s.shaft_journal_mm, u(clip.hi), nose),
    )
    port_x = (b1.hi + b0.lo) / 2
    socket_depth = lay.catheter_socket_depth
    port_d = 1.5 * lay.process.wall_mm
    cuts = [
        cylinder(lay.front_passage, -1.0, nose - socket_depth + 0.01),
        cylinder(
            lay.catheter_socket_diameter + lay.hole_compensation, nose - socket_depth, nose + 1.0
        ),
        radial_port(port_d, u(port_x), s.shaft_journal_mm / 2, 90.0),
    ]
    return single_solid(body.cut(*cuts).clean(), "front gear shaft")


def gear_shaft_rear(lay: ActuatorLayout) -> cq.Solid:
    """Rear hollow gear shaft: wheel, hub, journals through B2 and B3, clip groove and the
    hex end that drives the wire mount; the wire passes through its bore."""
    s, ax = lay.spec, lay.spec.axial_clearance_mm
    b2 = lay.bulkheads[2]
    u = lambda x: _rear_u(lay, x)  # noqa: E731
    hub_end = u(b2.hi + s.flange_mm + 2 * ax)
    clip = lay.clip_groove_x[1]
    body = _wheel_with_hub(lay, hub_end).fuse(
        cylinder(s.shaft_journal_mm, hub_end - 0.01, u(clip.hi)),
        cylinder(lay.clip_groove_mm, u(clip.hi) - 0.01, u(clip.lo) + 0.01),
        cylinder(s.shaft_journal_mm, u(clip.lo), u(lay.hex.hi) + 0.01),
        hexagon_prism(s.hex_mm, u(lay.hex.hi), u(lay.hex.lo)),
    )
    bore = cylinder(s.wire_passage_mm, -1.0, u(lay.hex.lo) + 1.0)
    return single_solid(body.cut(bore).clean(), "rear gear shaft")


def worm_z0(lay: ActuatorLayout) -> float:
    """Actuator z of a worm's print-frame origin (bottom end of its lower journal). [mm]"""
    return lay.boss_top_z - lay.worm_bushing_length + 0.3


def worm(lay: ActuatorLayout) -> cq.Solid:
    """Worm with journals: lower journal in the base bushing, thread, upper journal with a
    collar under the lid bushing, and a D-flat end for the knob."""
    s, ax = lay.spec, lay.spec.axial_clearance_mm
    z0 = worm_z0(lay)
    t = lay.worm_thread_z
    collar_top = lay.lid_z - s.flange_mm - ax
    top = lay.knob_z.hi - 2.0 - 0.3
    dj = s.worm_journal_mm
    thread = worm_thread(lay.drive).translate(cq.Vector(0, 0, t.lo - z0))
    body = thread.fuse(
        cylinder(dj, 0.0, t.lo - z0 + 0.01),
        cylinder(dj, t.hi - z0 - 0.01, top - z0),
        cylinder(dj + 4.0, collar_top - COLLAR_MM - z0, collar_top - z0),
    )
    flat = box((dj / 2 - 0.5, dj), (-dj, dj), (lay.knob_z.lo - 0.5 - z0, top - z0 + 1.0))
    return single_solid(body.cut(flat).clean(), "worm")


def knob(lay: ActuatorLayout) -> cq.Solid:
    """Fluted knob with a D-bore for the worm's flat and a pointer groove on top.

    Printed top down; one knob turn turns the magnet by 360 / ratio degrees."""
    s = lay.spec
    h, r = s.knob_height_mm, s.knob_mm / 2
    body = cylinder(s.knob_mm, 0.0, h)
    body = cq.Workplane().add(body).faces(">Z").edges().chamfer(1.0).val()
    flutes = [
        cylinder(3.0, -1.0, h + 1.0).translate(
            cq.Vector(
                r * math.cos(2 * math.pi * k / KNOB_FLUTES),
                r * math.sin(2 * math.pi * k / KNOB_FLUTES),
                0,
            )
        )
        for k in range(KNOB_FLUTES)
    ]
    dj = s.worm_journal_mm + lay.fit
    flat_x = s.worm_journal_mm / 2 - 0.5 + lay.fit / 2  # the worm's flat + half the fit
    bore = cylinder(dj, -1.0, h - 2.0).cut(box((flat_x, dj), (-dj, dj), (-2, h)))
    pointer = box((3.0, r - 2.5), (-0.6, 0.6), (h - 0.8, h + 1.0))
    return single_solid(body.cut(*flutes, bore, pointer).clean(), "knob")


def shaft_bushing(lay: ActuatorLayout) -> cq.Solid:
    """Double-flanged spool bushing for a gear shaft; drops into a bulkhead's U-slot."""
    s = lay.spec
    fl, ls = s.flange_mm, lay.spool_length
    inner = s.shaft_journal_mm + lay.running
    body = cylinder(s.spool_flange_mm, 0.0, fl).fuse(
        cylinder(s.spool_outer_mm, fl - 0.01, fl + ls + 0.01),
        cylinder(s.spool_flange_mm, fl + ls, 2 * fl + ls),
    )
    return single_solid(body.cut(cylinder(inner, -1.0, 2 * fl + ls + 1.0)).clean(), "shaft bushing")


def worm_bushing(lay: ActuatorLayout) -> cq.Solid:
    """Flanged bushing for a worm journal (one in the base boss, one in the lid)."""
    s = lay.spec
    fl = s.flange_mm
    body = cylinder(s.worm_bushing_flange_mm, 0.0, fl).fuse(
        cylinder(s.worm_bushing_outer_mm, fl - 0.01, fl + lay.worm_bushing_length)
    )
    bore = cylinder(s.worm_journal_mm + lay.running, -1.0, fl + lay.worm_bushing_length + 1.0)
    return single_solid(body.cut(bore).clean(), "worm bushing")


def shaft_clip(lay: ActuatorLayout) -> cq.Solid:
    """Printed snap clip (C-ring) for the clip groove; holds a shaft axially.

    The opening is a sector 0.8 groove diameters wide at the bore: its faces are radial,
    so they meet the ring's outer and inner faces square (a parallel-sided slot left
    63 deg wedges at the outer corners)."""
    inner = lay.clip_groove_mm + lay.fit
    outer = lay.spec.shaft_journal_mm + 4.0
    ring = tube(outer, inner, 0.0, lay.clip_mm)
    half = math.degrees(math.asin(0.8 * lay.clip_groove_mm / inner))
    opening = annular_sector(inner - 1.0, outer + 1.0, -half, 2 * half, -1.0, lay.clip_mm + 1.0)
    return single_solid(ring.cut(opening).clean(), "shaft clip")


def wire_mount_depth(lay: ActuatorLayout) -> float:
    """Depth of the wire mount's hex bore: engagement plus travel. [mm]"""
    return HEX_ENGAGEMENT_MM + lay.spec.wire_mount_travel_mm


def wire_mount_front(lay: ActuatorLayout) -> float:
    """Actuator-frame x of the wire mount's front face at mid-travel. [mm]"""
    return lay.hex.lo + wire_mount_depth(lay) - lay.spec.wire_mount_travel_mm / 2


def wire_mount(lay: ActuatorLayout) -> cq.Solid:
    """Sliding wire mount: a hex bore on the rear shaft's hex (torque, axial travel), a set
    screw to lock it, and a cap with the wire bore and a glue port. Front face at z = 0."""
    s = lay.spec
    depth = wire_mount_depth(lay)
    length = depth + CAP_MM
    hex_bore = hexagon_prism(s.hex_mm + lay.fit, -1.0, depth)
    wire_bore = cylinder(lay.wire_seat_diameter + lay.hole_compensation, depth - 1.0, length + 1.0)
    lead_in = WIRE_LEAD_IN_MM
    countersink = cq.Solid.makeCone(lead_in, 0.0, lead_in, cq.Vector(0, 0, depth - 0.01), Z_AXIS)
    set_screw = cq.Solid.makeCylinder(
        s.set_screw_tap_mm / 2, s.wire_mount_mm, cq.Vector(0, 0, depth / 2), X_AXIS
    )
    glue = radial_port(1.5 * lay.process.wall_mm, depth + CAP_MM / 2, s.wire_mount_mm / 2, 90.0)
    body = cylinder(s.wire_mount_mm, 0.0, length)
    body = cq.Workplane().add(body).faces(">Z").edges().chamfer(1.0).val()
    return single_solid(
        body.cut(hex_bore, wire_bore, countersink, set_screw, glue).clean(), "wire mount"
    )


def placements(lay: ActuatorLayout) -> dict[str, tuple[str, cq.Location]]:
    """Instance name -> (part name, print frame to actuator frame) of the turning parts."""
    s, ax = lay.spec, lay.spec.axial_clearance_mm
    h = lay.shaft_height
    b2 = lay.drive.spec.wheel_face_width_mm
    (xf, xr), (yf, yr) = lay.wheel_x, lay.worm_y
    out: dict[str, tuple[str, cq.Location]] = {}
    # Wheels: local +X (tooth space at mid-face) towards their worm, local Z along the shaft.
    out["gear_shaft_front"] = (
        "gear_shaft_front",
        frame((xf - b2 / 2, 0, h), (1, 0, 0), (0, math.copysign(1, yf), 0)),
    )
    out["gear_shaft_rear"] = (
        "gear_shaft_rear",
        frame((xr + b2 / 2, 0, h), (-1, 0, 0), (0, math.copysign(1, yr), 0)),
    )
    z0 = worm_z0(lay)
    for tag, x, y in (("front", xf, yf), ("rear", xr, yr)):
        # Worm: local +X (thread at mid-thread) towards the wheel axis.
        out[f"worm_{tag}"] = ("worm", frame((x, y, z0), (0, 0, 1), (0, -math.copysign(1, y), 0)))
        out[f"knob_{tag}"] = (
            "knob",
            frame((x, y, lay.knob_z.lo), (0, 0, 1), (0, -math.copysign(1, y), 0)),
        )
        out[f"worm_bushing_{tag}_base"] = (
            "worm_bushing",
            frame((x, y, lay.boss_top_z + s.flange_mm), (0, 0, -1), (1, 0, 0)),
        )
        out[f"worm_bushing_{tag}_lid"] = (
            "worm_bushing",
            frame((x, y, lay.lid_z - s.flange_mm), (0, 0, 1), (1, 0, 0)),
        )
    for k, b in enumerate(lay.bulkheads):
        start = b.lo - ax - s.flange_mm
        out[f"shaft_bushing_b{k}"] = ("shaft_bushing", frame((start, 0, h), (1, 0, 0), (0, 1, 0)))
    cf, cr = lay.clip_groove_x
    out["shaft_clip_front"] = ("shaft_clip", frame((cf.lo, 0, h), (1, 0, 0), (0, 0, 1)))
    out["shaft_clip_rear"] = ("shaft_clip", frame((cr.hi, 0, h), (-1, 0, 0), (0, 0, 1)))
    # Wire mount at mid-travel: front face `travel/2` behind the front end of its range.
    front_face = wire_mount_front(lay)
    out["wire_mount"] = ("wire_mount", frame((front_face, 0, h), (-1, 0, 0), (0, 1, 0)))
    return out
