"""The helical tracking groove: pitch, travel, and what a camera can read from them.

Seen from the side, a single-start helical groove on a turning piece appears as a notch
whose axial position moves linearly with the rotation (the paper's Experimental Setup):
``notch_position = pitch * angle / 360``. A camera that locates the notch to within
``position_uncertainty`` therefore reads the angle to within
``360 * position_uncertainty / pitch`` degrees, and a groove of axial travel ``T`` covers
``360 * T / pitch`` degrees (at most one turn; beyond that the notch is ambiguous).

The paper's demonstrator: notch travel 16 mm, a +-1 mm planar measurement error reads as
+-8.2 deg, i.e. 8.2 deg per mm of notch travel (pitch 360 / 8.2 = 43.9 mm).
Lengths in millimetres, angles in degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cad.errors import require

PAPER_DEG_PER_MM = 8.2
PAPER_TRAVEL_MM = 16.0


@dataclass(frozen=True)
class GrooveSpec:
    """Helical tracking groove of a mounting piece.

    pitch_mm : Axial advance of the groove per turn. [mm]
    travel_mm : Axial length of the piece's grooved surface = range of notch travel. [mm]
    width_mm : Axial width of the groove, measured in a plane containing the axis. [mm]
    depth_mm : Radial depth of the groove. [mm]
    """

    pitch_mm: float = 360.0 / PAPER_DEG_PER_MM
    travel_mm: float = PAPER_TRAVEL_MM
    width_mm: float = 0.8
    depth_mm: float = 0.35

    def __post_init__(self) -> None:
        require(self.pitch_mm > 0, "groove pitch", "positive", self.pitch_mm)
        require(self.travel_mm > 0, "groove travel", "positive", self.travel_mm)
        require(
            self.travel_mm <= self.pitch_mm * (1 + 1e-9),  # one turn, to rounding
            "groove travel",
            f"at most one pitch ({self.pitch_mm:.4g} mm) so every notch position means one angle",
            self.travel_mm,
        )
        require(
            0 < self.width_mm < self.pitch_mm / 2,
            "groove width",
            f"positive and below half the pitch ({self.pitch_mm / 2:.4g} mm)",
            self.width_mm,
        )
        require(self.depth_mm > 0, "groove depth", "positive", self.depth_mm)

    @property
    def resolution_deg_per_mm(self) -> float:
        """Rotation per millimetre of notch travel, 360 / pitch. [deg/mm]"""
        return 360.0 / self.pitch_mm

    @property
    def range_deg(self) -> float:
        """Rotation over which the notch stays on the piece, 360 travel / pitch. [deg]"""
        return 360.0 * self.travel_mm / self.pitch_mm

    def angle_uncertainty_deg(self, position_uncertainty_mm: float) -> float:
        """Angle error for a given notch position error. [deg]"""
        return self.resolution_deg_per_mm * position_uncertainty_mm

    @classmethod
    def from_camera(
        cls,
        pixel_size_mm: float,
        pixels_per_step: float,
        angle_step_deg: float,
        range_deg: float,
        width_mm: float = 0.8,
        depth_mm: float = 0.35,
    ) -> GrooveSpec:
        """Choose pitch and travel from what the camera resolves.

        Parameters
        ----------
        pixel_size_mm : Size of one image pixel on the object (field of view / pixels). [mm]
        pixels_per_step : How many pixels the notch must move for one angle step (2 or more
            for a reliable edge). [-]
        angle_step_deg : The smallest rotation the camera must see. [deg]
        range_deg : The rotation the groove must cover, at most 360. [deg]
        width_mm, depth_mm : Groove cross-section; the width should span a few pixels. [mm]
        """
        require(pixel_size_mm > 0, "camera pixel size", "positive", pixel_size_mm)
        require(pixels_per_step > 0, "pixels per angle step", "positive", pixels_per_step, "")
        require(angle_step_deg > 0, "angle step", "positive", angle_step_deg, "deg")
        require(0 < range_deg <= 360, "groove range", "in (0, 360] deg", range_deg, "deg")
        pitch = 360.0 * pixels_per_step * pixel_size_mm / angle_step_deg
        return cls(
            pitch_mm=pitch,
            travel_mm=pitch * range_deg / 360.0,
            width_mm=width_mm,
            depth_mm=depth_mm,
        )

    def helix_angle_deg(self, diameter_mm: float) -> float:
        """Angle of the groove to the piece's cross-section at ``diameter_mm``. [deg]"""
        return math.degrees(math.atan2(self.pitch_mm, math.pi * diameter_mm))
