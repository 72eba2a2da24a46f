"""Printability and fit: checks on the exported meshes and on the assembled solids.

Lengths in millimetres. Every check is one row of a table (list of dicts, written as CSV):
``item, check, value, limit, unit, passed, note``.

Per printed part, on the STL read back with trimesh:
    watertight      the mesh is closed and consistently oriented;
    volume          mesh volume vs the CAD solid's volume (relative difference);
    min_wall        thinnest wall, absolute (no percentile): the inward ray from every
                    triangle's centroid across the material to the face it leaves by, where
                    that face looks away within :data:`KNIFE_ANGLE_DEG` of straight back (a
                    wall, or a knife edge: a wedge sharper than that angle, e.g. a groove
                    running out through an end face); a ray that leaves by a face turned
                    further (the far side of a blunter corner) measures no wall. Against the
                    process minimum; the teeth are left to their own row (tooth_tip: the
                    exact tip thickness), the meshes of helicoids being folded slivers;
    build_volume    the part's extent in its print orientation fits the build volume.
Per assembly:
    interference    for every pair of instances whose boxes overlap, signed distances of
                    dense surface samples of each to the other (VTK implicit distance):
                    overlap deeper than ``INTERFERENCE_TOLERANCE_MM`` fails; contact is
                    reported; the smallest clearance is the value.
    gears           centre distance and shaft angle measured from the cylindrical journal
                    faces of the placed solids; tooth and thread counts from the solids;
                    worm/wheel flank clearance against backlash / 2 cos(alpha_n).
"""

from __future__ import annotations

import csv
import io
import itertools
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import cadquery as cq
import numpy as np
import pyvista as pv
import trimesh
import vtk
from OCP.BRepAdaptor import BRepAdaptor_Surface

from cad.actuator import ToothZone
from cad.assembly import Instance, RobotAssembly
from cad.meshing import location_matrix, transform_points
from cad.process import CadProcess
from cad.solids import cylinder
from design.atomic import write_text

VOLUME_TOLERANCE = 0.01
KNIFE_ANGLE_DEG = 60.0
"""A wedge sharper than this is a knife edge, measured as a wall; a blunter corner (a box's
90 deg) is no wall: the wall check counts a ray only where the face it leaves by looks
away from the face it entered by within this angle of straight back. [deg]"""
INTERFERENCE_TOLERANCE_MM = 0.03
SAMPLES_PER_MM2 = 0.5
CENTRE_DISTANCE_TOLERANCE_MM = 1e-3
COLUMNS = ("item", "check", "value", "limit", "unit", "passed", "note")


@dataclass(frozen=True)
class CheckRow:
    """One line of the check table."""

    item: str
    check: str
    value: float
    limit: str
    unit: str
    passed: bool
    note: str = ""


# --- per part, on the exported mesh ---------------------------------------------------


def load_stl(path: Path) -> trimesh.Trimesh:
    """Read an exported STL back (merging coincident vertices). [mm]"""
    mesh = trimesh.load_mesh(str(path), file_type="stl", process=True)
    if not isinstance(mesh, trimesh.Trimesh):
        raise TypeError(f"{path} did not load as a single mesh")
    return mesh


def _polydata(vertices: np.ndarray, triangles: np.ndarray) -> pv.PolyData:
    faces = np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel()
    return pv.PolyData(np.asarray(vertices, dtype=float), faces)


def wall_thickness(mesh: trimesh.Trimesh, faces: np.ndarray | None = None) -> np.ndarray:
    """Wall thickness at the centroids of ``faces`` (default all), shape (k,): the inward
    ray's length to the face it leaves by, where that face looks away within
    :data:`KNIFE_ANGLE_DEG` of straight back; inf where it does not (a blunt corner) or
    where the ray leaves nothing behind (an open mesh). [mm]"""
    poly = _polydata(mesh.vertices, mesh.faces)
    locator = vtk.vtkStaticCellLocator()
    locator.SetDataSet(poly)
    locator.BuildLocator()
    length = float(np.linalg.norm(mesh.extents)) * 1.5
    idx = np.arange(len(mesh.faces)) if faces is None else np.asarray(faces)
    normals = mesh.face_normals
    centroids = mesh.triangles_center[idx]
    inward = -normals[idx]
    facing = -math.cos(math.radians(KNIFE_ANGLE_DEG))
    out = np.full(len(idx), np.inf)
    points, cells = vtk.vtkPoints(), vtk.vtkIdList()
    for k, (i, c, n) in enumerate(zip(idx, centroids, inward, strict=True)):
        points.Reset()
        cells.Reset()
        locator.IntersectWithLine(c + n * 1e-4, c + n * length, 1e-9, points, cells)
        best, exit_face = np.inf, -1
        for j in range(points.GetNumberOfPoints()):
            if cells.GetId(j) == i:
                continue
            d = float(np.dot(np.asarray(points.GetPoint(j)) - c, n))
            if 1e-6 < d < best:
                best, exit_face = d, cells.GetId(j)
        if exit_face >= 0 and float(np.dot(normals[i], normals[exit_face])) <= facing:
            out[k] = best
    return out


def part_checks(
    name: str,
    stl_path: Path,
    cad_volume: float,
    process: CadProcess,
    teeth: ToothZone | None = None,
) -> tuple[list[CheckRow], trimesh.Trimesh]:
    """Watertight, volume, smallest wall (and tooth tip) and build volume of one part.

    ``teeth``: the part's tooth zone; its triangles are left out of the ray wall check
    (the meshes of helicoid flanks and tip lands are long folded slivers, whose rays
    measure the mesh, not the wall) and the exact normal tip thickness of the teeth is
    checked instead.
    """
    mesh = load_stl(stl_path)
    closed = bool(mesh.is_watertight and mesh.is_winding_consistent)
    rows = [
        CheckRow(name, "watertight", float(closed), "1", "", closed, f"{len(mesh.faces)} triangles")
    ]
    rel = abs(mesh.volume - cad_volume) / cad_volume
    rows.append(
        CheckRow(
            name,
            "volume",
            rel,
            f"<= {VOLUME_TOLERANCE:g}",
            "relative",
            bool(mesh.volume > 0 and rel <= VOLUME_TOLERANCE),
            f"mesh {mesh.volume:.2f} mm^3 vs CAD {cad_volume:.2f} mm^3",
        )
    )
    keep = np.ones(len(mesh.faces), dtype=bool)
    if teeth is not None:
        c = mesh.triangles_center
        r = np.hypot(c[:, 0], c[:, 1])
        keep = ~((r >= teeth.min_radius_mm) & (c[:, 2] >= teeth.z0_mm) & (c[:, 2] <= teeth.z1_mm))
    measured = np.flatnonzero(keep)
    thickness = wall_thickness(mesh, measured)
    thinnest = int(np.argmin(thickness))
    wall = float(thickness[thinnest])
    x, y, z = (float(v) for v in mesh.triangles_center[measured[thinnest]])
    limit = f">= {process.min_wall_mm:g} ({process.name})"
    rows.append(
        CheckRow(
            name,
            "min_wall",
            wall,
            limit,
            "mm",
            bool(wall >= process.min_wall_mm),
            f"thinnest wall or knife edge (wedge under {KNIFE_ANGLE_DEG:g} deg) over all "
            f"{len(thickness)} triangles"
            + (" outside the teeth" if teeth is not None else "")
            + f", at ({x:.2f}, {y:.2f}, {z:.2f}) mm in the print frame; "
            f"{int(np.sum(thickness < process.min_wall_mm))} under the limit",
        )
    )
    if teeth is not None:
        rows.append(
            CheckRow(
                name,
                "tooth_tip",
                teeth.tip_thickness_mm,
                limit,
                "mm",
                teeth.tip_thickness_mm >= process.min_wall_mm,
                "normal tooth thickness at the tip, from the involute geometry",
            )
        )
    # Print orientation is kept for z; x and y may be swapped on the bed.
    bx, by, bz = process.build_volume_mm
    ex, ey, ez = (float(e) for e in mesh.extents)
    xy, bed = sorted((ex, ey), reverse=True), sorted((bx, by), reverse=True)
    fits = bool(xy[0] <= bed[0] and xy[1] <= bed[1] and ez <= bz)
    rows.append(
        CheckRow(
            name,
            "build_volume",
            max(xy[0] / bed[0], xy[1] / bed[1], ez / bz),
            "<= 1",
            "fraction",
            fits,
            f"{ex:.1f} x {ey:.1f} x {ez:.1f} mm in {process.printer}",
        )
    )
    return rows, mesh


# --- assembly ------------------------------------------------------------------------


@dataclass
class PlacedMesh:
    """An instance's mesh in the base frame with dense surface samples. [mm]"""

    instance: Instance
    surface: pv.PolyData
    samples: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


def place_meshes(assembly: RobotAssembly, meshes: dict[str, trimesh.Trimesh]) -> list[PlacedMesh]:
    """Move every instance's part mesh into the base frame and sample its surface."""
    rng = np.random.default_rng(0)
    out = []
    for inst in assembly.instances:
        mesh = meshes[inst.part]
        m = location_matrix(inst.location)
        v = transform_points(np.asarray(mesh.vertices), m)
        tri = np.asarray(mesh.faces)
        # Area samples (barycentric, uniform by area), plus vertices and centroids.
        area = mesh.area_faces
        n = int(math.ceil(mesh.area * SAMPLES_PER_MM2))
        idx = rng.choice(len(tri), size=n, p=area / area.sum())
        r1, r2 = rng.random((2, n))
        flip = r1 + r2 > 1
        r1[flip], r2[flip] = 1 - r1[flip], 1 - r2[flip]
        a, b, c = v[tri[idx, 0]], v[tri[idx, 1]], v[tri[idx, 2]]
        samples = a + r1[:, None] * (b - a) + r2[:, None] * (c - a)
        samples = np.vstack([samples, v, v[tri].mean(axis=1)])
        out.append(PlacedMesh(inst, _polydata(v, tri), samples, v.min(axis=0), v.max(axis=0)))
    return out


def _signed_distance(points: np.ndarray, surface: pv.PolyData) -> np.ndarray:
    """Signed distance of points to a closed surface, negative inside. [mm]"""
    cloud = pv.PolyData(points)
    return np.asarray(cloud.compute_implicit_distance(surface)["implicit_distance"])


def pair_clearance(a: PlacedMesh, b: PlacedMesh, margin: float = 1.0) -> float | None:
    """Smallest signed distance between two placed meshes (negative: overlap depth), or
    None when their boxes are more than ``margin`` apart. [mm]"""
    if np.any(a.lo > b.hi + margin) or np.any(b.lo > a.hi + margin):
        return None
    best = math.inf
    for p, q in ((a, b), (b, a)):
        near = np.all((p.samples >= q.lo - margin) & (p.samples <= q.hi + margin), axis=1)
        if not np.any(near):
            continue
        best = min(best, float(_signed_distance(p.samples[near], q.surface).min()))
    return None if best == math.inf else best


def interference_checks(placed: list[PlacedMesh]) -> list[CheckRow]:
    """One row per pair of instances that come within 1 mm of each other."""
    rows = []
    for a, b in itertools.combinations(placed, 2):
        d = pair_clearance(a, b)
        if d is None:
            continue
        tol = INTERFERENCE_TOLERANCE_MM
        state = "overlap" if d < -tol else ("contact" if d <= tol else "clear")
        rows.append(
            CheckRow(
                f"{a.instance.name} / {b.instance.name}",
                "interference",
                d,
                f">= -{tol:g}",
                "mm",
                state != "overlap",
                state,
            )
        )
    return rows


def cylinder_axis(
    solid: cq.Shape, radius: float, tol: float = 1e-6
) -> tuple[np.ndarray, np.ndarray]:
    """Point and unit direction of the first cylindrical face of ``radius``. [mm]"""
    for face in solid.Faces():
        if face.geomType() != "CYLINDER":
            continue
        cyl = BRepAdaptor_Surface(face.wrapped).Cylinder()
        if abs(cyl.Radius() - radius) < tol:
            ax = cyl.Axis()
            p, d = ax.Location(), ax.Direction()
            return np.array([p.X(), p.Y(), p.Z()]), np.array([d.X(), d.Y(), d.Z()])
    raise ValueError(f"no cylindrical face of radius {radius} mm")


def axis_distance(p1: np.ndarray, d1: np.ndarray, p2: np.ndarray, d2: np.ndarray) -> float:
    """Shortest distance between two lines. [mm]"""
    n = np.cross(d1, d2)
    if np.linalg.norm(n) < 1e-12:
        return float(np.linalg.norm(np.cross(p2 - p1, d1)))
    return float(abs(np.dot(p2 - p1, n)) / np.linalg.norm(n))


def count_teeth(
    solid: cq.Shape, inner_radius: float, outer_radius: float, z0: float, z1: float
) -> int:
    """Number of separate pieces of ``solid`` inside an annulus about Z (print frame)."""
    ring = cylinder(2 * outer_radius, z0, z1).cut(cylinder(2 * inner_radius, z0 - 1, z1 + 1))
    return len(solid.intersect(ring).Solids())


def gear_checks(assembly: RobotAssembly, interference: list[CheckRow]) -> list[CheckRow]:
    """Centre distance, shaft angle, tooth count and flank clearance of both drives.

    ``interference``: the rows of :func:`interference_checks`, for the worm-wheel pairs'
    smallest distance.
    """
    lay = assembly.actuator.layout
    drive = lay.drive
    a = drive.centre_distance_mm
    rows = []
    distance = {r.item: r.value for r in interference}
    insts = {i.name: i for i in assembly.instances}
    for tag in ("front", "rear"):
        shaft = assembly.placed(insts[f"gear_shaft_{tag}"])
        worm = assembly.placed(insts[f"worm_{tag}"])
        p1, d1 = cylinder_axis(shaft, lay.spec.shaft_journal_mm / 2)
        p2, d2 = cylinder_axis(worm, lay.spec.worm_journal_mm / 2)
        dist = axis_distance(p1, d1, p2, d2)
        angle = math.degrees(math.acos(min(1.0, abs(float(np.dot(d1, d2))))))
        rows.append(
            CheckRow(
                f"drive {tag}",
                "centre_distance",
                dist,
                f"{a:.4f} +- {CENTRE_DISTANCE_TOLERANCE_MM:g}",
                "mm",
                abs(dist - a) <= CENTRE_DISTANCE_TOLERANCE_MM,
                "measured between the journal axes of the placed solids; a = m (q + z2) / 2",
            )
        )
        rows.append(
            CheckRow(
                f"drive {tag}", "shaft_angle", angle, "90 +- 0.01", "deg", abs(angle - 90) < 0.01
            )
        )
        clearance = distance.get(f"gear_shaft_{tag} / worm_{tag}")
        expected = (
            drive.backlash_mm / 2 * math.cos(math.radians(drive.spec.normal_pressure_angle_deg))
        )
        rows.append(
            CheckRow(
                f"drive {tag}",
                "flank_clearance",
                math.nan if clearance is None else clearance,
                f"> 0 (expected {expected:.3f})",
                "mm",
                clearance is not None and clearance > 0,
                "smallest worm-wheel distance on the meshes; expected backlash/2 cos(alpha_n)",
            )
        )
    wheel = drive.wheel_profile
    b2 = drive.spec.wheel_face_width_mm
    n_teeth = count_teeth(
        assembly.parts["gear_shaft_front"].solid,
        wheel.pitch_radius_mm,
        wheel.tip_radius_mm + 1.0,
        0.0,
        b2,
    )
    rows.append(
        CheckRow(
            "gear_shaft_front",
            "tooth_count",
            n_teeth,
            f"== {drive.spec.wheel_teeth}",
            "",
            n_teeth == drive.spec.wheel_teeth,
            "pieces of the wheel outside its pitch circle",
        )
    )
    return rows


# --- table ---------------------------------------------------------------------------


def rows_as_dicts(rows: list[CheckRow]) -> list[dict[str, object]]:
    """The table as a list of dicts (one per row)."""
    return [asdict(r) for r in rows]


def write_csv(rows: list[CheckRow], path: Path) -> Path:
    """Write the check table as CSV, atomically."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    for r in rows:
        d = asdict(r)
        d["value"] = f"{r.value:.6g}"
        writer.writerow(d)
    write_text(path, buf.getvalue())
    return Path(path)
