"""The model's field: the design's ``[external_magnet]`` (its parameters the registry's
``external_*``) and its ``[[field.sources]]`` (their parameters after
:data:`design.registry.NAMES`, :func:`design.registry.source_names`), superposed.

Permanent magnets give their exact field where the model's ``near_field`` effect is on and
their point dipole otherwise; uniform fields, coils and maps are exact always
(:mod:`design.fields`). The kinds of the sources and a map's grid are the model's structure
(:class:`FieldLayout`, one model per layout); their numbers are parameters, so studies and
calibration can free them. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import casadi as ca

from design.dipole import dipole_field, dipole_field_gradient
from design.fields.cylinder import cylinder_field
from design.fields.fieldmap import FieldMap
from design.fields.sources import (
    KINDS,
    MAX_CLEARANCE,
    PERMANENT,
    magnet_distance,
    source_field,
)
from design.geometry import ring_clearance, ring_radius
from design.records import Design
from design.wrench import FieldModel

if TYPE_CHECKING:
    from design.model.symbols import Symbols


@dataclass(frozen=True)
class FieldLayout:
    """The structure of a design's field.

    external : whether the design has an ``[external_magnet]``.
    kinds : the kinds of its ``[[field.sources]]``, in the file's order.
    maps : for each source its grid (a map) or None.
    """

    external: bool = True
    kinds: tuple[str, ...] = ()
    maps: tuple[FieldMap | None, ...] = ()

    @property
    def size(self) -> int:
        """Number of the sources' parameters (after :data:`design.registry.NAMES`)."""
        return sum(q.size for kind in self.kinds for q in KINDS[kind])

    @property
    def permanent(self) -> bool:
        """Whether the field has a permanent magnet (the robot must keep clear of it)."""
        return self.external or any(k in PERMANENT for k in self.kinds)

    def describe(self) -> str:
        """'external magnet + coil + coil', for messages."""
        parts = (["external magnet"] if self.external else []) + list(self.kinds)
        return " + ".join(parts) or "no field"


CLASSIC = FieldLayout()
"""The field of a design with its ``[external_magnet]`` alone (the paper's set-up)."""


def layout_of(design: Design) -> FieldLayout:
    """The :class:`FieldLayout` of ``design``."""
    return FieldLayout(
        design.external_magnet is not None,
        tuple(s.kind for s in design.sources),
        tuple(s.fieldmap for s in design.sources),
    )


def field_model(s: Symbols, exact: bool) -> FieldModel:
    """p (3) [m] -> (B [T], dB/dp [T/m]) of the model's sources superposed; permanent
    magnets exact with ``exact`` (the ``near_field`` effect), else their point dipoles."""

    def external(p: ca.SX) -> tuple[ca.SX, ca.SX]:
        offset = p - s.external_center
        if exact:
            return cylinder_field(
                offset,
                s.external_magnetization,
                s["external_diameter"],
                s["external_length"],
                s["external_remanence"],
            )
        return dipole_field(offset, s.external_moment), dipole_field_gradient(
            offset, s.external_moment
        )

    def model(p: ca.SX) -> tuple[ca.SX, ca.SX]:
        terms = [external(p)] if s.layout.external else []
        terms += [source_field(kind, q, p, exact, fm) for kind, q, fm in s.sources]
        if not terms:
            return ca.SX.zeros(3), ca.SX.zeros(3, 3)
        flux, grad = terms[0]
        for b, g in terms[1:]:
            flux, grad = flux + b, grad + g
        return flux, grad

    return model


def magnet_clearance(s: Symbols, position: ca.SX, frame: ca.SX) -> ca.SX:
    """Clearance of the tip rings to the nearest permanent magnet (the external magnet,
    :func:`design.geometry.ring_clearance`, and the sources'); negative where they touch;
    :data:`design.fields.sources.MAX_CLEARANCE` where the field has none. [m]"""
    from design.model.symbols import ring_positions

    centres = ring_positions(s, position, frame)
    out: Any = None
    if s.layout.external:
        out = ring_clearance(
            centres,
            s["magnet_outer_diameter"],
            s["magnet_length"],
            s.external_center,
            s.external_magnetization,
            s["external_diameter"],
            s["external_length"],
        )
    reach = ring_radius(s["magnet_outer_diameter"], s["magnet_length"])
    for kind, q, _ in s.sources:
        if kind in PERMANENT:
            for centre in centres:
                gap = magnet_distance(kind, q, centre) - reach
                out = gap if out is None else ca.fmin(out, gap)
    return ca.SX(MAX_CLEARANCE) if out is None else out
