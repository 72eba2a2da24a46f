"""A uniform field: an MRI scanner's bore, the centre of a coil system. SI units."""

from __future__ import annotations

import casadi as ca

__all__ = ["uniform_field"]


def uniform_field(offset: ca.SX, flux: ca.SX) -> tuple[ca.SX, ca.SX]:
    """B = ``flux`` (3,) [T] everywhere and G = 0 (3, 3) [T/m]; ``offset`` (3,) [m] is
    only the field point's shape."""
    del offset
    b = flux if isinstance(flux, ca.SX | ca.MX) else ca.DM(flux)
    return b, ca.SX.zeros(3, 3)
