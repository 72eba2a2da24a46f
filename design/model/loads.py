"""Effects as objects: what each switchable effect adds to the loads on the robot, composed
by :class:`~design.model.ring_pair.RingPairModel` (after PyElastica's external loads, each
a class with one method, composed by the system).

An effect here says which point masses it carries on the rigid tip (:meth:`masses`), what
distributed load per unit ``load_scale`` it puts on the rod (:meth:`weight_rate`) and what
it adds to the force and moment at the rod's end at a pose (:meth:`add`); the model calls
the effects it has switched on in :data:`TIP_EFFECTS`' order. CasADi symbols, SI units:
force [N], moment about the rod's end [N m], base frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

from design.model.effects import PRINTED_TIP
from design.model.symbols import Symbols


@dataclass(frozen=True)
class TipFrame:
    """Where the tip loads act: the model's symbols, the load scale, the rigid segment's
    length from the rod's end to the tracked point (``offset``, 0 without it) [m], the
    tip tangent (3,) and the point masses on the rigid tip (arm from the rod's end along
    the tangent [m], mass [kg])."""

    s: Symbols
    load: Any
    offset: Any
    tangent: Any
    masses: tuple[tuple[Any, Any], ...]


class TipEffect:
    """An effect's share of the loads (none by default)."""

    name: str = ""

    def masses(self, s: Symbols) -> list[tuple[Any, Any]]:
        """Point masses the effect carries on the rigid tip: (arm [m], mass [kg])."""
        return []

    def weight_rate(self, s: Symbols) -> Any | None:
        """Distributed load on the rod per unit ``load_scale`` [N/m], or None."""
        return None

    def add(self, at: TipFrame, force: Any, torque: Any) -> tuple[Any, Any]:
        """The force [N] and moment about the rod's end [N m] with the effect's added."""
        return force, torque


class PrintedTip(TipEffect):
    """The tip as built (:mod:`design.mounting`): the mounting pieces' masses ride on the
    rigid segment, and the loads at the tracked point act about the rod's end, ``offset``
    behind it."""

    name = PRINTED_TIP

    def masses(self, s: Symbols) -> list[tuple[Any, Any]]:
        return [
            (s.tip.proximal_arm, s.tip.proximal_mass),
            (s.tip.distal_arm, s.tip.distal_mass),
        ]

    def add(self, at: TipFrame, force: Any, torque: Any) -> tuple[Any, Any]:
        return force, torque + at.offset * ca.cross(at.tangent, force)


class Gravity(TipEffect):
    """The weight of catheter and wire (distributed) and of every point mass on the tip,
    along ``environment.gravity_m_s2``."""

    name = "gravity"

    def weight_rate(self, s: Symbols) -> Any:
        return s.rod_mass_per_length * s.gravity

    def add(self, at: TipFrame, force: Any, torque: Any) -> tuple[Any, Any]:
        g = at.load * at.s.gravity
        for arm, mass in at.masses:
            force = force + mass * g
            torque = torque + arm * ca.cross(at.tangent, mass * g)
        return force, torque


TIP_EFFECTS: tuple[TipEffect, ...] = (PrintedTip(), Gravity())
"""The effects with loads of their own, in the order the model adds them (the printed
tip's moment arm applies to the field's and the applied force, each weight has its own)."""


def tip_effects(effects: frozenset[str]) -> tuple[TipEffect, ...]:
    """The effects of :data:`TIP_EFFECTS` switched on in ``effects``, in order."""
    return tuple(e for e in TIP_EFFECTS if e.name in effects)
