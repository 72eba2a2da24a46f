"""Study files (TOML): what a design optimisation may change, what it maximises, what it
must respect. Loading validates the whole file and returns a frozen :class:`Study` in SI;
every bad value raises :class:`StudyError`, whose message names the key, what was
expected and what was found (like :class:`design.DesignError`).

Study file format
=================

A study names a base design (the fixed set-up: robot length, external magnet, remanences,
everything not freed), the quantities the optimiser may change with their bounds, the
objective, the constraints and their limits, the model effects and the solver settings.
Units are those of the key names (mm, MPa, deg; strains are fractions). Every section
and key is optional except ``name`` and ``[free]``.

```toml
name = "demonstrator-workspace"           # free text, names the outputs
description = "optional free text"
base_design = "embedded"                  # the demonstrator (default), or a design file
                                          # path, relative to the study file
effects = "none"                          # "none" (baseline), "default" (the model for
                                          # design work, the printed tip included), "all",
                                          # "default,torsion" or a list; near_field,
                                          # large_deflection, torsion, gravity, printed_tip
objective = "disc_radius"                 # or "area", "reach_ratio", or a weighted table:
# objective = { disc_radius = 1.0, reach_ratio = 0.5 }  (each term divided by its value
#                                         # for the base design, then weighted and summed)

[free]                                    # [low, high] in file units; others stay fixed
magnet_outer_diameter_mm = [2.0, 4.0]       # ring magnets (both rings equal)
magnet_inner_diameter_mm = [0.5, 2.0]
magnet_length_mm = [0.5, 3.0]
magnet_gap_mm = [0.0, 1.0]                  # face-to-face gap of the rings
catheter_outer_diameter_mm = [1.0, 4.0]
catheter_inner_diameter_mm = [0.5, 3.0]
catheter_youngs_modulus_mpa = [300, 3000] # only with at most one catheter material
wire_outer_diameter_mm = [0.2, 0.8]
external_distance_mm = [60.0, 200.0]      # rest tip (straight robot) to the external
                                          # magnet's centre, along the base design's
                                          # direction from the tip to that centre

[materials]                               # candidates; each combination is its own NLP
catheter = ["ptfe", "pebax_7233", "nylon_12"]   # names: optimize.sizing.materials.MATERIALS
wire = ["niti"]                           # absent: the tube keeps the base design's
                                          # E, Poisson ratio and density

[constraints]                             # defaults shown
max_outer_diameter_mm = 4.0               # printed tip and catheter; default: the base's
                                          # largest outer diameter
wire_clearance_mm = 0.05                  # ring bore and catheter bore >= wire OD + this
                                          # (0.05 at least: design.admissible.WIRE_CLEARANCE)
min_wall_mm = 0.1                         # radial wall of rings and catheter
magnet_clearance_mm = 5.0                 # tip rings to the external magnet's surface, at
                                          # every sampled configuration
twist_limit_deg = 10.0                    # |axial torque| L / GJ of each transmission
neutral_tolerance_mm = 1.0                # antiparallel rings: tip within this of straight
stable = true                             # reject optima with unstable sampled equilibria
# catheter_max_strain = 0.03              # override the material's allowable strain [-];
# wire_max_strain = 0.06                  # required when the tube has no material
# min_disc_radius_mm = 15.0               # optional: objectives as constraints
# min_reach_ratio = 0.9

[solver]
starts = 4                                # start 1 is the base design, others random
seed = 0                                  # random starts are reproducible
configurations = 24                       # K parallel-ring directions (the boundary)
neutral_configurations = 8                # antiparallel directions (neutral check), and
                                          # as many with the rings at right angles (twist)
max_iterations = 300                      # IPOPT iterations per start
tolerance = 1e-8                          # IPOPT tolerance (scaled problem)
hessian = "limited-memory"                # L-BFGS from the exact gradients (fast), or
                                          # "exact": second derivatives of the model

[[pareto]]                                # epsilon-constraint sweeps, one table each
against = "catheter_outer_diameter"       # or "external_distance", "magnet_volume"
points = 8
range_mm = [1.0, 4.0]                     # optional; range_mm3 for magnet_volume (both
                                          # rings); default: from the free bounds
```

Objectives: ``disc_radius`` is the radius of the largest disc about the robot's home
(:mod:`design.home`) inside the reachable set (the parallel-ring loop, as
:mod:`design.workspace` defines it),
``area`` the area of that loop (seen along x), ``reach_ratio`` the ratio of the smaller
to the larger reach (y against z; 1 is round).
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from design.admissible import WIRE_CLEARANCE
from design.designfile import DesignError, default_design, load_design, read_input
from design.designfile.keys import as_float, shown
from design.model import DEFAULT_EFFECTS, EFFECTS, PRINTED_TIP
from design.mounting import design_tip_geometry
from design.records import Design
from design.registry import PARAMETERS, current, file_key, file_unit
from design.suggest import did_you_mean
from design.units import DEG, MM, MM3
from optimize.sizing.materials import MATERIALS


class StudyError(ValueError):
    """A study file that cannot describe a study. The message is meant for the user."""


@dataclass(frozen=True)
class FreeKey:
    """One free quantity: file key, name, unit scale, lowest admissible low bound."""

    key: str
    name: str
    meaning: str
    scale: float
    low: float
    low_open: bool
    high: float


def _free_key(name: str) -> FreeKey:
    """A free model parameter, its key, unit, meaning and range from :mod:`design.registry`."""
    p = PARAMETERS[name]
    assert p.low is not None and p.high is not None
    return FreeKey(file_key(name), name, p.meaning, file_unit(name)[1], p.low, p.low_open, p.high)


FREE_KEYS: dict[str, FreeKey] = {
    k.key: k
    for k in (
        *(
            _free_key(name)
            for name in (
                "magnet_outer_diameter",
                "magnet_inner_diameter",
                "magnet_length",
                "magnet_gap",
                "catheter_outer_diameter",
                "catheter_inner_diameter",
                "catheter_youngs_modulus",
                "wire_outer_diameter",
                "stop_angle",  # the mounting pieces' stops (torsion and printed_tip)
                "pretwist",
            )
        ),
        # not a model parameter: the magnet placed on the axis (design.geometry)
        FreeKey("external_distance_mm", "external_distance", "magnet distance", MM, 0, True, 10000),
    )
}
"""Free quantities by file key."""

OBJECTIVES = ("disc_radius", "area", "reach_ratio", "controllable_disc_radius")
"""``controllable_disc_radius``: the NLP maximises the disc radius; among its accepted
starts and materials the design whose disc steerable from home without a snap
(:mod:`design.controllable`) is largest wins; alone, not weighted with others."""
PARETO_QUANTITIES = {
    # name: (range key, scale, sense of the epsilon constraint)
    "catheter_outer_diameter": ("range_mm", MM, "max"),
    "external_distance": ("range_mm", MM, "min"),
    "magnet_volume": ("range_mm3", MM3, "max"),
}
"""Pareto sweep quantities: workspace against the catheter size, the magnet's distance
and the magnet volume. ``max``: the quantity is bounded above by epsilon, ``min``: below."""
STUDY_EFFECTS = ("near_field", "large_deflection", "torsion", "gravity", PRINTED_TIP)
"""Effects a study may switch on, and the printed tip (hysteresis needs ordered paths)."""


@dataclass(frozen=True)
class Bound:
    """Bounds of one free quantity. [SI: m or Pa]"""

    name: str
    low: float
    high: float


@dataclass(frozen=True)
class Constraints:
    """Constraint limits, SI (``None``: not imposed).

    max_outer_diameter : the printed tip (:mod:`design.mounting`) and the catheter. [m]
    wire_clearance : ring and catheter bores minus wire OD, at least. [m]
    min_wall : radial wall of rings and catheter, at least. [m]
    magnet_clearance : tip rings to the external magnet's surface, at least. [m]
    twist_limit : twist of each transmission, at most. [rad]
    neutral_tolerance : tip deflection with antiparallel rings, at most. [m]
    stable : only stable sampled equilibria.
    catheter_max_strain, wire_max_strain : override the material's allowable strain. [-]
    min_disc_radius : optional lower bound of the disc radius. [m]
    min_reach_ratio : optional lower bound of the reach ratio. [-]
    """

    max_outer_diameter: float
    wire_clearance: float = WIRE_CLEARANCE
    min_wall: float = 0.1 * MM
    magnet_clearance: float = 5.0 * MM
    twist_limit: float = 10.0 * DEG
    neutral_tolerance: float = 1.0 * MM
    stable: bool = True
    catheter_max_strain: float | None = None
    wire_max_strain: float | None = None
    min_disc_radius: float | None = None
    min_reach_ratio: float | None = None


@dataclass(frozen=True)
class ParetoSweep:
    """One epsilon-constraint sweep: ``points`` values of ``against`` over [low, high]
    (SI: m or m^3; ``None``: from the free bounds)."""

    against: str
    points: int
    low: float | None = None
    high: float | None = None


@dataclass(frozen=True)
class Study:
    """A validated study, SI units. See the module docstring for the file format.

    base : the fixed set-up and the values of everything not freed.
    free : free quantities and their bounds, in the order of the file.
    catheter_materials, wire_materials : candidate material names; empty keeps the base.
    objective : (name, weight) pairs, weights > 0.
    """

    name: str
    base: Design
    free: tuple[Bound, ...]
    objective: tuple[tuple[str, float], ...] = (("disc_radius", 1.0),)
    constraints: Constraints | None = None
    catheter_materials: tuple[str, ...] = ()
    wire_materials: tuple[str, ...] = ()
    effects: frozenset[str] = frozenset()
    starts: int = 4
    seed: int = 0
    configurations: int = 24
    neutral_configurations: int = 8
    max_iterations: int = 300
    tolerance: float = 1e-8
    hessian: str = "limited-memory"
    pareto: tuple[ParetoSweep, ...] = ()
    description: str = ""
    base_source: str = "embedded"
    calibration: tuple[tuple[str, float], ...] = ()
    """Model factors calibrated on bench data (``ringpair study --data``), set on every
    candidate design's parameter vector: (name, value) pairs of factors a design file does
    not hold (e.g. ``bending_rigidity_scale``). [SI]"""

    @property
    def limits(self) -> Constraints:
        """The constraints, with the base design's defaults when none were given."""
        return self.constraints or Constraints(base_max_diameter(self.base))

    def bound(self, name: str) -> Bound | None:
        """Bounds of free quantity ``name`` (SI name), or None if it is fixed."""
        return next((b for b in self.free if b.name == name), None)


def base_max_diameter(design: Design) -> float:
    """The base design's largest outer diameter (its printed tip, :mod:`design.mounting`,
    or catheter). [m]"""
    return max(design_tip_geometry(design).outer_diameter, design.robot.catheter.outer_diameter)


TOP_KEYS = (
    "name",
    "description",
    "base_design",
    "effects",
    "objective",
    "free",
    "materials",
    "constraints",
    "solver",
    "pareto",
)
CONSTRAINT_KEYS: dict[str, tuple[float, str, float, float]] = {
    # key: (scale, meaning, low, high) in file units
    "max_outer_diameter_mm": (MM, "a diameter [mm]", 0.0, 100.0),
    "wire_clearance_mm": (MM, "a clearance [mm]", WIRE_CLEARANCE / MM, 10.0),
    "min_wall_mm": (MM, "a wall thickness [mm]", 0.0, 10.0),
    "magnet_clearance_mm": (MM, "a clearance [mm]", 0.0, 1000.0),
    "twist_limit_deg": (DEG, "an angle [deg]", 0.0, 180.0),
    "neutral_tolerance_mm": (MM, "a distance [mm]", 0.0, 1000.0),
    "catheter_max_strain": (1.0, "a strain (fraction)", 0.0, 0.5),
    "wire_max_strain": (1.0, "a strain (fraction)", 0.0, 0.5),
    "min_disc_radius_mm": (MM, "a radius [mm]", 0.0, 10000.0),
    "min_reach_ratio": (1.0, "a ratio", 0.0, 1.0),
}
SOLVER_KEYS: dict[str, tuple[type, float, float]] = {
    "starts": (int, 1, 1000),
    "seed": (int, 0, 2**63 - 1),
    "configurations": (int, 8, 180),
    "neutral_configurations": (int, 2, 180),
    "max_iterations": (int, 1, 100000),
    "tolerance": (float, 1e-14, 1e-2),
    "hessian": (str, 0, 0),
}
HESSIANS = ("limited-memory", "exact")


def _check_keys(path: str, node: Any, allowed: Any) -> dict[str, Any]:
    if not isinstance(node, dict):
        raise StudyError(f"[{path}] must be a table of keys; got {node!r}")
    for given in node:
        if given not in allowed:
            raise StudyError(f"unknown key {path}.{given}{did_you_mean(given, allowed)}")
    return node


def _is_number(value: Any) -> bool:
    return (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(as_float(value))  # a 400-digit integer is no finite number
    )


def _number(path: str, value: Any, low: float, high: float, what: str = "a number") -> float:
    if not _is_number(value) or not low <= float(value) <= high:
        raise StudyError(f"{path} must be {what} between {low:g} and {high:g}; got {shown(value)}")
    return float(value)


def _pair(path: str, value: Any, what: str) -> tuple[float, float]:
    if not (isinstance(value, list) and len(value) == 2 and all(map(_is_number, value))):
        raise StudyError(f"{path} must be [low, high], two finite numbers ({what}); got {value!r}")
    lo, hi = float(value[0]), float(value[1])
    if lo > hi:
        raise StudyError(f"{path} must be [low, high] with low <= high; got {value!r}")
    return lo, hi


def _free(node: Any) -> tuple[Bound, ...]:
    if isinstance(node, dict):
        node = {current(k): v for k, v in node.items()}
    node = _check_keys("free", node, FREE_KEYS)
    if not node:
        raise StudyError(
            f"[free] must name at least one free quantity; expected any of {', '.join(FREE_KEYS)}"
        )
    out = []
    for key, value in node.items():
        spec = FREE_KEYS[key]
        lo, hi = _pair(f"free.{key}", value, spec.meaning)
        too_low = lo <= spec.low if spec.low_open else lo < spec.low
        if too_low or hi > spec.high:
            rel = ">" if spec.low_open else ">="
            raise StudyError(
                f"free.{key} must lie within the physical range ({spec.meaning} {rel} "
                f"{spec.low:g} and <= {spec.high:g}); got {value!r}"
            )
        out.append(Bound(spec.name, lo * spec.scale, hi * spec.scale))
    return tuple(out)


def _effects(value: Any) -> frozenset[str]:
    """The study's model: 'none', 'default' (the model for design work), 'all'
    (STUDY_EFFECTS), a comma list (which may include 'default') or a list of names."""
    if isinstance(value, str):
        text = value.strip()
        if text == "all":
            return frozenset(STUDY_EFFECTS)
        names = [n.strip() for n in text.split(",") if n.strip()]
        if text in ("none", "baseline"):
            names = []
    elif isinstance(value, list) and all(isinstance(v, str) for v in value):
        names = [v.strip() for v in value]
    else:
        raise StudyError(
            "effects must be 'none', 'default', 'all', a comma list or a list of effect "
            f"names; got {value!r}"
        )
    if "default" in names:  # 'default,torsion': the model for design work and more
        names = [n for n in names if n != "default"] + sorted(DEFAULT_EFFECTS)
    for n in names:
        if n not in STUDY_EFFECTS:
            why = (
                " (known to the model but not usable in a study: it needs ordered paths)"
                if n in EFFECTS
                else did_you_mean(n, STUDY_EFFECTS)
            )
            raise StudyError(
                f"effects must name effects among {', '.join(STUDY_EFFECTS)} (or 'default'); "
                f"got {n!r}{why}"
            )
    return frozenset(names)


def _objective(value: Any) -> tuple[tuple[str, float], ...]:
    if isinstance(value, str):
        value = {value: 1.0}
    if not isinstance(value, dict) or not value:
        raise StudyError(
            f"objective must be one of {', '.join(OBJECTIVES)} or a table of weights; got {value!r}"
        )
    out = []
    for name, weight in value.items():
        if name not in OBJECTIVES:
            raise StudyError(
                f"objective must be one of {', '.join(OBJECTIVES)}; got {name!r}"
                f"{did_you_mean(name, OBJECTIVES)}"
            )
        out.append((name, _number(f"objective.{name}", weight, 0.0, 1e6, "a weight")))
    if not any(w > 0 for _, w in out):
        raise StudyError(f"objective must have at least one weight > 0; got {value!r}")
    if len(out) > 1 and any(n == "controllable_disc_radius" for n, _ in out):
        raise StudyError(
            "objective controllable_disc_radius stands alone (it is not weighted with "
            f"others); got {value!r}"
        )
    return tuple((n, w) for n, w in out if w > 0)


def _materials(node: Any) -> tuple[tuple[str, ...], tuple[str, ...]]:
    node = _check_keys("materials", node, ("catheter", "wire"))
    out = []
    for tube in ("catheter", "wire"):
        value = node.get(tube, [])
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise StudyError(f"materials.{tube} must be a list of material names; got {value!r}")
        for v in value:
            if v not in MATERIALS:
                raise StudyError(
                    f"materials.{tube} must name materials among {', '.join(MATERIALS)}; "
                    f"got {v!r}{did_you_mean(v, MATERIALS)}"
                )
        if len(set(value)) != len(value):
            raise StudyError(f"materials.{tube} must not repeat a material; got {value!r}")
        out.append(tuple(value))
    return out[0], out[1]


def _constraints(node: Any, base: Design) -> Constraints:
    node = _check_keys("constraints", node, (*CONSTRAINT_KEYS, "stable"))
    values: dict[str, Any] = {}
    for key, (scale, what, lo, hi) in CONSTRAINT_KEYS.items():
        if key in node:
            name = key.removesuffix("_mm").removesuffix("_deg")
            values[name] = _number(f"constraints.{key}", node[key], lo, hi, what) * scale
    if "stable" in node:
        if not isinstance(node["stable"], bool):
            raise StudyError(f"constraints.stable must be true or false; got {node['stable']!r}")
        values["stable"] = node["stable"]
    values.setdefault("max_outer_diameter", base_max_diameter(base))
    return Constraints(**values)


def _solver(node: Any) -> dict[str, Any]:
    node = _check_keys("solver", node, SOLVER_KEYS)
    out: dict[str, Any] = {}
    for key, (kind, lo, hi) in SOLVER_KEYS.items():
        if key not in node:
            continue
        v = node[key]
        if kind is str:
            if v not in HESSIANS:
                raise StudyError(
                    f"solver.{key} must be one of {', '.join(map(repr, HESSIANS))}; got {v!r}"
                )
            out[key] = v
            continue
        if kind is int and (isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi):
            raise StudyError(
                f"solver.{key} must be an integer between {lo:g} and {hi:g}; got {v!r}"
            )
        out[key] = v if kind is int else _number(f"solver.{key}", v, lo, hi)
    return out


def _pareto(value: Any) -> tuple[ParetoSweep, ...]:
    if not isinstance(value, list):
        raise StudyError(f"pareto must be an array of tables ([[pareto]]); got {value!r}")
    out = []
    for i, node in enumerate(value):
        path = f"pareto[{i}]"
        node = _check_keys(path, node, ("against", "points", "range_mm", "range_mm3"))
        against = node.get("against")
        if against not in PARETO_QUANTITIES:
            raise StudyError(
                f"{path}.against must be one of {', '.join(PARETO_QUANTITIES)}; got {against!r}"
                f"{did_you_mean(str(against), PARETO_QUANTITIES)}"
            )
        key, scale, _ = PARETO_QUANTITIES[against]
        other = {"range_mm", "range_mm3"} - {key}
        for k in other & set(node):
            raise StudyError(f"{path}.{k} does not fit against = {against!r}; expected {key}")
        points = node.get("points", 8)
        if isinstance(points, bool) or not isinstance(points, int) or not 2 <= points <= 1000:
            raise StudyError(f"{path}.points must be an integer between 2 and 1000; got {points!r}")
        lo = hi = None
        if key in node:
            lo, hi = _pair(f"{path}.{key}", node[key], "file units")
            if lo <= 0:
                raise StudyError(f"{path}.{key} must be positive; got {node[key]!r}")
            lo, hi = lo * scale, hi * scale
        out.append(ParetoSweep(against, points, lo, hi))
    return tuple(out)


def _base(value: Any, folder: Path | None) -> tuple[Design, str]:
    if value is None or value == "embedded":
        return default_design(), "embedded"
    if not isinstance(value, str) or not value.strip():
        raise StudyError(
            f"base_design must be 'embedded' or the path of a design file; got {value!r}"
        )
    path = Path(value)
    if not path.is_absolute() and folder is not None:
        path = folder / path
    try:
        return load_design(path), str(path)
    except DesignError as exc:
        raise StudyError(f"base_design: {exc}") from None


def study_from_dict(doc: dict[str, Any], folder: Path | None = None) -> Study:
    """Build a validated :class:`Study` (SI) from a parsed study-file document; relative
    ``base_design`` paths are taken from ``folder``."""
    _check_keys("study", doc, TOP_KEYS)
    name = doc.get("name")
    if not isinstance(name, str) or not name.strip():
        raise StudyError(f"name must be a non-empty string; got {name!r}")
    description = doc.get("description", "")
    if not isinstance(description, str):
        raise StudyError(f"description must be a string; got {description!r}")
    base, source = _base(doc.get("base_design"), folder)
    if "free" not in doc:
        raise StudyError(
            f"missing section [free]; expected [low, high] bounds of any of {', '.join(FREE_KEYS)}"
        )
    free = _free(doc["free"])
    catheter, wire = _materials(doc.get("materials", {}))
    if len(catheter) > 1 and any(b.name == "catheter_youngs_modulus" for b in free):
        raise StudyError(
            "free.catheter_youngs_modulus_mpa needs at most one catheter material (the "
            f"modulus is then free, the other constants are the material's); got {list(catheter)}"
        )
    constraints = _constraints(doc.get("constraints", {}), base)
    for tube, mats in (("catheter", catheter), ("wire", wire)):
        if not mats and getattr(constraints, f"{tube}_max_strain") is None:
            raise StudyError(
                f"constraints.{tube}_max_strain is required when materials.{tube} is not "
                "given (the base design's tube has no allowable strain); expected a strain "
                "between 0 and 0.5, e.g. 0.03"
            )
    solver = _solver(doc.get("solver", {}))
    effects = _effects(doc.get("effects", "none"))
    for b in free:
        if b.name in ("stop_angle", "pretwist") and not {"torsion", PRINTED_TIP} <= effects:
            raise StudyError(
                f"free.{file_key(b.name)} acts through the mounting pieces' stops, which the "
                "model has with effects torsion and printed_tip; got effects "
                f"{', '.join(sorted(effects)) or 'none'}"
            )
    return Study(
        name=name,
        base=base,
        free=free,
        objective=_objective(doc.get("objective", "disc_radius")),
        constraints=constraints,
        catheter_materials=catheter,
        wire_materials=wire,
        effects=effects,
        pareto=_pareto(doc.get("pareto", [])),
        description=description,
        base_source=source,
        **solver,
    )


def loads_study(text: str, source: str = "<string>", folder: Path | None = None) -> Study:
    """Parse and validate study-file text."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{source} is not valid TOML: {exc}") from None
    except RecursionError:
        raise StudyError(f"{source}: arrays or tables nested too deeply to read") from None
    try:
        return study_from_dict(doc, folder)
    except StudyError as exc:
        raise StudyError(f"{source}: {exc}") from None


def load_study(path: str | os.PathLike[str]) -> Study:
    """Read and validate a study file. Raises :class:`StudyError` on any problem."""
    p = Path(path)
    return loads_study(read_input(p, "study", StudyError), source=str(p), folder=p.parent)


def default_study() -> Study:
    """The embedded default study: the demonstrator's set-up, shipped with the package."""
    text = resources.files("optimize.sizing").joinpath("data/default_study.toml").read_text("utf-8")
    return loads_study(text, source="default study (embedded)")
