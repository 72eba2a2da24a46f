"""Dimensions and positions of the worm-gear actuator, as numbers (no solids).

CAD works in millimetres: every length here is in mm.

Actuator frame: x along the common shaft axis pointing to the robot (front), z up, base
plate underside at z = 0, shaft axis at height ``shaft_height``; right-handed. Front to
back along x::

    nose (catheter bonded) | front wall B0 | B1 | front wheel + worm (+y side)
    | rear wheel + worm (-y side) | B2 | rear wall B3 | hex | sliding wire mount

Each hollow gear shaft runs in two spool bushings (double-flanged) seated in U-slots of
two bulkheads and held down by tongues of the lid; the wheel is overhung on the inner end
of its shaft, so it prints wheel-face down without supports. Each worm stands vertically
beside its wheel, in a flanged bushing in a boss on the base and one in the lid, with a
knob on top. The two worms are on opposite sides so the wheels can sit close together.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from cad.errors import require
from cad.gears import WormDrive, WormDriveSpec
from cad.process import CadProcess, mm
from design.records import Design

HEX_ENGAGEMENT_MM = 15.0
"""Length of the rear shaft's hex the wire mount keeps anywhere in its travel. [mm]"""
CAP_MM = 6.0
"""Length of the wire mount's cap, which holds the wire's glued seat. [mm]"""
WIRE_LEAD_IN_MM = 1.5
"""Depth (and radius: a 90 deg cone) of the cone at the cap's inner face that leads the
wire into its seat. [mm]"""


@dataclass(frozen=True)
class ActuatorSpec:
    """Designer's choices for the actuator (mm).

    drive : The worm drive (both drives are equal).
    shaft_journal_mm : Diameter of the gear shafts where they run in the bushings. [mm]
    hub_mm : Diameter of the wheel hub between wheel and first bushing. [mm]
    spool_outer_mm, spool_flange_mm, flange_mm : Shaft bushing sleeve and flange
        diameters, and flange thickness of all bushings. [mm]
    worm_journal_mm, worm_bushing_outer_mm, worm_bushing_flange_mm : Worm bearing. [mm]
    bulkhead_mm, wall_mm, base_mm, lid_mm : Housing plate thicknesses. [mm]
    bearing_span_mm : Clear gap between the two bulkheads carrying one shaft. [mm]
    gear_clearance_mm : Between a worm and the nearest wheel, bulkhead or wall. [mm]
    axial_clearance_mm : End play at hubs, collars and clips. [mm]
    catheter_socket_mm : Least depth of the catheter's glued socket in the front shaft's
        nose (it reaches past the glue port at least). [mm]
    wire_passage_mm : Bore of the rear shaft for the wire; the front shaft's bore behind
        the catheter socket is the catheter's lumen (at most this), so the catheter
        bottoms on a shoulder. [mm]
    hex_mm : Across-flats of the rear shaft's hex end that drives the wire mount. [mm]
    wire_mount_travel_mm : Axial adjustment range of the wire mount. [mm]
    wire_mount_mm : Outer diameter of the wire mount. [mm]
    set_screw_tap_mm : Tap drill of the set screw that locks the wire mount (M3). [mm]
    lid_screw_clearance_mm, lid_screw_tap_mm : Lid screws (M3). [mm]
    knob_mm, knob_height_mm : Knob size. [mm]
    """

    drive: WormDriveSpec = field(default_factory=WormDriveSpec)
    shaft_journal_mm: float = 8.0
    hub_mm: float = 12.0
    spool_outer_mm: float = 12.0
    spool_flange_mm: float = 16.0
    flange_mm: float = 1.5
    worm_journal_mm: float = 6.0
    worm_bushing_outer_mm: float = 10.0
    worm_bushing_flange_mm: float = 13.0
    bulkhead_mm: float = 5.0
    wall_mm: float = 3.0
    base_mm: float = 4.0
    lid_mm: float = 4.0
    bearing_span_mm: float = 10.0
    gear_clearance_mm: float = 1.0
    axial_clearance_mm: float = 0.1
    catheter_socket_mm: float = 15.0
    wire_passage_mm: float = 1.5
    hex_mm: float = 6.0
    wire_mount_travel_mm: float = 10.0
    wire_mount_mm: float = 16.0
    set_screw_tap_mm: float = 2.5
    lid_screw_clearance_mm: float = 3.4
    lid_screw_tap_mm: float = 2.5
    knob_mm: float = 24.0
    knob_height_mm: float = 12.0


@dataclass(frozen=True)
class Span:
    """An interval along an axis, ``lo < hi``. [mm]"""

    lo: float
    hi: float

    @property
    def mid(self) -> float:
        return (self.lo + self.hi) / 2

    @property
    def length(self) -> float:
        return self.hi - self.lo


@dataclass(frozen=True)
class ActuatorLayout:
    """Every derived dimension and position of the actuator (mm, actuator frame)."""

    spec: ActuatorSpec
    drive: WormDrive
    process: CadProcess
    catheter_outer_mm: float
    catheter_inner_mm: float
    wire_mm: float
    shaft_height: float
    wheel_x: tuple[float, float]
    worm_y: tuple[float, float]
    bulkheads: tuple[Span, Span, Span, Span]
    nose_x: float
    hex: Span
    clip_groove_x: tuple[Span, Span]
    width: float
    lid_z: float
    boss_top_z: float
    worm_thread_z: Span
    knob_z: Span
    hole_compensation: float = 0.0
    """Added to the drawn diameter of the glued seats (catheter socket, wire seat) where
    the design asks for hole compensation: the process's hole shrink. [mm]"""

    # --- derived sizes -------------------------------------------------------------
    @property
    def catheter_socket_diameter(self) -> float:
        """The catheter's glued socket in the front shaft's nose: catheter + fit. [mm]"""
        return self.catheter_outer_mm + self.fit

    @property
    def catheter_socket_depth(self) -> float:
        """Depth of that socket: the spec's least, and past the glue port (between the
        front bulkheads) by 2 mm, so the port feeds the socket. [mm]"""
        port = (self.bulkheads[1].hi + self.bulkheads[0].lo) / 2
        return max(self.spec.catheter_socket_mm, self.nose_x - port + 2.0)

    @property
    def front_passage(self) -> float:
        """The front shaft's bore behind the catheter socket: the catheter's lumen (at most
        the spec's wire passage), at least the wire plus running clearance; smaller than
        the catheter, so the catheter bottoms on the shoulder. [mm]"""
        lumen = min(self.catheter_inner_mm, self.spec.wire_passage_mm)
        return max(lumen, self.wire_mm + self.running)

    @property
    def wire_seat_diameter(self) -> float:
        """The wire's glued seat through the wire mount's cap: wire + fit. [mm]"""
        return self.wire_mm + self.fit

    @property
    def wire_seat_depth(self) -> float:
        """Glued length of the wire in the cap: the cap's length less the lead-in cone down
        to the seat's bore (the wire is cut flush with the cap's back face). [mm]"""
        return CAP_MM - (WIRE_LEAD_IN_MM - self.wire_seat_diameter / 2)

    @property
    def fit(self) -> float:
        """Diametral allowance of a seat for a pushed-in part. [mm]"""
        return self.process.fit_allowance_mm

    @property
    def running(self) -> float:
        """Diametral running clearance. [mm]"""
        return self.process.running_clearance_mm

    @property
    def spool_length(self) -> float:
        """Sleeve length of a shaft bushing between its flanges. [mm]"""
        return self.spec.bulkhead_mm + 2 * self.spec.axial_clearance_mm

    @property
    def worm_bushing_length(self) -> float:
        """Sleeve length of a worm bushing below its flange. [mm]"""
        return self.spec.lid_mm

    @property
    def clip_groove_mm(self) -> float:
        """Diameter of the shafts at the clip groove. [mm]"""
        return self.spec.shaft_journal_mm - 1.2

    @property
    def clip_mm(self) -> float:
        """Thickness of a shaft clip. [mm]"""
        return 1.0

    @property
    def length(self) -> float:
        """Housing length along x. [mm]"""
        return self.bulkheads[0].hi - self.bulkheads[3].lo

    @property
    def height(self) -> float:
        """Housing height to the top of the lid. [mm]"""
        return self.lid_z + self.spec.lid_mm

    def shaft_span(self, which: int) -> Span:
        """x extent of gear shaft 0 (front) or 1 (rear). [mm]"""
        b2 = self.drive.spec.wheel_face_width_mm
        if which == 0:
            return Span(self.wheel_x[0] - b2 / 2, self.nose_x)
        return Span(self.hex.lo, self.wheel_x[1] + b2 / 2)


def actuator_layout(
    design: Design, process: CadProcess, spec: ActuatorSpec | None = None
) -> ActuatorLayout:
    """Place every part of the actuator for ``design`` and ``process``.

    Raises :class:`~cad.errors.CadError` naming the quantity for impossible geometry.
    """
    s = spec or ActuatorSpec()
    drive = WormDrive(s.drive, backlash_mm=process.backlash_mm)
    catheter, wire = mm(design.robot.catheter.outer_diameter), mm(design.robot.wire.outer_diameter)
    c, ax = s.gear_clearance_mm, s.axial_clearance_mm
    b2 = s.drive.wheel_face_width_mm
    ra1, ra2 = drive.worm_tip_diameter_mm / 2, drive.wheel_tip_diameter_mm / 2
    a = drive.centre_distance_mm

    require(
        catheter + process.fit_allowance_mm + 2 * process.wall_mm <= s.shaft_journal_mm,
        "actuator: catheter socket in the front shaft (catheter + fit + two walls)",
        f"at most the shaft journal diameter ({s.shaft_journal_mm:g} mm)",
        catheter + process.fit_allowance_mm + 2 * process.wall_mm,
    )
    require(
        s.wire_passage_mm > wire + process.running_clearance_mm,
        "actuator: wire passage diameter",
        f"larger than the wire plus running clearance ({wire + process.running_clearance_mm:g} mm)",
        s.wire_passage_mm,
    )
    passage = max(
        min(mm(design.robot.catheter.inner_diameter), s.wire_passage_mm),
        wire + process.running_clearance_mm,
    )
    require(
        passage < catheter,
        "actuator: front shaft bore behind the catheter socket (catheter lumen, at least the "
        "wire plus running clearance)",
        f"smaller than the catheter ({catheter:g} mm) so the catheter bottoms on a shoulder",
        passage,
    )
    require(
        s.hex_mm / math.cos(math.pi / 6) < s.shaft_journal_mm,
        "actuator: hex across corners",
        f"below the shaft journal diameter ({s.shaft_journal_mm:g} mm) so bushings pass",
        s.hex_mm / math.cos(math.pi / 6),
    )
    hex_min = s.wire_passage_mm + 2 * process.wall_mm
    require(
        hex_min <= s.hex_mm,
        "actuator: hex across flats",
        f"at least the wire passage plus two walls ({hex_min:g} mm)",
        s.hex_mm,
    )
    require(
        s.worm_journal_mm < drive.worm_root_diameter_mm,
        "actuator: worm journal diameter",
        f"below the worm root diameter ({drive.worm_root_diameter_mm:.3g} mm)",
        s.worm_journal_mm,
    )
    require(
        s.shaft_journal_mm + process.running_clearance_mm + 2 * process.wall_mm <= s.spool_outer_mm,
        "actuator: shaft bushing outer diameter",
        "at least the journal plus running clearance plus two walls",
        s.spool_outer_mm,
    )
    require(
        s.hub_mm < drive.wheel_root_diameter_mm - 2 * process.wall_mm,
        "actuator: wheel hub diameter",
        f"below the wheel root diameter less two walls "
        f"({drive.wheel_root_diameter_mm - 2 * process.wall_mm:.3g} mm)",
        s.hub_mm,
    )

    wheel_front = 0.0
    wheel_rear = wheel_front - (b2 / 2 + ra1 + c)
    reach = max(ra1 + c, b2 / 2 + s.flange_mm + 2.0)
    b1 = Span(wheel_front + reach, wheel_front + reach + s.bulkhead_mm)
    b0 = Span(b1.hi + s.bearing_span_mm, b1.hi + s.bearing_span_mm + s.bulkhead_mm)
    b2_ = Span(wheel_rear - reach - s.bulkhead_mm, wheel_rear - reach)
    b3 = Span(b2_.lo - s.bearing_span_mm - s.bulkhead_mm, b2_.lo - s.bearing_span_mm)
    clip_front = Span(b0.hi + s.flange_mm + 2 * ax, b0.hi + s.flange_mm + 2 * ax + 1.2)
    clip_rear = Span(b3.lo - s.flange_mm - 2 * ax - 1.2, b3.lo - s.flange_mm - 2 * ax)
    nose_x = clip_front.hi + 3.0
    hex_hi = clip_rear.lo - process.wall_mm  # the groove's outer collar: a structural wall
    # The mount keeps HEX_ENGAGEMENT_MM on the hex anywhere in its travel.
    hex_span = Span(hex_hi - s.wire_mount_travel_mm - HEX_ENGAGEMENT_MM, hex_hi)

    shaft_height = s.base_mm + ra2 + 2 * c + 2.0
    thread = drive.worm_thread_length_mm
    worm_thread = Span(shaft_height - thread / 2, shaft_height + thread / 2)
    boss_top = worm_thread.lo - s.flange_mm - ax
    require(
        boss_top - s.base_mm >= 0.0,
        "actuator: room under the worm for its bushing",
        "non-negative (raise the shaft or shorten the worm)",
        boss_top - s.base_mm,
    )
    lid_z = max(shaft_height + ra2 + 2 * c, worm_thread.hi + s.flange_mm + 2.0)
    width = 2 * (a + ra1 + c + s.wall_mm)
    knob = Span(
        lid_z + s.lid_mm + s.flange_mm + 1.0,
        lid_z + s.lid_mm + s.flange_mm + 1.0 + s.knob_height_mm,
    )
    return ActuatorLayout(
        spec=s,
        drive=drive,
        process=process,
        catheter_outer_mm=catheter,
        catheter_inner_mm=mm(design.robot.catheter.inner_diameter),
        wire_mm=wire,
        shaft_height=shaft_height,
        wheel_x=(wheel_front, wheel_rear),
        worm_y=(a, -a),
        bulkheads=(b0, b1, b2_, b3),
        nose_x=nose_x,
        hex=hex_span,
        clip_groove_x=(clip_front, clip_rear),
        width=width,
        lid_z=lid_z,
        boss_top_z=boss_top,
        worm_thread_z=worm_thread,
        knob_z=knob,
        hole_compensation=(process.hole_shrink_mm if design.tip.mounting.compensate_holes else 0.0),
    )
