"""Design files (TOML, docs/formats.md): load, validate, save.

Files speak millimetres, megapascals, tesla and kg/m^3 as their key names say; the
returned :class:`~design.records.Design` is in SI. Every bad value raises
:class:`DesignError` whose message names the key, what was expected and what was found.
"""

from __future__ import annotations

import math
import os
import stat
import tomllib
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import tomli_w

from design.atomic import write_text
from design.fields.fieldmap import FieldMapError, read_field_map
from design.fields.sources import KINDS as SOURCE_KINDS
from design.fields.sources import PERMANENT, magnet_distance
from design.geometry import (
    WIRE_CLEARANCE,
    cylinder_distance,
    rest_position,
    ring_centres,
    ring_clears_wire,
)
from design.mounting import design_tip_geometry
from design.obstacles import KINDS, gaps, tip_body
from design.process import DEFAULT_PROCESS, PROCESSES
from design.records import (
    Design,
    Environment,
    ExternalMagnet,
    Mounting,
    Obstacle,
    Robot,
    Source,
    Tip,
    Tube,
)
from design.registry import PARAMETERS, file_unit
from design.suggest import did_you_mean
from design.units import MM


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


def _number(path: str, value: Any, key: Key) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DesignError(f"{path} must be {key.expected()}; got {value!r}")
    x = float(value)
    if not (math.isfinite(x) and key.admits(x)):
        raise DesignError(f"{path} must be {key.expected()}; got {value!r}")
    return x


def _vector(path: str, value: Any, key: Key) -> tuple[float, float, float]:
    ok = isinstance(value, list) and len(value) == 3
    ok = ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ok = ok and all(math.isfinite(float(v)) and key.admits(float(v)) for v in value)
    if not ok:
        raise DesignError(f"{path} must be {key.expected()}; got {value!r}")
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
        "tip.mounting": {"process"},
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


def _tube(doc: dict[str, Any], name: str) -> Tube:
    s = _section(doc, name)
    od, idia = s["outer_diameter_mm"], s["inner_diameter_mm"]
    if idia >= od:
        raise DesignError(
            f"{name}.inner_diameter_mm must be smaller than outer_diameter_mm "
            f"({od / MM:g}); got {idia / MM:g}"
        )
    return Tube(
        od,
        idia,
        s["youngs_modulus_mpa"],
        s["poisson_ratio"],
        s["density_kg_m3"],
        s["friction_angle_deg"],
    )


def design_from_dict(doc: dict[str, Any], base: Path | None = None) -> Design:
    """Build a validated :class:`Design` (SI) from a parsed design-file document; a field
    map's ``file`` is relative to the folder ``base`` (default: the working directory)."""
    for given in doc:
        if given not in TOP_KEYS:
            raise DesignError(f"unknown key {given}{did_you_mean(given, TOP_KEYS)}")
    name = doc.get("name")
    if not isinstance(name, str) or not name.strip():
        raise DesignError(f"name must be a non-empty string; got {name!r}")
    description = doc.get("description", "")
    if not isinstance(description, str):
        raise DesignError(f"description must be a string; got {description!r}")

    robot_s = _section(doc, "robot")
    catheter = _tube(doc, "robot.catheter")
    wire = _tube(doc, "robot.wire")
    if wire.outer_diameter >= catheter.inner_diameter:
        raise DesignError(
            "robot.wire.outer_diameter_mm must be smaller than robot.catheter.inner_diameter_mm "
            f"({catheter.inner_diameter / MM:g}) so the wire fits inside the catheter; "
            f"got {wire.outer_diameter / MM:g}"
        )
    robot = Robot(robot_s["free_length_mm"], catheter, wire)

    t = _section(doc, "tip")
    tip = Tip(
        t["magnet_outer_diameter_mm"],
        t["magnet_inner_diameter_mm"],
        t["magnet_length_mm"],
        t["remanence_t"],
        t["gap_mm"],
        t["density_kg_m3"],
        t["mass_g"],
        _mounting(doc),
    )
    if tip.magnet_inner_diameter >= tip.magnet_outer_diameter:
        raise DesignError(
            "tip.magnet_inner_diameter_mm must be smaller than magnet_outer_diameter_mm "
            f"({tip.magnet_outer_diameter / MM:g}); got {tip.magnet_inner_diameter / MM:g}"
        )
    if not ring_clears_wire(tip.magnet_inner_diameter, wire.outer_diameter):
        raise DesignError(
            "tip.magnet_inner_diameter_mm must be at least robot.wire.outer_diameter_mm "
            f"({wire.outer_diameter / MM:g}) plus {WIRE_CLEARANCE / MM:g} so the wire turns "
            f"in the ring; got {tip.magnet_inner_diameter / MM:g}"
        )

    sources = _sources(doc, base)
    ext = None
    if "external_magnet" in doc or not sources:
        ext = _external_magnet(doc)

    environment = Environment()
    if "environment" in doc:
        env = _section(doc, "environment")
        obstacles = _obstacles(doc["environment"].get("obstacles", []))
        environment = Environment(gravity=env.get("gravity_m_s2"), obstacles=obstacles)

    design = Design(name, robot, tip, ext, environment, description, sources)
    _check_rod(design)
    _check_clearance(design)
    _check_obstacles(design)
    return design


def _check_rod(design: Design) -> None:
    """Reject a free length the printed tip's rigid segment leaves no flexible rod under
    (:meth:`design.mounting.TipGeometry.rod_length`)."""
    geometry = design_tip_geometry(design)
    if not geometry.rod_length(design.robot.free_length) > 0:
        raise DesignError(
            "robot.free_length_mm must be longer than the printed tip's rigid offset "
            f"({geometry.rigid_offset / MM:.4g} mm from where the catheter enters the "
            "proximal mounting piece to the proximal ring's centre, set by [tip] and "
            f"[tip.mounting]) so a flexible rod remains; got {design.robot.free_length / MM:g}"
        )


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
        raise DesignError(
            f"[field] holds only the list [[field.sources]]; got {extra or node!r}"
        )
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


def _check_obstacles(design: Design) -> None:
    """The straight, unloaded robot's tip (its printed body, the larger) must start
    outside every obstacle, and a lumen must be wider than the tip."""
    body = tip_body(design, printed=True)
    rest = np.array([[design.robot.free_length, 0.0, 0.0]])
    axis = np.array([[1.0, 0.0, 0.0]])
    for i, o in enumerate(design.environment.obstacles):
        path = f"environment.obstacles[{i}]"
        if o.kind == "lumen" and o.radius <= body.radius:
            raise DesignError(
                f"{path}.radius_mm = {o.radius / MM:g} is narrower than the tip (radius "
                f"{body.radius / MM:.4g} mm); expected a lumen wider than the tip"
            )
        gap = float(gaps(o, rest, axis, body)[0][0])
        if not gap >= 0:
            raise DesignError(
                f"{path}: the straight robot's tip starts inside this {o.kind} (gap "
                f"{gap / MM:.4g} mm); expected the tip outside it at rest"
            )


def _mounting(doc: dict[str, Any]) -> Mounting:
    """The optional ``[tip.mounting]`` section: ``process`` (a name of
    :data:`design.process.PROCESSES`, default resin) sets the defaults of the wall, fit,
    clearance and density keys."""
    node = doc["tip"].get("mounting", {})
    if not isinstance(node, dict):
        raise DesignError(f"[tip.mounting] must be a table of keys; got {node!r}")
    process = node.get("process", DEFAULT_PROCESS)
    if process not in PROCESSES:
        raise DesignError(
            f"tip.mounting.process must be one of {', '.join(map(repr, PROCESSES))}; "
            f"got {process!r}"
        )
    given = _section({"tip": {"mounting": node}}, "tip.mounting")
    # keys the file leaves out take the process's value (the registry's default is resin's)
    values = {field: given[key] for key, field in _MOUNTING.items() if key in node}
    return Mounting.printed_by(process, **values)


_MOUNTING = {
    p.key.rsplit(".", 1)[1]: p.field.rsplit(".", 1)[1]
    for p in PARAMETERS.values()
    if p.key and p.field and p.key.startswith("tip.mounting.")
}
"""The ``[tip.mounting]`` keys of the registry and the record fields they set."""


def _check_clearance(design: Design) -> None:
    """Reject a permanent magnet (the external magnet, a source) that overlaps the straight
    robot (base to distal ring)."""
    tip = design.tip
    proximal, distal = ring_centres(
        rest_position(design.robot.free_length), np.array([1.0, 0.0, 0.0]), tip.spacing
    )
    x = np.linspace(0.0, distal[0] + tip.magnet_length / 2, 4001)
    # The tip rings are the thickest part; the body is the catheter.
    near_tip = x >= proximal[0] - tip.magnet_length / 2
    r_body = np.where(
        near_tip, tip.magnet_outer_diameter / 2, design.robot.catheter.outer_diameter / 2
    )
    points = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    bodies = []
    ext = design.external_magnet
    if ext is not None:
        gap = cylinder_distance(
            points - np.asarray(ext.center), ext.magnetization, ext.diameter / 2, ext.length / 2
        )
        bodies.append(("external_magnet.center_mm", "magnet", gap))
    for i, src in enumerate(design.sources):
        if src.kind in PERMANENT:
            gap = source_distance(src, points)
            bodies.append((f"field.sources[{i + 1}].center_mm", f"{src.kind} magnet", gap))
    for key, what, gap in bodies:
        overlap = np.flatnonzero(gap < r_body)
        if overlap.size:
            raise DesignError(
                f"{key} places the {what} on the straight robot: it must clear the robot "
                f"(base to distal ring, radius {r_body[overlap[0]] / MM:g} mm); got an "
                f"overlap at x = {x[overlap[0]] / MM:.2f} mm in the base frame"
            )


def source_distance(source: Source, points: np.ndarray) -> np.ndarray:
    """Distance of ``points`` (n, 3) to a permanent magnet source's body
    (:func:`design.fields.sources.magnet_distance`), 0 inside. [m]"""
    p = ca.SX.sym("p", 3)
    q: dict[str, Any] = {
        k.name: ca.DM(np.ravel(getattr(source, k.name))) for k in SOURCE_KINDS[source.kind]
    }
    fn = ca.Function("distance", [p], [magnet_distance(source.kind, q, p)])
    distances = fn.map(len(points))(np.asarray(points, float).T)
    return np.asarray(distances, dtype=float).ravel()


MAX_INPUT_BYTES = 64 * 1024 * 1024
"""Largest input file (design, study, measurements, targets) read. [bytes]"""


def read_regular(path: str | os.PathLike[str], encoding: str = "utf-8") -> str:
    """The text of ``path`` if it is a regular file of at most :data:`MAX_INPUT_BYTES`;
    OSError saying what it is otherwise (a FIFO, a device or a socket is never opened: it
    could block or never end)."""
    p = Path(path)
    info = os.stat(p)  # FileNotFoundError, IsADirectoryError below: as open() would say
    if stat.S_ISDIR(info.st_mode):
        raise IsADirectoryError(21, "is a folder", str(p))
    if not stat.S_ISREG(info.st_mode):
        raise OSError(f"{p} is not a regular file (a device, FIFO or socket); not read")
    if info.st_size > MAX_INPUT_BYTES:
        raise OSError(f"{p} has {info.st_size:,} bytes, more than {MAX_INPUT_BYTES:,}; not read")
    with p.open("r", encoding=encoding) as f:
        text = f.read(MAX_INPUT_BYTES + 1)
    if len(text) > MAX_INPUT_BYTES:
        raise OSError(f"{p} grew past {MAX_INPUT_BYTES:,} bytes while read; not read")
    return text


def read_input(path: Path, kind: str, error: type[Exception]) -> str:
    """The UTF-8 text of the ``kind`` file (e.g. "design") at ``path``; ``error`` with
    one message if it does not exist or cannot be read."""
    try:
        return read_regular(path)
    except FileNotFoundError:
        raise error(f"{kind} file {path} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{kind} file {path} cannot be read: {exc}") from None


def load_design(path: str | os.PathLike[str]) -> Design:
    """Read and validate a design file. Raises :class:`DesignError` on any problem."""
    p = Path(path)
    return loads_design(read_input(p, "design", DesignError), source=str(p))


def loads_design(text: str, source: str = "<string>") -> Design:
    """Parse and validate design-file text."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise DesignError(f"{source} is not valid TOML: {exc}") from None
    except RecursionError:
        raise DesignError(f"{source}: arrays or tables nested too deeply to read") from None
    folder = Path(source).parent if source != "<string>" else None
    try:
        return design_from_dict(doc, folder)
    except DesignError as exc:
        raise DesignError(f"{source}: {exc}") from None


def default_design() -> Design:
    """The paper's demonstrator, shipped with the package."""
    text = resources.files("design").joinpath("data/demonstrator.toml").read_text("utf-8")
    return loads_design(text, source="demonstrator (embedded)")


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
    if explicit or mounting.process != DEFAULT_PROCESS:
        doc["tip"]["mounting"] = {"process": mounting.process}
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
