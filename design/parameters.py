"""The model's numeric parameters: names, units and how each follows from a design.

Every model takes one flat vector of the design's physical inputs (sizes, moduli,
remanences, positions, friction), in SI, in the order of ``NAMES``. Derived quantities
(rigidities, moments, spacing) are formulas on these symbols inside the model, so NLPs
and calibration can free any physical input and get exact derivatives through the model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from design.params import Design


@dataclass(frozen=True)
class Parameter:
    """One scalar model input. ``value`` reads it off a design. [unit as given]"""

    name: str
    unit: str
    meaning: str
    value: Callable[[Design], float]


def _component(get: Callable[[Design], tuple], i: int) -> Callable[[Design], float]:
    return lambda d: float(get(d)[i])


def _tube_field(tube: str, name: str) -> Callable[[Design], float]:
    return lambda d: float(getattr(getattr(d.robot, tube), name))


def _vector(prefix: str, unit: str, meaning: str, get: Callable[[Design], tuple]) -> list:
    return [
        Parameter(f"{prefix}_{a}", unit, f"{meaning}, {a}", _component(get, i))
        for i, a in enumerate("xyz")
    ]


def _one(d: Design) -> float:
    return 1.0


def _gravity(d: Design) -> tuple[float, float, float]:
    return d.environment.gravity or (0.0, 0.0, 0.0)


_TABLE: list[Parameter] = [
    Parameter(
        "free_length", "m", "clamped base to proximal ring centre", lambda d: d.robot.free_length
    ),
    *[
        Parameter(
            f"{tube}_{field}",
            unit,
            f"{tube} {field.replace('_', ' ')}",
            _tube_field(tube, field),
        )
        for tube in ("catheter", "wire")
        for field, unit in (
            ("outer_diameter", "m"),
            ("inner_diameter", "m"),
            ("youngs_modulus", "Pa"),
            ("poisson_ratio", "-"),
            ("density", "kg/m^3"),
            ("friction_angle", "rad"),
        )
    ],
    Parameter(
        "ring_outer_diameter", "m", "ring outer diameter", lambda d: d.tip.magnet_outer_diameter
    ),
    Parameter(
        "ring_inner_diameter", "m", "ring inner diameter", lambda d: d.tip.magnet_inner_diameter
    ),
    Parameter("ring_length", "m", "ring length", lambda d: d.tip.magnet_length),
    Parameter("ring_remanence", "T", "ring remanence", lambda d: d.tip.remanence),
    Parameter("ring_gap", "m", "face-to-face gap of the rings", lambda d: d.tip.gap),
    Parameter("ring_density", "kg/m^3", "ring density", lambda d: d.tip.density),
    Parameter("tip_mass", "kg", "extra mass at the tip (mounting pieces)", lambda d: d.tip.mass),
    Parameter(
        "external_diameter", "m", "external cylinder diameter", lambda d: d.external_magnet.diameter
    ),
    Parameter(
        "external_length", "m", "external cylinder length", lambda d: d.external_magnet.length
    ),
    Parameter(
        "external_remanence",
        "T",
        "external magnet remanence",
        lambda d: d.external_magnet.remanence,
    ),
    *_vector("external_center", "m", "external magnet centre", lambda d: d.external_magnet.center),
    *_vector(
        "external_axis",
        "-",
        "external magnetisation direction",
        lambda d: d.external_magnet.magnetization,
    ),
    *_vector("gravity", "m/s^2", "acceleration of gravity", _gravity),
    *[
        Parameter(name, "-", f"calibration factor on the {what} (1 = as designed)", _one)
        for name, what in (
            ("bending_rigidity_scale", "bending rigidity EI of catheter + wire"),
            ("wire_torsion_scale", "torsional rigidity GJ of the wire"),
            ("catheter_torsion_scale", "torsional rigidity GJ of the catheter"),
        )
    ],
    Parameter("load_scale", "-", "multiplies every load (1 = physical; continuation)", _one),
]

PARAMETERS: dict[str, Parameter] = {p.name: p for p in _TABLE}
NAMES: tuple[str, ...] = tuple(PARAMETERS)
"""Parameter names in vector order."""


def parameter_vector(design: Design) -> np.ndarray:
    """Numeric parameter vector of ``design`` in the order of ``NAMES``, shape (n,). [SI]"""
    return np.array([PARAMETERS[n].value(design) for n in NAMES], dtype=float)


def index(name: str) -> int:
    """Position of a parameter in the vector; KeyError names the valid ones."""
    try:
        return NAMES.index(name)
    except ValueError:
        raise KeyError(f"unknown model parameter {name!r}; expected one of {NAMES}") from None
