"""Worm drive: involute geometry, numbers measured back from the solids, self-locking.

References: ISO 21771:2007 (involute, base circle); DIN 3975 / Niemann & Winter Bd. III
sec. 24 (worm geometry, a = m (q + z2) / 2, self-locking when gamma < arctan(mu/cos an)).
"""

from __future__ import annotations

import math
from dataclasses import replace

import cadquery as cq
import numpy as np
import pytest
import vtk

from cad.assembly import RobotAssembly
from cad.build import CadReport
from cad.checks import _polydata, load_stl, pair_clearance, place_meshes
from cad.gears import WormDrive, WormDriveSpec
from cad.involute import ToothProfile
from cad.selflocking import self_locking


def test_flank_is_the_involute_of_the_base_circle() -> None:
    # Parametric involute of a circle of radius rb, unwinding clockwise from angle t0:
    # P(t) = rb (cos(t0 - t) - t sin(t0 - t), sin(t0 - t) + t cos(t0 - t)).
    drive = WormDrive(WormDriveSpec(), backlash_mm=0.2)
    profile = drive.wheel_profile
    rb = profile.base_radius_mm
    t0 = float(profile.half_angle(rb))
    wire = profile.wire()
    flanks = [e for e in wire.Edges() if e.geomType() == "BSPLINE"]
    assert len(flanks) == 2 * profile.teeth
    # Tooth 0 is centred on +X; its left flank lies between 0 and half a pitch.
    half_pitch = math.pi / profile.teeth
    (left,) = [
        e for e in flanks if 0 < math.atan2(e.positionAt(0.5).y, e.positionAt(0.5).x) < half_pitch
    ]
    worst = 0.0
    for s in np.linspace(0.0, 1.0, 41):
        p = left.positionAt(s)
        r = math.hypot(p.x, p.y)
        t = math.sqrt(max((r / rb) ** 2 - 1.0, 0.0))
        q = rb * np.array(
            [math.cos(t0 - t) - t * math.sin(t0 - t), math.sin(t0 - t) + t * math.cos(t0 - t)]
        )
        worst = max(worst, float(np.hypot(p.x - q[0], p.y - q[1])))
    assert worst < 2e-3  # mm


def test_worm_geometry_numbers() -> None:
    drive = WormDrive(WormDriveSpec(module_mm=1.5, wheel_teeth=30, diameter_quotient=10.0), 0.2)
    assert drive.lead_angle_deg == pytest.approx(math.degrees(math.atan(0.1)))
    assert drive.centre_distance_mm == pytest.approx(1.5 * (10 + 30) / 2)
    assert drive.ratio == pytest.approx(30.0)
    # Same normal module on both members: the worm's transverse profile and the wheel's.
    worm, wheel = drive.worm_profile, drive.wheel_profile
    assert worm.pitch_radius_mm + wheel.pitch_radius_mm == pytest.approx(drive.centre_distance_mm)
    tan_an = math.tan(math.radians(20.0))
    gamma = math.radians(drive.lead_angle_deg)
    assert math.tan(wheel.transverse_pressure_angle) * math.cos(gamma) == pytest.approx(tan_an)
    assert math.tan(worm.transverse_pressure_angle) * math.sin(gamma) == pytest.approx(tan_an)


def _axis_from_circles(solid: cq.Shape, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Axis through the centres of the circular edges of ``radius`` (journal ends). [mm]"""
    centres = [
        np.array(e.arcCenter().toTuple())
        for e in solid.Edges()
        if e.geomType() == "CIRCLE" and abs(e.radius() - radius) < 1e-6
    ]
    a = centres[0]
    b = max(centres, key=lambda c: float(np.linalg.norm(c - a)))
    assert np.linalg.norm(b - a) > 5.0
    return a, (b - a) / np.linalg.norm(b - a)


def _line_distance(p1, d1, p2, d2) -> float:
    n = np.cross(d1, d2)
    return float(abs(np.dot(p2 - p1, n)) / np.linalg.norm(n))


def test_centre_distance_measured_from_the_solids(fdm_assembly: RobotAssembly) -> None:
    lay = fdm_assembly.actuator.layout
    insts = {i.name: i for i in fdm_assembly.instances}
    for tag in ("front", "rear"):
        shaft = fdm_assembly.placed(insts[f"gear_shaft_{tag}"])
        worm = fdm_assembly.placed(insts[f"worm_{tag}"])
        p1, d1 = _axis_from_circles(shaft, lay.spec.shaft_journal_mm / 2)
        p2, d2 = _axis_from_circles(worm, lay.spec.worm_journal_mm / 2)
        assert abs(float(np.dot(d1, d2))) < 1e-9  # axes cross at 90 deg
        assert _line_distance(p1, d1, p2, d2) == pytest.approx(
            lay.drive.centre_distance_mm, abs=1e-6
        )


def test_tooth_count_measured_from_the_solid(fdm_assembly: RobotAssembly) -> None:
    drive = fdm_assembly.actuator.layout.drive
    wheel = fdm_assembly.parts["gear_shaft_front"].solid  # print frame: wheel from z = 0
    r = (drive.wheel_profile.pitch_radius_mm + drive.wheel_profile.tip_radius_mm) / 2
    circle = cq.Edge.makeCircle(r, cq.Vector(0, 0, drive.spec.wheel_face_width_mm / 2))
    assert len(wheel.intersect(circle).Edges()) == drive.spec.wheel_teeth


def test_worm_axial_pitch_measured_from_the_exported_mesh(fdm_build: CadReport) -> None:
    # A line parallel to the worm's axis through the thread crosses it once per axial
    # pitch p_x = pi m (single start). OCCT's line/B-spline intersection misses crossings
    # of the helicoid faces, so this is measured on the exported STL.
    drive = fdm_build.assembly.actuator.layout.drive
    teeth = fdm_build.assembly.actuator.teeth["worm"]
    mesh = load_stl(fdm_build.out_dir / "stl" / "worm.stl")
    rw = (drive.worm_profile.pitch_radius_mm + drive.worm_profile.tip_radius_mm) / 2
    tree = vtk.vtkOBBTree()
    tree.SetDataSet(_polydata(mesh.vertices, mesh.faces))
    tree.BuildLocator()
    hits = vtk.vtkPoints()
    tree.IntersectWithLine((rw, 0.0, teeth.z0_mm + 0.5), (rw, 0.0, teeth.z1_mm - 0.5), hits, None)
    z = np.sort([hits.GetPoint(i)[2] for i in range(hits.GetNumberOfPoints())])
    assert len(z) % 2 == 0 and len(z) >= 10  # enter/leave pairs, several turns
    mids = (z[0::2] + z[1::2]) / 2
    pitch = np.diff(mids)
    assert pitch == pytest.approx(np.full_like(pitch, math.pi * drive.spec.module_mm), abs=0.02)


def test_flank_clearance_is_the_backlash(fdm_build: CadReport) -> None:
    drive = fdm_build.assembly.actuator.layout.drive
    expected = drive.backlash_mm / 2 * math.cos(math.radians(drive.spec.normal_pressure_angle_deg))
    rows = [r for r in fdm_build.checks if r["check"] == "flank_clearance"]
    assert len(rows) == 2
    for row in rows:
        assert row["value"] == pytest.approx(expected, abs=0.02)  # mesh chord 0.02 mm


def test_wheel_turned_past_the_backlash_collides_with_the_worm(fdm_build: CadReport) -> None:
    assembly = fdm_build.assembly
    meshes = {
        n: load_stl(fdm_build.out_dir / "stl" / f"{n}.stl") for n in ("gear_shaft_front", "worm")
    }
    insts = {i.name: i for i in assembly.instances}
    drive = assembly.actuator.layout.drive
    play_deg = math.degrees(drive.backlash_mm / 2 / drive.wheel_profile.pitch_radius_mm)

    def clearance(turn_deg: float) -> float:
        shaft = insts["gear_shaft_front"]
        # Turn the wheel about its own axis (print-frame Z) before placing it.
        loc = shaft.location * cq.Location(cq.Vector(), cq.Vector(0, 0, 1), turn_deg)
        sub = replace(assembly, instances=[replace(shaft, location=loc), insts["worm_front"]])
        a, b = place_meshes(sub, meshes)
        d = pair_clearance(a, b)
        assert d is not None
        return d

    assert clearance(0.0) > 0.05
    assert clearance(3 * play_deg) < -0.02
    assert clearance(-3 * play_deg) < -0.02


def test_self_locking_either_side_of_the_limit() -> None:
    # Limit: mu* = tan(gamma) cos(alpha_n); gamma = atan(1/10), alpha_n = 20 deg.
    gamma = math.degrees(math.atan(0.1))
    mu_limit = 0.1 * math.cos(math.radians(20.0))
    below = self_locking(gamma, 0.95 * mu_limit, 20.0)
    above = self_locking(gamma, 1.05 * mu_limit, 20.0)
    assert not below.self_locking and below.backward_efficiency > 0
    assert above.self_locking and above.backward_efficiency < 0
    assert self_locking(gamma, mu_limit, 20.0).margin_deg == pytest.approx(0.0, abs=1e-9)


def test_demonstrator_drive_is_self_locking_with_numbers(fdm_build: CadReport) -> None:
    lock = fdm_build.self_locking
    assert lock is not None
    assert lock.lead_angle_deg == pytest.approx(5.7106, abs=1e-4)
    assert lock.friction_angle_deg == pytest.approx(
        math.degrees(math.atan(0.2 / math.cos(math.radians(20))))
    )
    assert lock.self_locking
    # Frictionless limit: a screw is 100 % efficient.
    assert self_locking(5.71, 0.0).forward_efficiency == pytest.approx(1.0)


def test_profile_rejects_pointed_teeth() -> None:
    from cad.errors import CadError

    profile = ToothProfile(8, 1.0, math.radians(20.0), 1.6, 1.25)
    with pytest.raises(CadError, match="tooth tip half-thickness"):
        profile.check("wheel")
