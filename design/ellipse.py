"""Ellipses in a plane: the least-squares fit of a set of points and their distances to it.

The paper evaluates its robot by fitting an ellipse to the tracked tip positions and
reporting the RMS distance of the points to it (Sayres & Pittiglio, *Design of Magnetic
Continuum Robots with Tunable Force Response Using Rotational Ring Pairs*, sec. "Workspace
Evaluation"); ringpair recomputes that evaluation on simulated tips.

The fit is Fitzgibbon, Pilu & Fisher's direct least-squares ellipse (*Direct least square
fitting of ellipses*, IEEE TPAMI 21(5), 1999), in the numerically stable form of Halir &
Flusser (1998): minimise the algebraic distance of the conic a x^2 + b xy + c y^2 + d x +
e y + f = 0 subject to 4 a c - b^2 = 1, which always gives an ellipse. Distances are to the
closest point of the ellipse, found on a dense sampling of it and refined by Newton's
method on the parameter. Units: those of the points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SAMPLES = 2048
"""Samples of the ellipse that start the search for each point's closest point."""


@dataclass(frozen=True)
class Ellipse:
    """center (2,), semi-axes (a >= b), and the angle of the a axis from the first
    coordinate axis [rad]."""

    center: np.ndarray
    semi_axes: np.ndarray
    angle: float

    def point(self, t: np.ndarray) -> np.ndarray:
        """Points (..., 2) at parameters t [rad]."""
        c, s = np.cos(self.angle), np.sin(self.angle)
        u = self.semi_axes[0] * np.cos(t)
        v = self.semi_axes[1] * np.sin(t)
        return self.center + np.stack([c * u - s * v, s * u + c * v], axis=-1)

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Distance of each of ``points`` (N, 2) to the closest point of the ellipse."""
        points = np.atleast_2d(points)
        t = 2 * np.pi * np.arange(SAMPLES) / SAMPLES
        d = np.linalg.norm(points[:, None, :] - self.point(t)[None], axis=2)
        best = t[np.argmin(d, axis=1)]
        c, s = np.cos(self.angle), np.sin(self.angle)
        local = points - self.center
        x = c * local[:, 0] + s * local[:, 1]  # in the ellipse's own axes
        y = -s * local[:, 0] + c * local[:, 1]
        a, b = self.semi_axes
        for _ in range(8):  # Newton on d/dt |p - e(t)|^2 / 2 = 0
            ct, st = np.cos(best), np.sin(best)
            g = (a * ct - x) * (-a * st) + (b * st - y) * (b * ct)
            h = a * a * st * st + b * b * ct * ct - (a * ct - x) * a * ct - (b * st - y) * b * st
            best = best - np.where(h > 0, g / np.where(h > 0, h, 1.0), 0.0)
        return np.hypot(x - a * np.cos(best), y - b * np.sin(best))


def fit_ellipse(points: np.ndarray) -> Ellipse:
    """The direct least-squares ellipse through ``points`` (N, 2), N >= 5 (module
    docstring)."""
    points = np.asarray(points, float)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 5:
        raise ValueError("an ellipse fit needs at least 5 points (N, 2)")
    shift = points.mean(axis=0)
    scale = np.abs(points - shift).max() or 1.0
    x, y = ((points - shift) / scale).T
    quadratic = np.column_stack([x * x, x * y, y * y])
    linear = np.column_stack([x, y, np.ones_like(x)])
    s1, s2, s3 = quadratic.T @ quadratic, quadratic.T @ linear, linear.T @ linear
    t = -np.linalg.solve(s3, s2.T)
    m = s1 + s2 @ t
    m = np.array([m[2] / 2, -m[1], m[0] / 2])  # C1^-1 M, C1 the constraint 4ac - b^2
    _, vectors = np.linalg.eig(m)
    vectors = np.real(vectors)
    condition = 4 * vectors[0] * vectors[2] - vectors[1] ** 2
    a1 = vectors[:, np.argmax(condition)]
    a, b, c = a1
    d, e, f = t @ a1
    # Centre, axes and angle of a x^2 + b xy + c y^2 + d x + e y + f = 0.
    det = 4 * a * c - b * b
    cx, cy = (b * e - 2 * c * d) / det, (b * d - 2 * a * e) / det
    value = a * cx * cx + b * cx * cy + c * cy * cy + d * cx + e * cy + f
    eig, axes = np.linalg.eigh(np.array([[a, b / 2], [b / 2, c]]))
    semi = np.sqrt(-value / eig)
    major = int(np.argmax(semi))
    semi = np.array([semi[major], semi[1 - major]])
    angle = float(np.arctan2(axes[1, major], axes[0, major]))
    return Ellipse(center=shift + scale * np.array([cx, cy]), semi_axes=scale * semi, angle=angle)
