"""The ``[[environment.obstacles]]`` tables of a design file (docs/formats.md), checked."""

from __future__ import annotations

import math
from typing import Any

from design.designfile.keys import DesignError, Key, _number, _vector
from design.obstacles import KINDS
from design.records import Obstacle
from design.suggest import did_you_mean
from design.units import MM

OBSTACLE_KEYS = {"kind", "point_mm", "normal", "radius_mm", "friction"}


def _obstacles(raw: Any) -> tuple[Obstacle, ...]:
    """The ``[[environment.obstacles]]`` tables (docs/formats.md), checked. [SI]"""
    if not isinstance(raw, list) or not all(isinstance(o, dict) for o in raw):
        raise DesignError(
            f"environment.obstacles must be an array of tables ([[environment.obstacles]]); "
            f"got {raw!r}"
        )
    out = []
    for i, node in enumerate(raw):
        path = f"environment.obstacles[{i}]"
        for given in node:
            if given not in OBSTACLE_KEYS:
                raise DesignError(f"unknown key {path}.{given}{did_you_mean(given, OBSTACLE_KEYS)}")
        kind = node.get("kind")
        if kind not in KINDS:
            raise DesignError(f"{path}.kind must be one of {', '.join(KINDS)}; got {kind!r}")
        needs = {"point_mm"} | ({"normal"} if kind != "sphere" else set())
        needs |= {"radius_mm"} if kind != "plane" else set()
        for key in sorted(needs):
            if key not in node:
                raise DesignError(f"missing key {path}.{key} (a {kind} needs {sorted(needs)})")
        for key in sorted(set(node) - needs - {"kind", "friction"}):
            raise DesignError(f"{path}.{key} does not apply to a {kind}; remove it")
        anywhere = Key("point_mm", "a point", vector=True)
        px, py, pz = _vector(f"{path}.point_mm", node["point_mm"], anywhere)
        point = (px * MM, py * MM, pz * MM)
        normal = (0.0, 0.0, 0.0)
        if "normal" in node:
            n = _vector(f"{path}.normal", node["normal"], Key("normal", "a direction", vector=True))
            length = math.sqrt(sum(c * c for c in n))
            if not length > 0:
                raise DesignError(f"{path}.normal must be a non-zero vector; got {list(n)}")
            normal = (n[0] / length, n[1] / length, n[2] / length)
        radius = 0.0
        if "radius_mm" in node:
            positive = Key("radius_mm", "a radius", low=0.0, low_open=True)
            radius = _number(f"{path}.radius_mm", node["radius_mm"], positive) * MM
        friction = 0.0
        if "friction" in node:
            coefficient = Key("friction", "a Coulomb coefficient", low=0.0)
            friction = _number(f"{path}.friction", node["friction"], coefficient)
            if friction > 0:
                raise DesignError(
                    f"{path}.friction = {friction:g}: friction at obstacles is not modelled "
                    "yet (contact is frictionless); remove it or set 0"
                )
        out.append(Obstacle(kind, point, normal, radius, friction))
    return tuple(out)
