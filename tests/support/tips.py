"""Tip pieces drawn from the whole range the CAD accepts, for property tests of the solids."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from cad.mounting import MountingSpec
from design.mounting import MAX_STOP_ANGLE
from design.process import PROCESSES
from design.records import Design, Mounting


def drawn_tip(demonstrator: Design, seed: int) -> tuple[Design, MountingSpec, str]:
    """The demonstrator with its tip and ``[tip.mounting]`` drawn from seed ``seed``, the
    groove spec drawn with it, and a line naming the draw for failure messages.

    Rings from the smallest that fit over the wire (1 mm across: the MRI example's) to
    twice the demonstrator's, a third as long to twice; their bore from the least that
    seats them over the distal piece's wire bore up; below the catheter's bore they sit on
    a narrowed passage (at 180 deg a groove pass left a 0.28 mm web by the glue port of
    1 mm rings)."""
    rng = np.random.default_rng(seed)
    process = PROCESSES[str(rng.choice(sorted(PROCESSES)))]
    mounting = Mounting(
        process=process.name,
        wall=float(rng.uniform(1.0, 4.0)) * process.min_wall,
        fit_allowance=float(rng.uniform(-0.05, 0.3)) * 1e-3,
        running_clearance=float(rng.uniform(0.0, 0.4)) * 1e-3,
        density=float(rng.uniform(900.0, 2000.0)),
        stop_angle=float(rng.uniform(math.radians(10.0), MAX_STOP_ANGLE)),
    )
    spec = MountingSpec(groove_range_deg=float(rng.uniform(180.0, 360.0)))
    tip, robot = demonstrator.tip, demonstrator.robot
    wire, lumen = robot.wire.outer_diameter * 1e3, robot.catheter.inner_diameter * 1e3
    outer = float(np.exp(rng.uniform(0.0, np.log(8.0))))  # log-uniform: small rings as often
    least = wire + max(mounting.fit_allowance * 1e3, 0.05) + 0.05
    bore = float(rng.uniform(least, max(least, min(outer - 0.3, 3.0))))
    passage = 0.0 if bore > lumen else float(rng.uniform(wire + 0.05, bore - 0.02))
    scale_l = rng.uniform(1 / 3, 2.0)
    tip = replace(
        tip,
        mounting=replace(mounting, passage_diameter=passage * 1e-3),
        magnet_outer_diameter=outer * 1e-3,
        magnet_inner_diameter=bore * 1e-3,
        magnet_length=tip.magnet_length * scale_l,
    )
    why = (
        f"seed {seed}: {tip.mounting}, rings {outer:.2f} / {bore:.2f} mm, length x "
        f"{scale_l:.2f}, groove range {spec.groove_range_deg:.1f} deg"
    )
    return replace(demonstrator, tip=tip), spec, why
