"""The field a design steers in: the ``[external_magnet]`` section and the
``[[field.sources]]`` list (docs/formats.md), each value checked."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from design.designfile.keys import (
    EXTERNAL_SHAPES,
    UNIT_TOLERANCE,
    DesignError,
    Key,
    _number,
    _section,
    _vector,
)
from design.fields.fieldmap import FieldMapError, read_field_map
from design.fields.sources import KINDS as SOURCE_KINDS
from design.records import ExternalMagnet, Source
from design.suggest import did_you_mean


def _external_magnet(doc: dict[str, Any]) -> ExternalMagnet:
    if "external_magnet" not in doc:
        raise DesignError(
            "missing section [external_magnet] (or a field of [[field.sources]]); the "
            "robot needs a field to steer in"
        )
    e = _section(doc, "external_magnet")
    shape = doc["external_magnet"].get("shape")
    if shape not in EXTERNAL_SHAPES:
        raise DesignError(
            f"external_magnet.shape must be one of {', '.join(map(repr, EXTERNAL_SHAPES))}; "
            f"got {shape!r}"
        )
    mag = e["magnetization"]
    norm = math.sqrt(sum(c * c for c in mag))
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        raise DesignError(
            "external_magnet.magnetization must be a unit vector (length 1 within "
            f"{UNIT_TOLERANCE:g}); got {list(mag)} of length {norm:.6g}"
        )
    mag = tuple(c / norm for c in mag)
    return ExternalMagnet(
        shape,
        e["diameter_mm"],
        e["length_mm"],
        e["remanence_t"],
        e["center_mm"],
        mag,
    )


def _sources(doc: dict[str, Any], base: Path | None) -> tuple[Source, ...]:
    """The ``[[field.sources]]`` list (docs/formats.md), each checked against its kind's
    quantities (:data:`design.fields.sources.KINDS`); a map's grid read from its file."""
    node = doc.get("field", {})
    if not isinstance(node, dict) or set(node) - {"sources"}:
        extra = sorted(set(node) - {"sources"}) if isinstance(node, dict) else []
        raise DesignError(f"[field] holds only the list [[field.sources]]; got {extra or node!r}")
    raw = node.get("sources", [])
    if not isinstance(raw, list) or not all(isinstance(t, dict) for t in raw):
        raise DesignError(f"field.sources must be a list of tables [[field.sources]]; got {raw!r}")
    return tuple(_source(i + 1, t, base) for i, t in enumerate(raw))


def _source(number: int, table: dict[str, Any], base: Path | None) -> Source:
    where = f"field.sources[{number}]"
    kind = table.get("kind")
    if kind not in SOURCE_KINDS:
        raise DesignError(
            f"{where}.kind must be one of {', '.join(map(repr, SOURCE_KINDS))}; got {kind!r}"
        )
    quantities = {q.key: q for q in SOURCE_KINDS[kind]}
    allowed = {"kind", *quantities} | ({"file"} if kind == "map" else set())
    for given in table:
        if given not in allowed:
            raise DesignError(
                f"unknown key {where}.{given} for a {kind} source"
                f"{did_you_mean(given, allowed)}; expected {', '.join(sorted(allowed))}"
            )
    values: dict[str, Any] = {}
    for key, q in quantities.items():
        path = f"{where}.{key}"
        raw = table.get(key, q.default)
        if raw is None:
            raise DesignError(f"missing key {path} ({q.meaning}) for a {kind} source")
        spec = Key(key, q.meaning, q.scale, q.low, q.high, q.low_open, q.size == 3)
        if q.size == 1:
            values[q.name] = _number(path, raw, spec) * q.scale
            continue
        v = _vector(path, raw, spec)
        if q.unit_vector:
            norm = math.sqrt(sum(c * c for c in v))
            if abs(norm - 1.0) > UNIT_TOLERANCE:
                raise DesignError(
                    f"{path} must be a unit vector (length 1 within {UNIT_TOLERANCE:g}); "
                    f"got {list(v)} of length {norm:.6g}"
                )
            v = (v[0] / norm, v[1] / norm, v[2] / norm)
        values[q.name] = (v[0] * q.scale, v[1] * q.scale, v[2] * q.scale)
    if kind != "map":
        return Source(kind, **values)  # type: ignore[arg-type]
    name = table.get("file")
    if not isinstance(name, str) or not name.strip():
        raise DesignError(f"missing key {where}.file (the field map's CSV file) for a map source")
    where_file = Path(name) if base is None else base / name
    try:
        fieldmap = read_field_map(where_file)
    except FieldMapError as exc:
        raise DesignError(f"{where}.file: {exc}") from None
    resolved = str(where_file.resolve())
    return Source(kind, file=resolved, fieldmap=fieldmap, **values)  # type: ignore[arg-type]
