"""The axially magnetised solid cylinder (:mod:`design.cylinder_field`, exact field and
closed-form gradient), in the field kernels' convention."""

from __future__ import annotations

import casadi as ca

from design.cylinder_field import cylinder_field as _exact

__all__ = ["cylinder_field"]


def cylinder_field(
    offset: ca.SX, magnetization: ca.SX, diameter: ca.SX, length: ca.SX, remanence: ca.SX
) -> tuple[ca.SX, ca.SX]:
    """B (3,) [T] and G = dB/dp (3, 3) [T/m] of the cylinder of ``diameter`` and
    ``length`` [m] magnetised along the unit ``magnetization`` (its axis) with
    ``remanence`` [T], at ``offset`` (3,) from its centre [m], base frame."""
    return _exact(offset, magnetization, diameter / 2, length, remanence)
