"""Cross-section properties of the transmissions. Plain arithmetic, so each function takes
floats or CasADi symbols alike (one formula for simulation and NLPs).

SI units are used for all inputs and outputs.
"""

from __future__ import annotations

import math
from typing import Any

from design.records import Robot, Tube


def second_moment_of_area(outer_diameter: Any, inner_diameter: Any) -> Any:
    """Area moment of an annulus about a diameter, I = pi (D^4 - d^4) / 64. [m^4]"""
    return math.pi * (outer_diameter**4 - inner_diameter**4) / 64.0


def polar_moment_of_area(outer_diameter: Any, inner_diameter: Any) -> Any:
    """Polar area moment of an annulus, J = 2 I. [m^4]"""
    return 2.0 * second_moment_of_area(outer_diameter, inner_diameter)


def shear_modulus(youngs_modulus: Any, poisson_ratio: Any) -> Any:
    """Isotropic shear modulus G = E / (2 (1 + nu)). [Pa]"""
    return youngs_modulus / (2.0 * (1.0 + poisson_ratio))


def tube_bending_rigidity(tube: Tube) -> float:
    """E I of one tube. [N m^2]"""
    return tube.youngs_modulus * second_moment_of_area(tube.outer_diameter, tube.inner_diameter)


def tube_torsional_rigidity(tube: Tube) -> float:
    """G J of one tube. [N m^2]"""
    g = shear_modulus(tube.youngs_modulus, tube.poisson_ratio)
    return g * polar_moment_of_area(tube.outer_diameter, tube.inner_diameter)


def bending_rigidity(robot: Robot) -> float:
    """Catheter and wire bend together about one neutral axis: EI = E_c I_c + E_w I_w.

    The wire sits loose inside the catheter, so the two curvatures are equal but the
    sections do not act compositely (no shear transfer): the rigidities add. [N m^2]
    """
    return tube_bending_rigidity(robot.catheter) + tube_bending_rigidity(robot.wire)
