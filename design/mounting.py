"""The tip as built: the two printed mounting pieces, from one geometry.

The CAD (:mod:`cad.mounting`) builds its solids from :func:`tip_geometry`; the model
(:mod:`design.model`, effect ``printed_tip``) takes from it each piece's mass and centre of
mass, the rigid tip segment and where the rings sit on it; studies bound its outer
diameter. Every function takes numbers or CasADi expressions alike. SI units are used for
all inputs and outputs.

Pieces (each in its own frame: +z distal, z = 0 at its proximal face; radial sizes are
diameters)::

    proximal (on the catheter, turns the proximal ring, theta2):
        catheter socket with a glue reservoir and a radial fill port | wire passage (the
        catheter's lumen, or the design's narrower passage; one wall long) | ring pocket,
        ring flush with the shoulder | bearing sleeve, its end cut by the stop notch
    distal (on the wire, turns the distal ring, theta1):
        journal (runs in the sleeve, its end face bears on the shoulder) holding the ring
        pocket, ring recessed by the gap | stop key at the journal's root, riding in the
        notch | body with the wire bore, a glue chamber and a radial fill port

Radially, from the ring out: seat (ring + fit allowance), journal wall, running clearance,
sleeve wall, groove depth. So the outer diameter is

    D = max(D_m + fit + 2 w + c, catheter socket + 2 relief, wire chamber + 2 relief)
        + 2 (w + groove depth),

with the wall ``w``, the running clearance ``c`` and the fit allowance of the design's
``tip.mounting`` (by default its process's, :data:`design.process.PROCESSES`: the wall
:data:`~design.process.WALL_FACTOR` times the process's thinnest reliable wall).

The rigid tip segment runs from the proximal piece's proximal face (where the catheter
enters its socket: the flexible rod ends there) to the distal piece's far face. The
proximal ring's centre, the robot's tracked point (``robot.free_length`` ends there, as
``docs/formats.md`` says), lies :attr:`TipGeometry.rigid_offset` along it.

Rotational stops (the paper's "relative rotational limits"): the key (angular width
:data:`KEY_ANGLE`) rides in the notch, which spans the stop angle plus the key, so the
relative rotation theta1 - theta2 of the rings is held within [0, stop angle]: 0 is
parallel, 180 deg antiparallel.

Tracking (the paper's helical groove): a single-start groove of pitch p on a piece shows,
seen from the side, a notch whose axial position moves by p / 360 mm per degree; on a
visible length l it reads (l - groove width - 2 w) 360 / p degrees: the groove stops a
wall w short of either end face (run out through a face, its flank would meet the face in
a knife edge). Each piece's pitch is the
largest that reads the groove range (default 180 deg, the paper's sweep) on its visible
length: the proximal piece's length below the stop notch, the distal piece's body (its
journal runs inside the sleeve); a piece is lengthened where that pitch would be under
:data:`PITCH_PER_WIDTH` groove widths. :attr:`TipGeometry.proximal_readout` and
``distal_readout`` give the readout resolution in m per rad (mm per degree: the same number
times 1000 pi / 180).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import casadi as ca
import numpy as np

from design.geometry import is_symbolic

KEY_ANGLE = math.radians(30.0)
"""Angular width of the stop key. [rad]"""
GROOVE_RANGE = math.pi
"""Rotation each groove reads by default: the paper's sweep, 0-180 deg. [rad]"""
PITCH_PER_WIDTH = 8.0
"""Least groove pitch over its width: the notch blurs at most 360 / 8 = 45 deg of rotation
(and CadQuery's helical sweep cuts reliably only at such pitches). [-]"""
STOP_MARGIN = math.radians(60.0)
"""The notch spans the stop angle plus the key; this much of the sleeve's turn stays
whole, so it still bears the journal: the stop angle is at most 2 pi - key - margin. [rad]"""
MAX_STOP_ANGLE = 2 * math.pi - KEY_ANGLE - STOP_MARGIN
"""Largest stop angle the pieces can make (270 deg). [rad]"""


@dataclass(frozen=True)
class TipGeometry:
    """Every dimension of the two pieces and what the model needs from them.

    Diameters, lengths and z positions in each piece's own frame [m]; volumes [m^3],
    masses [kg], angles [rad]. Numbers or CasADi expressions, as the inputs were.
    """

    magnet_length: Any
    gap: Any
    # radial
    outer_diameter: Any
    wall: Any
    seat_diameter: Any
    journal_diameter: Any
    sleeve_bore: Any
    socket_diameter: Any
    reservoir_diameter: Any
    passage_diameter: Any
    wire_bore: Any
    chamber_diameter: Any
    port_diameter: Any
    groove_depth: Any
    groove_width: Any
    # proximal piece, axial
    socket_depth: Any
    reservoir_length: Any
    shoulder_z: Any
    sleeve_length: Any
    notch_depth: Any
    notch_span: Any
    proximal_length: Any
    # distal piece, axial
    journal_length: Any
    pocket_depth_distal: Any
    key_height: Any
    key_angle: Any
    body_length: Any
    chamber_z: Any
    distal_length: Any
    # tracking
    proximal_pitch: Any
    distal_pitch: Any
    groove_range: Any
    # what the model takes
    proximal_volume: Any
    distal_volume: Any
    proximal_centroid: Any
    distal_centroid: Any
    proximal_mass: Any
    distal_mass: Any

    @property
    def rigid_offset(self) -> Any:
        """From the rigid segment's start (the proximal piece's proximal face, where the
        flexible rod ends) to the proximal ring's centre, the tracked point. [m]"""
        return self.shoulder_z - self.magnet_length / 2

    def rod_length(self, free_length: Any) -> Any:
        """The flexible rod under this tip: ``free_length`` (clamp to the tracked point)
        less :attr:`rigid_offset`; a design is admissible only where it is positive. [m]"""
        return free_length - self.rigid_offset

    @property
    def rigid_length(self) -> Any:
        """The rigid tip segment: proximal face of the proximal piece to the far face of
        the distal piece. [m]"""
        return self.shoulder_z + self.distal_length

    @property
    def proximal_arm(self) -> Any:
        """Proximal piece's centre of mass from the rigid segment's start. [m]"""
        return self.proximal_centroid

    @property
    def distal_arm(self) -> Any:
        """Distal piece's centre of mass from the rigid segment's start (its frame starts
        at the shoulder). [m]"""
        return self.shoulder_z + self.distal_centroid

    @property
    def proximal_readout(self) -> Any:
        """Notch travel per rotation on the proximal piece, pitch / 2 pi. [m/rad]"""
        return self.proximal_pitch / (2 * math.pi)

    @property
    def distal_readout(self) -> Any:
        """Notch travel per rotation on the distal piece's body, pitch / 2 pi. [m/rad]"""
        return self.distal_pitch / (2 * math.pi)


def _max(*values: Any) -> Any:
    """The largest of ``values`` (CasADi's fmax for expressions)."""
    if is_symbolic(*values):
        out = values[0]
        for v in values[1:]:
            out = ca.fmax(out, v)
        return out
    return max(values)


def _disc(diameter: Any, z0: Any, z1: Any) -> tuple[Any, Any]:
    """(volume, first moment about z = 0) of a solid cylinder on the axis from z0 to z1.
    [m^3, m^4]"""
    volume = math.pi / 4 * diameter**2 * (z1 - z0)
    return volume, volume * (z0 + z1) / 2


def _ring(outer: Any, inner: Any, z0: Any, z1: Any, fraction: Any = 1) -> tuple[Any, Any]:
    """(volume, first moment) of a fraction of an annulus (outer, inner diameters) from z0
    to z1. [m^3, m^4]"""
    vo, mo = _disc(outer, z0, z1)
    vi, mi = _disc(inner, z0, z1)
    return fraction * (vo - vi), fraction * (mo - mi)


def _port(diameter: Any, z: Any, inner: Any, outer: Any) -> tuple[Any, Any]:
    """(volume, first moment) of a radial hole of ``diameter`` at height z from the
    diameter ``inner`` out to ``outer`` (the curved ends taken flat). [m^3, m^4]"""
    volume = math.pi / 4 * diameter**2 * (outer - inner) / 2
    return volume, volume * z


def _sum(added: list, removed: list) -> tuple[Any, Any]:
    """Volume and centroid of added less removed parts. [m^3, m]"""
    volume = sum(v for v, _ in added) - sum(v for v, _ in removed)
    moment = sum(m for _, m in added) - sum(m for _, m in removed)
    return volume, moment / volume


def tip_geometry(
    magnet_outer_diameter: Any,
    magnet_inner_diameter: Any,
    magnet_length: Any,
    gap: Any,
    catheter_outer_diameter: Any,
    wire_outer_diameter: Any,
    catheter_inner_diameter: Any,
    wall: Any,
    fit_allowance: Any,
    running_clearance: Any,
    density: Any,
    stop_angle: Any,
    *,
    groove_range: Any = GROOVE_RANGE,
    outer_diameter: Any = None,
    socket_depth: Any = None,
    passage_diameter: Any = None,
) -> TipGeometry:
    """The two mounting pieces of a tip (the module's docstring draws them).

    magnet_outer_diameter, magnet_inner_diameter, magnet_length, gap : the rings. [m]
    catheter_outer_diameter, wire_outer_diameter, catheter_inner_diameter : the
        transmissions bonded into the pieces. [m]
    wall, fit_allowance, running_clearance, density : of the print
        (:class:`~design.records.Mounting`). [m, m, m, kg/m^3]
    stop_angle : relative rotation theta1 - theta2 the stops allow, from 0. [rad]
    groove_range : rotation each tracking groove reads (at most 2 pi). [rad]
    outer_diameter : the pieces' outer diameter; None: the smallest that holds every wall
        (a larger one is the CAD designer's choice; the model uses the smallest). [m]
    socket_depth : depth of the catheter's glued socket; None: two catheter diameters
        (and at least the glue reservoir and a wall either side). [m]
    passage_diameter : the proximal piece's wire passage; None: the catheter's bore. [m]

    Derived choices, all scaled by the wall w: groove depth w / 2 and width 1.6 w, glue
    ports w across, glue reliefs 0.6 w deep and 2 w long, key 2 w high, axial clearance of
    key and sleeve the running clearance. Volumes are exact for the axisymmetric features
    and the notch and key sectors; the helical groove removes its share width / pitch of
    the annulus over its centre's travel (exact for a screw sweep), the radial ports as
    straight holes: together within a few tenths of a percent of the CAD solid's volume
    (tests/cad/test_cad_mounting.py).
    """
    w, fit, clr = wall, fit_allowance, running_clearance
    passage = catheter_inner_diameter if passage_diameter is None else passage_diameter
    groove_depth, groove_width = w / 2, 1.6 * w
    port, relief, reservoir_length = w, 0.6 * w, 2 * w
    key_height, axial_clearance = 2 * w, clr
    spacing = magnet_length + gap

    seat = magnet_outer_diameter + fit
    journal = seat + 2 * w
    sleeve_bore = journal + clr
    wire_bore = wire_outer_diameter + fit
    chamber = _max(wire_bore, port) + 2 * relief
    socket = catheter_outer_diameter + fit
    reservoir = socket + 2 * relief
    skin = 2 * (w + groove_depth)
    needed = _max(sleeve_bore, reservoir, chamber) + skin
    outer = needed if outer_diameter is None else outer_diameter

    if socket_depth is None:
        socket_depth = _max(2 * catheter_outer_diameter, reservoir_length + 2 * w)
    journal_length = _max(spacing + w, key_height + 2 * axial_clearance + w, journal / 2)
    sleeve_length = journal_length - axial_clearance
    notch_depth = key_height + axial_clearance
    notch_span = stop_angle + KEY_ANGLE
    # Each grooved length reads groove_range at a pitch of at least PITCH_PER_WIDTH widths,
    # the groove stopping a wall short of either end face (a groove that runs out through a
    # face leaves a knife edge between its flank and the face):
    # l >= b (1 + PITCH_PER_WIDTH range / 2 pi) + 2 w, b the groove width.
    least_visible = groove_width * (1 + PITCH_PER_WIDTH * groove_range / (2 * math.pi)) + 2 * w
    # The proximal groove ends below the notch (its end in the notch left a knife edge).
    shoulder = _max(socket_depth + w + magnet_length, least_visible + notch_depth - sleeve_length)
    proximal_length = shoulder + sleeve_length
    # The body holds its glue chamber between two walls and a readable groove.
    body = _max(reservoir_length + 2 * w, least_visible)
    distal_length = journal_length + body
    chamber_z = journal_length + body / 2

    def pitch(visible: Any) -> Any:
        return 2 * math.pi * (visible - groove_width - 2 * w) / groove_range

    proximal_pitch, distal_pitch = pitch(proximal_length - notch_depth), pitch(body)
    groove_inner = outer - 2 * groove_depth
    # A screw sweep removes width / pitch of the annulus over its centre's travel, which
    # runs from a wall plus half the width above a piece's grooved length to as far below.
    b2 = groove_width / 2
    notch_share = notch_span / (2 * math.pi)
    key_share = KEY_ANGLE / (2 * math.pi)
    port_z = socket_depth / 2
    proximal_volume, proximal_centroid = _sum(
        [_disc(outer, 0, proximal_length)],
        [
            _disc(socket, 0, socket_depth),
            _ring(reservoir, socket, port_z - reservoir_length / 2, port_z + reservoir_length / 2),
            _port(port, port_z, reservoir, outer),
            _disc(passage, socket_depth, shoulder - magnet_length),
            _disc(seat, shoulder - magnet_length, shoulder),
            _disc(sleeve_bore, shoulder, proximal_length),
            _ring(outer, sleeve_bore, proximal_length - notch_depth, proximal_length, notch_share),
            _ring(
                outer,
                groove_inner,
                w + b2,
                proximal_length - notch_depth - w - b2,
                groove_width / proximal_pitch,
            ),
        ],
    )
    distal_volume, distal_centroid = _sum(
        [
            _disc(journal, 0, journal_length),
            _disc(outer, journal_length, distal_length),
            _ring(outer, sleeve_bore, journal_length - key_height, journal_length, key_share),
        ],
        [
            _disc(seat, 0, spacing),
            _disc(wire_bore, spacing, distal_length),
            _ring(
                chamber,
                wire_bore,
                chamber_z - reservoir_length / 2,
                chamber_z + reservoir_length / 2,
            ),
            _port(port, chamber_z, chamber, outer),
            _ring(
                outer,
                groove_inner,
                journal_length + w + b2,
                distal_length - w - b2,
                groove_width / distal_pitch,
            ),
        ],
    )
    return TipGeometry(
        magnet_length=magnet_length,
        gap=gap,
        outer_diameter=outer,
        wall=w,
        seat_diameter=seat,
        journal_diameter=journal,
        sleeve_bore=sleeve_bore,
        socket_diameter=socket,
        reservoir_diameter=reservoir,
        passage_diameter=passage,
        wire_bore=wire_bore,
        chamber_diameter=chamber,
        port_diameter=port,
        groove_depth=groove_depth,
        groove_width=groove_width,
        socket_depth=socket_depth,
        reservoir_length=reservoir_length,
        shoulder_z=shoulder,
        sleeve_length=sleeve_length,
        notch_depth=notch_depth,
        notch_span=notch_span,
        proximal_length=proximal_length,
        journal_length=journal_length,
        pocket_depth_distal=spacing,
        key_height=key_height,
        key_angle=KEY_ANGLE,
        body_length=body,
        chamber_z=chamber_z,
        distal_length=distal_length,
        proximal_pitch=proximal_pitch,
        distal_pitch=distal_pitch,
        groove_range=groove_range,
        proximal_volume=proximal_volume,
        distal_volume=distal_volume,
        proximal_centroid=proximal_centroid,
        distal_centroid=distal_centroid,
        proximal_mass=density * proximal_volume,
        distal_mass=density * distal_volume,
    )


def design_tip_geometry(design: Any, **choices: Any) -> TipGeometry:
    """:func:`tip_geometry` of a :class:`~design.records.Design` (numbers), printed with its
    ``tip.mounting`` process; ``choices`` are :func:`tip_geometry`'s keywords. [SI]"""
    tip, robot, m = design.tip, design.robot, design.tip.mounting
    return tip_geometry(
        tip.magnet_outer_diameter,
        tip.magnet_inner_diameter,
        tip.magnet_length,
        tip.magnet_gap,
        robot.catheter.outer_diameter,
        robot.wire.outer_diameter,
        robot.catheter.inner_diameter,
        m.wall,
        m.fit_allowance,
        m.running_clearance,
        m.density,
        m.stop_angle,
        **({"passage_diameter": passage_diameter(design)} | choices),
    )


def passage_diameter(design: Any) -> float:
    """The proximal piece's wire passage of ``design``: its ``tip.mounting``'s, or the
    catheter's bore where that is 0. [m]"""
    return design.tip.mounting.passage_diameter or design.robot.catheter.inner_diameter


def geometry_values(geometry: TipGeometry) -> dict[str, float]:
    """The fields of a numeric :class:`TipGeometry` as floats, by name. [SI]"""
    return {f.name: float(np.asarray(getattr(geometry, f.name))) for f in fields(geometry)}
