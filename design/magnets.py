"""Magnetic moments of uniformly magnetised bodies from geometry and remanence.

A uniformly magnetised body of volume V and magnetisation M = B_r / mu0 has the total
moment m = M V exactly, whatever its shape; that moment is also the one its far field
(point dipole) is built from. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

import math
from typing import Any

from design.constants import MU0


def magnetization(remanence: Any) -> Any:
    """Magnetisation of a permanent magnet from its remanence, M = B_r / mu0. [A/m]"""
    return remanence / MU0


def ring_volume(outer_diameter: Any, inner_diameter: Any, length: Any) -> Any:
    """Volume of a ring (hollow cylinder). [m^3]"""
    return math.pi * (outer_diameter**2 - inner_diameter**2) / 4.0 * length


def ring_moment(outer_diameter: Any, inner_diameter: Any, length: Any, remanence: Any) -> Any:
    """Moment magnitude of a uniformly magnetised ring (axial or diametric alike). [A m^2]"""
    return magnetization(remanence) * ring_volume(outer_diameter, inner_diameter, length)


def cylinder_moment(diameter: Any, length: Any, remanence: Any) -> Any:
    """Moment magnitude of a uniformly magnetised solid cylinder. [A m^2]"""
    return ring_moment(diameter, 0.0, length, remanence)
