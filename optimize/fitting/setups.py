"""Random set-ups from the whole design space the tool accepts: for property tests and
for the diagnosis benchmark's planted data sets (:mod:`optimize.fitting.planted`).

Not around the paper's demonstrator: ring sizes, free lengths, tube stiffness, external
magnet shape, distance, off-axis position and direction, and gravity are all drawn, and
every drawn set-up is a valid design file (it goes through the design-file checks).

Ranges (file units): ring outer diameter 1.5-5 mm, length 0.3-3 mm, face-to-face gap
0-3 mm; free length 80-250 mm; catheter and wire Young's moduli 0.2-3 x nominal
(log-uniform); external magnet diameter 10-80 mm with length / diameter 0.3-3, its face
8-120 mm from the rest tip and its centre up to 60 mm off the robot's axis, magnetised
along any direction; gravity absent or along any direction. :func:`on_axis` puts the
magnet on the robot's axis, magnetised along it (the paper's arrangement): a set-up that
is its own mirror image in every plane through the axis but for gravity, where the
robot's states meet symmetric bifurcations; drawn positions almost never are.
"""

from __future__ import annotations

import math

import numpy as np

from design.admissible import WIRE_CLEARANCE
from design.designfile import DesignError, default_design, design_from_dict, design_to_dict
from design.geometry import cylinder_distance, rest_position
from design.records import Design
from design.units import MM

FACE_MM = (8.0, 120.0)
"""Range of the external magnet's face distance from the rest tip. [mm]"""


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


def _unit(rng: np.random.Generator, plane: bool) -> list[float]:
    """A random unit vector; in the x-z plane if ``plane``."""
    v = rng.normal(size=3)
    if plane:
        v[1] = 0.0
    return list(v / np.linalg.norm(v))


def random_design(
    rng: np.random.Generator,
    symmetric: bool = False,
    *,
    face_mm: tuple[float, float] = FACE_MM,
) -> Design:
    """A valid design drawn from the ranges in the module docstring. ``symmetric``: the
    magnet's centre and axis and gravity in the x-z plane, so that the set-up is its own
    mirror image in that plane (y -> -y). ``face_mm``: the range of the external magnet's
    face distance from the rest tip, within FACE_MM. [mm]"""
    nominal = design_to_dict(default_design())
    for _ in range(1000):
        doc = design_to_dict(default_design())
        doc["name"] = "random set-up"
        doc["description"] = ""
        robot, tip, ext = doc["robot"], doc["tip"], doc["external_magnet"]
        robot["free_length_mm"] = rng.uniform(80.0, 250.0)
        for tube in ("catheter", "wire"):
            e = nominal["robot"][tube]["youngs_modulus_mpa"]
            robot[tube]["youngs_modulus_mpa"] = e * _log_uniform(rng, 0.2, 3.0)
        outer = rng.uniform(1.5, 5.0)
        wire = robot["wire"]["outer_diameter_mm"]
        tip["magnet_outer_diameter_mm"] = outer
        tip["magnet_inner_diameter_mm"] = rng.uniform(wire + WIRE_CLEARANCE / MM, outer - 0.4)
        tip["magnet_length_mm"] = rng.uniform(0.3, 3.0)
        tip["gap_mm"] = rng.uniform(0.0, 3.0)
        tip["remanence_t"] = rng.uniform(1.2, 1.45)
        diameter = rng.uniform(10.0, 80.0)
        length = diameter * _log_uniform(rng, 0.3, 3.0)
        ext["diameter_mm"], ext["length_mm"] = diameter, length
        ext["remanence_t"] = rng.uniform(1.2, 1.45)
        axis = _unit(rng, symmetric)
        ext["magnetization"] = axis
        # The centre: up to 60 mm off the axis, anywhere along it that puts the face
        # 8-120 mm from the rest tip.
        off = rng.uniform(0.0, 60.0)
        angle = 0.0 if symmetric else rng.uniform(0.0, 2 * math.pi)
        along = rng.uniform(-60.0, 250.0)
        rest = robot["free_length_mm"]
        centre = [rest + along, off * math.cos(angle), off * math.sin(angle)]
        if symmetric:
            centre = [rest + along, 0.0, off * (1 if rng.random() < 0.5 else -1)]
        ext["center_mm"] = centre
        face = float(
            cylinder_distance(
                rest_position(rest) - np.array(centre),
                np.array(axis),
                diameter / 2,
                length / 2,
            )
        )
        if not face_mm[0] <= face <= face_mm[1]:
            continue
        doc.pop("environment", None)
        if rng.random() < 0.7:
            doc["environment"] = {"gravity_m_s2": [9.81 * c for c in _unit(rng, symmetric)]}
        try:
            return design_from_dict(doc)
        except DesignError:
            continue
    raise RuntimeError("no valid random design in 1000 draws")


def on_axis(
    rng: np.random.Generator, design: Design, face_mm: tuple[float, float] = FACE_MM
) -> Design:
    """``design`` with its external magnet (a cylinder) on the robot's axis, magnetised
    along it towards or away from the robot, its face drawn ``face_mm`` from the rest tip
    (module docstring). [mm]"""
    doc = design_to_dict(design)
    ext = doc["external_magnet"]
    face = rng.uniform(*face_mm)
    ext["center_mm"] = [design.robot.free_length / MM + face + ext["length_mm"] / 2, 0.0, 0.0]
    ext["magnetization"] = [1.0 if rng.random() < 0.5 else -1.0, 0.0, 0.0]
    return design_from_dict(doc)


def face_distance(design: Design) -> float:
    """Distance from the rest tip to the external magnet's surface. [m]"""
    ext = design.external_magnet
    offset = rest_position(design.robot.free_length) - np.asarray(ext.center)
    return float(
        cylinder_distance(offset, np.asarray(ext.magnetization), ext.diameter / 2, ext.length / 2)
    )
