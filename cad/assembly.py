"""The whole robot as one assembly: actuator, catheter and wire, mounting pieces, rings.

CAD works in millimetres. The assembly frame is the design's base frame in mm: origin at
the clamped base (the tip of the front gear shaft's nose, where the catheter leaves the
actuator), +x along the undeformed robot, z up. The proximal ring's centre sits at
x = free length, the distal ring's one centre spacing further (``docs/formats.md``).
The pose shown: theta2 = 0 and theta1 in the middle of the rotation limits.

Printed parts carry their print frame; reference bodies (ring magnets, catheter, wire)
are bought parts, shown and checked for interference but not exported for printing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cadquery as cq
import numpy as np

from cad.actuator import Actuator
from cad.mounting import MountingDims, MountingPieces
from cad.process import mm
from cad.solids import cylinder, frame, tube
from cad.stock import cuts
from design.geometry import rest_position, ring_centres
from design.records import Design

Colour = tuple[float, float, float]

COLOURS: dict[str, Colour] = {
    "housing": (0.80, 0.82, 0.86),
    "lid": (0.80, 0.82, 0.86),
    "gear_shaft_front": (0.95, 0.60, 0.15),
    "gear_shaft_rear": (0.20, 0.55, 0.85),
    "worm": (0.35, 0.75, 0.45),
    "knob": (0.25, 0.25, 0.28),
    "shaft_bushing": (0.78, 0.62, 0.30),
    "worm_bushing": (0.78, 0.62, 0.30),
    "shaft_clip": (0.55, 0.20, 0.60),
    "wire_mount": (0.85, 0.30, 0.35),
    "mounting_piece_proximal": (0.95, 0.60, 0.15),
    "mounting_piece_distal": (0.20, 0.55, 0.85),
    "ring_magnet": (0.62, 0.64, 0.68),
    "catheter": (0.96, 0.96, 0.92),
    "wire": (0.55, 0.55, 0.58),
}

DESCRIPTIONS: dict[str, str] = {
    "housing": "base, side walls, bulkheads with U-slot bushing seats, worm bosses",
    "lid": "lid with tongues holding the shaft bushings and the upper worm bushings, zero marks",
    "gear_shaft_front": "worm wheel + hollow shaft; catheter bonded in its nose (theta2)",
    "gear_shaft_rear": "worm wheel + hollow shaft with hex end for the wire mount (theta1)",
    "worm": "single-start ZI worm with journals, collar and D-flat",
    "knob": "fluted knob with pointer, on the worm's D-flat",
    "shaft_bushing": "double-flanged spool bushing for a gear shaft",
    "worm_bushing": "flanged bushing for a worm journal",
    "shaft_clip": "snap clip holding a gear shaft axially",
    "wire_mount": "sliding wire mount on the hex, set screw M3, wire bonded in the cap",
    "mounting_piece_proximal": "tip piece on the catheter: ring seat, sleeve, helical groove",
    "mounting_piece_distal": "tip piece on the wire: ring seat, journal, key, helical groove",
    "ring_magnet": "diametrically magnetised ring magnet (bought)",
    "catheter": "outer catheter (bought, cut to length), glued in the front shaft's nose "
    "and the proximal tip piece; turns the proximal ring",
    "wire": "inner wire (bought, cut to length), glued in the wire mount's cap and the "
    "distal tip piece; turns the distal ring",
}


@dataclass(frozen=True)
class Part:
    """One distinct part.

    name : Part name (file names use it).
    solid : The part in its print frame (reference bodies: in their own frame). [mm]
    quantity : How many instances the assembly uses.
    printed : True for parts to print; False for bought reference bodies.
    colour : RGB in [0, 1] for renders and the STEP file.
    description : One line for the parts table.
    """

    name: str
    solid: cq.Solid
    quantity: int
    printed: bool
    colour: Colour
    description: str


@dataclass(frozen=True)
class Instance:
    """One placed copy of a part.

    name : Unique instance name (the STEP assembly's node names).
    part : Name of its :class:`Part`.
    location : Part frame -> assembly (base) frame. [mm]
    explode : Offset of this instance in the exploded view, base frame. [mm]
    group : ``"actuator"`` or ``"tip"`` (for close-up views).
    """

    name: str
    part: str
    location: cq.Location
    explode: tuple[float, float, float]
    group: str


@dataclass(frozen=True)
class RobotAssembly:
    """All parts and instances of the robot, in the base frame (mm)."""

    parts: dict[str, Part]
    instances: list[Instance]
    actuator: Actuator
    mounting: MountingPieces
    theta1_deg: float
    theta2_deg: float

    def placed(self, instance: Instance, exploded: bool = False) -> cq.Solid:
        """The instance's solid in the base frame (optionally moved out). [mm]"""
        solid = self.parts[instance.part].solid.moved(instance.location)
        if exploded:
            solid = solid.translate(cq.Vector(*instance.explode))
        return solid

    def to_cq(self, exploded: bool = False) -> cq.Assembly:
        """A :class:`cadquery.Assembly` with one named, coloured node per instance, each
        its own shape (STEP: one product per instance, named as it)."""
        assy = cq.Assembly(name="ringpair_robot")
        for inst in self.instances:
            loc = inst.location
            if exploded:
                loc = cq.Location(cq.Vector(*inst.explode)) * loc
            part = self.parts[inst.part]
            rgb = part.colour
            # A copy for a repeated part: each instance its own STEP product, named as
            # the instance (a shared solid makes one product, named after the first).
            solid = part.solid.copy() if part.quantity > 1 else part.solid
            assy.add(
                solid,
                name=inst.name,
                loc=loc,
                color=cq.Color(rgb[0], rgb[1], rgb[2], 1.0),
            )
        return assy


def _actuator_explode(name: str) -> tuple[float, float, float]:
    """Exploded-view offset of an actuator instance, by kind. [mm]"""
    table = {
        "lid": (0.0, 0.0, 70.0),
        "knob": (0.0, 0.0, 125.0),
        "worm_bushing_front_lid": (0.0, 0.0, 100.0),
        "worm_bushing_rear_lid": (0.0, 0.0, 100.0),
        "worm": (0.0, 0.0, 50.0),
        "gear_shaft": (0.0, 0.0, 35.0),
        "shaft_bushing": (0.0, 0.0, 35.0),
        "shaft_clip_front": (12.0, 0.0, 35.0),
        "shaft_clip_rear": (-12.0, 0.0, 35.0),
        "wire_mount": (-30.0, 0.0, 35.0),
        "worm_bushing": (0.0, 0.0, 25.0),
    }
    for key in sorted(table, key=len, reverse=True):
        if name.startswith(key):
            return table[key]
    return (0.0, 0.0, 0.0)


def ring_magnet(dims: MountingDims) -> cq.Solid:
    """A ring magnet in its own frame: on +Z from its proximal face, z = 0. [mm]"""
    return tube(dims.magnet_outer_diameter, dims.magnet_inner_diameter, 0.0, dims.magnet_length)


def tip_locations(
    design: Design, dims: MountingDims, theta1_deg: float, theta2_deg: float
) -> dict[str, cq.Location]:
    """Where the tip pieces and rings sit in the base frame (pieces in their own frames).

    The ring centres are the model's (:func:`design.geometry.ring_centres` on the straight
    robot: the proximal ring at the rest tip, the distal one a centre spacing further).
    Each ring lies at the bottom of its piece's pocket (the proximal ring under the
    shoulder, the distal ring a pocket depth, the centre spacing, into its piece), so the
    distal piece's journal end bears on the shoulder and the rings' facing faces are the
    gap apart. A piece's local +X (the ring's north at angle 0) is turned by its angle from
    +y towards +z about +x. [mm], [deg]
    """
    d = dims
    tangent = np.array([1.0, 0.0, 0.0])
    proximal, distal = (
        mm(centre)
        for centre in ring_centres(
            rest_position(design.robot.free_length), tangent, design.tip.spacing
        )
    )

    def about_x(angle_deg: float, centre: np.ndarray, offset: float) -> cq.Location:
        """The frame at ``offset`` along the tangent from a ring centre. [mm]"""
        a = math.radians(angle_deg)
        origin = centre + offset * tangent
        return frame(tuple(origin), tuple(tangent), (0, math.cos(a), math.sin(a)))

    half = d.magnet_length / 2
    return {
        "mounting_piece_proximal": about_x(theta2_deg, proximal, half - d.shoulder_z),
        "mounting_piece_distal": about_x(theta1_deg, distal, half - d.pocket_depth_distal),
        "ring_magnet_proximal": about_x(theta2_deg, proximal, -half),
        "ring_magnet_distal": about_x(theta1_deg, distal, -half),
    }


def distal_print_flip(dims: MountingDims) -> cq.Location:
    """Distal piece frame -> its print frame: turned over, far face on the bed. [mm]"""
    return frame((0.0, 0.0, dims.distal_length), (0, 0, -1), (1, 0, 0))


def build_assembly(
    design: Design,
    actuator: Actuator,
    mounting: MountingPieces,
    theta1_deg: float | None = None,
    theta2_deg: float = 0.0,
) -> RobotAssembly:
    """Put actuator, catheter, wire, mounting pieces and rings into the base frame.

    Parameters
    ----------
    design : The robot (SI).
    actuator, mounting : Built parts (mm).
    theta1_deg : Distal ring angle; default: middle of the stops' range (relative to
        theta2). [deg]
    theta2_deg : Proximal ring angle. [deg]
    """
    lay = actuator.layout
    d = mounting.dims
    if theta1_deg is None:
        theta1_deg = theta2_deg + d.stop_angle_deg / 2

    to_base = cq.Location(cq.Vector(-lay.nose_x, 0.0, -lay.shaft_height))
    parts: dict[str, Part] = {}
    instances: list[Instance] = []
    counts: dict[str, int] = {}
    for inst_name, (part, loc) in actuator.instances.items():
        counts[part] = counts.get(part, 0) + 1
        instances.append(
            Instance(inst_name, part, to_base * loc, _actuator_explode(inst_name), "actuator")
        )
    for name, solid in actuator.parts.items():
        parts[name] = Part(name, solid, counts[name], True, COLOURS[name], DESCRIPTIONS[name])

    tip = tip_locations(design, d, theta1_deg, theta2_deg)
    flip = distal_print_flip(d)
    parts["mounting_piece_proximal"] = Part(
        "mounting_piece_proximal",
        mounting.proximal,
        1,
        True,
        COLOURS["mounting_piece_proximal"],
        DESCRIPTIONS["mounting_piece_proximal"],
    )
    # The distal piece prints standing on its far face (journal up): no overhang.
    parts["mounting_piece_distal"] = Part(
        "mounting_piece_distal",
        mounting.distal.moved(flip),
        1,
        True,
        COLOURS["mounting_piece_distal"],
        DESCRIPTIONS["mounting_piece_distal"],
    )
    parts["ring_magnet"] = Part(
        "ring_magnet", ring_magnet(d), 2, False, COLOURS["ring_magnet"], DESCRIPTIONS["ring_magnet"]
    )
    explode = {
        "mounting_piece_proximal": (-4.0, 0.0, 0.0),
        "mounting_piece_distal": (12.0, 0.0, 0.0),
        "ring_magnet_proximal": (2.0, 0.0, 0.0),
        "ring_magnet_distal": (6.0, 0.0, 0.0),
    }
    for name, loc in tip.items():
        part = "ring_magnet" if name.startswith("ring") else name
        if name == "mounting_piece_distal":
            loc = loc * flip.inverse
        instances.append(Instance(name, part, loc, explode[name], "tip"))
    tubes = cuts(design, lay, d)
    # Catheter: from the front shaft's socket floor to the proximal piece's socket floor.
    cath, c = design.robot.catheter, tubes["catheter"]
    parts["catheter"] = Part(
        "catheter",
        tube(mm(cath.outer_diameter), mm(cath.inner_diameter), 0.0, c.length),
        1,
        False,
        COLOURS["catheter"],
        DESCRIPTIONS["catheter"],
    )
    instances.append(
        Instance(
            "catheter",
            "catheter",
            frame((c.start, 0, 0), (1, 0, 0), (0, 1, 0)),
            (-4.0, 0.0, 0.0),
            "tip",
        )
    )
    # Wire: flush with the wire mount's back face and with the distal piece's far face.
    wire, w = design.robot.wire, tubes["wire"]
    parts["wire"] = Part(
        "wire",
        cylinder(mm(wire.outer_diameter), 0.0, w.length)
        if wire.inner_diameter == 0
        else tube(mm(wire.outer_diameter), mm(wire.inner_diameter), 0.0, w.length),
        1,
        False,
        COLOURS["wire"],
        DESCRIPTIONS["wire"],
    )
    wire_loc = frame((w.start, 0.0, 0.0), (1, 0, 0), (0, 1, 0))
    instances.append(Instance("wire", "wire", wire_loc, (0.0, 0.0, 0.0), "tip"))
    return RobotAssembly(parts, instances, actuator, mounting, theta1_deg, theta2_deg)
