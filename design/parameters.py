"""The model's numeric parameters: names, units and how each follows from a design.

A model takes one flat parameter vector; this table fixes its entries so that simulation,
calibration and NLPs address the same quantities by name. SI units throughout.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from design.magnets import cylinder_moment, ring_moment
from design.params import Design
from design.sections import bending_rigidity


@dataclass(frozen=True)
class Parameter:
    """One scalar model parameter. ``value`` reads it off a design. [unit as given]"""

    name: str
    unit: str
    meaning: str
    value: Callable[[Design], float]


def _ring_moment(d: Design) -> float:
    t = d.tip
    return ring_moment(
        t.magnet_outer_diameter, t.magnet_inner_diameter, t.magnet_length, t.remanence
    )


def _external_moment(i: int) -> Callable[[Design], float]:
    def value(d: Design) -> float:
        e = d.external_magnet
        return cylinder_moment(e.diameter, e.length, e.remanence) * e.magnetization[i]

    return value


def _external_center(i: int) -> Callable[[Design], float]:
    return lambda d: d.external_magnet.center[i]


PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in (
        Parameter(
            "free_length",
            "m",
            "clamped base to proximal ring centre",
            lambda d: d.robot.free_length,
        ),
        Parameter(
            "bending_rigidity",
            "N m^2",
            "EI of catheter plus wire",
            lambda d: bending_rigidity(d.robot),
        ),
        Parameter("ring_moment", "A m^2", "moment magnitude of each tip ring", _ring_moment),
        Parameter("ring_spacing", "m", "centre spacing of the rings", lambda d: d.tip.spacing),
        *(
            Parameter(
                f"external_moment_{a}", "A m^2", f"external dipole moment, {a}", _external_moment(i)
            )
            for i, a in enumerate("xyz")
        ),
        *(
            Parameter(
                f"external_center_{a}", "m", f"external magnet centre, {a}", _external_center(i)
            )
            for i, a in enumerate("xyz")
        ),
    )
}

BASELINE = tuple(PARAMETERS)
"""Parameter names of the baseline model, in vector order."""


def parameter_vector(design: Design, names: tuple[str, ...] = BASELINE) -> np.ndarray:
    """Numeric parameter vector of ``design`` in the order of ``names``, shape (n,). [SI]"""
    return np.array([PARAMETERS[n].value(design) for n in names], dtype=float)
