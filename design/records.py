"""Frozen parameter records of one robot and its set-up.

SI units are used for all fields (m, Pa, T, kg/m^3, m/s^2). Design files in millimetres
and megapascals are converted at the boundary by :mod:`design.designfile`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

from design.fields.fieldmap import FieldMap
from design.geometry import magnet_spacing
from design.process import DEFAULT_PROCESS, PROCESSES

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
class Mounting:
    """The printed mounting pieces of the tip (:mod:`design.mounting`).

    process : How they are printed, a name of :data:`design.process.PROCESSES`; it sets
        the defaults of the next four.
    wall : The pieces' structural wall. [m]
    fit_allowance : Diametral allowance of a glued seat (ring, catheter, wire). [m]
    running_clearance : Diametral and axial clearance of the running fit. [m]
    density : Density of the printed material. [kg/m^3]
    stop_angle : The rotational stops hold the rings' relative angle theta1 - theta2 (at
        the tip) within [0, stop_angle]: 0 parallel, pi antiparallel. [rad]
    pretwist : Commanded offset of the wire (theta1) against the catheter, set when the
        robot is assembled: with the stops it presses the rings against one (the paper
        "locks" them so). [rad]
    compensate_holes : Whether the CAD draws every bore that must fit (the glued seats of
        rings, catheter and wire, in the tip pieces and the actuator) wider by the
        process's hole shrink (:attr:`design.process.PrintProcess.hole_shrink`), so that
        it prints at the size the model takes. Geometry only: the model's robot is the
        printed one either way.
    passage_diameter : The proximal piece's wire passage, from the catheter's socket to the
        ring's pocket; 0 (default) for the catheter's bore continued. A narrower passage
        lets rings whose bore is below the catheter's seat on the pocket floor. [m]
    """

    process: str = DEFAULT_PROCESS
    wall: float = PROCESSES[DEFAULT_PROCESS].wall
    fit_allowance: float = PROCESSES[DEFAULT_PROCESS].fit_allowance
    running_clearance: float = PROCESSES[DEFAULT_PROCESS].running_clearance
    density: float = PROCESSES[DEFAULT_PROCESS].density
    stop_angle: float = math.pi
    pretwist: float = 0.0
    compensate_holes: bool = False
    passage_diameter: float = 0.0

    @classmethod
    def printed_by(cls, process: str, **values: Any) -> Mounting:
        """The pieces printed by ``process`` (:data:`design.process.PROCESSES`), its wall,
        fit, clearance and density unless ``values`` give them."""
        p = PROCESSES[process]
        numbers = {
            "wall": p.wall,
            "fit_allowance": p.fit_allowance,
            "running_clearance": p.running_clearance,
            "density": p.density,
        }
        return cls(process, **{**numbers, **values})


@dataclass(frozen=True)
class Tip:
    """The two equal, diametrically magnetised ring magnets at the tip.

    magnet_outer_diameter, magnet_inner_diameter, magnet_length : Ring size. [m]
    magnet_remanence : Remanent flux density of the ring material. [T]
    magnet_gap : Face-to-face gap; centre spacing is magnet_length + magnet_gap. [m]
    density : Magnet mass density. [kg/m^3]
    mass : Extra mass carried at the proximal ring's centre (glue; the mounting pieces'
        own mass comes from ``mounting``). [kg]
    mounting : The printed mounting pieces.
    """

    magnet_outer_diameter: float
    magnet_inner_diameter: float
    magnet_length: float
    magnet_remanence: float
    magnet_gap: float
    density: float
    mass: float = 0.0
    mounting: Mounting = field(default_factory=Mounting)

    @property
    def spacing(self) -> float:
        """Centre-to-centre distance of the two rings along the tip tangent. [m]"""
        return magnet_spacing(self.magnet_length, self.magnet_gap)

    @property
    def gap(self) -> float:
        """Old name of :attr:`magnet_gap` (the registry's), read with a warning. [m]"""
        _renamed("Tip.gap", "Tip.magnet_gap")
        return self.magnet_gap

    @property
    def remanence(self) -> float:
        """Old name of :attr:`magnet_remanence` (the registry's), read with a warning. [T]"""
        _renamed("Tip.remanence", "Tip.magnet_remanence")
        return self.magnet_remanence


def _renamed(old: str, new: str) -> None:
    warnings.warn(f"{old} is now {new}", DeprecationWarning, stacklevel=3)


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
class Source:
    """One field source of ``[[field.sources]]`` (docs/formats.md), superposed with the
    others and the ``[external_magnet]``; its kind's quantities
    (:data:`design.fields.sources.KINDS`) are set, the others keep their defaults.

    kind : "uniform", "cylinder", "cuboid", "sphere", "coil" or "map".
    b : uniform: the field vector. [T]
    diameter, length : cylinder (and sphere: diameter) size. [m]
    dimensions : cuboid side lengths along the base axes x, y, z. [m]
    center : centre (map: where the map's origin lies), base frame. [m]
    magnetization : unit magnetisation direction, base frame. [-]
    remanence : remanent flux density. [T]
    radius, turns, current, axis : coil: loop radius [m], number of turns [-], current per
        turn [A], unit normal (right-hand rule) [-].
    file : map: the grid file's path, as resolved when read.
    fieldmap : map: the grid read from ``file``.
    """

    kind: str
    b: Vector3 = (0.0, 0.0, 0.0)
    diameter: float = 0.0
    length: float = 0.0
    dimensions: Vector3 = (0.0, 0.0, 0.0)
    center: Vector3 = (0.0, 0.0, 0.0)
    magnetization: Vector3 = (0.0, 0.0, 1.0)
    remanence: float = 0.0
    radius: float = 0.0
    turns: float = 1.0
    current: float = 0.0
    axis: Vector3 = (0.0, 0.0, 1.0)
    file: str = ""
    fieldmap: FieldMap | None = field(default=None, repr=False)


@dataclass(frozen=True)
class Obstacle:
    """One rigid obstacle, base frame (:mod:`design.obstacles`).

    kind : 'plane', 'sphere' or 'lumen'.
    point : plane: a point on it; sphere: its centre; lumen: a point on its axis. [m]
    normal : plane: the outward unit normal (the robot's side); lumen: the unit axis;
        sphere: (0, 0, 0). [-]
    radius : sphere, lumen (0 for a plane). [m]
    friction : Coulomb coefficient (0: frictionless). [-]
    """

    kind: str
    point: Vector3
    normal: Vector3 = (0.0, 0.0, 0.0)
    radius: float = 0.0
    friction: float = 0.0


@dataclass(frozen=True)
class Environment:
    """Optional surroundings.

    gravity : acceleration of gravity, base frame, or None. [m/s^2]
    obstacles : rigid obstacles the tip may press on (none by default).
    """

    gravity: Vector3 | None = None
    obstacles: tuple[Obstacle, ...] = ()


@dataclass(frozen=True)
class Design:
    """One robot and its set-up, as in a design file (docs/formats.md). The field is the
    ``external_magnet`` (None: the design has none) and the ``sources`` superposed."""

    name: str
    robot: Robot
    tip: Tip
    external_magnet: ExternalMagnet | None
    environment: Environment = field(default_factory=Environment)
    description: str = ""
    sources: tuple[Source, ...] = ()
