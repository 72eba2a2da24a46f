"""Field sources: the kinds a design file's ``[[field.sources]]`` lists, the quantities
each kind has (one table, read by the design-file reader, the parameter vector and the
model), and the superposed field of a list of sources on CasADi symbols.

Kinds (docs/formats.md): permanent magnets ``cylinder`` (axially magnetised), ``cuboid``
(edges along the base axes), ``sphere``; ``uniform`` (a field vector, no gradient);
``coil`` (a circular current loop of ``turns`` thin turns); ``map`` (a field sampled on a
grid, :mod:`design.fields.fieldmap`). Each source's numeric quantities are model
parameters (:func:`parameter_names`), so calibration and NLPs can free them; the kind
and, for a map, its grid are the model's structure. SI units are used for all inputs
and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

from design.dipole import dipole_field, dipole_field_gradient
from design.fields.coil import coil_field
from design.fields.cuboid import cuboid_field
from design.fields.cylinder import cylinder_field
from design.fields.fieldmap import FieldMap, map_field
from design.fields.sphere import sphere_field, sphere_moment
from design.fields.uniform import uniform_field
from design.geometry import SMOOTH, cylinder_distance
from design.magnets import cylinder_moment, magnetization

__all__ = [
    "KINDS",
    "PERMANENT",
    "Quantity",
    "magnet_distance",
    "parameter_names",
    "source_field",
    "superposed_field",
]


@dataclass(frozen=True)
class Quantity:
    """One numeric quantity of a source kind.

    name : the :class:`~design.records.Source` field and the parameter's suffix.
    unit : SI unit. size : 1 or 3 (a vector, base frame).
    key : the design-file key (its unit's suffix included); scale : file unit in SI.
    low, high, low_open : the admissible range in file units (each component of a vector).
    unit_vector : a direction, normalised by the reader (length 1 within 1e-3).
    default : the value where the file leaves the key out (file units), or None (required).
    """

    name: str
    unit: str
    size: int
    key: str
    scale: float
    meaning: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    unit_vector: bool = False
    default: Any = None


_MM = 1e-3
_CENTER = Quantity("center", "m", 3, "center_mm", _MM, "centre, base frame", -10000, 10000)
_REMANENCE = Quantity("remanence", "T", 1, "remanence_t", 1.0, "remanence", 0.0, 2.0)
_MAGNETIZATION = Quantity(
    "magnetization", "-", 3, "magnetization", 1.0, "magnetisation direction", unit_vector=True
)
_DIAMETER = Quantity("diameter", "m", 1, "diameter_mm", _MM, "diameter", 0.0, 10000, True)

KINDS: dict[str, tuple[Quantity, ...]] = {
    "uniform": (Quantity("b", "T", 3, "b_t", 1.0, "field vector", -100.0, 100.0),),
    "cylinder": (
        _DIAMETER,
        Quantity("length", "m", 1, "length_mm", _MM, "length", 0.0, 10000, True),
        _REMANENCE, _CENTER, _MAGNETIZATION,
    ),
    "cuboid": (
        Quantity(
            "dimensions", "m", 3, "dimensions_mm", _MM, "side lengths along x, y, z",
            0.0, 10000, True,
        ),
        _REMANENCE, _CENTER, _MAGNETIZATION,
    ),
    "sphere": (_DIAMETER, _REMANENCE, _CENTER, _MAGNETIZATION),
    "coil": (
        Quantity("radius", "m", 1, "radius_mm", _MM, "loop radius", 0.0, 10000, True),
        Quantity("turns", "-", 1, "turns", 1.0, "number of turns", 0.0, 1e7, True),
        Quantity("current", "A", 1, "current_a", 1.0, "current per turn", -1e6, 1e6),
        _CENTER,
        Quantity(
            "axis", "-", 3, "axis", 1.0, "loop normal (right-hand rule)", unit_vector=True
        ),
    ),
    "map": (
        Quantity(
            "center", "m", 3, "center_mm", _MM, "where the map's origin lies, base frame",
            -10000, 10000, default=[0.0, 0.0, 0.0],
        ),
    ),
}  # fmt: skip
"""Each kind's quantities, in parameter order; ``map`` also has ``file``."""
PERMANENT = ("cylinder", "cuboid", "sphere")
"""The kinds that are permanent magnets: exact field with the model's ``near_field``,
their point dipole otherwise; the robot must stay clear of them."""


def parameter_names(number: int, kind: str) -> list[str]:
    """The model parameters of source ``number`` (1-based, in the file's order) of
    ``kind``: ``source<number>_<quantity>``, vectors with ``_x``, ``_y``, ``_z``."""
    out = []
    for q in KINDS[kind]:
        stem = f"source{number}_{q.name}"
        out += [f"{stem}_{a}" for a in "xyz"] if q.size == 3 else [stem]
    return out


def split_parameters(kind: str, block: ca.SX) -> dict[str, ca.SX]:
    """The quantities of a ``kind`` source from its parameter block (:func:`parameter_names`
    order); directions normalised."""
    out, i = {}, 0
    for q in KINDS[kind]:
        value = block[i : i + q.size]
        out[q.name] = value / ca.norm_2(value) if q.unit_vector else value
        i += q.size
    return out


def moment(kind: str, q: dict[str, ca.SX]) -> ca.SX:
    """Total moment of a permanent magnet, Br / mu0 V along its magnetisation. [A m^2]"""
    if kind == "cylinder":
        size = cylinder_moment(q["diameter"], q["length"], q["remanence"])
    elif kind == "sphere":
        size = sphere_moment(q["diameter"], q["remanence"])
    else:
        d = q["dimensions"]
        size = magnetization(q["remanence"]) * d[0] * d[1] * d[2]
    return size * q["magnetization"]


def source_field(
    kind: str, q: dict[str, ca.SX], point: ca.SX, exact: bool, fieldmap: FieldMap | None = None
) -> tuple[ca.SX, ca.SX]:
    """B (3,) [T] and G = dB/dp (3, 3) [T/m] of one source with quantities ``q``
    (:func:`split_parameters`) at ``point`` (3,), base frame [m]; a permanent magnet's
    exact field with ``exact``, else its point dipole."""
    if kind == "uniform":
        return uniform_field(point, q["b"])
    offset = point - q["center"]
    if kind == "map":
        assert fieldmap is not None, "a map source needs its grid"
        return map_field(offset, fieldmap)
    if kind == "coil":
        return coil_field(offset, q["axis"], q["radius"], q["turns"], q["current"])
    if kind == "sphere" or (kind in PERMANENT and not exact):
        if kind == "sphere":
            return sphere_field(offset, q["magnetization"], q["diameter"], q["remanence"])
        m = moment(kind, q)
        return dipole_field(offset, m), dipole_field_gradient(offset, m)
    if kind == "cylinder":
        return cylinder_field(
            offset, q["magnetization"], q["diameter"], q["length"], q["remanence"]
        )
    if kind == "cuboid":
        return cuboid_field(offset, q["dimensions"], q["magnetization"], q["remanence"])
    raise ValueError(f"unknown source kind {kind!r}; expected one of {', '.join(KINDS)}")


def superposed_field(terms: list[tuple[ca.SX, ca.SX]]) -> tuple[ca.SX, ca.SX]:
    """The sum of several sources' (B, G). [T, T/m]"""
    flux: Any = ca.SX.zeros(3)
    grad: Any = ca.SX.zeros(3, 3)
    for b, g in terms:
        flux, grad = flux + b, grad + g
    return flux, grad


def magnet_distance(kind: str, q: dict[str, ca.SX], point: ca.SX) -> ca.SX:
    """Distance from ``point`` (3,) [m] to a permanent magnet's body (0 inside). [m]"""
    offset = point - q["center"]
    if kind == "cylinder":
        return cylinder_distance(offset, q["magnetization"], q["diameter"] / 2, q["length"] / 2)
    if kind == "sphere":
        return ca.sqrt(ca.sumsqr(offset) + SMOOTH**2) - q["diameter"] / 2
    outside = ca.fmax(ca.fabs(offset) - q["dimensions"] / 2, 0)
    return ca.sqrt(ca.sumsqr(outside) + SMOOTH**2)


MAX_CLEARANCE = 1.0
"""The clearance reported where no permanent magnet is near (none in the design). [m]"""
