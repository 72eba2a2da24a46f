"""Worm drive geometry: a ZI (involute helicoid) worm and a helical involute wheel.

The pair is a crossed-axis involute helical set at 90 degrees (ISO 21771 applied to
both members, DIN 3975 names): the worm is an involute helical gear with ``z1`` teeth
(threads) and helix angle ``90 - gamma``; the wheel is an involute helical gear with
``z2`` teeth and helix angle ``gamma``, of the same hand. Both are cut by the same normal
rack (normal module ``m_n = m cos(gamma)``, normal pressure angle ``alpha_n``), so they
are exactly conjugate (point contact, like any non-throated printed worm wheel) at the
centre distance ``a = (d1 + d2) / 2``. Lengths in millimetres, angles in degrees at the
interface, radians inside formulas.

Frames: each solid is built in its print frame, axis along +Z, from z = 0 upwards. At
the mid-plane of the face (``z = face_width / 2``) the worm's thread and the wheel's tooth
*space* are centred on local +X, so placing both +X axes on the common perpendicular,
pointing at each other, meshes them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from cad.errors import require
from cad.involute import ToothProfile

if TYPE_CHECKING:  # the drive's numbers are read without the CAD kernel (steering's knob ratio)
    import cadquery as cq


@dataclass(frozen=True)
class WormDriveSpec:
    """Numbers chosen by the designer for one worm drive.

    module_mm : Axial module of the worm = transverse module of the wheel, m. [mm]
    wheel_teeth : z2. [-]
    worm_starts : Number of threads z1 (1 for a self-locking drive). [-]
    diameter_quotient : q = d1 / m; the lead angle is arctan(z1 / q). [-]
    normal_pressure_angle_deg : alpha_n. [deg]
    wheel_face_width_mm : b2. [mm]
    addendum_factor, dedendum_factor : h_a = factor * m, h_f = factor * m. [-]
    """

    module_mm: float = 1.5
    wheel_teeth: int = 30
    worm_starts: int = 1
    diameter_quotient: float = 10.0
    normal_pressure_angle_deg: float = 20.0
    wheel_face_width_mm: float = 8.0
    addendum_factor: float = 1.0
    dedendum_factor: float = 1.25

    @property
    def ratio(self) -> float:
        """Transmission ratio z2 / z1: worm (knob) turns per wheel (ring) turn. [-]"""
        return self.wheel_teeth / self.worm_starts


@dataclass(frozen=True)
class WormDrive:
    """Derived geometry of one worm drive (all lengths in mm, angles in degrees).

    backlash_mm : Circular backlash at the wheel's pitch circle (= axial play of the
        worm), split equally between worm thread and wheel teeth. [mm]
    """

    spec: WormDriveSpec
    backlash_mm: float

    def __post_init__(self) -> None:
        s = self.spec
        require(s.module_mm > 0, "worm drive: module", "positive", s.module_mm)
        require(s.worm_starts >= 1, "worm drive: worm starts", "at least 1", s.worm_starts, "")
        require(s.wheel_teeth >= 12, "worm drive: wheel teeth", "at least 12", s.wheel_teeth, "")
        require(
            s.diameter_quotient > 2 * s.dedendum_factor + 2,
            "worm drive: diameter quotient q",
            f"above {2 * s.dedendum_factor + 2:g} so the worm keeps a core",
            s.diameter_quotient,
            "",
        )
        require(
            0 <= self.backlash_mm < s.module_mm,
            "worm drive: backlash",
            f"between 0 and the module ({s.module_mm:g} mm)",
            self.backlash_mm,
        )
        self.worm_profile.check("worm thread")
        self.wheel_profile.check("worm wheel teeth")

    @property
    def lead_angle_deg(self) -> float:
        """gamma = arctan(z1 / q). [deg]"""
        return math.degrees(math.atan(self.spec.worm_starts / self.spec.diameter_quotient))

    @property
    def ratio(self) -> float:
        """Transmission ratio z2 / z1: worm turns per wheel turn. [-]"""
        return self.spec.ratio

    @property
    def normal_module_mm(self) -> float:
        """m_n = m cos(gamma). [mm]"""
        return self.spec.module_mm * math.cos(math.radians(self.lead_angle_deg))

    @property
    def worm_pitch_diameter_mm(self) -> float:
        """d1 = q m. [mm]"""
        return self.spec.diameter_quotient * self.spec.module_mm

    @property
    def wheel_pitch_diameter_mm(self) -> float:
        """d2 = z2 m. [mm]"""
        return self.spec.wheel_teeth * self.spec.module_mm

    @property
    def centre_distance_mm(self) -> float:
        """a = (d1 + d2) / 2. [mm]"""
        return (self.worm_pitch_diameter_mm + self.wheel_pitch_diameter_mm) / 2

    @property
    def worm_lead_mm(self) -> float:
        """Axial advance of the thread per worm turn, p_z = pi m z1. [mm]"""
        return math.pi * self.spec.module_mm * self.spec.worm_starts

    @property
    def wheel_lead_mm(self) -> float:
        """Axial length of one full turn of the wheel's tooth helix, pi d2 / tan(gamma). [mm]"""
        return math.pi * self.wheel_pitch_diameter_mm / math.tan(math.radians(self.lead_angle_deg))

    def _transverse_pressure_angle(self, helix_angle: float) -> float:
        alpha_n = math.radians(self.spec.normal_pressure_angle_deg)
        return math.atan(math.tan(alpha_n) / math.cos(helix_angle))

    @property
    def worm_profile(self) -> ToothProfile:
        """Transverse section of the worm (perpendicular to its axis): an involute."""
        s, gamma = self.spec, math.radians(self.lead_angle_deg)
        transverse_module = self.worm_pitch_diameter_mm / s.worm_starts
        # Axial thread thickness reduced by backlash/2 <=> transverse angle reduced by
        # (backlash/2) 2 pi / lead; as a circular thickness at r1 that is (backlash/2) q/z1.
        thinning = (self.backlash_mm / 2) * s.diameter_quotient / s.worm_starts
        return ToothProfile(
            teeth=s.worm_starts,
            transverse_module_mm=transverse_module,
            transverse_pressure_angle=self._transverse_pressure_angle(math.pi / 2 - gamma),
            addendum_mm=s.addendum_factor * s.module_mm,
            dedendum_mm=s.dedendum_factor * s.module_mm,
            thinning_mm=thinning,
        )

    @property
    def wheel_profile(self) -> ToothProfile:
        """Transverse section of the wheel: involute teeth of transverse module m."""
        s, gamma = self.spec, math.radians(self.lead_angle_deg)
        return ToothProfile(
            teeth=s.wheel_teeth,
            transverse_module_mm=s.module_mm,
            transverse_pressure_angle=self._transverse_pressure_angle(gamma),
            addendum_mm=s.addendum_factor * s.module_mm,
            dedendum_mm=s.dedendum_factor * s.module_mm,
            thinning_mm=self.backlash_mm / 2,
        )

    @property
    def worm_tip_diameter_mm(self) -> float:
        """d_a1. [mm]"""
        return 2 * self.worm_profile.tip_radius_mm

    @property
    def worm_root_diameter_mm(self) -> float:
        """d_f1. [mm]"""
        return 2 * self.worm_profile.root_radius_mm

    @property
    def wheel_tip_diameter_mm(self) -> float:
        """d_a2. [mm]"""
        return 2 * self.wheel_profile.tip_radius_mm

    @property
    def wheel_root_diameter_mm(self) -> float:
        """d_f2. [mm]"""
        return 2 * self.wheel_profile.root_radius_mm

    @property
    def wheel_tip_thickness_mm(self) -> float:
        """Normal tooth thickness of the wheel at its tip circle, s_an = 2 psi(r_a) r_a
        cos(beta_a), with tan(beta_a) = tan(gamma) r_a / r. [mm]"""
        p = self.wheel_profile
        ra = p.tip_radius_mm
        beta_a = math.atan(math.tan(math.radians(self.lead_angle_deg)) * ra / p.pitch_radius_mm)
        return 2 * float(p.half_angle(ra)) * ra * math.cos(beta_a)

    @property
    def worm_tip_thickness_mm(self) -> float:
        """Normal thread thickness of the worm at its tip cylinder: the axial thickness
        2 psi(r_a) p_z / (2 pi) times cos(gamma_a), tan(gamma_a) = p_z / (2 pi r_a). [mm]"""
        p = self.worm_profile
        ra = p.tip_radius_mm
        axial = 2 * float(p.half_angle(ra)) * self.worm_lead_mm / (2 * math.pi)
        gamma_a = math.atan(self.worm_lead_mm / (2 * math.pi * ra))
        return axial * math.cos(gamma_a)

    @property
    def worm_thread_length_mm(self) -> float:
        """Thread length b1: the length over which the wheel's tip circle reaches the
        worm's tip cylinder, plus one axial pitch each side, rounded up to whole leads. [mm]
        """
        ra2, ra1 = self.wheel_tip_diameter_mm / 2, self.worm_tip_diameter_mm / 2
        engaged = 2 * math.sqrt(max(ra2**2 - (self.centre_distance_mm - ra1) ** 2, 0.0))
        pitch = math.pi * self.spec.module_mm
        return math.ceil((engaged + 2 * pitch) / self.worm_lead_mm) * self.worm_lead_mm

    def table(self) -> dict[str, float]:
        """The drive's numbers for reports, keyed with their unit."""
        return {
            "module_mm": self.spec.module_mm,
            "wheel_teeth": self.spec.wheel_teeth,
            "worm_starts": self.spec.worm_starts,
            "ratio": self.ratio,
            "lead_angle_deg": self.lead_angle_deg,
            "worm_pitch_diameter_mm": self.worm_pitch_diameter_mm,
            "wheel_pitch_diameter_mm": self.wheel_pitch_diameter_mm,
            "centre_distance_mm": self.centre_distance_mm,
            "backlash_mm": self.backlash_mm,
            "worm_thread_length_mm": self.worm_thread_length_mm,
            "wheel_tip_thickness_mm": self.wheel_tip_thickness_mm,
            "worm_tip_thickness_mm": self.worm_tip_thickness_mm,
        }


def helical_prism(profile: ToothProfile, length_mm: float, lead_mm: float) -> cq.Solid:
    """Sweep ``profile`` along +Z over ``length_mm``, turning one revolution per ``lead_mm``
    (right hand), with the profile as drawn (tooth 0 on +X) at the mid-plane. [mm]"""
    import cadquery as cq

    twist_deg = 360.0 * length_mm / lead_mm
    wire = profile.wire().rotate(cq.Vector(), cq.Vector(0, 0, 1), -twist_deg / 2)
    solid = cq.Solid.extrudeLinearWithRotation(
        wire, [], cq.Vector(0, 0, 0), cq.Vector(0, 0, length_mm), twist_deg
    )
    return solid.fix()


@functools.lru_cache(maxsize=8)
def worm_thread(drive: WormDrive) -> cq.Solid:
    """The worm's threaded body, length b1, axis +Z from z = 0; thread on +X at mid. [mm]

    Cached per drive: solids are immutable, every operation on them returns a new one.
    """
    return helical_prism(drive.worm_profile, drive.worm_thread_length_mm, drive.worm_lead_mm)


@functools.lru_cache(maxsize=8)
def wheel_teeth(drive: WormDrive) -> cq.Solid:
    """The wheel's toothed disc, face width b2, axis +Z from z = 0; at mid-face a tooth
    space is centred on +X. [mm]"""
    import cadquery as cq

    profile = drive.wheel_profile
    solid = helical_prism(profile, drive.spec.wheel_face_width_mm, drive.wheel_lead_mm)
    half_pitch = 180.0 / drive.spec.wheel_teeth
    return solid.rotate(cq.Vector(), cq.Vector(0, 0, 1), half_pitch)
