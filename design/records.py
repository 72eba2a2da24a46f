"""Frozen parameter records of one robot and its set-up.

SI units are used for all fields (m, Pa, T, kg/m^3, m/s^2). Design files in millimetres
and megapascals are converted at the boundary by :mod:`design.designfile`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from design.geometry import magnet_spacing

Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class Tube:
    """One coaxial transmission element (the outer catheter or the inner wire).

    outer_diameter : Outer diameter. [m]
    inner_diameter : Inner diameter, 0 for a solid wire. [m]
    youngs_modulus : Young's modulus in bending. [Pa]
    poisson_ratio : Poisson's ratio; shear modulus is E / (2 (1 + nu)). [-]
    density : Mass density. [kg/m^3]
    friction_angle : Half-width of the transmission's backlash/friction play: the tip angle
        trails the command by this much in the direction of travel. [rad]
    """

    outer_diameter: float
    inner_diameter: float
    youngs_modulus: float
    poisson_ratio: float
    density: float
    friction_angle: float = 0.0


@dataclass(frozen=True)
class Robot:
    """The flexible body: catheter and wire bending together over the free length.

    free_length : Clamped base to the proximal tip magnet's centre. [m]
    """

    free_length: float
    catheter: Tube
    wire: Tube


@dataclass(frozen=True)
class Tip:
    """The two equal, diametrically magnetised ring magnets at the tip.

    magnet_outer_diameter, magnet_inner_diameter, magnet_length : Ring size. [m]
    remanence : Remanent flux density of the ring material. [T]
    gap : Face-to-face gap; centre spacing is magnet_length + gap. [m]
    density : Magnet mass density. [kg/m^3]
    mass : Extra mass carried at the tip (mounting pieces, glue). [kg]
    """

    magnet_outer_diameter: float
    magnet_inner_diameter: float
    magnet_length: float
    remanence: float
    gap: float
    density: float
    mass: float = 0.0

    @property
    def spacing(self) -> float:
        """Centre-to-centre distance of the two rings along the tip tangent. [m]"""
        return magnet_spacing(self.magnet_length, self.gap)


@dataclass(frozen=True)
class ExternalMagnet:
    """The fixed actuating magnet: an axially magnetised cylinder.

    diameter, length : Cylinder size. [m]
    remanence : Remanent flux density. [T]
    center : Centre, base frame. [m]
    magnetization : Unit vector of the magnetisation (the cylinder axis), base frame. [-]
    """

    shape: str
    diameter: float
    length: float
    remanence: float
    center: Vector3
    magnetization: Vector3


@dataclass(frozen=True)
class Environment:
    """Optional surroundings. gravity : acceleration of gravity, base frame, or None. [m/s^2]"""

    gravity: Vector3 | None = None


@dataclass(frozen=True)
class Design:
    """One robot and its set-up, as in a design file (spec/formats.md)."""

    name: str
    robot: Robot
    tip: Tip
    external_magnet: ExternalMagnet
    environment: Environment = field(default_factory=Environment)
    description: str = ""
