"""The design's field sources as surfaces for the set-up render, in the base frame (mm):
the ``[external_magnet]`` and the permanent-magnet sources split into their north (red)
and south (blue) halves along the magnetisation (as the rings are drawn), coils as a
copper ring of their radius. A uniform field and a map have no body: they are named in
the render's title instead (:func:`bodiless`)."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from cad.assembly import Colour
from design.records import Design
from design.units import MM

NORTH: Colour = (0.85, 0.25, 0.22)
SOUTH: Colour = (0.22, 0.40, 0.80)
COPPER: Colour = (0.80, 0.50, 0.25)


def _halves(
    centre: np.ndarray, axis: np.ndarray, length: float, body
) -> list[tuple[pv.PolyData, Colour]]:
    """North and south halves of a body ``body(centre, half_length)`` along ``axis``."""
    return [
        (body(centre + sign * axis * length / 4, length / 2), colour)
        for sign, colour in ((1.0, NORTH), (-1.0, SOUTH))
    ]


def _cylinder(centre: np.ndarray, axis: np.ndarray, diameter: float, length: float):
    def body(c: np.ndarray, h: float) -> pv.PolyData:
        return pv.Cylinder(center=c, direction=axis, radius=diameter / 2, height=h, resolution=96)

    return _halves(centre, axis, length, body)


def source_meshes(design: Design) -> list[tuple[pv.PolyData, Colour]]:
    """Surfaces of every field source of ``design`` with a body, base frame. [mm]"""
    out: list[tuple[pv.PolyData, Colour]] = []
    ext = design.external_magnet
    if ext is not None:
        out += _cylinder(
            np.array(ext.center) / MM,
            np.array(ext.magnetization),
            ext.diameter / MM,
            ext.length / MM,
        )
    for s in design.sources:
        centre, axis = np.array(s.center) / MM, np.array(s.magnetization)
        if s.kind == "cylinder":
            out += _cylinder(centre, axis, s.diameter / MM, s.length / MM)
        elif s.kind == "sphere":
            r = s.diameter / MM / 2
            ball = pv.Sphere(radius=r, center=centre, theta_resolution=64, phi_resolution=64)
            out += [
                (ball.clip(normal=-axis, origin=centre), NORTH),
                (ball.clip(normal=axis, origin=centre), SOUTH),
            ]
        elif s.kind == "cuboid":
            half = np.array(s.dimensions) / MM / 2
            block = pv.Box(bounds=np.column_stack([centre - half, centre + half]).ravel())
            block = block.triangulate().subdivide(3)
            out += [
                (block.clip(normal=-axis, origin=centre), NORTH),
                (block.clip(normal=axis, origin=centre), SOUTH),
            ]
        elif s.kind == "coil":
            loop = pv.Circle(radius=s.radius / MM, resolution=180)
            loop = pv.lines_from_points(np.vstack([loop.points, loop.points[:1]]))
            # the loop drawn in its plane: turn the circle's normal (z) onto the coil's axis
            turned = loop.transform(_onto(np.array(s.axis)), inplace=False)
            thickness = max(s.radius / MM / 30, 1.0)
            out.append((turned.translate(centre).tube(radius=thickness, n_sides=24), COPPER))
    return out


def bodiless(design: Design) -> list[str]:
    """The sources a render cannot draw, in words (a uniform field, a field map)."""
    words = []
    for s in design.sources:
        if s.kind == "uniform":
            words.append("uniform field " + ", ".join(f"{b * 1e3:g}" for b in s.b) + " mT")
        elif s.kind == "map":
            words.append("field map")
    return words


def _onto(axis: np.ndarray) -> np.ndarray:
    """4x4 rotation taking +z onto the unit vector ``axis`` (Rodrigues)."""
    z = np.array([0.0, 0.0, 1.0])
    v, c = np.cross(z, axis), float(np.dot(z, axis))
    m = np.eye(4)
    if np.linalg.norm(v) < 1e-12:
        m[:3, :3] = np.diag([1.0, np.sign(c) or 1.0, np.sign(c) or 1.0])
        return m
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    m[:3, :3] = np.eye(3) + k + k @ k / (1.0 + c)
    return m
