"""Designs and values of a study: the free quantities of a design, the design with given
values (tube sections and materials kept consistent), the material combinations to try,
and the bounds of each constraint group. SI units."""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from design.admissible import RULES
from design.geometry import external_distance, magnet_centre_at
from design.records import Design
from design.registry import design_with, index, parameter_vector
from optimize.sizing.materials import Material, material
from optimize.sizing.nlp_problem import RING_STIFFNESS_MARGIN
from optimize.sizing.studyfile import PARETO_QUANTITIES, Study


def free_values(study: Study, design: Design) -> np.ndarray:
    """Values of the study's free quantities on ``design``, shape (n_free,). [SI]"""
    p = parameter_vector(design)
    out = []
    for b in study.free:
        if b.name == "external_distance":
            centre = design.external_magnet.center
            out.append(external_distance(design.robot.free_length, centre))
        else:
            out.append(float(p[index(b.name)]))
    return np.array(out)


def study_parameters(study: Study, design: Design) -> np.ndarray:
    """The model parameter vector of ``design`` in ``study``: its own, with the study's
    calibrated factors (:attr:`Study.calibration`) set. [SI]"""
    p = parameter_vector(design)
    for name, value in study.calibration:
        p[index(name)] = value
    return p


def candidate_design(
    study: Study,
    values: Mapping[str, float] | np.ndarray,
    catheter: Material | None = None,
    wire: Material | None = None,
    name: str | None = None,
) -> Design:
    """The base design with the free quantities set to ``values`` (SI, by name or in the
    order of ``study.free``) and the tubes made of the given materials."""
    if not isinstance(values, Mapping):
        values = {b.name: float(x) for b, x in zip(study.free, values, strict=True)}
    base = study.base
    robot = base.robot
    for prefix, m in (("catheter", catheter), ("wire", wire)):
        if m is not None:
            tube = replace(
                getattr(robot, prefix),
                youngs_modulus=m.youngs_modulus,
                poisson_ratio=m.poisson_ratio,
                density=m.density,
            )
            robot = replace(robot, **{prefix: tube})
    design = replace(base, name=name or base.name, robot=robot)
    design = design_with(design, {k: v for k, v in values.items() if k != "external_distance"})
    if "external_distance" in values:
        ext = design.external_magnet
        distance = float(values["external_distance"])
        centre = magnet_centre_at(design.robot.free_length, ext.center, distance)
        ext = replace(ext, center=(float(centre[0]), float(centre[1]), float(centre[2])))
        design = replace(design, external_magnet=ext)
    return design


def material_combinations(study: Study) -> list[tuple[Material | None, Material | None]]:
    """Every (catheter, wire) material pair of the study (None keeps the base tube)."""
    cat: list[Material | None] = [material(m) for m in study.catheter_materials] or [None]
    wire: list[Material | None] = [material(m) for m in study.wire_materials] or [None]
    return list(itertools.product(cat, wire))


START_SECONDS_PER_CONFIGURATION = 0.01
"""Time of one NLP start per configuration it samples (``configurations`` plus twice
``neutral_configurations``): 0.005 to 0.016 s measured on the development machine (2
cores) by benchmarks/estimates.py on the small test study (40 configurations). [s]"""


def nlp_starts(study: Study, pareto: bool = True) -> int:
    """NLP starts a study solves: every start of every material pair, for the optimum and,
    with ``pareto``, for every point of its Pareto sweeps."""
    points = sum(p.points for p in study.pareto) if pareto else 0
    return (1 + points) * study.starts * len(material_combinations(study))


def nlp_seconds(study: Study, pareto: bool = True) -> float:
    """Estimated time of :func:`nlp_starts`, one worker. [s]"""
    sampled = study.configurations + 2 * study.neutral_configurations
    return nlp_starts(study, pareto) * sampled * START_SECONDS_PER_CONFIGURATION


def _strain_limits(
    study: Study, cat: Material | None, wire: Material | None
) -> tuple[float, float]:
    lim = study.limits
    out = []
    for override, m in ((lim.catheter_max_strain, cat), (lim.wire_max_strain, wire)):
        if override is not None:
            out.append(override)
        elif m is not None:
            out.append(m.allowable_strain)
        else:  # the study validation requires one of them
            raise ValueError("a tube without material needs a max strain")
    return out[0], out[1]


def group_bounds(
    study: Study,
    cat: Material | None,
    wire: Material | None,
    epsilon: Mapping[str, float] | None,
) -> dict[str, tuple[float, float]]:
    """(lower, upper) of every constraint group, SI."""
    lim = study.limits
    inf = math.inf
    strain_c, strain_w = _strain_limits(study, cat, wire)
    out = {
        "strain.catheter": (-inf, strain_c),
        "strain.wire": (-inf, strain_w),
        "twist.wire": (-lim.twist_limit, lim.twist_limit),
        "twist.catheter": (-lim.twist_limit, lim.twist_limit),
        "neutral": (-inf, lim.neutral_tolerance),
        "magnet_clearance": (lim.magnet_clearance, inf),
        "ring_stiffness": (RING_STIFFNESS_MARGIN, inf),
        "ring_on_wire": (RULES["ring_on_wire"].bound(lim), inf),
        "wire_in_catheter": (RULES["wire_in_catheter"].bound(lim), inf),
        "ring_wall": (RULES["ring_wall"].bound(lim), inf),
        "catheter_wall": (RULES["catheter_wall"].bound(lim), inf),
        "ring_diameter": (-inf, lim.max_outer_diameter),
        "ring_seat": (RULES["ring_seat"].bound(lim), inf),
        "catheter_diameter": (-inf, lim.max_outer_diameter),
        "epsilon.catheter_outer_diameter": (-inf, inf),
        "epsilon.external_distance": (-inf, inf),
        "epsilon.magnet_volume": (-inf, inf),
        "min_disc_radius": (lim.min_disc_radius or -inf, inf),
        "min_reach_ratio": (lim.min_reach_ratio or -inf, inf),
    }
    for name, value in (epsilon or {}).items():
        if name not in PARETO_QUANTITIES:
            raise ValueError(
                f"epsilon bound on {name!r}; expected one of {', '.join(PARETO_QUANTITIES)}"
            )
        sense = PARETO_QUANTITIES[name][2]
        out[f"epsilon.{name}"] = (-inf, value) if sense == "max" else (value, inf)
    return out
