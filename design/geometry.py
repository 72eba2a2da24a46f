"""Geometry of the set-up shared by the model, the NLP and design-file checks.

Each function takes numbers (numpy arrays, broadcasting over leading axes) or CasADi
expressions alike. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

SMOOTH = 1e-12
"""Floor under square roots of squared lengths, keeping them differentiable at zero. [m]"""


def _symbolic(*values: Any) -> bool:
    return any(isinstance(v, ca.SX | ca.MX | ca.DM) for v in values)


def cylinder_distance(offset: Any, axis: Any, radius: Any, half_length: Any) -> Any:
    """Distance from a point to a solid cylinder (0 inside). [m]

    offset : point minus the cylinder's centre, shape (3,) (numpy: (..., 3)). [m]
    axis : unit vector of the cylinder's axis, shape (3,). [-]
    radius, half_length : of the cylinder. [m]
    The distance is hypot(max(|a| - half_length, 0), max(rho - radius, 0)) with the axial
    and radial coordinates a and rho of the point: exact outside the cylinder.
    """
    if _symbolic(offset, axis, radius, half_length):
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


def ring_radius(outer_diameter: Any, length: Any) -> Any:
    """Radius of the sphere that holds a ring (about its centre). [m]"""
    if _symbolic(outer_diameter, length):
        return ca.sqrt((outer_diameter / 2) ** 2 + (length / 2) ** 2)
    return np.hypot(outer_diameter / 2, length / 2)
