"""A design file's keys: one :class:`Key` per numeric quantity, from the registry
(:mod:`design.registry`), and the reading of one section's keys into SI values, checking
names, types and ranges (:class:`DesignError` names the key, what was expected and what
was found)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from design.registry import PARAMETERS, file_unit
from design.suggest import did_you_mean


class DesignError(ValueError):
    """A design file that cannot describe a robot. The message is meant for the user."""


@dataclass(frozen=True)
class Key:
    """One numeric key of a design file.

    scale : factor from the file's unit to SI.
    low, high : admissible range in file units; ``None`` is unbounded.
    low_open : whether ``low`` itself is excluded.
    """

    name: str
    meaning: str
    scale: float = 1.0
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    vector: bool = False
    default: float | None = None
    """Optional key (the project's addition to the spec) when not None; its value in SI."""

    def expected(self) -> str:
        lo = (
            "" if self.low is None else (f"> {self.low:g}" if self.low_open else f">= {self.low:g}")
        )
        hi = "" if self.high is None else f"<= {self.high:g}"
        rng = " and ".join(x for x in (lo, hi) if x)
        if self.vector:
            return "an array of three finite numbers" + (f", each {rng}" if rng else "")
        return f"a number {rng}".rstrip()

    def admits(self, x: float) -> bool:
        """Whether the finite number ``x`` lies in the key's range."""
        too_low = self.low is not None and (x <= self.low if self.low_open else x < self.low)
        return not (too_low or (self.high is not None and x > self.high))


def _sections() -> dict[str, tuple[Key, ...]]:
    """The numeric keys of each section, from the registry (:mod:`design.registry`): one
    key per quantity (a vector's three parameters share theirs), in the registry's order."""
    sections: dict[str, list[Key]] = {"robot": [], "robot.catheter": [], "robot.wire": []}
    for p in PARAMETERS.values():
        if p.key is None or p.field is None:
            continue
        vector = "[" in p.field
        if vector and not p.field.endswith("[0]"):
            continue
        section, leaf = p.key.rsplit(".", 1)
        meaning = p.meaning.rsplit(",", 1)[0] if vector else p.meaning
        label, size = file_unit(p.name)
        optional = "optional: " if p.default is not None else ""
        sections.setdefault(section, []).append(
            Key(
                leaf,
                f"{optional}{meaning} [{label}]",
                size,
                p.low,
                p.high,
                p.low_open,
                vector,
                p.default,
            )
        )
    return {name: tuple(keys) for name, keys in sections.items()}


SECTIONS: dict[str, tuple[Key, ...]] = _sections()
OPTIONAL_SECTIONS = {"environment"}
OPTIONAL_KEYS = {"environment.gravity_m_s2"}
TOP_KEYS = {"name", "description", "robot", "tip", "external_magnet", "environment", "field"}
EXTERNAL_SHAPES = ("cylinder",)
UNIT_TOLERANCE = 1e-3


def as_float(value: int | float) -> float:
    """``value`` as a float; an integer too large for one (TOML integers have any number of
    digits) is an infinity of its sign, which no key admits."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def shown(value: Any) -> str:
    """``repr(value)`` for a message, a long one (a 400-digit integer) cut to its start."""
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"


def _number(path: str, value: Any, key: Key) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DesignError(f"{path} must be {key.expected()}; got {shown(value)}")
    x = as_float(value)
    if not (math.isfinite(x) and key.admits(x)):
        raise DesignError(f"{path} must be {key.expected()}; got {shown(value)}")
    return x


def _vector(path: str, value: Any, key: Key) -> tuple[float, float, float]:
    ok = isinstance(value, list) and len(value) == 3
    ok = ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ok = ok and all(math.isfinite(as_float(v)) and key.admits(as_float(v)) for v in value)
    if not ok:
        raise DesignError(f"{path} must be {key.expected()}; got {shown(value)}")
    return (float(value[0]), float(value[1]), float(value[2]))


def _section(doc: dict[str, Any], name: str) -> dict[str, Any]:
    """Read one section's numeric keys into SI values, checking names, types and ranges."""
    node: Any = doc
    for part in name.split("."):
        node = node.get(part) if isinstance(node, dict) else None
    if node is None:
        raise DesignError(f"missing section [{name}]")
    if not isinstance(node, dict):
        raise DesignError(f"[{name}] must be a table of keys; got {node!r}")
    keys = {k.name: k for k in SECTIONS[name]}
    subsections = {s.split(".")[-1] for s in SECTIONS if s.startswith(name + ".")}
    extra = {
        "external_magnet": {"shape"},
        "tip.mounting": {"process", "compensate_holes"},
        "environment": {"obstacles"},
    }.get(name, set())
    for given in node:
        if given not in keys and given not in subsections and given not in extra:
            allowed = set(keys) | subsections | extra
            raise DesignError(f"unknown key {name}.{given}{did_you_mean(given, allowed)}")
    out: dict[str, Any] = {}
    for key in keys.values():
        path = f"{name}.{key.name}"
        if key.name not in node:
            if key.default is not None:
                out[key.name] = key.default
                continue
            if path in OPTIONAL_KEYS:
                continue
            raise DesignError(f"missing key {path} ({key.meaning}); expected {key.expected()}")
        raw = node[key.name]
        if key.vector:
            v = _vector(path, raw, key)
            out[key.name] = (v[0] * key.scale, v[1] * key.scale, v[2] * key.scale)
        else:
            out[key.name] = _number(path, raw, key) * key.scale
    return out
