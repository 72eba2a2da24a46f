"""Geometry of the set-up shared by the model, the NLP, design-file checks, the workspace
and the CAD: where the rest tip, the rings and the external magnet are, and how far apart.

Base frame: origin at the clamp, +x along the straight robot. The proximal ring's centre,
the tracked tip, lies at s = L (``robot.free_length``); the distal ring's lies one centre
spacing (ring length + gap) further along the tip tangent. In the paper's baseline the
proximal ring's centre is the rod's end; with the printed tip (:mod:`design.mounting`,
model effect ``printed_tip``) the rod ends ``rigid_offset`` before it and a rigid segment
carries the rings, so the straight robot's tracked tip is at s = L either way. The external
magnet's distance is measured from the rest tip, so a study moves the magnet along the line
from the rest tip through its centre.

Each function takes numbers (numpy arrays, broadcasting over leading axes) or CasADi
expressions alike. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

SMOOTH = 1e-12
"""Floor under square roots of squared lengths, keeping them differentiable at zero. [m]"""


def is_symbolic(*values: Any) -> bool:
    """Whether any of ``values`` is a CasADi expression or matrix (else numbers)."""
    return any(isinstance(v, ca.SX | ca.MX | ca.DM) for v in values)


def cylinder_distance(offset: Any, axis: Any, radius: Any, half_length: Any) -> Any:
    """Distance from a point to a solid cylinder (0 inside). [m]

    offset : point minus the cylinder's centre, shape (3,) (numpy: (..., 3)). [m]
    axis : unit vector of the cylinder's axis, shape (3,). [-]
    radius, half_length : of the cylinder. [m]
    The distance is hypot(max(|a| - half_length, 0), max(rho - radius, 0)) with the axial
    and radial coordinates a and rho of the point: exact outside the cylinder.
    """
    if is_symbolic(offset, axis, radius, half_length):
        axial = ca.dot(offset, axis)
        radial = ca.sqrt(ca.fmax(ca.sumsqr(offset) - axial**2, 0) + SMOOTH**2)
        outside_axial = ca.fmax(ca.fabs(axial) - half_length, 0)
        outside_radial = ca.fmax(radial - radius, 0)
        return ca.sqrt(outside_axial**2 + outside_radial**2 + SMOOTH**2)
    offset = np.asarray(offset, float)
    axial = offset @ np.asarray(axis, float)
    radial = np.sqrt(np.maximum(np.sum(offset**2, axis=-1) - axial**2, 0.0))
    outside_axial = np.maximum(np.abs(axial) - half_length, 0.0)
    outside_radial = np.maximum(radial - radius, 0.0)
    return np.hypot(outside_axial, outside_radial)


def rest_position(free_length: Any) -> Any:
    """The unloaded, straight rod's tip (the proximal ring's centre), base frame: (L, 0, 0),
    shape (3,). [m]"""
    if is_symbolic(free_length):
        return ca.vertcat(free_length, 0, 0)
    return np.array([free_length, 0.0, 0.0])


def magnet_spacing(magnet_length: Any, gap: Any) -> Any:
    """Centre-to-centre distance of the two rings along the tip tangent: ring length plus the
    face-to-face gap. [m]"""
    return magnet_length + gap


def ring_centres(tip_position: Any, tangent: Any, spacing: Any) -> tuple[Any, Any]:
    """(proximal, distal) ring centres, base frame, shape (3,) each: the proximal ring sits
    on the rod tip, the distal ring one ``spacing`` further along the unit ``tangent``. [m]"""
    return tip_position, tip_position + spacing * tangent


def ring_clearance(
    centres: Any,
    magnet_outer_diameter: Any,
    magnet_length: Any,
    external_center: Any,
    external_magnetization: Any,
    external_diameter: Any,
    external_length: Any,
) -> Any:
    """Clearance of the rings to the external magnet: the least distance of a ring centre to
    the cylinder (:func:`cylinder_distance`) less the radius of the sphere that holds a ring
    (:func:`ring_radius`); negative where they may touch. [m]

    centres : the ring centres (e.g. :func:`ring_centres`), each shape (3,). [m]
    magnet_outer_diameter, magnet_length : the rings' size. [m]
    external_center : the external magnet's centre, base frame, shape (3,). [m]
    external_magnetization : unit vector of its axis, shape (3,). [-]
    external_diameter, external_length : its size. [m]
    """
    half, radius = external_length / 2, external_diameter / 2
    reach = ring_radius(magnet_outer_diameter, magnet_length)
    distances = [
        cylinder_distance(centre - external_center, external_magnetization, radius, half)
        for centre in centres
    ]
    if is_symbolic(*distances):
        nearest = distances[0]
        for d in distances[1:]:
            nearest = ca.fmin(nearest, d)
        return nearest - reach
    return np.minimum.reduce(distances) - reach


def _offset_from_rest(free_length: Any, magnet_centre: Any, symbolic: bool) -> tuple[Any, Any]:
    """(rest tip, magnet centre less the rest tip), shape (3,) each, CasADi columns when
    ``symbolic``. [m]"""
    rest = rest_position(free_length)
    if symbolic:
        return ca.vertcat(rest), ca.vertcat(magnet_centre) - ca.vertcat(rest)
    return rest, np.asarray(magnet_centre, float) - rest


def external_distance(free_length: Any, magnet_centre: Any) -> Any:
    """Distance of the external magnet's centre (shape (3,); numpy: (..., 3)) from the rest
    tip. [m]"""
    symbolic = is_symbolic(free_length, magnet_centre)
    _, offset = _offset_from_rest(free_length, magnet_centre, symbolic)
    return ca.norm_2(offset) if symbolic else np.linalg.norm(offset, axis=-1)


def magnet_centre_at(free_length: Any, magnet_centre: Any, distance: Any) -> Any:
    """The external magnet's centre moved along the line from the rest tip through
    ``magnet_centre`` to ``distance`` from the rest tip, shape (3,) (numpy: centres
    (..., 3) and distances (...) broadcast). [m]"""
    symbolic = is_symbolic(free_length, magnet_centre, distance)
    rest, offset = _offset_from_rest(free_length, magnet_centre, symbolic)
    if symbolic:
        return rest + distance * (offset / ca.norm_2(offset))
    norm = np.linalg.norm(offset, axis=-1, keepdims=True)
    return rest + np.asarray(distance, float)[..., None] * (offset / norm)


def segment_distances(loop: Any) -> Any:
    """Distance from the origin to each side of the closed polygon ``loop`` (vertices in
    order, shape (S, 2)): side i joins vertex i to vertex i + 1, the last to the first;
    shape (S,) (CasADi: (S, 1)). [m]

    Each is the distance to the nearest point of the side, min over t in [0, 1] of
    |a + t (b - a)|: continuously differentiable in the vertices wherever it is not zero
    (the minimiser is unique), so an NLP can bound it.
    """
    if is_symbolic(loop):
        a = loop
        ab = ca.vertcat(loop[1:, :], loop[0, :]) - a
        t = -ca.sum2(a * ab) / ca.fmax(ca.sum2(ab * ab), 1e-300)
        t = ca.fmin(ca.fmax(t, 0), 1)
        closest = a + ca.repmat(t, 1, 2) * ab
        return ca.sqrt(ca.sum2(closest * closest) + SMOOTH**2)
    a = np.asarray(loop, float)
    ab = np.roll(a, -1, axis=0) - a
    t = np.clip(-np.sum(a * ab, axis=1) / np.maximum(np.sum(ab * ab, axis=1), 1e-300), 0, 1)
    return np.linalg.norm(a + t[:, None] * ab, axis=1)


def curve_distances(loop: Any) -> Any:
    """Distance from the origin to each arc of the smooth closed curve through the samples
    ``loop`` (vertices in order, shape (S, 2)), shape (S,) (CasADi: (S, 1)). [m]

    Arc i joins vertex i to vertex i + 1 as the Catmull-Rom (cubic Hermite) curve through
    its neighbours, tangents (P_i+1 - P_i-1) / 2 and (P_i+2 - P_i) / 2; the distance is
    that of the arc's point at the chord's nearest parameter (:func:`segment_distances`),
    first-order exact in the arc's bow. A loop of K samples of a smooth curve of radius R
    lies inside it by the chord's sagitta, R (1 - cos(pi / K)) (0.17 mm for K = 24, R = 20
    mm); the arcs follow it to O(K^-4): a workspace measured on 24 samples (the NLP's) and on
    720 (the forward sweep's) agree. Smooth where :func:`segment_distances` is.
    """
    if is_symbolic(loop):
        a = loop
        b = ca.vertcat(loop[1:, :], loop[0, :])
        before = ca.vertcat(loop[-1, :], loop[:-1, :])
        after = ca.vertcat(loop[2:, :], loop[:2, :])
        ab = b - a
        t = -ca.sum2(a * ab) / ca.fmax(ca.sum2(ab * ab), 1e-300)
        t = ca.fmin(ca.fmax(t, 0), 1)
        bow = _arc_bow(t, a, b, before, after, lambda u: ca.repmat(u, 1, 2))
        closest = a + ca.repmat(t, 1, 2) * ab + bow
        return ca.sqrt(ca.sum2(closest * closest) + SMOOTH**2)
    a = np.asarray(loop, float)
    b, before, after = np.roll(a, -1, axis=0), np.roll(a, 1, axis=0), np.roll(a, -2, axis=0)
    ab = b - a
    t = np.clip(-np.sum(a * ab, axis=1) / np.maximum(np.sum(ab * ab, axis=1), 1e-300), 0, 1)
    bow = _arc_bow(t, a, b, before, after, lambda u: u[:, None])
    return np.linalg.norm(a + t[:, None] * ab + bow, axis=1)


def _arc_bow(t: Any, a: Any, b: Any, before: Any, after: Any, column: Any) -> Any:
    """The Catmull-Rom arc's offset from its chord at parameter t (:func:`curve_distances`):
    h10 m_a + h11 m_b + (h00 - 1 + t) a + (h01 - t) b, the Hermite basis h. [m]"""
    h00 = 2 * t**3 - 3 * t**2 + 1
    h10 = t**3 - 2 * t**2 + t
    h01 = -2 * t**3 + 3 * t**2
    h11 = t**3 - t**2
    m_a, m_b = (b - before) / 2, (after - a) / 2
    return column(h10) * m_a + column(h11) * m_b + column(h00 - 1 + t) * a + column(h01 - t) * b


def curve_disc_radius(loop: Any) -> Any:
    """Radius of the largest disc around the origin inside the smooth closed curve through
    the samples ``loop`` (S, 2): the distance to its nearest arc (:func:`curve_distances`),
    0 when the loop does not wind around the origin or has fewer than three vertices. [m]

    The workspace's disc (about the robot's home, :mod:`design.home`), the same whether the
    loop has the NLP's few samples or the forward sweep's many."""
    if is_symbolic(loop):
        if loop.size1() < 3:
            return ca.SX(0)
        winds = ca.fabs(winding_number(loop)) > 0.5
        return ca.if_else(winds, ca.mmin(curve_distances(loop)), 0)
    loop = np.asarray(loop, float)
    if loop.shape[0] < 3 or winding_number(loop) == 0:
        return 0.0
    return float(curve_distances(loop).min())


def winding_number(loop: Any) -> Any:
    """How often the closed polygon ``loop`` (S, 2) winds around the origin,
    counter-clockwise positive: the sum of the angles its sides subtend, over 2 pi. An
    integer for numbers; for CasADi the sum itself (an integer but where the loop
    crosses the origin). [-]"""
    if is_symbolic(loop):
        a, b = loop, ca.vertcat(loop[1:, :], loop[0, :])
        cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        return ca.sum1(ca.atan2(cross, ca.sum2(a * b))) / (2 * np.pi)
    a = np.asarray(loop, float)
    b = np.roll(a, -1, axis=0)
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return int(np.rint(np.sum(np.arctan2(cross, np.sum(a * b, axis=1))) / (2 * np.pi)))


def disc_radius(loop: Any) -> Any:
    """Radius of the largest disc around the origin inside the closed polygon ``loop``
    (S, 2): the distance to its nearest side (:func:`segment_distances`), 0 when the loop
    does not wind around the origin or has fewer than three vertices. [m]

    The workspace's metric (the loop of tip deflections with parallel rings, seen along
    x, about the rest tip); an NLP bounds the smooth :func:`segment_distances` instead.
    """
    if is_symbolic(loop):
        if loop.size1() < 3:
            return ca.SX(0)
        winds = ca.fabs(winding_number(loop)) > 0.5
        return ca.if_else(winds, ca.mmin(segment_distances(loop)), 0)
    loop = np.asarray(loop, float)
    if loop.shape[0] < 3 or winding_number(loop) == 0:
        return 0.0
    return float(segment_distances(loop).min())


def ring_radius(outer_diameter: Any, length: Any) -> Any:
    """Radius of the sphere that holds a ring (about its centre). [m]"""
    if is_symbolic(outer_diameter, length):
        return ca.sqrt((outer_diameter / 2) ** 2 + (length / 2) ** 2)
    return np.hypot(outer_diameter / 2, length / 2)
