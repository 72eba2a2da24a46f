"""The two mounting pieces of the tip, built from :func:`design.mounting.tip_geometry`.

CAD works in millimetres: every length here is in mm, angles in degrees.

Every dimension comes from the design's one tip geometry (:mod:`design.mounting`, which
the model uses for the pieces' mass, centre of mass and rigid segment): this module turns
it into millimetres, checks that the pieces can be made and builds the solids.

Each piece is built in its own frame: axis +Z pointing distally (towards the tip), z = 0
at its proximal face, angles measured about +Z from local +X, which is the ring's
magnetisation direction at angle 0. In the robot's base frame the pieces sit with local
Z along the tip tangent (+x) and local X along +y, so a piece angle is the magnet angle
theta of ``docs/formats.md``.

Proximal piece (on the catheter, turns the proximal ring, theta2)
    catheter socket with a glue reservoir ring and a radial fill port | wire passage
    (the catheter lumen continued, or the design's narrower ``passage_diameter_mm``) | ring
    pocket, ring flush with the shoulder | bearing sleeve that receives the distal piece's
    journal, with the stop notch cut in its end.
Distal piece (on the wire, turns the distal ring, theta1)
    journal (runs in the sleeve; its end face bears on the shoulder and sets the gap)
    holding the ring pocket, ring recessed by the gap | stop key on the shoulder, riding in
    the notch | body with the wire bore, a glue reservoir and a radial fill port.

The journal-in-sleeve keeps both rings coaxial; the end face on the shoulder keeps the
face-to-face gap at ``design.tip.magnet_gap``; the key in the notch limits the relative rotation
theta1 - theta2 to [0, ``design.tip.mounting.stop_angle``] (the rotational stops). Each
piece carries a single-start helical tracking groove (:mod:`cad.tracking`) whose pitch
lets its visible length read the groove range; its helix is phased to cross local +X at
the piece's proximal face (z = 0), but it ends a wall short of either face, so where it
starts is no mark of angle 0: the stop key's centre is (the distal piece's; on the
proximal piece, where the key's centre sits against the notch's edge with the rings
parallel).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cadquery as cq

from cad.errors import require
from cad.process import CadProcess, get_process, mm
from cad.solids import Z_AXIS, annular_sector, cylinder, radial_port, single_solid
from cad.tracking import GrooveSpec
from design.admissible import WIRE_CLEARANCE, admits, quantities
from design.mounting import GROOVE_RANGE, MAX_STOP_ANGLE, TipGeometry, design_tip_geometry
from design.process import PROCESSES as SI_PROCESSES
from design.process import PrintProcess
from design.records import Design, Mounting
from design.units import DEG, MM


@dataclass(frozen=True)
class MountingSpec:
    """Designer's choices beyond the design file (lengths in mm, angles in deg); the
    defaults make the pieces the model knows (:func:`design.mounting.tip_geometry`). The
    wall, fits and material are the design's own ``tip.mounting``, never chosen here.

    groove_range_deg : Rotation each tracking groove reads, 180 (the paper's sweep) to
        360. [deg]
    outer_diameter_mm : Outer diameter of both pieces; ``None`` uses the smallest that
        holds every wall. [mm]
    socket_depth_mm : Depth of the catheter socket; ``None``: two catheter diameters. [mm]
    """

    groove_range_deg: float = math.degrees(GROOVE_RANGE)
    outer_diameter_mm: float | None = None
    socket_depth_mm: float | None = None


@dataclass(frozen=True)
class MountingDims:
    """Every derived dimension of the two pieces. [mm] or [deg] as named.

    Proximal piece: ``socket_*``, ``passage_diameter``, ``shoulder_z`` (z of the shoulder
    the journal bears on), ``sleeve_*``, ``notch_*``, ``proximal_length``.
    Distal piece: ``journal_*``, ``pocket_depth_distal``, ``wire_bore``, ``chamber_*``,
    ``key_*``, ``body_length``, ``distal_length``. Grooves: ``*_pitch``, ``groove_*``.
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
    stop_angle_deg: float
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
    proximal_pitch: float
    distal_pitch: float
    groove_width: float
    groove_depth: float
    hole_compensation: float = 0.0

    def drawn(self, diameter: float) -> float:
        """The diameter to draw for a fit bore of printed ``diameter``: wider by the
        process's hole shrink where the design asks for hole compensation
        (``hole_compensation``, diametral). [mm]"""
        return diameter + self.hole_compensation

    @property
    def socket_port_z(self) -> float:
        """z of the proximal piece's glue port (mid-socket). [mm]"""
        return self.socket_depth / 2

    def port_angle(self, piece: str) -> float:
        """Angle of ``piece``'s radial glue port: half a turn from where its tracking groove
        crosses the port's height, so the nearest pass of the groove is half a pitch away
        (at 180 deg a pass 1 mm off left a 0.28 mm web on small rings). [deg]"""
        z, pitch = (
            (self.socket_port_z, self.proximal_pitch)
            if piece == "proximal"
            else (self.chamber_z, self.distal_pitch)
        )
        return (360.0 * z / pitch + 180.0) % 360.0

    def groove(self, piece: str) -> GrooveSpec:
        """The tracking groove of ``piece`` (``"proximal"`` or ``"distal"``): its pitch and
        the notch travel on the visible length (the proximal piece below its stop notch, the
        distal piece's body) less the width and a wall at either end."""
        proximal = self.proximal_length - self.notch_depth
        visible = proximal if piece == "proximal" else self.body_length
        pitch = self.proximal_pitch if piece == "proximal" else self.distal_pitch
        travel = visible - self.groove_width - 2 * self.wall  # a wall short of either face
        return GrooveSpec(pitch, travel, self.groove_width, self.groove_depth)

    def groove_span(self, piece: str) -> tuple[float, float]:
        """z of the groove centre's start and end on ``piece``: a wall plus half the width
        inside the grooved length (the proximal piece below its notch, the distal piece's
        body), so the groove ends square inside the faces instead of running out through
        them. [mm]"""
        lo = 0.0 if piece == "proximal" else self.journal_length
        hi = self.proximal_length - self.notch_depth if piece == "proximal" else self.distal_length
        margin = self.wall + self.groove_width / 2
        return lo + margin, hi - margin


@dataclass(frozen=True)
class TrackingReport:
    """What the camera can read from one piece's groove.

    piece : ``"proximal"`` or ``"distal"``.
    pitch_mm : Groove pitch. [mm]
    travel_mm : Notch travel on the piece's visible length. [mm]
    resolution_deg_per_mm : Rotation per mm of notch travel. [deg/mm]
    readout_mm_per_deg : Notch travel per degree of rotation, pitch / 360. [mm/deg]
    range_deg : Rotation the notch covers on this piece. [deg]
    """

    piece: str
    pitch_mm: float
    travel_mm: float
    resolution_deg_per_mm: float
    readout_mm_per_deg: float
    range_deg: float


@dataclass(frozen=True)
class MountingPieces:
    """The two pieces (solids in their own frames) and their dimensions."""

    proximal: cq.Solid
    distal: cq.Solid
    dims: MountingDims
    spec: MountingSpec
    geometry: TipGeometry
    mounting: Mounting
    process: CadProcess

    def tracking(self) -> tuple[TrackingReport, TrackingReport]:
        """Readout resolution and range of both grooves."""
        out = []
        for piece in ("proximal", "distal"):
            g = self.dims.groove(piece)
            out.append(
                TrackingReport(
                    piece=piece,
                    pitch_mm=g.pitch_mm,
                    travel_mm=g.travel_mm,
                    resolution_deg_per_mm=g.resolution_deg_per_mm,
                    readout_mm_per_deg=g.pitch_mm / 360.0,
                    range_deg=g.range_deg,
                )
            )
        return out[0], out[1]

    def describe(self) -> list[str]:
        """Lines for reports: the rules the pieces were made with (walls and clearances),
        what the model takes from them, and what each groove reads. [mm, g, deg]"""
        d, g, m, p = self.dims, self.geometry, self.mounting, self.process
        lines = [
            f"tip pieces ({p.name}): wall {d.wall:g} mm (process minimum "
            f"{p.min_wall_mm:g}), fit allowance {mm(m.fit_allowance):g} mm, running "
            f"clearance {mm(m.running_clearance):g} mm; outer diameter "
            f"{d.outer_diameter:.3g} mm, rigid segment {mm(g.rigid_length):.3g} mm (tracked "
            f"point {mm(g.rigid_offset):.3g} mm along it), masses "
            f"{g.proximal_mass * 1e3:.3g} g + {g.distal_mass * 1e3:.3g} g; stops "
            f"0-{d.stop_angle_deg:g} deg",
        ]
        for t in self.tracking():
            lines.append(
                f"{t.piece} groove: pitch {t.pitch_mm:.3g} mm, {t.readout_mm_per_deg:.4f} mm "
                f"per deg, reads {t.range_deg:.0f} deg over {t.travel_mm:.3g} mm"
            )
        return lines


def tip_design(design: Design, process: str | PrintProcess | CadProcess | None = None) -> Design:
    """``design`` with the tip pieces printed by ``process``: None or the design's own
    process: the design as it is (its ``tip.mounting``, the pieces the model carries);
    another process: ``tip.mounting`` reprinted with that process's wall, fits and
    density (stops and pre-twist kept), pieces the design's model does not know."""
    mounting = design.tip.mounting
    if process is None or get_process(process).si == SI_PROCESSES.get(mounting.process):
        return design
    p = get_process(process).si
    reprinted = replace(
        mounting,
        process=p.name,
        wall=p.wall,
        fit_allowance=p.fit_allowance,
        running_clearance=p.running_clearance,
        density=p.density,
    )
    return replace(design, tip=replace(design.tip, mounting=reprinted))


def tip_process(
    design: Design, process: str | PrintProcess | CadProcess | None = None
) -> CadProcess:
    """The process the tip pieces are printed with: ``process``, or the design's
    ``tip.mounting.process`` (resin by default) when None."""
    return get_process(design.tip.mounting.process if process is None else process)


def tip_geometry_for(design: Design, spec: MountingSpec) -> TipGeometry:
    """The one tip geometry of ``design`` (:func:`design.mounting.design_tip_geometry`:
    its own ``tip.mounting``, as the model takes it), with the spec's choices. [SI]"""
    optional = {"outer_diameter": spec.outer_diameter_mm, "socket_depth": spec.socket_depth_mm}
    return design_tip_geometry(
        design,
        groove_range=spec.groove_range_deg * DEG,
        **{k: v * MM for k, v in optional.items() if v is not None},
    )


def mounting_dims(
    design: Design,
    process: str | PrintProcess | CadProcess | None = None,
    spec: MountingSpec | None = None,
) -> MountingDims:
    """Every dimension of the pieces of ``design`` printed with ``process`` (None: the
    design's own ``tip.mounting``, :func:`tip_design`), in mm, checked.

    Raises :class:`~cad.errors.CadError` naming the quantity for any impossible geometry.
    """
    spec = spec or MountingSpec()
    proc = tip_process(design, process)
    design = tip_design(design, process)
    tip, wire, cath = design.tip, design.robot.wire, design.robot.catheter
    Dm, dm = mm(tip.magnet_outer_diameter), mm(tip.magnet_inner_diameter)
    dw = mm(wire.outer_diameter)
    w = mm(tip.mounting.wall)
    # a ring shorter than the meshes' chord tolerance has no seat the CAD can draw and mesh
    # (1e-300 mm left the tessellation without faces)
    require(
        mm(tip.magnet_length) >= proc.linear_deflection_mm,
        "tip ring: magnet length (tip.magnet_length_mm)",
        f"at least the {proc.name} meshes' chord tolerance ({proc.linear_deflection_mm:g} mm)",
        mm(tip.magnet_length),
    )
    require(tip.magnet_gap >= 0, "tip ring: gap", "zero or positive", mm(tip.magnet_gap))
    q = quantities(design)
    require(
        admits("ring_wall", q),
        "tip ring: magnet bore",
        f"smaller than its outer diameter ({Dm:g} mm)",
        dm,
    )
    require(
        admits("ring_on_wire", q),
        "tip ring: magnet bore",
        f"at least the wire diameter ({dw:g} mm) plus {mm(WIRE_CLEARANCE):g} mm so the wire "
        "turns in it",
        dm,
    )
    require(
        w >= proc.min_wall_mm,
        "mounting piece: wall",
        f"at least the {proc.name} minimum wall ({proc.min_wall_mm:g} mm)",
        w,
    )
    require(
        180.0 <= spec.groove_range_deg <= 360.0,
        "tracking groove: range",
        "between 180 deg (the paper's sweep) and 360 deg (one turn)",
        spec.groove_range_deg,
        "deg",
    )
    stop = math.degrees(tip.mounting.stop_angle)
    require(
        0 < stop <= math.degrees(MAX_STOP_ANGLE) + 1e-9,
        "mounting pieces: stop angle",
        f"in (0, {math.degrees(MAX_STOP_ANGLE):g}] deg so the sleeve keeps a bearing",
        stop,
        "deg",
    )
    if spec.socket_depth_mm is not None:
        require(
            spec.socket_depth_mm > 0,
            "proximal piece: socket depth",
            "positive",
            spec.socket_depth_mm,
        )
    g = tip_geometry_for(design, spec)
    d = {name: mm(float(getattr(g, name))) for name in _LENGTHS}
    # the ring rests on the pocket floor: its bore over the larger of wire bore and passage
    # (the message names the wire bore where the wire bore alone is too wide)
    seated = admits("ring_seat", quantities(design, g))
    bore = (
        f"the magnet bore (tip.magnet_inner_diameter_mm = {dm:g}) so the ring rests on the "
        "pocket floor"
    )
    require(
        seated or d["wire_bore"] < dm,
        "distal piece: wire bore diameter (robot.wire.outer_diameter_mm + fit allowance)",
        f"smaller than {bore}: a wider ring bore or a thinner wire",
        d["wire_bore"],
    )
    passage = (
        "tip.mounting.passage_diameter_mm"
        if tip.mounting.passage_diameter
        else ("robot.catheter.inner_diameter_mm, the catheter's bore continued")
    )
    least = mm(design.robot.wire.outer_diameter + WIRE_CLEARANCE)
    require(
        seated,
        f"proximal piece: wire passage diameter ({passage})",
        f"smaller than {bore}: a wider ring bore, or a narrower passage "
        f"([tip.mounting] passage_diameter_mm, at least {least:g} for the wire to turn)",
        d["passage_diameter"],
    )
    outer, skin = d["outer_diameter"], 2 * (w + d["groove_depth"])
    # The derived outer diameter is the needed one to rounding; compare with that slack.
    slack = 1e-9 * max(outer, 1.0)
    clr = mm(tip.mounting.running_clearance)
    require(
        d["seat_diameter"] <= outer - skin - 2 * w - clr + slack,
        "mounting piece: magnet seat diameter (magnet + fit allowance)",
        f"at most {outer - skin - 2 * w - clr:.3g} mm for a piece of outer diameter "
        f"{outer:g} mm (journal wall {w:g}, running clearance {clr:g}, sleeve wall {w:g} "
        f"and groove depth {d['groove_depth']:g} mm)",
        d["seat_diameter"],
    )
    socket = "proximal piece: catheter socket diameter (catheter + fit + glue relief)"
    for name, what in (
        ("reservoir_diameter", socket),
        ("chamber_diameter", "distal piece: glue chamber diameter"),
    ):
        require(
            d[name] + skin <= outer + slack,
            what,
            f"at most {outer - skin:.3g} mm for a piece of outer diameter {outer:g} mm",
            d[name],
        )
    require(
        d["reservoir_length"] < d["socket_depth"],
        "proximal piece: socket depth",
        f"longer than the glue reservoir ({d['reservoir_length']:.3g} mm)",
        d["socket_depth"],
    )
    key = math.degrees(float(g.key_angle))
    return MountingDims(
        magnet_outer_diameter=Dm,
        magnet_inner_diameter=dm,
        catheter_outer_diameter=mm(cath.outer_diameter),
        wire_diameter=dw,
        stop_angle_deg=stop,
        notch_start_deg=-key / 2,
        notch_span_deg=stop + key,
        key_start_deg=-key / 2,
        key_angle_deg=key,
        key_inner_diameter=d["sleeve_bore"],
        chamber_length=d["reservoir_length"],
        hole_compensation=proc.hole_shrink_mm if tip.mounting.compensate_holes else 0.0,
        **d,
    )


_LENGTHS = (
    "magnet_length", "gap", "outer_diameter", "wall", "seat_diameter", "socket_diameter",
    "socket_depth", "reservoir_diameter", "reservoir_length", "port_diameter",
    "passage_diameter", "shoulder_z", "sleeve_bore", "sleeve_length", "notch_depth",
    "proximal_length", "journal_diameter", "journal_length", "pocket_depth_distal",
    "wire_bore", "chamber_diameter", "chamber_z", "key_height", "body_length",
    "distal_length", "proximal_pitch", "distal_pitch", "groove_width", "groove_depth",
)  # fmt: skip
"""The :class:`~design.mounting.TipGeometry` lengths :class:`MountingDims` holds in mm."""


def helical_groove(
    outer_diameter: float, groove: GrooveSpec, z_start: float, z_end: float
) -> cq.Solid:
    """The cutter of a single-start right-hand helical groove on a cylinder.

    The rectangular profile (``width`` along the axis, ``2 depth`` radially, centred on
    the surface) sits at the helix start in the XZ plane, which contains the axis, and is
    swept along ``cq.Wire.makeHelix`` with a Frenet frame (``isFrenet=True`` keeps it
    from twisting). The helix (the groove's centre) runs from ``z_start`` to ``z_end``,
    where the groove ends in faces that contain the axis, and is phased so that the groove
    crosses +X at z = 0. [mm]
    """
    radius = outer_diameter / 2
    height = z_end - z_start
    helix = cq.Wire.makeHelix(groove.pitch_mm, height, radius)
    profile = cq.Workplane("XZ").center(radius, 0.0).rect(2 * groove.depth_mm, groove.width_mm)
    cutter = profile.sweep(cq.Workplane().add(helix), isFrenet=True).val()
    phase_deg = 360.0 * z_start / groove.pitch_mm
    return cutter.rotate(cq.Vector(), Z_AXIS, phase_deg).translate(cq.Vector(0, 0, z_start))


def proximal_piece(d: MountingDims, with_groove: bool = True) -> cq.Solid:
    """The proximal mounting piece (on the catheter), in its own frame. [mm]"""
    envelope = cylinder(d.outer_diameter, 0.0, d.proximal_length)
    port_z = d.socket_port_z
    cuts = [
        cylinder(d.drawn(d.socket_diameter), -1.0, d.socket_depth),
        cylinder(
            d.reservoir_diameter, port_z - d.reservoir_length / 2, port_z + d.reservoir_length / 2
        ),
        radial_port(d.port_diameter, port_z, d.outer_diameter / 2, d.port_angle("proximal")),
        cylinder(d.passage_diameter, d.socket_depth - 0.1, d.shoulder_z - d.magnet_length + 0.1),
        cylinder(d.drawn(d.seat_diameter), d.shoulder_z - d.magnet_length, d.shoulder_z + 0.1),
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
        groove = helical_groove(d.outer_diameter, d.groove("proximal"), *d.groove_span("proximal"))
    return _cut_all(envelope, groove, cuts)


def distal_piece(d: MountingDims, with_groove: bool = True) -> cq.Solid:
    """The distal mounting piece (on the wire), in its own frame. [mm]"""
    jl = d.journal_length

    def turned(solid: cq.Solid) -> cq.Solid:
        # Cylinders with their seam at 180 deg, away from the key
        # and the groove's start: with the seam at 0, OCCT's cut of the groove from the
        # fused envelope removed nothing for some sizes.
        return solid.rotate(cq.Vector(), Z_AXIS, 180.0)

    envelope = turned(cylinder(d.journal_diameter, 0.0, jl + 0.01)).fuse(
        turned(cylinder(d.outer_diameter, jl, d.distal_length)),
        annular_sector(
            d.key_inner_diameter,
            d.outer_diameter,
            d.key_start_deg,
            d.key_angle_deg,
            jl - d.key_height,
            jl + 0.01,
        ),
    )
    groove = None
    if with_groove:
        groove = helical_groove(d.outer_diameter, d.groove("distal"), *d.groove_span("distal"))
    cz = d.chamber_z
    cuts = [
        cylinder(d.drawn(d.seat_diameter), -1.0, d.pocket_depth_distal),
        cylinder(d.drawn(d.wire_bore), d.pocket_depth_distal - 0.1, d.distal_length + 1.0),
        cylinder(d.chamber_diameter, cz - d.chamber_length / 2, cz + d.chamber_length / 2),
        radial_port(d.port_diameter, cz, d.outer_diameter / 2, d.port_angle("distal")),
    ]
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
    process: str | PrintProcess | CadProcess | None = None,
    spec: MountingSpec | None = None,
    with_groove: bool = True,
) -> MountingPieces:
    """Build both mounting pieces for ``design`` printed with ``process``.

    Parameters
    ----------
    design : The robot (SI); its ring, wire and catheter sizes set the seats and bores,
        its ``tip.mounting`` the stops (and, with ``process`` None, the process).
    process : None (the pieces the model knows): the design's own ``tip.mounting``
        (process, wall, fits, density); another process reprints them with its numbers
        (:func:`tip_design`).
    spec : Designer's choices; the defaults make the pieces the model knows.
    with_groove : Leave the helical groove out (for checks against closed-form volumes).
    """
    spec = spec or MountingSpec()
    proc = tip_process(design, process)
    design = tip_design(design, process)
    dims = mounting_dims(design, proc, spec)
    return MountingPieces(
        proximal=proximal_piece(dims, with_groove),
        distal=distal_piece(dims, with_groove),
        dims=dims,
        spec=spec,
        geometry=tip_geometry_for(design, spec),
        mounting=design.tip.mounting,
        process=proc,
    )
