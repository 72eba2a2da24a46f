"""The parameter registry: each scalar quantity of a robot and its set-up, once.

Every model takes one flat vector of the design's physical inputs (sizes, moduli,
remanences, positions, friction), in SI, in the order of ``NAMES``. Derived quantities
(rigidities, moments, spacing) are formulas on these symbols inside the model, so NLPs
and calibration can free any physical input and get exact derivatives through the model.

One name per quantity, everywhere (model, study files, calibration, ``--set``, tolerance
studies, reports): the design file's key without its unit, prefixed by the section the
file nests it in where the key alone would be ambiguous (``catheter_``, ``wire_``,
``external_``, and ``magnet_`` for the tip's rings: ``tip.gap_mm`` is ``magnet_gap``,
``tip.magnet_length_mm`` is ``magnet_length``). Where a file or option gives a value, it
is in the quantity's file unit (:data:`FILE_UNITS`) with the unit's suffix on the key
(``magnet_length_mm``). Old names (:data:`RENAMED`) are still read, with a warning.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from design.records import Design
from design.units import DEG, GRAM, MM, MPA


@dataclass(frozen=True)
class Parameter:
    """One scalar model input.

    field : where it lives in a :class:`~design.records.Design`, a dotted path of record
        attributes with a component index for vectors (``"tip.gap"``,
        ``"external_magnet.center[0]"``); None for a factor of the model alone (always 1
        in a design, freed by calibration).
    unit : its SI unit.
    """

    name: str
    unit: str
    meaning: str
    field: str | None

    def value(self, design: Design) -> float:
        """Its value in ``design``. [unit]"""
        if self.field is None:
            return 1.0
        path, i = _split(self.field)
        node: Any = design
        for part in path:
            node = getattr(node, part)
        if i is None:
            return float(node)
        return 0.0 if node is None else float(node[i])  # (no gravity: a zero vector)


def _split(field: str) -> tuple[list[str], int | None]:
    """A field path's attributes and component index."""
    path, _, rest = field.partition("[")
    return path.split("."), (int(rest.rstrip("]")) if rest else None)


def _vector(prefix: str, unit: str, meaning: str, field: str) -> list[Parameter]:
    return [
        Parameter(f"{prefix}_{a}", unit, f"{meaning}, {a}", f"{field}[{i}]")
        for i, a in enumerate("xyz")
    ]


_TABLE: list[Parameter] = [
    Parameter("free_length", "m", "clamped base to proximal ring centre", "robot.free_length"),
    *[
        Parameter(
            f"{tube}_{field}", unit, f"{tube} {field.replace('_', ' ')}", f"robot.{tube}.{field}"
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
    Parameter("magnet_outer_diameter", "m", "ring outer diameter", "tip.magnet_outer_diameter"),
    Parameter("magnet_inner_diameter", "m", "ring inner diameter", "tip.magnet_inner_diameter"),
    Parameter("magnet_length", "m", "ring length", "tip.magnet_length"),
    Parameter("magnet_remanence", "T", "ring remanence", "tip.remanence"),
    Parameter("magnet_gap", "m", "face-to-face gap of the rings", "tip.gap"),
    Parameter("magnet_density", "kg/m^3", "ring density", "tip.density"),
    Parameter("tip_mass", "kg", "extra mass at the tip (mounting pieces)", "tip.mass"),
    Parameter("external_diameter", "m", "external cylinder diameter", "external_magnet.diameter"),
    Parameter("external_length", "m", "external cylinder length", "external_magnet.length"),
    Parameter(
        "external_remanence", "T", "external magnet remanence", "external_magnet.remanence"
    ),
    *_vector("external_center", "m", "external magnet centre", "external_magnet.center"),
    *_vector(
        "external_magnetization",
        "-",
        "external magnetisation direction",
        "external_magnet.magnetization",
    ),
    *_vector("gravity", "m/s^2", "acceleration of gravity", "environment.gravity"),
    *[
        Parameter(name, "-", f"calibration factor on the {what} (1 = as designed)", None)
        for name, what in (
            ("bending_rigidity_scale", "bending rigidity EI of catheter + wire"),
            ("wire_torsion_scale", "torsional rigidity GJ of the wire"),
            ("catheter_torsion_scale", "torsional rigidity GJ of the catheter"),
        )
    ],
    Parameter("load_scale", "-", "multiplies every load (1 = physical; continuation)", None),
]

PARAMETERS: dict[str, Parameter] = {p.name: p for p in _TABLE}
NAMES: tuple[str, ...] = tuple(PARAMETERS)
"""Parameter names in vector order."""


def parameter_vector(design: Design) -> np.ndarray:
    """Numeric parameter vector of ``design`` in the order of ``NAMES``, shape (n,). [SI]"""
    return np.array([PARAMETERS[n].value(design) for n in NAMES], dtype=float)


def design_with(design: Design, values: dict[str, float]) -> Design:
    """``design`` with the named parameters set (SI): the inverse of
    :func:`parameter_vector` for the parameters a design holds. A model-only factor (no
    ``field``) or an unknown name is a KeyError."""
    for name, value in values.items():
        field = PARAMETERS[name].field if name in PARAMETERS else None
        if field is None:
            raise KeyError(f"{name!r} is not a quantity of a design")
        path, i = _split(field)
        design = _replaced(design, path, i, float(value))
    return design


def _replaced(node: Any, path: list[str], i: int | None, value: float) -> Any:
    head, rest = path[0], path[1:]
    if rest:
        return replace(node, **{head: _replaced(getattr(node, head), rest, i, value)})
    if i is None:
        return replace(node, **{head: value})
    vector = list(getattr(node, head) or (0.0, 0.0, 0.0))
    vector[i] = value
    return replace(node, **{head: tuple(vector)})


def index(name: str) -> int:
    """Position of a parameter in the vector; KeyError names the valid ones."""
    try:
        return NAMES.index(name)
    except ValueError:
        raise KeyError(f"unknown model parameter {name!r}; expected one of {NAMES}") from None


FILE_UNITS: dict[str, tuple[str, float, str]] = {
    "m": ("mm", MM, "mm"),
    "rad": ("deg", DEG, "deg"),
    "Pa": ("MPa", MPA, "mpa"),
    "kg": ("g", GRAM, "g"),
}
"""SI unit -> (the unit files, options and reports use, its size in SI, the key suffix);
other units (T, -, kg/m^3, m/s^2) are used as they are."""

RENAMED: dict[str, str] = {
    **{f"ring_{q}": f"magnet_{q}" for q in (
        "outer_diameter", "inner_diameter", "length", "gap", "remanence", "density"
    )},
    **{f"external_axis_{a}": f"external_magnetization_{a}" for a in "xyz"},
}
"""Old name -> name (the tip's quantities were called ``ring_*`` and the external
magnetisation ``external_axis_*`` before the names followed the design file)."""


def file_unit(name: str) -> tuple[str, float]:
    """The unit a value of parameter ``name`` is given in by files and options, and its
    size in SI (``("mm", 1e-3)`` for a length)."""
    unit = PARAMETERS[name].unit
    label, size, _ = FILE_UNITS.get(unit, (unit, 1.0, ""))
    return label, size


def file_key(name: str) -> str:
    """The key of parameter ``name`` in study files and tables: the name and its file
    unit's suffix (``magnet_length_mm``, ``catheter_youngs_modulus_mpa``)."""
    suffix = FILE_UNITS.get(PARAMETERS[name].unit, ("", 1.0, ""))[2]
    return f"{name}_{suffix}" if suffix else name


def current(name: str) -> str:
    """``name``, or for an old name (or an old name with a unit suffix, as study files
    have it) the current one, with a FutureWarning that says so."""
    for old, new in RENAMED.items():
        if name == old or name.startswith(old + "_"):
            now = new + name[len(old):]
            warnings.warn(
                f"'{name}' is now called '{now}'; the old name will stop working",
                FutureWarning,
                stacklevel=2,
            )
            return now
    return name
