"""ringpair.cad: geometry of the robot's parts, exported, checked and rendered.

CAD works in millimetres (and degrees); the design it reads is in SI. Entry point:
:func:`build_parts` builds the mounting pieces and the worm-gear actuator for a design,
writes STEP/STL/3MF, checks printability and fit, and renders PNGs.

The names below are loaded when first used: the CAD kernel and the renderer take seconds
to import, and a command that reads only numbers from here (steering's knob ratio,
:mod:`cad.layout`) should not wait for them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from design.lazy import lazy_exports

_WHERE = {
    "Actuator": "cad.actuator",
    "build_actuator": "cad.actuator",
    "RobotAssembly": "cad.assembly",
    "build_assembly": "cad.assembly",
    "CadReport": "cad.build",
    "build_parts": "cad.build",
    "CadError": "cad.errors",
    "WormDrive": "cad.gears",
    "WormDriveSpec": "cad.gears",
    "ActuatorSpec": "cad.layout",
    "MountingPieces": "cad.mounting",
    "MountingSpec": "cad.mounting",
    "TrackingReport": "cad.mounting",
    "build_mounting_pieces": "cad.mounting",
    "FDM": "cad.process",
    "PROCESSES": "cad.process",
    "RESIN": "cad.process",
    "CadProcess": "cad.process",
    "get_process": "cad.process",
    "FRICTION_COEFFICIENTS": "cad.selflocking",
    "SelfLocking": "cad.selflocking",
    "self_locking": "cad.selflocking",
    "GrooveSpec": "cad.tracking",
    "PrintProcess": "design.process",
}
__all__ = [
    "Actuator",
    "ActuatorSpec",
    "CadError",
    "CadProcess",
    "CadReport",
    "FDM",
    "FRICTION_COEFFICIENTS",
    "GrooveSpec",
    "MountingPieces",
    "MountingSpec",
    "PROCESSES",
    "PrintProcess",
    "RESIN",
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


__getattr__, __dir__ = lazy_exports(__name__, _WHERE)

if TYPE_CHECKING:
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
