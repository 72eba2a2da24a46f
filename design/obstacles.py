"""Rigid obstacles (planes, spheres, lumens) and the gap between them and the tip's body.

The tip's body is the solid cylinder the robot would touch with: the printed tip's outer
diameter over its rigid segment with ``printed_tip``, else the rings' outer diameter from
the proximal ring's proximal face to the distal ring's far face (:func:`tip_body`). Its
axis runs along the tip tangent t through the tracked point P, from P - back t to
P + front t, radius R.

The gap (:func:`gaps`), positive outside, and the point of the body nearest to the
obstacle, with the unit normal along which the obstacle pushes the tip:

- ``plane`` (a point p0 and outward normal n, the side the robot stays on): the lowest
  point of the cylinder is on an end rim: min over the ends e of n (e - p0) - R s,
  s = sqrt(1 - (n t)^2), at e - R (n - (n t) t) / s; exact.
- ``sphere`` (centre c, radius rho, the robot outside): the distance from c to the solid
  cylinder, minus rho (the cylinder's side, an end face or a rim, by where c projects);
  exact.
- ``lumen`` (a point p0 on its axis u, radius rho, the tip inside a vessel): rho minus the
  largest distance of the two end rims from the lumen's axis, each rim at RIM_POINTS
  points (the side of a cylinder inside a tube touches with a rim).

SI units (m).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from design.records import Obstacle

KINDS = ("plane", "sphere", "lumen")
RIM_POINTS = 720
"""Points per end rim where the lumen's gap is sampled (a radius-3 mm rim: 26 um apart,
the gap to about 0.1 um)."""


@dataclass(frozen=True)
class TipBody:
    """The tip's solid cylinder about its tracked point: radius [m], and how far it
    reaches behind (``back``) and ahead of (``front``) the tracked point along the tip
    tangent [m]."""

    radius: float
    back: float
    front: float


def tip_body(design: Any, printed: bool) -> TipBody:
    """The tip's body of ``design`` (a :class:`~design.records.Design`): the printed
    tip's (``printed``, :func:`design.mounting.design_tip_geometry`) or the bare rings'
    (module docstring). [m]"""
    from design.mounting import design_tip_geometry

    tip = design.tip
    if printed:
        g = design_tip_geometry(design)
        offset = float(g.rigid_offset)
        return TipBody(float(g.outer_diameter) / 2, offset, float(g.rigid_length) - offset)
    h = tip.magnet_length
    return TipBody(tip.magnet_outer_diameter / 2, h / 2, h + tip.magnet_gap + h / 2)


def _ends(position: np.ndarray, tangent: np.ndarray, body: TipBody) -> np.ndarray:
    """The axis's two ends, (N, 2, 3). [m]"""
    return np.stack([position - body.back * tangent, position + body.front * tangent], axis=1)


def _plane(o: Obstacle, position, tangent, body):
    n = np.asarray(o.normal, float) / np.linalg.norm(o.normal)
    ends = _ends(position, tangent, body)
    nt = tangent @ n
    lateral = n[None, :] - nt[:, None] * tangent
    s = np.linalg.norm(lateral, axis=1)
    heights = (ends - np.asarray(o.point)) @ n  # (N, 2)
    k = np.argmin(heights, axis=1)
    rows = np.arange(len(position))
    unit = np.where(s[:, None] > 1e-12, lateral / np.maximum(s, 1e-300)[:, None], 0.0)
    gap = heights[rows, k] - body.radius * s
    point = ends[rows, k] - body.radius * unit
    return gap, point, np.broadcast_to(n, point.shape).copy()


def _sphere(o: Obstacle, position, tangent, body):
    start = position - body.back * tangent
    length = body.back + body.front
    rel = np.asarray(o.point) - start
    h = np.einsum("ij,ij->i", rel, tangent)
    radial = rel - h[:, None] * tangent
    rc = np.linalg.norm(radial, axis=1)
    out = np.where(rc[:, None] > 1e-15, radial / np.maximum(rc, 1e-300)[:, None], 0.0)
    hc = np.clip(h, 0.0, length)
    # the body's point nearest to the centre: on the axis at hc, out to the radius at most
    nearest = start + hc[:, None] * tangent + np.minimum(rc, body.radius)[:, None] * out
    away = nearest - np.asarray(o.point)
    distance = np.linalg.norm(away, axis=1)
    inside = (h >= 0) & (h <= length) & (rc <= body.radius)
    gap = np.where(inside, -np.inf, distance - o.radius)
    normal = away / np.maximum(distance, 1e-300)[:, None]
    return gap, nearest, normal


def _lumen(o: Obstacle, position, tangent, body):
    u = np.asarray(o.normal, float) / np.linalg.norm(o.normal)
    ends = _ends(position, tangent, body)
    # two unit vectors across the tangent
    helper = np.where(np.abs(tangent[:, :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    e1 = np.cross(tangent, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(tangent, e1)
    phi = np.linspace(0.0, 2 * np.pi, RIM_POINTS, endpoint=False)
    ring = body.radius * (
        np.cos(phi)[None, :, None] * e1[:, None, :] + np.sin(phi)[None, :, None] * e2[:, None, :]
    )  # (N, P, 3)
    points = (ends[:, :, None, :] + ring[:, None, :, :]).reshape(len(position), -1, 3)
    rel = points - np.asarray(o.point)
    radial = rel - (rel @ u)[:, :, None] * u
    r = np.linalg.norm(radial, axis=2)
    k = np.argmax(r, axis=1)
    rows = np.arange(len(position))
    gap = o.radius - r[rows, k]
    point = points[rows, k]
    normal = -radial[rows, k] / np.maximum(r[rows, k], 1e-300)[:, None]
    return gap, point, normal


def gaps(
    obstacle: Obstacle, position: np.ndarray, tangent: np.ndarray, body: TipBody
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For tips at ``position`` (N, 3) with ``tangent`` (N, 3): (gap (N,), positive
    outside, -inf with a sphere's centre inside the body [m]; the body's point nearest to
    the obstacle (N, 3) [m]; the unit normal along which the obstacle pushes there
    (N, 3))."""
    position = np.atleast_2d(position)
    tangent = np.atleast_2d(tangent)
    return {"plane": _plane, "sphere": _sphere, "lumen": _lumen}[obstacle.kind](
        obstacle, position, tangent, body
    )
