"""Reading a design file: the document's sections into a validated
:class:`~design.records.Design` (SI)."""

from __future__ import annotations

import os
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

from design.admissible import WIRE_CLEARANCE, admits
from design.designfile.checks import _check_obstacles, _check_rod, check_clearance
from design.designfile.environment import _obstacles
from design.designfile.fields import _external_magnet, _sources
from design.designfile.inputs import read_input
from design.designfile.keys import TOP_KEYS, DesignError, _section
from design.designfile.writer import design_to_dict
from design.process import DEFAULT_PROCESS, PROCESSES
from design.records import Design, Environment, Mounting, Robot, Tip, Tube
from design.registry import PARAMETERS
from design.suggest import did_you_mean
from design.units import MM


def _tube(doc: dict[str, Any], name: str) -> Tube:
    s = _section(doc, name)
    od, idia = s["outer_diameter_mm"], s["inner_diameter_mm"]
    tube = name.rsplit(".", 1)[1]
    if not admits(f"{tube}_wall", {f"{tube}_outer_diameter": od, f"{tube}_inner_diameter": idia}):
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
    bore = {
        "catheter_inner_diameter": catheter.inner_diameter,
        "wire_outer_diameter": wire.outer_diameter,
    }
    if not admits("wire_in_catheter", bore):
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
    ring = {
        "magnet_outer_diameter": tip.magnet_outer_diameter,
        "magnet_inner_diameter": tip.magnet_inner_diameter,
        "wire_outer_diameter": wire.outer_diameter,
    }
    if not admits("ring_wall", ring):
        raise DesignError(
            "tip.magnet_inner_diameter_mm must be smaller than magnet_outer_diameter_mm "
            f"({tip.magnet_outer_diameter / MM:g}); got {tip.magnet_inner_diameter / MM:g}"
        )
    if not admits("ring_on_wire", ring):
        raise DesignError(
            "tip.magnet_inner_diameter_mm must be at least robot.wire.outer_diameter_mm "
            f"({wire.outer_diameter / MM:g}) plus {WIRE_CLEARANCE / MM:g} so the wire turns "
            f"in the ring; got {tip.magnet_inner_diameter / MM:g}"
        )

    passage = tip.mounting.passage_diameter
    least = wire.outer_diameter + WIRE_CLEARANCE
    if passage and not least <= passage <= catheter.inner_diameter:
        raise DesignError(
            "tip.mounting.passage_diameter_mm must be at least robot.wire.outer_diameter_mm "
            f"plus {WIRE_CLEARANCE / MM:g} ({least / MM:g}) so the wire turns in it, and at most "
            f"robot.catheter.inner_diameter_mm ({catheter.inner_diameter / MM:g}); got "
            f"{passage / MM:g} (0 or left out: the catheter's bore)"
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
    check_clearance(design)
    _check_obstacles(design)
    return design


def revalidated(design: Design) -> Design:
    """``design`` through every check a design file passes (written out and read back):
    for a record built in code, e.g. a design with parameters set (``ringpair synth
    --set``). DesignError names the file key at fault."""
    return design_from_dict(design_to_dict(design, explicit=True))


def _mounting(doc: dict[str, Any]) -> Mounting:
    """The optional ``[tip.mounting]`` section: ``process`` (a name of
    :data:`design.process.PROCESSES`, default resin) sets the defaults of the wall, fit,
    clearance and density keys; ``compensate_holes`` (default false) widens the fit bores
    the CAD draws by the process's hole shrink."""
    node = doc["tip"].get("mounting", {})
    if not isinstance(node, dict):
        raise DesignError(f"[tip.mounting] must be a table of keys; got {node!r}")
    process = node.get("process", DEFAULT_PROCESS)
    if process not in PROCESSES:
        raise DesignError(
            f"tip.mounting.process must be one of {', '.join(map(repr, PROCESSES))}; "
            f"got {process!r}"
        )
    compensate = node.get("compensate_holes", False)
    if not isinstance(compensate, bool):
        raise DesignError(
            f"tip.mounting.compensate_holes must be true or false; got {compensate!r}"
        )
    given = _section({"tip": {"mounting": node}}, "tip.mounting")
    # keys the file leaves out take the process's value (the registry's default is resin's)
    values = {field: given[key] for key, field in _MOUNTING.items() if key in node}
    return Mounting.printed_by(process, compensate_holes=compensate, **values)


_MOUNTING = {
    p.key.rsplit(".", 1)[1]: p.field.rsplit(".", 1)[1]
    for p in PARAMETERS.values()
    if p.key and p.field and p.key.startswith("tip.mounting.")
}
"""The ``[tip.mounting]`` keys of the registry and the record fields they set."""


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
