"""The parameter registry: each scalar quantity of a robot and its set-up, once.

Every model takes one flat vector of the design's physical inputs (sizes, moduli,
remanences, positions, friction), in SI, in the order of ``NAMES``. Derived quantities
(rigidities, moments, spacing) are formulas on these symbols inside the model, so NLPs
and calibration can free any physical input and get exact derivatives through the model.

One name per quantity, everywhere (model, study files, calibration, ``--set``, tolerance
studies, reports): the design file's key without its unit, prefixed by the section the
file nests it in where the key alone would be ambiguous (``catheter_``, ``wire_``,
``external_``, and ``magnet_`` for the tip's rings: ``tip.gap_mm`` is ``magnet_gap``,
``tip.magnet_length_mm`` is ``magnet_length``). Where a file or option gives a value, it
is in the quantity's file unit (:data:`FILE_UNITS`) with the unit's suffix on the key
(``magnet_length_mm``). Old names (:data:`RENAMED`) are still read, with a warning.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from design.fields.sources import KINDS, parameter_names
from design.mounting import MAX_STOP_ANGLE
from design.process import RESIN
from design.records import Design
from design.units import DEG, GRAM, MM, MPA


@dataclass(frozen=True)
class FitSpec:
    """How calibration frees a parameter (:mod:`optimize.fitting.calibrate`).

    kind : 'log' (fit u = ln(p / p0), for positive quantities) or 'linear'
        (fit u = (p - p0) / step).
    lower, upper : admissible physical range of the fit (absolute). [SI]
    prior : one-sigma width of the optional prior, in fit units (log: relative).
    step : SI value of one fit unit for 'linear'. [SI]
    span : for 'linear', the fit may move at most this far from the nominal value. [SI]
    """

    kind: str
    lower: float
    upper: float
    prior: float
    step: float = 1.0
    span: float = np.inf

    def physical(self, u: float, p0: float) -> float:
        """The parameter's value [SI] at fit unit ``u`` about its nominal value ``p0`` [SI]."""
        return p0 * float(np.exp(u)) if self.kind == "log" else p0 + self.step * u

    def fit_unit(self, p: float, p0: float) -> float:
        """The fit unit of value ``p`` about the nominal value ``p0`` [SI] (the inverse of
        :meth:`physical`; 'log': NaN unless both are positive). [-]"""
        if self.kind == "log":
            return math.log(p / p0) if p > 0 and p0 > 0 else math.nan
        return (p - p0) / self.step

    def unit_size(self, p: float) -> float:
        """The SI size of one fit unit at value ``p``: dp/du. [SI]"""
        return abs(p) if self.kind == "log" else self.step


@dataclass(frozen=True)
class Parameter:
    """One scalar model input.

    field : where it lives in a :class:`~design.records.Design`, a dotted path of record
        attributes with a component index for vectors (``"tip.magnet_gap"``,
        ``"external_magnet.center[0]"``); None for a factor of the model alone (always 1
        in a design, freed by calibration) or an applied load (``default``, 0).
    unit : its SI unit.
    key : its design-file key, ``section.key`` (vectors: one key for three parameters).
    low, high, low_open : the range a design file admits, in file units (None: unbounded).
    default : for a key the file may leave out, its value. [SI]
    tolerance : manufacturing or placement tolerance, one sigma: ('rel', fraction) or
        ('abs', SI value); None where the tolerance study leaves it exact.
    fit : how calibration frees it; None where it cannot.
    """

    name: str
    unit: str
    meaning: str
    field: str | None
    key: str | None = None
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    default: float | None = None
    tolerance: tuple[str, float] | None = None
    fit: FitSpec | None = None

    def value(self, design: Design) -> float:
        """Its value in ``design``. [unit]"""
        if self.field is None:  # a model factor (1), or an applied load (its default, 0)
            return 1.0 if self.default is None else self.default
        path, i = _split(self.field)
        node: Any = design
        for part in path:
            node = getattr(node, part)
            if node is None and part == "external_magnet":
                return 0.0  # (no external magnet: the model's field leaves it out)
        if i is None:
            return float(node)
        return 0.0 if node is None else float(node[i])  # (no gravity: a zero vector)


def _split(field: str) -> tuple[list[str], int | None]:
    """A field path's attributes and component index."""
    path, _, rest = field.partition("[")
    return path.split("."), (int(rest.rstrip("]")) if rest else None)


def _vector(prefix: str, unit: str, meaning: str, field: str, key: str, **kw: Any) -> list:
    return [
        Parameter(f"{prefix}_{a}", unit, f"{meaning}, {a}", f"{field}[{i}]", key, **kw)
        for i, a in enumerate("xyz")
    ]


_MODULUS_FIT = FitSpec("log", 1e5, 1e12, 0.5)
_REMANENCE_FIT = FitSpec("log", 0.05, 2.5, 0.1)
_FRICTION_FIT = FitSpec("linear", 0.0, 45 * DEG, 5.0, DEG)
_PLACEMENT_FIT = FitSpec("linear", -10.0, 10.0, 5.0, MM, 0.05)


def _tube(tube: str, modulus_tolerance: float) -> list[Parameter]:
    """The parameters of one coaxial element (``robot.<tube>``)."""
    section = f"robot.{tube}"

    def one(field: str, unit: str, key: str, **kw: Any) -> Parameter:
        meaning = f"{tube} {field.replace('_', ' ')}"
        return Parameter(
            f"{tube}_{field}", unit, meaning, f"{section}.{field}", f"{section}.{key}", **kw
        )

    return [
        one("outer_diameter", "m", "outer_diameter_mm", low=0.0, high=50.0, low_open=True),
        one("inner_diameter", "m", "inner_diameter_mm", low=0.0, high=50.0),
        one(
            "youngs_modulus",
            "Pa",
            "youngs_modulus_mpa",
            low=0.0,
            high=1e6,
            low_open=True,
            tolerance=("rel", modulus_tolerance),
            fit=_MODULUS_FIT,
        ),
        one("poisson_ratio", "-", "poisson_ratio", low=-1.0, high=0.5, low_open=True),
        one("density", "kg/m^3", "density_kg_m3", low=0.0, high=30000.0, low_open=True),
        one(
            "friction_angle",
            "rad",
            "friction_angle_deg",
            low=0.0,
            high=90.0,
            default=0.0,
            fit=_FRICTION_FIT,
        ),
    ]


_TABLE: list[Parameter] = [
    Parameter(
        "free_length",
        "m",
        "clamped base to proximal ring centre",
        "robot.free_length",
        "robot.free_length_mm",
        0.0,
        10000.0,
        True,
        fit=FitSpec("linear", 1e-3, 10.0, 5.0, MM, 0.05),
    ),
    # NiTi wire moduli spread less than extruded tubes' (5 % against 10 %)
    *_tube("catheter", 0.10),
    *_tube("wire", 0.05),
    # ground magnet rings hold +-0.02 mm; NdFeB grades spread 2 % in remanence
    Parameter(
        "magnet_outer_diameter",
        "m",
        "ring outer diameter",
        "tip.magnet_outer_diameter",
        "tip.magnet_outer_diameter_mm",
        0.0,
        100.0,
        True,
        tolerance=("abs", 0.02 * MM),
    ),
    Parameter(
        "magnet_inner_diameter",
        "m",
        "ring inner diameter",
        "tip.magnet_inner_diameter",
        "tip.magnet_inner_diameter_mm",
        0.0,
        100.0,
        tolerance=("abs", 0.02 * MM),
    ),
    Parameter(
        "magnet_length",
        "m",
        "ring length",
        "tip.magnet_length",
        "tip.magnet_length_mm",
        0.0,
        100.0,
        True,
        tolerance=("abs", 0.02 * MM),
    ),
    Parameter(
        "magnet_remanence",
        "T",
        "ring remanence",
        "tip.magnet_remanence",
        "tip.remanence_t",
        0.0,
        1.6,
        tolerance=("rel", 0.02),
        fit=_REMANENCE_FIT,
    ),
    Parameter(
        "magnet_gap",
        "m",
        "face-to-face gap of the rings",
        "tip.magnet_gap",
        "tip.gap_mm",
        0.0,
        100.0,
    ),
    Parameter(
        "magnet_density",
        "kg/m^3",
        "ring density",
        "tip.density",
        "tip.density_kg_m3",
        0.0,
        30000.0,
        True,
    ),
    Parameter(
        "tip_mass",
        "kg",
        "extra mass at the proximal ring's centre (glue)",
        "tip.mass",
        "tip.mass_g",
        0.0,
        1000.0,
        default=0.0,
        fit=FitSpec("linear", 0.0, 0.5, 1.0, 1e-3),
    ),
    # the printed mounting pieces (design.mounting); process numbers default to resin's
    *[
        Parameter(
            f"mount_{field}",
            unit,
            f"mounting pieces' {meaning}",
            f"tip.mounting.{field}",
            f"tip.mounting.{key}",
            low,
            high,
            True,
            default=getattr(RESIN, field),
        )
        for field, unit, meaning, key, low, high in (
            ("wall", "m", "wall", "wall_mm", 0.0, 20.0),
            ("fit_allowance", "m", "fit allowance of glued seats", "fit_allowance_mm", -1.0, 5.0),
            (
                "running_clearance",
                "m",
                "running clearance",
                "running_clearance_mm",
                0.0,
                5.0,
            ),
            ("density", "kg/m^3", "material density", "density_kg_m3", 0.0, 30000.0),
        )
    ],
    Parameter(
        "mount_passage_diameter",
        "m",
        "mounting pieces' wire passage (0: the catheter's bore)",
        "tip.mounting.passage_diameter",
        "tip.mounting.passage_diameter_mm",
        0.0,
        50.0,
        default=0.0,
    ),
    Parameter(
        "stop_angle",
        "rad",
        "stops: relative rotation theta1 - theta2 allowed, from 0",
        "tip.mounting.stop_angle",
        "tip.mounting.stop_angle_deg",
        0.0,
        round(MAX_STOP_ANGLE / DEG, 9),
        True,
        default=np.pi,
    ),
    Parameter(
        "pretwist",
        "rad",
        "pre-twist: commanded offset of the wire against the catheter",
        "tip.mounting.pretwist",
        "tip.mounting.pretwist_deg",
        -3600.0,
        3600.0,
        default=0.0,
    ),
    Parameter(
        "external_diameter",
        "m",
        "external cylinder diameter",
        "external_magnet.diameter",
        "external_magnet.diameter_mm",
        0.0,
        10000.0,
        True,
    ),
    Parameter(
        "external_length",
        "m",
        "external cylinder length",
        "external_magnet.length",
        "external_magnet.length_mm",
        0.0,
        10000.0,
        True,
    ),
    Parameter(
        "external_remanence",
        "T",
        "external magnet remanence",
        "external_magnet.remanence",
        "external_magnet.remanence_t",
        0.0,
        1.6,
        tolerance=("rel", 0.02),
        fit=_REMANENCE_FIT,
    ),
    # the external magnet is placed to +-1 mm, within 10 m of the robot
    *_vector(
        "external_center",
        "m",
        "external magnet centre",
        "external_magnet.center",
        "external_magnet.center_mm",
        low=-10000.0,
        high=10000.0,
        tolerance=("abs", 1 * MM),
        fit=_PLACEMENT_FIT,
    ),
    *_vector(
        "external_magnetization",
        "-",
        "external magnetisation direction",
        "external_magnet.magnetization",
        "external_magnet.magnetization",
        fit=FitSpec("linear", -2.0, 2.0, 5.0, 0.01, 0.5),
    ),
    # a lab, a centrifuge up to ten g
    *_vector(
        "gravity",
        "m/s^2",
        "acceleration of gravity",
        "environment.gravity",
        "environment.gravity_m_s2",
        low=-100.0,
        high=100.0,
    ),
    *[
        Parameter(
            name,
            "-",
            f"calibration factor on the {what} (1 = as designed)",
            None,
            fit=FitSpec("log", 1e-3, 1e3, prior),
        )
        for name, what, prior in (
            ("bending_rigidity_scale", "bending rigidity EI of catheter + wire", 0.5),
            ("wire_torsion_scale", "torsional rigidity GJ of the wire", 1.0),
            ("catheter_torsion_scale", "torsional rigidity GJ of the catheter", 1.0),
        )
    ],
    Parameter("load_scale", "-", "multiplies every load (1 = physical; continuation)", None),
    *[
        Parameter(f"applied_{what}_{axis}", unit, f"{meaning}, {axis}", None, default=0.0)
        for what, unit, meaning in (
            ("force", "N", "force applied at the tracked point, base frame"),
            ("moment", "N m", "moment applied about the tracked point, base frame"),
        )
        for axis in "xyz"
    ],
]
APPLIED_LOAD: tuple[str, ...] = tuple(
    f"applied_{what}_{axis}" for what in ("force", "moment") for axis in "xyz"
)
"""An external wrench on the tip at the tracked point (0 in a design): the tip stiffness's
derivative (:mod:`design.stiffness`), a contact force, a test's push. [N, N m]"""

PARAMETERS: dict[str, Parameter] = {p.name: p for p in _TABLE}
NAMES: tuple[str, ...] = tuple(PARAMETERS)
"""Parameter names in vector order."""
FITTED: tuple[str, ...] = tuple(n for n in NAMES if PARAMETERS[n].fit is not None)
"""The parameters calibration can free, in vector order."""


def parameter_vector(design: Design) -> np.ndarray:
    """Numeric parameter vector of ``design`` in the order of ``NAMES``, shape (n,). [SI]"""
    return np.array([PARAMETERS[n].value(design) for n in NAMES], dtype=float)


def source_names(design: Design) -> list[str]:
    """The parameters of ``design``'s ``[[field.sources]]``, in their vector order (after
    :data:`NAMES`): ``source<i>_<quantity>`` (:func:`design.fields.sources.parameter_names`)."""
    return [n for i, src in enumerate(design.sources) for n in parameter_names(i + 1, src.kind)]


def source_vector(design: Design) -> np.ndarray:
    """The values of :func:`source_names` in ``design``, shape (k,). [SI]"""
    out: list[float] = []
    for src in design.sources:
        for q in KINDS[src.kind]:
            out.extend(np.ravel(getattr(src, q.name)).astype(float))
    return np.array(out, dtype=float)


def model_vector(design: Design) -> np.ndarray:
    """The model's parameter vector of ``design``: :func:`parameter_vector` followed by
    :func:`source_vector`, shape (len(NAMES) + k,). [SI]"""
    return np.r_[parameter_vector(design), source_vector(design)]


def source_parameter(name: str) -> tuple[int, str, int | None] | None:
    """(source number, quantity, component) of a source parameter's name
    (``source2_center_x`` -> (2, "center", 0)), or None if ``name`` is none."""
    match = re.fullmatch(r"source(\d+)_([a-z]+?)(?:_([xyz]))?", name)
    if not match:
        return None
    number, quantity, axis = match.groups()
    return int(number), quantity, None if axis is None else "xyz".index(axis)


def _with_source(design: Design, name: str, value: float) -> Design:
    number, quantity, component = source_parameter(name) or (0, "", None)
    if not 1 <= number <= len(design.sources):
        raise KeyError(f"{name!r}: the design has {len(design.sources)} field sources")
    src = design.sources[number - 1]
    if quantity not in {q.name for q in KINDS[src.kind]}:
        raise KeyError(f"{name!r}: a {src.kind} source has no {quantity}")
    if component is None:
        new = replace(src, **{quantity: float(value)})  # type: ignore[arg-type]
    else:
        vector = list(getattr(src, quantity))
        vector[component] = float(value)
        new = replace(src, **{quantity: tuple(vector)})  # type: ignore[arg-type]
    sources = list(design.sources)
    sources[number - 1] = new
    return replace(design, sources=tuple(sources))


def design_with(design: Design, values: dict[str, float]) -> Design:
    """``design`` with the named parameters set (SI): the inverse of
    :func:`parameter_vector` and :func:`source_vector` for the parameters a design holds.
    A model-only factor (no ``field``) or an unknown name is a KeyError."""
    for name, value in values.items():
        if name not in PARAMETERS and source_parameter(name):
            design = _with_source(design, name, value)
            continue
        field = PARAMETERS[name].field if name in PARAMETERS else None
        if field is None:
            raise KeyError(f"{name!r} is not a quantity of a design")
        path, i = _split(field)
        design = _replaced(design, path, i, float(value))
    return design


def _replaced(node: Any, path: list[str], i: int | None, value: float) -> Any:
    head, rest = path[0], path[1:]
    if rest:
        return replace(node, **{head: _replaced(getattr(node, head), rest, i, value)})
    if i is None:
        return replace(node, **{head: value})
    vector = list(getattr(node, head) or (0.0, 0.0, 0.0))
    vector[i] = value
    return replace(node, **{head: tuple(vector)})


def index(name: str) -> int:
    """Position of a parameter in the vector; KeyError names the valid ones."""
    try:
        return NAMES.index(name)
    except ValueError:
        raise KeyError(f"unknown model parameter {name!r}; expected one of {NAMES}") from None


FILE_UNITS: dict[str, tuple[str, float, str]] = {
    "m": ("mm", MM, "mm"),
    "rad": ("deg", DEG, "deg"),
    "Pa": ("MPa", MPA, "mpa"),
    "kg": ("g", GRAM, "g"),
}
"""SI unit -> (the unit files, options and reports use, its size in SI, the key suffix);
other units (T, -, kg/m^3, m/s^2) are used as they are."""

RENAMED: dict[str, str] = {
    **{
        f"ring_{q}": f"magnet_{q}"
        for q in ("outer_diameter", "inner_diameter", "length", "gap", "remanence", "density")
    },
    **{f"external_axis_{a}": f"external_magnetization_{a}" for a in "xyz"},
}
"""Old name -> name (the tip's quantities were called ``ring_*`` and the external
magnetisation ``external_axis_*`` before the names followed the design file)."""


def file_unit(name: str) -> tuple[str, float]:
    """The unit a value of parameter ``name`` is given in by files and options, and its
    size in SI (``("mm", 1e-3)`` for a length)."""
    unit = PARAMETERS[name].unit
    label, size, _ = FILE_UNITS.get(unit, (unit, 1.0, ""))
    return label, size


def file_key(name: str) -> str:
    """The key of parameter ``name`` in study files and tables: the name and its file
    unit's suffix (``magnet_length_mm``, ``catheter_youngs_modulus_mpa``)."""
    suffix = FILE_UNITS.get(PARAMETERS[name].unit, ("", 1.0, ""))[2]
    return f"{name}_{suffix}" if suffix else name


def current(name: str) -> str:
    """``name``, or for an old name (or an old name with a unit suffix, as study files
    have it) the current one, with a FutureWarning that says so."""
    for old, new in RENAMED.items():
        if name == old or name.startswith(old + "_"):
            now = new + name[len(old) :]
            warnings.warn(
                f"'{name}' is now called '{now}'; the old name will stop working",
                FutureWarning,
                stacklevel=2,
            )
            return now
    return name
