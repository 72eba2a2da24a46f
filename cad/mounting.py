"""The two mounting pieces of the tip: seats for the ring magnets, bonded to wire and catheter.

CAD works in millimetres: every length here is in mm, angles in degrees.

Each piece is built in its own frame: axis +Z pointing distally (towards the tip), z = 0
at its proximal face, angles measured about +Z from local +X, which is the ring's
magnetisation direction at angle 0. In the robot's base frame the pieces sit with local
Z along the tip tangent (+x) and local X along +y, so a piece angle is the magnet angle
theta of ``spec/formats.md``.

Proximal piece (on the catheter, turns the proximal ring, theta2)
    catheter socket with a glue reservoir ring and a radial fill port | wire passage
    (the catheter lumen continued) | ring pocket, ring flush with the shoulder | bearing
    sleeve that receives the distal piece's journal, with the stop notch cut in its end.
Distal piece (on the wire, turns the distal ring, theta1)
    journal (runs in the sleeve; its end face bears on the shoulder and sets the gap)
    holding the ring pocket, ring recessed by the gap | stop key on the shoulder, riding in
    the notch | body with the wire bore, a glue reservoir and a radial fill port.

The journal-in-sleeve keeps both rings coaxial; the end face on the shoulder keeps the
face-to-face gap at ``design.tip.gap``; the key in the notch limits the relative rotation
theta1 - theta2 to ``rotation_limits_deg``. Both pieces carry the single-start helical
tracking groove (:mod:`cad.tracking`), which crosses local +X at the piece's proximal face
(z = 0) and runs past both faces.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cadquery as cq

from cad.errors import require
from cad.process import PrintProcess, mm
from cad.solids import Z_AXIS, annular_sector, cylinder, radial_port, single_solid
from cad.tracking import GrooveSpec
from design.geometry import WIRE_CLEARANCE, ring_clears_wire
from design.records import Design


@dataclass(frozen=True)
class MountingSpec:
    """Designer's choices for the mounting pieces (lengths in mm, angles in deg).

    groove : The helical tracking groove.
    wall_mm : Structural wall; ``None`` uses the process default (1.25 x minimum). [mm]
    outer_diameter_mm : Outer diameter of both pieces; ``None`` uses the smallest that
        holds every wall. [mm]
    socket_depth_mm : Depth of the catheter socket in the proximal piece. [mm]
    key_angle_deg : Angular width of the stop key. [deg]
    key_height_mm : Axial height of the stop key. [mm]
    axial_clearance_mm : Between the key's shoulder and the sleeve end. [mm]
    rotation_limits_deg : Admissible relative rotation theta1 - theta2 (distal minus
        proximal) allowed by key and notch. [deg]
    glue_relief_depth_mm : Radial depth of the glue reservoir rings. [mm]
    glue_port_mm : Diameter of the radial glue ports; ``None`` uses the wall. [mm]
    """

    groove: GrooveSpec = field(default_factory=GrooveSpec)
    wall_mm: float | None = None
    outer_diameter_mm: float | None = None
    socket_depth_mm: float = 5.0
    key_angle_deg: float = 30.0
    key_height_mm: float = 1.0
    axial_clearance_mm: float = 0.2
    rotation_limits_deg: tuple[float, float] = (0.0, 180.0)
    glue_relief_depth_mm: float = 0.3
    glue_port_mm: float | None = None


@dataclass(frozen=True)
class MountingDims:
    """Every derived dimension of the two pieces. [mm] or [deg] as named.

    Proximal piece: ``socket_*``, ``passage_diameter``, ``shoulder_z`` (z of the shoulder
    the journal bears on), ``sleeve_*``, ``notch_*``, ``proximal_length``.
    Distal piece: ``journal_*``, ``pocket_depth_distal``, ``wire_bore``, ``chamber_*``,
    ``key_*``, ``body_length``, ``distal_length``.
    """

    magnet_outer_diameter: float
    magnet_inner_diameter: float
    magnet_length: float
    gap: float
    outer_diameter: float
    wall: float
    seat_diameter: float
    catheter_outer_diameter: float
    wire_diameter: float
    socket_diameter: float
    socket_depth: float
    reservoir_diameter: float
    reservoir_length: float
    port_diameter: float
    passage_diameter: float
    shoulder_z: float
    sleeve_bore: float
    sleeve_length: float
    notch_start_deg: float
    notch_span_deg: float
    notch_depth: float
    proximal_length: float
    journal_diameter: float
    journal_length: float
    pocket_depth_distal: float
    wire_bore: float
    chamber_diameter: float
    chamber_length: float
    chamber_z: float
    key_start_deg: float
    key_angle_deg: float
    key_height: float
    key_inner_diameter: float
    body_length: float
    distal_length: float
    groove_pitch: float
    groove_width: float
    groove_depth: float

    @property
    def socket_port_z(self) -> float:
        """z of the proximal piece's glue port (mid-socket). [mm]"""
        return self.socket_depth / 2


@dataclass(frozen=True)
class TrackingReport:
    """What the camera can read from one piece's groove.

    piece : ``"proximal"`` or ``"distal"``.
    pitch_mm : Groove pitch. [mm]
    travel_mm : Grooved axial length of the piece (notch travel). [mm]
    resolution_deg_per_mm : Rotation per mm of notch travel. [deg/mm]
    range_deg : Rotation the notch covers on this piece. [deg]
    """

    piece: str
    pitch_mm: float
    travel_mm: float
    resolution_deg_per_mm: float
    range_deg: float


@dataclass(frozen=True)
class MountingPieces:
    """The two pieces (solids in their own frames) and their dimensions."""

    proximal: cq.Solid
    distal: cq.Solid
    dims: MountingDims
    spec: MountingSpec

    def tracking(self) -> tuple[TrackingReport, TrackingReport]:
        """Angular resolution and range of both grooves."""
        d = self.dims
        out = []
        # The distal groove is visible on the body; the journal runs inside the sleeve.
        for piece, travel in (("proximal", d.proximal_length), ("distal", d.body_length)):
            out.append(
                TrackingReport(
                    piece=piece,
                    pitch_mm=d.groove_pitch,
                    travel_mm=travel,
                    resolution_deg_per_mm=360.0 / d.groove_pitch,
                    range_deg=min(360.0, 360.0 * travel / d.groove_pitch),
                )
            )
        return out[0], out[1]


def mounting_dims(design: Design, process: PrintProcess, spec: MountingSpec) -> MountingDims:
    """Derive and check every dimension of the pieces from the design and the process.

    Raises :class:`~cad.errors.CadError` naming the quantity for any impossible geometry.
    """
    tip, wire, cath = design.tip, design.robot.wire, design.robot.catheter
    Dm, dm, Lm, gap = (
        mm(tip.magnet_outer_diameter),
        mm(tip.magnet_inner_diameter),
        mm(tip.magnet_length),
        mm(tip.gap),
    )
    dw, Dc, dc = mm(wire.outer_diameter), mm(cath.outer_diameter), mm(cath.inner_diameter)
    fit, clr = process.fit_allowance_mm, process.running_clearance_mm
    g = spec.groove
    w = spec.wall_mm if spec.wall_mm is not None else process.wall_mm
    port = spec.glue_port_mm if spec.glue_port_mm is not None else process.wall_mm
    rd = spec.glue_relief_depth_mm

    spacing = mm(tip.spacing)  # ring centre to ring centre: the distal pocket's depth
    require(Lm > 0, "tip ring: magnet length", "positive", Lm)
    require(gap >= 0, "tip ring: gap", "zero or positive", gap)
    require(dm < Dm, "tip ring: magnet bore", f"smaller than its outer diameter ({Dm:g} mm)", dm)
    require(
        ring_clears_wire(tip.magnet_inner_diameter, wire.outer_diameter),
        "tip ring: magnet bore",
        f"at least the wire diameter ({dw:g} mm) plus {mm(WIRE_CLEARANCE):g} mm so the wire "
        "turns in it",
        dm,
    )
    require(
        w >= process.min_wall_mm,
        "mounting piece: wall",
        f"at least the {process.name} minimum wall ({process.min_wall_mm:g} mm)",
        w,
    )
    require(port > 0, "mounting piece: glue port diameter", "positive", port)
    require(rd > 0, "mounting piece: glue relief depth", "positive", rd)
    require(
        spec.socket_depth_mm > 0, "proximal piece: socket depth", "positive", spec.socket_depth_mm
    )
    require(spec.key_height_mm > 0, "distal piece: key height", "positive", spec.key_height_mm)
    require(
        spec.axial_clearance_mm > 0,
        "mounting pieces: axial clearance",
        "positive",
        spec.axial_clearance_mm,
    )
    lo, hi = spec.rotation_limits_deg
    require(
        hi > lo, "mounting pieces: upper rotation limit", f"above the lower ({lo:g} deg)", hi, "deg"
    )
    notch_span = hi - lo + spec.key_angle_deg
    require(
        0 < spec.key_angle_deg and notch_span <= 300.0,
        "mounting pieces: rotation range plus key angle",
        "at most 300 deg so the sleeve keeps a bearing",
        notch_span,
        "deg",
    )

    seat = Dm + fit
    wire_bore = dw + fit
    require(
        wire_bore < dm,
        "distal piece: wire bore diameter (wire + fit allowance)",
        f"smaller than the magnet bore ({dm:g} mm) so the ring rests on the pocket floor",
        wire_bore,
    )
    require(
        dc < dm,
        "proximal piece: wire passage diameter (catheter inner diameter)",
        f"smaller than the magnet bore ({dm:g} mm) so the ring rests on the pocket floor",
        dc,
    )
    socket = Dc + fit
    journal = seat + 2 * w
    sleeve_bore = journal + clr
    chamber = max(wire_bore, port) + 2 * rd
    reservoir = socket + 2 * rd
    require(
        port < min(socket, chamber),
        "mounting piece: glue port diameter",
        f"smaller than the reservoir it feeds ({min(socket, chamber):.3g} mm)",
        port,
    )
    skin = 2 * (w + g.depth_mm)
    needed = max(sleeve_bore, reservoir, chamber) + skin
    outer = spec.outer_diameter_mm if spec.outer_diameter_mm is not None else needed
    # The derived outer diameter is the needed one to rounding; compare with that slack.
    slack = 1e-9 * max(outer, 1.0)
    require(
        seat <= outer - skin - 2 * w - clr + slack,
        "mounting piece: magnet seat diameter (magnet + fit allowance)",
        f"at most {outer - skin - 2 * w - clr:.3g} mm for a piece of outer diameter "
        f"{outer:g} mm (journal wall {w:g}, running clearance {clr:g}, sleeve wall {w:g} "
        f"and groove depth {g.depth_mm:g} mm)",
        seat,
    )
    require(
        reservoir + skin <= outer + slack,
        "proximal piece: catheter socket diameter (catheter + fit + glue relief)",
        f"at most {outer - skin:.3g} mm for a piece of outer diameter {outer:g} mm",
        reservoir,
    )
    require(
        chamber + skin <= outer + slack,
        "distal piece: glue chamber diameter",
        f"at most {outer - skin:.3g} mm for a piece of outer diameter {outer:g} mm",
        chamber,
    )

    key_height = spec.key_height_mm
    journal_length = max(spacing + w, key_height + spec.axial_clearance_mm + w, 0.5 * journal)
    sleeve_length = journal_length - spec.axial_clearance_mm
    reservoir_length = port + 0.4
    require(
        reservoir_length < spec.socket_depth_mm,
        "proximal piece: socket depth",
        f"longer than the glue reservoir ({reservoir_length:.3g} mm)",
        spec.socket_depth_mm,
    )
    shoulder = max(spec.socket_depth_mm + w + Lm, g.travel_mm - sleeve_length)
    body = max(g.travel_mm, reservoir_length + 2 * w)
    chamber_length = reservoir_length
    return MountingDims(
        magnet_outer_diameter=Dm,
        magnet_inner_diameter=dm,
        magnet_length=Lm,
        gap=gap,
        outer_diameter=outer,
        wall=w,
        seat_diameter=seat,
        catheter_outer_diameter=Dc,
        wire_diameter=dw,
        socket_diameter=socket,
        socket_depth=spec.socket_depth_mm,
        reservoir_diameter=reservoir,
        reservoir_length=reservoir_length,
        port_diameter=port,
        passage_diameter=dc,
        shoulder_z=shoulder,
        sleeve_bore=sleeve_bore,
        sleeve_length=sleeve_length,
        notch_start_deg=lo - spec.key_angle_deg / 2,
        notch_span_deg=notch_span,
        notch_depth=key_height + spec.axial_clearance_mm,
        proximal_length=shoulder + sleeve_length,
        journal_diameter=journal,
        journal_length=journal_length,
        pocket_depth_distal=spacing,
        wire_bore=wire_bore,
        chamber_diameter=chamber,
        chamber_length=chamber_length,
        chamber_z=journal_length + body / 2,
        key_start_deg=-spec.key_angle_deg / 2,
        key_angle_deg=spec.key_angle_deg,
        key_height=key_height,
        key_inner_diameter=sleeve_bore,
        body_length=body,
        distal_length=journal_length + body,
        groove_pitch=g.pitch_mm,
        groove_width=g.width_mm,
        groove_depth=g.depth_mm,
    )


def helical_groove(
    outer_diameter: float, groove: GrooveSpec, z_start: float, z_end: float
) -> cq.Solid:
    """The cutter of a single-start right-hand helical groove on a cylinder.

    The rectangular profile (``width`` along the axis, ``2 depth`` radially, centred on
    the surface) sits at the helix start in the XZ plane, which contains the axis, and is
    swept along ``cq.Wire.makeHelix`` with a Frenet frame (``isFrenet=True`` keeps it
    from twisting). The helix runs from ``z_start`` to ``z_end`` (past both faces) and is
    phased so that the groove crosses +X at z = 0. [mm]
    """
    radius = outer_diameter / 2
    height = z_end - z_start
    helix = cq.Wire.makeHelix(groove.pitch_mm, height, radius)
    profile = cq.Workplane("XZ").center(radius, 0.0).rect(2 * groove.depth_mm, groove.width_mm)
    cutter = profile.sweep(cq.Workplane().add(helix), isFrenet=True).val()
    phase_deg = 360.0 * z_start / groove.pitch_mm
    return cutter.rotate(cq.Vector(), Z_AXIS, phase_deg).translate(cq.Vector(0, 0, z_start))


def proximal_piece(d: MountingDims, spec: MountingSpec, with_groove: bool = True) -> cq.Solid:
    """The proximal mounting piece (on the catheter), in its own frame. [mm]"""
    envelope = cylinder(d.outer_diameter, 0.0, d.proximal_length)
    port_z = d.socket_port_z
    cuts = [
        cylinder(d.socket_diameter, -1.0, d.socket_depth),
        cylinder(
            d.reservoir_diameter, port_z - d.reservoir_length / 2, port_z + d.reservoir_length / 2
        ),
        radial_port(d.port_diameter, port_z, d.outer_diameter / 2, 180.0),
        cylinder(d.passage_diameter, d.socket_depth - 0.1, d.shoulder_z - d.magnet_length + 0.1),
        cylinder(d.seat_diameter, d.shoulder_z - d.magnet_length, d.shoulder_z + 0.1),
        cylinder(d.sleeve_bore, d.shoulder_z, d.proximal_length + 1.0),
        annular_sector(
            d.sleeve_bore - 0.2,
            d.outer_diameter + 0.2,
            d.notch_start_deg,
            d.notch_span_deg,
            d.proximal_length - d.notch_depth,
            d.proximal_length + 1.0,
        ),
    ]
    groove = None
    if with_groove:
        e = spec.groove.width_mm + 1.0
        groove = helical_groove(d.outer_diameter, spec.groove, -e, d.proximal_length + e)
    return _cut_all(envelope, groove, cuts)


def distal_piece(d: MountingDims, spec: MountingSpec, with_groove: bool = True) -> cq.Solid:
    """The distal mounting piece (on the wire), in its own frame. [mm]"""
    jl = d.journal_length
    envelope = cylinder(d.journal_diameter, 0.0, jl + 0.01).fuse(
        cylinder(d.outer_diameter, jl, d.distal_length),
        annular_sector(
            d.key_inner_diameter,
            d.outer_diameter,
            d.key_start_deg,
            d.key_angle_deg,
            jl - d.key_height,
            jl + 0.01,
        ),
    )
    cz = d.chamber_z
    cuts = [
        cylinder(d.seat_diameter, -1.0, d.pocket_depth_distal),
        cylinder(d.wire_bore, d.pocket_depth_distal - 0.1, d.distal_length + 1.0),
        cylinder(d.chamber_diameter, cz - d.chamber_length / 2, cz + d.chamber_length / 2),
        radial_port(d.port_diameter, cz, d.outer_diameter / 2, 180.0),
    ]
    groove = None
    if with_groove:
        e = spec.groove.width_mm + 1.0
        groove = helical_groove(d.outer_diameter, spec.groove, -e, d.distal_length + e)
    return _cut_all(envelope, groove, cuts)


def _cut_all(envelope: cq.Shape, groove: cq.Solid | None, cuts: list[cq.Solid]) -> cq.Solid:
    """Cut the groove from the plain envelope first (a few faces: fast and robust), then the
    inner features; check that one valid solid remains."""
    result = envelope.clean()
    if groove is not None:
        result = result.cut(groove).clean()
    return single_solid(result.cut(*cuts).clean(), "mounting piece")


def build_mounting_pieces(
    design: Design,
    process: PrintProcess,
    spec: MountingSpec | None = None,
    with_groove: bool = True,
) -> MountingPieces:
    """Build both mounting pieces for ``design`` printed with ``process``.

    Parameters
    ----------
    design : The robot (SI); its ring, wire and catheter sizes set the seats and bores.
    process : Fits, clearances and minimum wall.
    spec : Designer's choices; defaults reproduce the paper's tracking groove.
    with_groove : Leave the helical groove out (for checks against closed-form volumes).
    """
    spec = spec or MountingSpec()
    dims = mounting_dims(design, process, spec)
    return MountingPieces(
        proximal=proximal_piece(dims, spec, with_groove),
        distal=distal_piece(dims, spec, with_groove),
        dims=dims,
        spec=spec,
    )
