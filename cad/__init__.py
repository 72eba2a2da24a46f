"""ringpair.cad: geometry of the robot's parts, exported, checked and rendered.

CAD works in millimetres (and degrees); the design it reads is in SI. Entry point:
:func:`build_parts` builds the mounting pieces and the worm-gear actuator for a design,
writes STEP/STL/3MF, checks printability and fit, and renders PNGs.
"""

from cad.actuator import Actuator, build_actuator
from cad.assembly import RobotAssembly, build_assembly
from cad.build import CadReport, build_parts
from cad.errors import CadError
from cad.gears import WormDrive, WormDriveSpec
from cad.layout import ActuatorSpec
from cad.mounting import MountingPieces, MountingSpec, TrackingReport, build_mounting_pieces
from cad.process import FDM, PROCESSES, RESIN, CadProcess, get_process
from cad.selflocking import FRICTION_COEFFICIENTS, SelfLocking, self_locking
from cad.tracking import GrooveSpec
from design.process import PrintProcess

__all__ = [
    "FDM",
    "FRICTION_COEFFICIENTS",
    "PROCESSES",
    "RESIN",
    "Actuator",
    "ActuatorSpec",
    "CadError",
    "CadProcess",
    "CadReport",
    "GrooveSpec",
    "MountingPieces",
    "MountingSpec",
    "PrintProcess",
    "RobotAssembly",
    "SelfLocking",
    "TrackingReport",
    "WormDrive",
    "WormDriveSpec",
    "build_actuator",
    "build_assembly",
    "build_mounting_pieces",
    "build_parts",
    "get_process",
    "self_locking",
]
