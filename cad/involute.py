"""Involute tooth profiles in the transverse plane, as numbers and as CadQuery wires.

A helical involute gear (and a ZI worm, which is one with a few teeth and a helix angle
near 90 degrees) is the transverse profile of this module swept along a helix. All
lengths are in millimetres, angles in radians. The profile of tooth 0 is centred on the
+x axis of the transverse plane; teeth follow counter-clockwise.

Reference: ISO 21771:2007 (cylindrical involute gears), sections 4-5: base radius
``r_b = r cos(alpha_t)``, involute function ``inv(a) = tan(a) - a``, transverse tooth
half-angle at radius ``y``: ``psi(y) = psi_p + inv(alpha_t) - inv(arccos(r_b / y))``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cad.errors import require

if TYPE_CHECKING:  # profiles as numbers need no CAD kernel; its wires import it when made
    import cadquery as cq

FLANK_POINTS = 12


def involute_function(pressure_angle: float | np.ndarray) -> float | np.ndarray:
    """inv(a) = tan(a) - a. [rad]"""
    return np.tan(pressure_angle) - pressure_angle


@dataclass(frozen=True)
class ToothProfile:
    """Transverse tooth profile of a cylindrical involute gear.

    teeth : Number of teeth (threads, for a worm). [-]
    transverse_module_mm : Transverse module m_t; pitch diameter is ``teeth * m_t``. [mm]
    transverse_pressure_angle : alpha_t. [rad]
    addendum_mm, dedendum_mm : Tooth height above and below the pitch circle. [mm]
    thinning_mm : Reduction of the transverse circular tooth thickness at the pitch circle
        (half of the mesh backlash is usually given to each member). [mm]
    """

    teeth: int
    transverse_module_mm: float
    transverse_pressure_angle: float
    addendum_mm: float
    dedendum_mm: float
    thinning_mm: float = 0.0

    @property
    def pitch_radius_mm(self) -> float:
        """r = z m_t / 2. [mm]"""
        return self.teeth * self.transverse_module_mm / 2

    @property
    def base_radius_mm(self) -> float:
        """r_b = r cos(alpha_t). [mm]"""
        return self.pitch_radius_mm * math.cos(self.transverse_pressure_angle)

    @property
    def tip_radius_mm(self) -> float:
        """r_a = r + h_a. [mm]"""
        return self.pitch_radius_mm + self.addendum_mm

    @property
    def root_radius_mm(self) -> float:
        """r_f = r - h_f. [mm]"""
        return self.pitch_radius_mm - self.dedendum_mm

    def half_angle(self, radius_mm: float | np.ndarray) -> float | np.ndarray:
        """Half the angular tooth thickness at ``radius_mm`` (>= base radius). [rad]"""
        r, rb = self.pitch_radius_mm, self.base_radius_mm
        psi_pitch = math.pi / (2 * self.teeth) - self.thinning_mm / (2 * r)
        alpha = np.arccos(np.clip(rb / np.asarray(radius_mm, dtype=float), -1.0, 1.0))
        return (
            psi_pitch
            + involute_function(self.transverse_pressure_angle)
            - (involute_function(alpha))
        )

    def check(self, name: str) -> None:
        """Raise :class:`~cad.errors.CadError` for a profile that cannot exist."""
        require(self.teeth >= 1, f"{name}: number of teeth", "at least 1", self.teeth, "")
        require(
            self.root_radius_mm > 0,
            f"{name}: root radius",
            "positive (dedendum smaller than the pitch radius)",
            self.root_radius_mm,
        )
        tip_half = float(self.half_angle(self.tip_radius_mm))
        require(
            tip_half > 0,
            f"{name}: tooth tip half-thickness",
            "positive (teeth must not be pointed; lower the addendum or the backlash)",
            math.degrees(tip_half),
            "deg",
        )
        foot = max(self.root_radius_mm, self.base_radius_mm)
        space = 2 * math.pi / self.teeth - 2 * float(self.half_angle(foot))
        require(
            space > 0,
            f"{name}: tooth space at the root",
            "positive (teeth overlap at the root)",
            math.degrees(space),
            "deg",
        )

    def flank(self, n: int = FLANK_POINTS) -> tuple[np.ndarray, np.ndarray]:
        """Polar points (radius [mm], half-angle [rad]) of one flank, foot to tip."""
        foot = max(self.root_radius_mm, self.base_radius_mm)
        # Denser near the base circle, where the involute curves most.
        s = np.linspace(0.0, 1.0, n) ** 1.5
        radii = foot + (self.tip_radius_mm - foot) * s
        return radii, np.asarray(self.half_angle(radii))

    def points(self, n: int = FLANK_POINTS) -> np.ndarray:
        """Closed polyline of the whole profile, counter-clockwise, shape (k, 2). [mm]

        For plotting and tests; the solid uses :meth:`wire`, with exact arcs.
        """
        radii, half = self.flank(n)
        rf = self.root_radius_mm
        out: list[tuple[float, float]] = []
        for k in range(self.teeth):
            c = 2 * math.pi * k / self.teeth
            if rf < radii[0]:
                out.append(_polar(rf, c - half[0]))
            out += [_polar(r, c - h) for r, h in zip(radii, half, strict=True)]
            out += [_polar(r, c + h) for r, h in zip(radii[::-1], half[::-1], strict=True)]
            if rf < radii[0]:
                out.append(_polar(rf, c + half[0]))
        return np.array(out)

    def wire(self, n: int = FLANK_POINTS) -> cq.Wire:
        """Closed profile wire in the XY plane: spline flanks, arc tips and roots. [mm]"""
        import cadquery as cq

        radii, half = self.flank(n)
        rf, ra = self.root_radius_mm, self.tip_radius_mm
        radial_foot = rf < radii[0] - 1e-9
        edges: list[cq.Edge] = []
        pitch_angle = 2 * math.pi / self.teeth
        for k in range(self.teeth):
            c = pitch_angle * k
            right = [_vec(r, c - h) for r, h in zip(radii, half, strict=True)]
            left = [_vec(r, c + h) for r, h in zip(radii[::-1], half[::-1], strict=True)]
            if radial_foot:
                edges.append(cq.Edge.makeLine(_vec(rf, c - half[0]), right[0]))
            edges.append(cq.Edge.makeSpline(right))
            edges.append(cq.Edge.makeThreePointArc(right[-1], _vec(ra, c), left[0]))
            edges.append(cq.Edge.makeSpline(left))
            foot_left = _vec(rf, c + half[0]) if radial_foot else left[-1]
            if radial_foot:
                edges.append(cq.Edge.makeLine(left[-1], foot_left))
            next_c = c + pitch_angle
            foot_next = _vec(rf, next_c - half[0])
            mid = _vec(rf, c + pitch_angle / 2)
            edges.append(cq.Edge.makeThreePointArc(foot_left, mid, foot_next))
        return cq.Wire.assembleEdges(edges)


def _polar(radius: float, angle: float) -> tuple[float, float]:
    return (radius * math.cos(angle), radius * math.sin(angle))


def _vec(radius: float, angle: float) -> cq.Vector:
    import cadquery as cq

    return cq.Vector(radius * math.cos(angle), radius * math.sin(angle), 0.0)
