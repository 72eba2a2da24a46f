"""The worm-gear actuator: every part in its print frame and where it sits.

CAD works in millimetres. Two independent self-locking worm drives turn two hollow gear
shafts on one axis: the front shaft holds the catheter (bonded in its nose) and turns the
proximal ring (theta2); the rear shaft turns the wire, bonded in a mount that slides on
the shaft's hex end (axial adjustment of the wire length, i.e. of the ring spacing) and
is locked by a set screw; it turns the distal ring (theta1). Layout: :mod:`cad.layout`;
parts: :mod:`cad.housing`, :mod:`cad.drivetrain`; gear geometry: :mod:`cad.gears`.
"""

from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq

from cad import drivetrain
from cad.housing import housing_parts
from cad.layout import ActuatorLayout, ActuatorSpec, actuator_layout
from cad.process import CadProcess
from cad.selflocking import (
    DEFAULT_MATERIAL_PAIR,
    SelfLocking,
    friction_coefficient,
    self_locking,
)
from design.records import Design


@dataclass(frozen=True)
class ToothZone:
    """Where a part's teeth are, in its print frame: radius above ``min_radius_mm``
    between ``z0_mm`` and ``z1_mm``; and the teeth's normal tip thickness. [mm]

    The mesh wall check leaves this zone to the exact tip thickness: rays through the
    folded sliver triangles of helicoid meshes measure the mesh, not the wall.
    """

    min_radius_mm: float
    z0_mm: float
    z1_mm: float
    tip_thickness_mm: float


def tooth_zones(lay: ActuatorLayout) -> dict[str, ToothZone]:
    """Tooth zones of the gear shafts and the worm (print frames). [mm]"""
    d = lay.drive
    wheel = ToothZone(
        d.wheel_root_diameter_mm / 2 - 0.01,
        -0.01,
        d.spec.wheel_face_width_mm + 0.01,
        d.wheel_tip_thickness_mm,
    )
    z0 = drivetrain.worm_z0(lay)
    worm = ToothZone(
        # less the root facets' sagitta: the thread's run-out at its end planes reaches the
        # root (a knife edge not yet mended, issue 52: fusing or cutting the helicoid
        # breaks its mesh)
        d.worm_root_diameter_mm / 2 - 0.1,
        lay.worm_thread_z.lo - z0 - 0.01,
        lay.worm_thread_z.hi - z0 + 0.01,
        d.worm_tip_thickness_mm,
    )
    return {"gear_shaft_front": wheel, "gear_shaft_rear": wheel, "worm": worm}


@dataclass(frozen=True)
class Actuator:
    """The actuator's parts.

    layout : All dimensions and positions (mm, actuator frame).
    parts : Part name -> solid in its print frame. [mm]
    instances : Instance name -> (part name, print frame to actuator frame).
    locking : Self-locking check of the (two equal) worm drives.
    teeth : Part name -> where its teeth are (gear shafts, worm).
    """

    layout: ActuatorLayout
    parts: dict[str, cq.Solid]
    instances: dict[str, tuple[str, cq.Location]]
    locking: SelfLocking
    teeth: dict[str, ToothZone]


def build_actuator(
    design: Design,
    process: CadProcess,
    spec: ActuatorSpec | None = None,
    material_pair: str | None = None,
) -> Actuator:
    """Build the actuator for ``design`` printed with ``process``.

    Parameters
    ----------
    design : The robot (SI); catheter and wire sizes set the shaft bores and the mount.
    process : Fits, clearances, backlash.
    spec : Designer's choices (gear module, tooth count, bushings, ...).
    material_pair : Flank material pair for the self-locking check, a key of
        :data:`cad.selflocking.FRICTION_COEFFICIENTS`; default by process.
    """
    lay = actuator_layout(design, process, spec)
    pair = material_pair or DEFAULT_MATERIAL_PAIR.get(process.name, "pla-pla-dry")
    locking = self_locking(
        lay.drive.lead_angle_deg,
        friction_coefficient(pair),
        lay.drive.spec.normal_pressure_angle_deg,
        pair,
    )
    parts: dict[str, cq.Solid] = {
        "gear_shaft_front": drivetrain.gear_shaft_front(lay),
        "gear_shaft_rear": drivetrain.gear_shaft_rear(lay),
        "worm": drivetrain.worm(lay),
        "knob": drivetrain.knob(lay),
        "shaft_bushing": drivetrain.shaft_bushing(lay),
        "worm_bushing": drivetrain.worm_bushing(lay),
        "shaft_clip": drivetrain.shaft_clip(lay),
        "wire_mount": drivetrain.wire_mount(lay),
    }
    instances = dict(drivetrain.placements(lay))
    for name, (solid, loc) in housing_parts(lay).items():
        parts[name] = solid
        instances[name] = (name, loc)
    return Actuator(
        layout=lay, parts=parts, instances=instances, locking=locking, teeth=tooth_zones(lay)
    )
