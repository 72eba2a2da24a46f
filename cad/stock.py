"""The bought tubes and wire cut to length, where each end is glued, and the fasteners.

CAD works in millimetres: every length here is in mm. Base frame of :mod:`cad.assembly`
(origin at the front gear shaft's nose, where the flexible robot starts; +x towards the
tip).

Catheter: its proximal end bottoms in the front gear shaft's nose socket
(:attr:`cad.layout.ActuatorLayout.catheter_socket_depth` deep), its distal end in the
proximal tip piece's socket (``socket_depth``); in between runs the free length less the
rigid tip segment's offset (the flexible rod, :mod:`design.mounting`). Wire: its proximal
end is cut flush with the back face of the wire mount's cap (glued over the cap's length
less its lead-in cone, the mount at mid-travel), its distal end flush with the distal tip
piece's far face (glued from the ring pocket's floor to that face).
"""

from __future__ import annotations

from dataclasses import dataclass

from cad.drivetrain import wire_mount_depth, wire_mount_front
from cad.layout import CAP_MM, ActuatorLayout
from cad.mounting import MountingDims
from cad.process import mm
from design.records import Design


@dataclass(frozen=True)
class Seat:
    """Where one end of a tube or wire is glued.

    holder : The instance that holds it (a name of :class:`cad.assembly.RobotAssembly`'s
        instances).
    engagement : Glued length of the tube inside the holder. [mm]
    bore : Diameter of the holder's seat (tube + fit). [mm]
    floored : True where the tube's end bears on the seat's floor (a shoulder). [-]
    """

    holder: str
    engagement: float
    bore: float
    floored: bool


@dataclass(frozen=True)
class Cut:
    """A tube or wire cut from stock.

    name : The part (``"catheter"`` or ``"wire"``).
    start, end : x of its proximal and distal ends, base frame. [mm]
    seats : The seat of its proximal end, then of its distal end.
    """

    name: str
    start: float
    end: float
    seats: tuple[Seat, Seat]

    @property
    def length(self) -> float:
        """Cut length. [mm]"""
        return self.end - self.start


def cuts(design: Design, lay: ActuatorLayout, d: MountingDims) -> dict[str, Cut]:
    """The catheter and the wire, cut to length, with their seats (module docstring). [mm]"""
    free = mm(design.robot.free_length)
    rod_end = free - (d.shoulder_z - d.magnet_length / 2)  # proximal piece's proximal face
    catheter = Cut(
        "catheter",
        -lay.catheter_socket_depth,
        rod_end + d.socket_depth,
        (
            Seat("gear_shaft_front", lay.catheter_socket_depth, lay.catheter_socket_diameter, True),
            Seat("mounting_piece_proximal", d.socket_depth, d.socket_diameter, True),
        ),
    )
    # The distal piece's frame starts a pocket depth short of the distal ring's face.
    distal_origin = free + mm(design.tip.spacing) + d.magnet_length / 2 - d.pocket_depth_distal
    mount_front = wire_mount_front(lay) - lay.nose_x
    wire = Cut(
        "wire",
        mount_front - wire_mount_depth(lay) - CAP_MM,
        distal_origin + d.distal_length,
        (
            Seat("wire_mount", lay.wire_seat_depth, lay.wire_seat_diameter, False),
            Seat(
                "mounting_piece_distal",
                d.distal_length - d.pocket_depth_distal,
                d.wire_bore,
                False,
            ),
        ),
    )
    return {"catheter": catheter, "wire": wire}


@dataclass(frozen=True)
class Fastener:
    """A bought screw.

    name : Part name in the lists.
    standard : Catalogue designation (ISO standard, size, length).
    quantity : How many the robot uses.
    diameter, length : Nominal thread diameter and length. [mm]
    head : Head diameter (0 for a set screw). [mm]
    where : What it holds.
    """

    name: str
    standard: str
    quantity: int
    diameter: float
    length: float
    head: float
    where: str


STANDARD_LENGTHS_MM = (3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0)
"""Catalogue lengths of M3 screws (ISO 4762, ISO 4026). [mm]"""


def fasteners(lay: ActuatorLayout) -> list[Fastener]:
    """The actuator's screws: four lid screws through the lid into the end bulkheads'
    tapped holes (the longest catalogue length that stays in the tap hole), and the wire
    mount's set screw (the longest that sits below the mount's surface on the hex). [mm]"""
    from cad.housing import SCREW_DEPTH_MM

    s = lay.spec
    lid = max(x for x in STANDARD_LENGTHS_MM if x <= s.lid_mm + SCREW_DEPTH_MM - 0.5)
    wall = (s.wire_mount_mm - s.hex_mm) / 2  # hex flat to the mount's surface
    grub = max(x for x in STANDARD_LENGTHS_MM if x <= wall)
    return [
        Fastener(
            "lid_screw",
            f"ISO 4762 M3 x {lid:g} socket head cap screw",
            4,
            3.0,
            lid,
            5.5,
            f"lid to the end bulkheads (self-taps the {s.lid_screw_tap_mm:g} mm holes)",
        ),
        Fastener(
            "set_screw",
            f"ISO 4026 M3 x {grub:g} set screw, flat point",
            1,
            3.0,
            grub,
            0.0,
            f"locks the wire mount on the hex (self-taps the {s.set_screw_tap_mm:g} mm hole)",
        ),
    ]
