"""Checks of a whole design that no single key can make: a flexible rod left under the
printed tip, a permanent magnet clear of the straight robot, the straight robot's tip
outside every obstacle."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from design.admissible import admits, quantities
from design.designfile.keys import DesignError
from design.fields.sources import KINDS as SOURCE_KINDS
from design.fields.sources import PERMANENT, magnet_distance
from design.geometry import cylinder_distance, rest_position, ring_centres
from design.mounting import design_tip_geometry
from design.obstacles import gaps, tip_body
from design.records import Design, Source
from design.units import MM


def _check_rod(design: Design) -> None:
    """Reject a free length the printed tip's rigid segment leaves no flexible rod under
    (:meth:`design.mounting.TipGeometry.rod_length`)."""
    geometry = design_tip_geometry(design)
    if not admits("rod_length", quantities(design, geometry)):
        raise DesignError(
            "robot.free_length_mm must be longer than the printed tip's rigid offset "
            f"({geometry.rigid_offset / MM:.4g} mm from where the catheter enters the "
            "proximal mounting piece to the proximal ring's centre, set by [tip] and "
            f"[tip.mounting]) so a flexible rod remains; got {design.robot.free_length / MM:g}"
        )


def _check_obstacles(design: Design) -> None:
    """The straight, unloaded robot's tip (its printed body, the larger) must start
    outside every obstacle, and a lumen must be wider than the tip."""
    body = tip_body(design, printed=True)
    rest = np.array([[design.robot.free_length, 0.0, 0.0]])
    axis = np.array([[1.0, 0.0, 0.0]])
    for i, o in enumerate(design.environment.obstacles):
        path = f"environment.obstacles[{i}]"
        if o.kind == "lumen" and o.radius <= body.radius:
            raise DesignError(
                f"{path}.radius_mm = {o.radius / MM:g} is narrower than the tip (radius "
                f"{body.radius / MM:.4g} mm); expected a lumen wider than the tip"
            )
        gap = float(gaps(o, rest, axis, body)[0][0])
        if not gap >= 0:
            raise DesignError(
                f"{path}: the straight robot's tip starts inside this {o.kind} (gap "
                f"{gap / MM:.4g} mm); expected the tip outside it at rest"
            )


def check_clearance(design: Design) -> None:
    """Reject a permanent magnet (the external magnet, a source) that overlaps the straight
    robot (base to distal ring)."""
    tip = design.tip
    proximal, distal = ring_centres(
        rest_position(design.robot.free_length), np.array([1.0, 0.0, 0.0]), tip.spacing
    )
    x = np.linspace(0.0, distal[0] + tip.magnet_length / 2, 4001)
    # The tip rings are the thickest part; the body is the catheter.
    near_tip = x >= proximal[0] - tip.magnet_length / 2
    r_body = np.where(
        near_tip, tip.magnet_outer_diameter / 2, design.robot.catheter.outer_diameter / 2
    )
    points = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    bodies = []
    ext = design.external_magnet
    if ext is not None:
        gap = cylinder_distance(
            points - np.asarray(ext.center), ext.magnetization, ext.diameter / 2, ext.length / 2
        )
        bodies.append(("external_magnet.center_mm", "magnet", gap))
    for i, src in enumerate(design.sources):
        if src.kind in PERMANENT:
            gap = source_distance(src, points)
            bodies.append((f"field.sources[{i + 1}].center_mm", f"{src.kind} magnet", gap))
    for key, what, gap in bodies:
        overlap = np.flatnonzero(gap < r_body)
        if overlap.size:
            raise DesignError(
                f"{key} places the {what} on the straight robot: it must clear the robot "
                f"(base to distal ring, radius {r_body[overlap[0]] / MM:g} mm); got an "
                f"overlap at x = {x[overlap[0]] / MM:.2f} mm in the base frame"
            )


def source_distance(source: Source, points: np.ndarray) -> np.ndarray:
    """Distance of ``points`` (n, 3) to a permanent magnet source's body
    (:func:`design.fields.sources.magnet_distance`), 0 inside. [m]"""
    p = ca.SX.sym("p", 3)
    q: dict[str, Any] = {
        k.name: ca.DM(np.ravel(getattr(source, k.name))) for k in SOURCE_KINDS[source.kind]
    }
    fn = ca.Function("distance", [p], [magnet_distance(source.kind, q, p)])
    distances = fn.map(len(points))(np.asarray(points, float).T)
    return np.asarray(distances, dtype=float).ravel()
