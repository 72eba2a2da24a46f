"""ringpair.design: what the robot is and how it behaves.

Design files, the physics (written once on CasADi symbols) and the batch equilibrium.
SI units are used for all inputs and outputs.
"""

from design.designfile import DesignError, default_design, load_design, save_design
from design.equilibrium import Equilibria, solve_design, solve_equilibria
from design.model import EFFECTS, RingPairModel
from design.records import Design, Environment, ExternalMagnet, Robot, Tip, Tube

__all__ = [
    "EFFECTS",
    "Design",
    "DesignError",
    "Environment",
    "Equilibria",
    "ExternalMagnet",
    "RingPairModel",
    "Robot",
    "Tip",
    "Tube",
    "default_design",
    "load_design",
    "save_design",
    "solve_design",
    "solve_equilibria",
]
