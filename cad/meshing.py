"""Triangle meshes of the CAD solids, and the placement of meshes by CadQuery locations.

CAD works in millimetres: vertices are in mm.

``tessellate`` meshes with an *absolute* chord tolerance (CadQuery's own ``tessellate``
uses a tolerance relative to each face's size, which leaves the long helical faces of a
worm 0.3 mm off). Surface-deflection control is off: on the high-degree B-spline faces
of swept threads it multiplies the triangle count by four for a few hundredths of a
percent of volume.
"""

from __future__ import annotations

import cadquery as cq
import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.IMeshTools import IMeshTools_Parameters
from OCP.TopAbs import TopAbs_Orientation
from OCP.TopLoc import TopLoc_Location


def tessellate(
    solid: cq.Shape, linear_deflection_mm: float, angular_deflection_rad: float = 0.3
) -> tuple[np.ndarray, np.ndarray]:
    """Vertices, shape (n, 3) [mm], and triangles, shape (m, 3) [-], of ``solid``.

    OCCT meshes faces so that neighbouring faces share their edge points; coincident
    vertices of neighbouring faces are merged here, so a valid solid gives a closed
    (watertight), outward-oriented surface.
    """
    params = IMeshTools_Parameters()
    params.Deflection = linear_deflection_mm
    params.Angle = angular_deflection_rad
    params.Relative = False
    params.InParallel = True
    params.ControlSurfaceDeflection = False
    BRepMesh_IncrementalMesh(solid.wrapped, params)
    verts: list[np.ndarray] = []
    tris: list[np.ndarray] = []
    offset = 0
    for face in solid.Faces():
        loc = TopLoc_Location()
        poly = BRep_Tool.Triangulation_s(face.wrapped, loc)
        if poly is None:
            continue
        trsf = loc.Transformation()
        nodes = np.array(
            [poly.Node(i).Transformed(trsf).Coord() for i in range(1, poly.NbNodes() + 1)]
        )
        t = np.array(
            [poly.Triangle(i).Get() for i in range(1, poly.NbTriangles() + 1)], dtype=np.int64
        )
        t -= 1
        if face.wrapped.Orientation() == TopAbs_Orientation.TopAbs_REVERSED:
            t = t[:, [0, 2, 1]]
        verts.append(nodes)
        tris.append(t + offset)
        offset += len(nodes)
    v = np.vstack(verts)
    t = np.vstack(tris)
    # Merge the copies of edge points that neighbouring faces share.
    key = np.round(v / 1e-7).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    v = v[first]
    t = inverse.reshape(-1)[t]
    keep = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    return v, t[keep]


def location_matrix(location: cq.Location) -> np.ndarray:
    """The 4 x 4 homogeneous matrix of a CadQuery location (mm)."""
    trsf = location.wrapped.Transformation()
    m = np.eye(4)
    for i in range(3):
        for j in range(4):
            m[i, j] = trsf.Value(i + 1, j + 1)
    return m


def transform_points(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4 x 4 homogeneous transform to points, shape (n, 3). [mm]"""
    return points @ matrix[:3, :3].T + matrix[:3, 3]
