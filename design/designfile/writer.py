"""Writing a design file: a :class:`~design.records.Design` back to the document (file
units) and to TOML text."""

from __future__ import annotations

import os
from dataclasses import replace
from typing import Any

import tomli_w

from design.atomic import write_text
from design.fields.sources import KINDS as SOURCE_KINDS
from design.process import DEFAULT_PROCESS
from design.records import Design, Mounting, Obstacle
from design.registry import PARAMETERS, file_unit
from design.units import MM


def _file_units(x: float, scale: float) -> float:
    """SI value in file units, rounded to 12 significant digits so 1.8 mm stays 1.8."""
    return x if scale == 1.0 else float(f"{x / scale:.12g}")


def design_to_dict(design: Design, explicit: bool = False) -> dict[str, Any]:
    """The design-file document (file units) of a :class:`Design`: every key of
    :data:`SECTIONS`, optional keys only where they differ from their default; with
    ``explicit``, the ``[tip.mounting]`` section in full (process, wall, fits, density,
    stops, pre-twist: a hand-off that does not lean on defaults a later version may
    change)."""
    doc: dict[str, Any] = {"name": design.name}
    if design.description:
        doc["description"] = design.description
    doc["robot"] = {}
    doc["tip"] = {}
    if design.external_magnet is not None:
        doc["external_magnet"] = {"shape": design.external_magnet.shape}
    mounting = design.tip.mounting
    defaults = Mounting.printed_by(mounting.process)
    if explicit or mounting.process != DEFAULT_PROCESS or mounting.compensate_holes:
        doc["tip"]["mounting"] = {"process": mounting.process}
        if explicit or mounting.compensate_holes:
            doc["tip"]["mounting"]["compensate_holes"] = mounting.compensate_holes
    for p in PARAMETERS.values():
        if p.key is None or p.field is None:
            continue
        section, leaf = p.key.rsplit(".", 1)
        if section == "environment" and design.environment.gravity is None:
            continue
        if section == "external_magnet" and design.external_magnet is None:
            continue
        value = p.value(design)
        default = p.default
        if section == "tip.mounting":  # the process's value
            default = p.value(replace(design, tip=replace(design.tip, mounting=defaults)))
            if explicit:
                default = None
        if "[" not in p.field and default is not None and value == default:
            continue
        node = doc
        for part in section.split("."):
            node = node.setdefault(part, {})
        if "[" in p.field:
            node.setdefault(leaf, []).append(_file_units(value, file_unit(p.name)[1]))
        else:
            node[leaf] = _file_units(value, file_unit(p.name)[1])
    if design.environment.obstacles:
        doc.setdefault("environment", {})["obstacles"] = [
            _obstacle_table(o) for o in design.environment.obstacles
        ]
    if design.sources:
        doc["field"] = {"sources": _sources_to_list(design)}
    return doc


def _obstacle_table(o: Obstacle) -> dict[str, Any]:
    """One ``[[environment.obstacles]]`` table (file units) of an obstacle."""
    table: dict[str, Any] = {"kind": o.kind, "point_mm": [_file_units(c, MM) for c in o.point]}
    if o.kind != "sphere":
        table["normal"] = [float(c) for c in o.normal]
    if o.kind != "plane":
        table["radius_mm"] = _file_units(o.radius, MM)
    if o.friction:
        table["friction"] = o.friction
    return table


def _sources_to_list(design: Design) -> list[dict[str, Any]]:
    """The ``[[field.sources]]`` tables of ``design`` (file units)."""
    out = []
    for src in design.sources:
        table: dict[str, Any] = {"kind": src.kind}
        for q in SOURCE_KINDS[src.kind]:
            value = getattr(src, q.name)
            if q.size == 3:
                table[q.key] = [_file_units(v, q.scale) for v in value]
            else:
                table[q.key] = _file_units(value, q.scale)
        if src.kind == "map":
            table["file"] = src.file
        out.append(table)
    return out


def dumps_design(design: Design, explicit: bool = False) -> str:
    """Design-file text of a :class:`Design` (``explicit``: :func:`design_to_dict`)."""
    return tomli_w.dumps(design_to_dict(design, explicit))


def save_design(design: Design, path: str | os.PathLike[str], explicit: bool = False) -> None:
    """Write a design file atomically (``explicit``: :func:`design_to_dict`)."""
    write_text(path, dumps_design(design, explicit))
