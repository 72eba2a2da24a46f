"""Small solid primitives and frames shared by the part modules.

CAD works in millimetres: every length here is in mm, angles in degrees.
"""

from __future__ import annotations

import math

import cadquery as cq

X_AXIS = cq.Vector(1, 0, 0)
Y_AXIS = cq.Vector(0, 1, 0)
Z_AXIS = cq.Vector(0, 0, 1)
ORIGIN = cq.Vector(0, 0, 0)


def cylinder(diameter: float, z0: float, z1: float) -> cq.Solid:
    """Solid cylinder on the Z axis from z0 to z1. [mm]"""
    return cq.Solid.makeCylinder(diameter / 2, z1 - z0, cq.Vector(0, 0, z0), Z_AXIS)


def tube(outer: float, inner: float, z0: float, z1: float) -> cq.Solid:
    """Hollow cylinder on the Z axis from z0 to z1. [mm]"""
    return cylinder(outer, z0, z1).cut(cylinder(inner, z0 - 1.0, z1 + 1.0))


def cylinder_along(
    diameter: float, start: tuple[float, float, float], direction: cq.Vector, length: float
) -> cq.Solid:
    """Solid cylinder from ``start`` along unit ``direction`` over ``length``. [mm]"""
    return cq.Solid.makeCylinder(diameter / 2, length, cq.Vector(*start), direction)


def box(x: tuple[float, float], y: tuple[float, float], z: tuple[float, float]) -> cq.Solid:
    """Axis-aligned box spanning the given (lo, hi) intervals. [mm]"""
    return cq.Solid.makeBox(x[1] - x[0], y[1] - y[0], z[1] - z[0], cq.Vector(x[0], y[0], z[0]))


def annular_sector(
    inner_diameter: float,
    outer_diameter: float,
    start_deg: float,
    span_deg: float,
    z0: float,
    z1: float,
) -> cq.Solid:
    """Ring sector about Z from ``start_deg`` over ``span_deg``, z0 to z1. [mm]"""
    h = z1 - z0
    outer = cq.Solid.makeCylinder(outer_diameter / 2, h, cq.Vector(0, 0, z0), Z_AXIS, span_deg)
    inner = cq.Solid.makeCylinder(inner_diameter / 2, h, cq.Vector(0, 0, z0), Z_AXIS, span_deg)
    return outer.cut(inner).rotate(ORIGIN, Z_AXIS, start_deg)


def radial_port(diameter: float, z: float, outer_radius: float, angle_deg: float) -> cq.Solid:
    """Radial hole from the Z axis outwards at height ``z``, towards ``angle_deg``. [mm]"""
    a = math.radians(angle_deg)
    direction = cq.Vector(math.cos(a), math.sin(a), 0)
    return cq.Solid.makeCylinder(diameter / 2, outer_radius + 1.0, cq.Vector(0, 0, z), direction)


def hexagon_prism(across_flats: float, z0: float, z1: float) -> cq.Solid:
    """Hexagonal prism on the Z axis (flats normal to +-X), z0 to z1. [mm]"""
    r = across_flats / 2 / math.cos(math.pi / 6)
    pts = [
        cq.Vector(
            r * math.cos(math.radians(30 + 60 * k)), r * math.sin(math.radians(30 + 60 * k)), z0
        )
        for k in range(6)
    ]
    face = cq.Face.makeFromWires(cq.Wire.makePolygon(pts, close=True))
    return cq.Solid.extrudeLinear(face, cq.Vector(0, 0, z1 - z0))


def frame(
    origin: tuple[float, float, float],
    z_dir: tuple[float, float, float],
    x_dir: tuple[float, float, float],
) -> cq.Location:
    """Location mapping a part's local frame to one with this origin, Z and X (right-handed)."""
    return cq.Location(cq.Plane(cq.Vector(*origin), cq.Vector(*x_dir), cq.Vector(*z_dir)))


def single_solid(shape: cq.Shape, name: str) -> cq.Solid:
    """The one valid solid of ``shape``; raise :class:`~cad.errors.CadError` otherwise."""
    from cad.errors import require

    solids = shape.Solids()
    require(
        len(solids) == 1, f"{name}: number of solids", "1 (one connected part)", len(solids), ""
    )
    solid = solids[0]
    require(solid.isValid(), f"{name}: solid", "valid after the boolean operations", 0, "")
    return solid
