"""The design NLP: choose the free quantities of a study to maximise the workspace, with
the robot's equilibria as constraints, solved by IPOPT with exact derivatives through the
model's own CasADi expressions.

Formulation (one material combination, one start):

- Variables: the free quantities, scaled to [0, 1] by their bounds; the model's unknowns
  x_k at K parallel-ring configurations (theta1 = theta2 = phi_j, phi_j = 2 pi j / K: the
  boundary of the reachable set, :mod:`design.workspace`) and at K_n antiparallel ones
  (theta1 = phi_j + pi, theta2 = phi_j: the neutral loop), each scaled by its size at the
  warm start; epigraph variables rho (disc radius) and t (reach ratio).
- Equilibrium: ``RingPairModel.residual(x_k, command_k, params) = 0`` for every k, where
  ``params`` is the base design's parameter vector with the free entries replaced.
- Objectives (maximised; several are weighted after division by their base-design value):
  ``disc_radius``: rho <= |p(phi_j) - p_rest| for all j (the largest disc around the rest
  position inside the parallel loop, measured at its vertices); ``area``: the shoelace
  area of the parallel loop (seen along x); ``reach_ratio``: t <= w_z / w_y and
  t <= w_y / w_z with the y and z widths of the loop (smooth maxima in the NLP, exact
  sample maxima when reported).
- Constraints (named groups, reported by name): bending strain at the base and at the tip
  of the rod (|M| / EI x outer radius, M from the rod's stiffness and its coordinates) of
  each tube within its material's allowable strain; twist of each transmission
  (|axial torque| L / GJ, from the ``torsion`` model's own torque expression, or the
  solved tip angles when ``torsion`` is on) within the limit at every configuration;
  rings on the wire and the wire in the catheter with clearance; walls; the largest outer
  diameter; clearance of both rings to the external magnet's surface at every
  configuration; the neutral tip deflection within tolerance; optional lower bounds on
  disc radius and reach ratio; epsilon bounds (Pareto) on the catheter diameter, the
  magnet distance and the magnet volume. Stability of every sampled equilibrium is
  checked after the solve (the model's ``stability`` minors); an unstable optimum is
  rejected.

Multi-start: start 1 is the base design, the others are drawn uniformly in the bounds
(seeded); a start that fails is recorded with IPOPT's status and does not stop the study.
If no start is feasible, a minimum-violation problem (one slack per constraint group)
tells which constraints conflict and by how much.

SI units are used for all inputs and outputs; file units only in reports.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from design import cantilever
from design.equilibrium import solve_equilibria
from design.magnets import ring_volume
from design.model import RingPairModel, Symbols
from design.parameters import NAMES, index, parameter_vector
from design.params import Design
from optimize.materials import Material, material
from optimize.study import DEG, MM, MM3, PARETO_QUANTITIES, ParetoSweep, Study

SMOOTH_MAX_SHARPNESS = 200.0
"""Sharpness of the log-sum-exp maximum used for the reach widths, in units of the
deflection scale (bias at most log(K) / 200 of that scale)."""
FEASIBILITY_TOLERANCE = 1e-6
"""A constraint row counts as satisfied within this, in its group's file unit, plus this
relative to its limit (IPOPT relaxes bounds by about 1e-8 relative)."""
ACTIVE_TOLERANCE = 1e-5
"""A constraint row is active when within this of its limit (file unit) or its multiplier
is nonzero."""
TINY = 1e-20
"""Floor under square roots of squared norms, keeping them smooth at zero. [m or -]"""

METRICS = (
    "disc_radius",
    "area",
    "reach_y",
    "reach_z",
    "reach_ratio",
    "neutral_deflection",
    "max_deflection",
    "magnet_volume",
    "external_distance",
    "catheter_outer_diameter",
)
"""Workspace and design metrics reported for every solution, SI (m, m^2, -, m^3)."""

# group: (file-unit scale, unit label, meaning)
GROUPS: dict[str, tuple[float, str, str]] = {
    "strain.catheter": (1e-2, "%", "bending strain of the catheter"),
    "strain.wire": (1e-2, "%", "bending strain of the wire"),
    "twist.wire": (DEG, "deg", "twist of the wire (distal ring)"),
    "twist.catheter": (DEG, "deg", "twist of the catheter (proximal ring)"),
    "neutral": (MM, "mm", "tip deflection with antiparallel rings"),
    "magnet_clearance": (MM, "mm", "rings to the external magnet's surface"),
    "ring_on_wire": (MM, "mm", "ring bore minus wire OD"),
    "wire_in_catheter": (MM, "mm", "catheter bore minus wire OD"),
    "ring_wall": (MM, "mm", "radial wall of the rings"),
    "catheter_wall": (MM, "mm", "radial wall of the catheter"),
    "ring_diameter": (MM, "mm", "ring outer diameter"),
    "catheter_diameter": (MM, "mm", "catheter outer diameter"),
    "epsilon.catheter_outer_diameter": (MM, "mm", "catheter OD (Pareto bound)"),
    "epsilon.external_distance": (MM, "mm", "external magnet distance (Pareto bound)"),
    "epsilon.magnet_volume": (MM3, "mm^3", "volume of both rings (Pareto bound)"),
    "min_disc_radius": (MM, "mm", "disc radius (lower bound)"),
    "min_reach_ratio": (1.0, "-", "reach ratio (lower bound)"),
}
"""Constraint groups: scale from SI to the unit they are reported in, unit, meaning."""


# --------------------------------------------------------------------------- the problem


@dataclass(frozen=True)
class Structure:
    """What fixes the NLP's shape (one compiled solver per structure)."""

    effects: frozenset[str]
    free: tuple[str, ...]
    configurations: int
    neutral_configurations: int


def commands(structure: Structure) -> np.ndarray:
    """Sampled commands, shape (2, K + 2 K_n): K parallel (the boundary), K_n antiparallel
    (neutral), then K_n with the rings at right angles (theta1 = theta2 + pi/2, where the
    rings' mutual torque, and so the twist, is largest). [rad]"""
    k, kn = structure.configurations, structure.neutral_configurations
    phi = 2 * np.pi * np.arange(k) / k
    psi = 2 * np.pi * np.arange(kn) / kn
    return np.vstack(
        [np.concatenate([phi, psi + np.pi, psi + np.pi / 2]), np.concatenate([phi, psi, psi])]
    )


def _params_expression(free: tuple[str, ...], v: ca.SX, base: ca.SX) -> ca.SX:
    """Model parameter vector with the free entries replaced by ``v`` (SI)."""
    entries = list(ca.vertsplit(base))
    for i, name in enumerate(free):
        if name == "external_distance":
            rest = ca.vertcat(entries[index("free_length")], 0, 0)
            ids = [index(f"external_center_{a}") for a in "xyz"]
            centre = ca.vertcat(*[base[j] for j in ids])
            direction = (centre - rest) / ca.norm_2(centre - rest)
            new = rest + v[i] * direction
            for j, jj in enumerate(ids):
                entries[jj] = new[j]
        else:
            entries[index(name)] = v[i]
    return ca.vertcat(*entries)


def _smooth_max(values: ca.SX, scale: ca.SX) -> ca.SX:
    """log-sum-exp maximum of ``values`` (unit of ``scale``), shifted for overflow."""
    a = SMOOTH_MAX_SHARPNESS * values / scale
    top = ca.mmax(a)
    return scale * (top + ca.log(ca.sum1(ca.exp(a - top)))) / SMOOTH_MAX_SHARPNESS


@dataclass(frozen=True)
class Core:
    """The study's metrics and constraint rows as CasADi functions of (v, X, P).

    v : free quantities (SI), shape (n_free,); X : unknowns, shape (n, K + K_n);
    P : model parameter vector of the start design, shape (len(NAMES),).
    ``rows`` lists the constraint group of every row of ``g``.
    """

    structure: Structure
    model: RingPairModel
    commands: np.ndarray
    params: ca.Function  # (v, P) -> prm
    evaluate: ca.Function  # (v, X, P) -> g, metrics, distances, widths_smooth, area_signed
    rows: tuple[str, ...]
    variable_groups: frozenset[str]
    """Groups that depend on the free quantities (the others cannot be active)."""


@lru_cache(maxsize=8)
def core(structure: Structure) -> Core:
    """Build the metric and constraint expressions of a structure (cached)."""
    model = RingPairModel(structure.effects)
    torsion = "torsion" in structure.effects
    twist_model = None if torsion else RingPairModel(structure.effects | {"torsion"})
    n, nf = model.n_unknowns, len(structure.free)
    cmd = commands(structure)
    k_par, k_all = structure.configurations, cmd.shape[1]
    v = ca.SX.sym("v", nf)
    big_x = ca.SX.sym("X", n, k_all)
    base = ca.SX.sym("P", len(NAMES))
    prm = _params_expression(structure.free, v, base)
    s = Symbols(prm)
    length, ei = s["free_length"], s.bending_rigidity
    rest = ca.vertcat(length, 0, 0)
    gravity = s["load_scale"] * s.rod_mass_per_length * s.gravity
    w = gravity if "gravity" in structure.effects else ca.SX.zeros(3)
    stiff = cantilever.stiffness(length, ei)
    w_response = cantilever.distributed_load_response(w, length, ei)
    ring_radius = ca.sqrt((s["ring_outer_diameter"] / 2) ** 2 + (s["ring_length"] / 2) ** 2)

    rows: list[tuple[str, ca.SX]] = []
    deflection = []
    for k in range(k_all):
        x, c = big_x[:, k], ca.DM(cmd[:, k])
        position, frame, angles = model.pose(x, c, prm)
        deflection.append(position - rest)
        # Bending moment at the base and at the tip from the rod's loads Q = K (q - q_w).
        f_y, f_z, t_y, t_z = ca.vertsplit(stiff @ (x[:4] - w_response))
        base_moment = ca.vertcat(
            t_y - length * f_z - length**2 / 2 * w[2], t_z + length * f_y + length**2 / 2 * w[1]
        )
        for moment in (base_moment, ca.vertcat(t_y, t_z)):
            curvature = ca.sqrt(ca.sumsqr(moment) + TINY**2) / ei
            rows.append(("strain.catheter", curvature * s["catheter_outer_diameter"] / 2))
            rows.append(("strain.wire", curvature * s["wire_outer_diameter"] / 2))
        if twist_model is None:
            twist = angles - c
        else:
            r_twist, _ = twist_model.residual(ca.vertcat(x[:4], c), c, prm)
            twist = -r_twist[4:6]
        rows.append(("twist.wire", twist[0]))
        rows.append(("twist.catheter", twist[1]))
        for centre in (position, position + s.ring_spacing * frame[:, 0]):
            offset = centre - s.external_center
            axial = ca.dot(offset, s.external_axis)
            radial = ca.sqrt(ca.fmax(ca.sumsqr(offset) - axial**2, 0) + TINY**2)
            gap = ca.fmax(
                ca.fabs(axial) - s["external_length"] / 2, radial - s["external_diameter"] / 2
            )
            rows.append(("magnet_clearance", gap - ring_radius))
        if k_par <= k < k_par + structure.neutral_configurations:
            rows.append(("neutral", ca.sqrt(ca.sumsqr(deflection[-1]) + TINY**2)))
    wire = s["wire_outer_diameter"]
    rows += [
        ("ring_on_wire", s["ring_inner_diameter"] - wire),
        ("wire_in_catheter", s["catheter_inner_diameter"] - wire),
        ("ring_wall", (s["ring_outer_diameter"] - s["ring_inner_diameter"]) / 2),
        ("catheter_wall", (s["catheter_outer_diameter"] - s["catheter_inner_diameter"]) / 2),
        ("ring_diameter", s["ring_outer_diameter"]),
        ("catheter_diameter", s["catheter_outer_diameter"]),
    ]
    volume = 2 * ring_volume(s["ring_outer_diameter"], s["ring_inner_diameter"], s["ring_length"])
    distance = ca.norm_2(s.external_center - rest)
    rows += [
        ("epsilon.catheter_outer_diameter", s["catheter_outer_diameter"]),
        ("epsilon.external_distance", distance),
        ("epsilon.magnet_volume", volume),
    ]
    d = ca.horzcat(*deflection[:k_par])[1:, :]  # (2, K), y and z of the parallel loop
    dist = ca.sqrt(ca.sum1(d * d) + TINY**2).T
    area_signed = 0.5 * ca.sum2(
        d[0, :] * ca.horzcat(d[1, 1:], d[1, 0]) - ca.horzcat(d[0, 1:], d[0, 0]) * d[1, :]
    )
    reach_y = (ca.mmax(d[0, :]) - ca.mmin(d[0, :])) / 2
    reach_z = (ca.mmax(d[1, :]) - ca.mmin(d[1, :])) / 2
    neutral = ca.horzcat(*deflection[k_par : k_par + structure.neutral_configurations])
    metrics = ca.vertcat(
        ca.mmin(dist),
        ca.fabs(area_signed),
        reach_y,
        reach_z,
        ca.fmin(reach_y, reach_z) / ca.fmax(ca.fmax(reach_y, reach_z), 1e-300),
        ca.mmax(ca.sqrt(ca.sum1(neutral * neutral))),
        ca.mmax(dist),
        volume,
        distance,
        s["catheter_outer_diameter"],
    )
    scale = ca.SX.sym("scale")
    widths = ca.vertcat(
        _smooth_max(d[0, :].T, scale) + _smooth_max(-d[0, :].T, scale),
        _smooth_max(d[1, :].T, scale) + _smooth_max(-d[1, :].T, scale),
    )
    evaluate = ca.Function(
        "study_metrics",
        [v, big_x, base, scale],
        [ca.vertcat(*[r for _, r in rows]), metrics, dist, widths, area_signed],
        ["v", "X", "P", "scale"],
        ["g", "metrics", "distances", "widths", "area_signed"],
        {"cse": True},
    )
    params = ca.Function("study_params", [v, base], [prm], ["v", "P"], ["params"])
    unknowns = ca.vertcat(v, ca.vec(big_x))
    free_groups = frozenset(g for g, r in rows if ca.depends_on(r, unknowns))
    return Core(structure, model, cmd, params, evaluate, tuple(g for g, _ in rows), free_groups)


@dataclass(frozen=True)
class Problem:
    """The NLP of a structure and its IPOPT ``solver``.

    Variables: (z (n_free), x~ (n x (K + 2 K_n), column-major), rho~, t). Parameters:
    (model parameter vector P, unknown scales xs (n), lower and upper bounds of the free
    quantities, objective norms (disc, area, 1), area orientation sign, objective weights
    (disc, area, reach ratio), deflection scale). Constraints: equilibria (scaled by xs),
    epigraph rows, then the constraint groups' rows (Core.rows, then min_disc_radius and
    min_reach_ratio), each divided by its group's file-unit scale (``row_scale``).
    """

    core: Core
    solver: ca.Function
    n_variables: int
    n_constraints: int
    row_scale: np.ndarray  # scale of every inequality row (file unit, SI per unit)


def _ipopt_options(max_iterations: int, tolerance: float, hessian: str) -> dict[str, Any]:
    return {
        "ipopt.hessian_approximation": hessian,
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "print_time": False,
        "ipopt.max_iter": max_iterations,
        "ipopt.tol": tolerance,
        "ipopt.acceptable_tol": max(tolerance * 100, 1e-6),
        "error_on_fail": False,
    }


def _symbolic_nlp(c: Core, relaxed: bool) -> tuple[dict[str, ca.SX], np.ndarray, list[str]]:
    """NLP expressions. Variables (z, x~, rho~, t[, slacks]); returns (nlp, row scales of the
    inequality part, group of each inequality row)."""
    st = c.structure
    n, nf, k_all = c.model.n_unknowns, len(st.free), c.commands.shape[1]
    z = ca.SX.sym("z", nf)
    xt = ca.SX.sym("xt", n, k_all)
    rho_t = ca.SX.sym("rho")
    t = ca.SX.sym("t")
    p_base = ca.SX.sym("P", len(NAMES))
    xs = ca.SX.sym("xs", n)
    lo, hi = ca.SX.sym("lo", nf), ca.SX.sym("hi", nf)
    norms = ca.SX.sym("norms", 3)
    area_sign, scale = ca.SX.sym("area_sign"), ca.SX.sym("dscale")
    weights = ca.SX.sym("weights", 3)
    v = lo + (hi - lo) * z
    big_x = xt * ca.repmat(xs, 1, k_all)
    prm = c.params(v, p_base)
    g_rows, _, dist, widths, area_signed = c.evaluate(v, big_x, p_base, scale)
    rho = rho_t * norms[0]
    equilibrium = []
    for k in range(k_all):
        r, _ = c.model.residual(big_x[:, k], ca.DM(c.commands[:, k]), prm)
        equilibrium.append(r / xs)
    groups = list(c.rows) + ["min_disc_radius", "min_reach_ratio"]
    row_scale = np.array([GROUPS[g][0] for g in groups])
    ineq = ca.vertcat(g_rows, rho, t) / ca.DM(row_scale)
    epigraph = ca.vertcat(dist - rho, widths[1] - t * widths[0], widths[0] - t * widths[1]) / scale
    objective = -(
        weights[0] * rho_t + weights[1] * area_sign * area_signed / norms[1] + weights[2] * t
    )
    variables = [z, ca.vec(xt), rho_t, t]
    params = ca.vertcat(p_base, xs, lo, hi, norms, area_sign, weights, scale)
    if relaxed:
        names = list(GROUPS)
        slack = ca.SX.sym("slack", len(names))
        which = ca.DM([names.index(g) for g in groups])
        s_rows = ca.vertcat(*[slack[int(i)] for i in np.asarray(which).ravel()])
        g = ca.vertcat(*equilibrium, epigraph, ineq + s_rows, ineq - s_rows)
        variables.append(slack)
        objective = ca.sum1(slack)
    else:
        g = ca.vertcat(*equilibrium, epigraph, ineq)
    nlp = {"x": ca.vertcat(*variables), "p": params, "f": objective, "g": g}
    return nlp, row_scale, groups


@lru_cache(maxsize=8)
def problem(
    structure: Structure, max_iterations: int, tolerance: float, hessian: str = "limited-memory"
) -> Problem:
    """The IPOPT solver of a structure (cached per process). ``hessian``: IPOPT's
    ``hessian_approximation``, "exact" (second derivatives of the model) or
    "limited-memory" (L-BFGS from the exact gradients)."""
    c = core(structure)
    nlp, row_scale, _ = _symbolic_nlp(c, relaxed=False)
    options = _ipopt_options(max_iterations, tolerance, hessian)
    solver = ca.nlpsol("design_nlp", "ipopt", nlp, options)
    return Problem(c, solver, nlp["x"].numel(), nlp["g"].numel(), row_scale)


@lru_cache(maxsize=8)
def restoration(
    structure: Structure, max_iterations: int, hessian: str = "limited-memory"
) -> ca.Function:
    """The minimum-violation NLP of a structure (one slack per constraint group)."""
    nlp, _, _ = _symbolic_nlp(core(structure), relaxed=True)
    options = _ipopt_options(max_iterations, 1e-8, hessian)
    return ca.nlpsol("design_restoration", "ipopt", nlp, options)


# ------------------------------------------------------------------------ designs, values


def free_values(study: Study, design: Design) -> np.ndarray:
    """Values of the study's free quantities on ``design``, shape (n_free,). [SI]"""
    p = parameter_vector(design)
    out = []
    for b in study.free:
        if b.name == "external_distance":
            centre = np.asarray(design.external_magnet.center)
            out.append(float(np.linalg.norm(centre - [design.robot.free_length, 0, 0])))
        else:
            out.append(float(p[index(b.name)]))
    return np.array(out)


def design_with(
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

    def tube(t: Any, prefix: str, m: Material | None) -> Any:
        if m is not None:
            t = replace(
                t, youngs_modulus=m.youngs_modulus, poisson_ratio=m.poisson_ratio, density=m.density
            )
        keys = {
            "outer_diameter": f"{prefix}_outer_diameter",
            "inner_diameter": f"{prefix}_inner_diameter",
            "youngs_modulus": f"{prefix}_youngs_modulus",
        }
        return replace(t, **{f: float(values[k]) for f, k in keys.items() if k in values})

    robot = replace(
        base.robot,
        catheter=tube(base.robot.catheter, "catheter", catheter),
        wire=tube(base.robot.wire, "wire", wire),
    )
    tip_keys = {
        "magnet_outer_diameter": "ring_outer_diameter",
        "magnet_inner_diameter": "ring_inner_diameter",
        "magnet_length": "ring_length",
        "gap": "ring_gap",
    }
    tip = replace(base.tip, **{f: float(values[k]) for f, k in tip_keys.items() if k in values})
    ext = base.external_magnet
    if "external_distance" in values:
        rest = np.array([base.robot.free_length, 0.0, 0.0])
        direction = np.asarray(ext.center) - rest
        direction /= np.linalg.norm(direction)
        centre = rest + float(values["external_distance"]) * direction
        ext = replace(ext, center=(float(centre[0]), float(centre[1]), float(centre[2])))
    return replace(
        base,
        name=name or base.name,
        robot=robot,
        tip=tip,
        external_magnet=ext,
    )


def material_combinations(study: Study) -> list[tuple[Material | None, Material | None]]:
    """Every (catheter, wire) material pair of the study (None keeps the base tube)."""
    cat: list[Material | None] = [material(m) for m in study.catheter_materials] or [None]
    wire: list[Material | None] = [material(m) for m in study.wire_materials] or [None]
    return list(itertools.product(cat, wire))


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


def _group_bounds(
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
        "ring_on_wire": (lim.wire_clearance, inf),
        "wire_in_catheter": (lim.wire_clearance, inf),
        "ring_wall": (lim.min_wall, inf),
        "catheter_wall": (lim.min_wall, inf),
        "ring_diameter": (-inf, lim.max_outer_diameter),
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


# ----------------------------------------------------------------------------- results


@dataclass(frozen=True)
class ConstraintState:
    """One constraint group at a solution (its worst row).

    value, limit : SI (m, rad, -, m^3); the group's ``unit`` and ``scale`` (SI per unit)
        convert them for reports. ``limit`` is the bound that binds first.
    margin : distance to the limit, positive inside. [SI]
    active : at its limit (within ACTIVE_TOLERANCE) or with a nonzero multiplier.
    multiplier : largest |Lagrange multiplier| of the group's rows (scaled problem).
    """

    name: str
    value: float
    limit: float
    margin: float
    active: bool
    multiplier: float
    unit: str
    scale: float

    def describe(self) -> str:
        v, lim = self.value / self.scale, self.limit / self.scale
        flag = " (active)" if self.active else ""
        return f"{self.name}: {v:.6g} {self.unit}, limit {lim:.6g} {self.unit}{flag}"


@dataclass(frozen=True)
class Conflict:
    """A constraint group that stays violated at the least-violating design.

    violation : how far beyond its limit, SI; ``unit``/``scale`` as in ConstraintState.
    """

    name: str
    violation: float
    limit: float
    unit: str
    scale: float
    meaning: str

    def describe(self) -> str:
        return (
            f"{self.name} ({self.meaning}) misses its limit {self.limit / self.scale:.6g} "
            f"{self.unit} by {self.violation / self.scale:.4g} {self.unit}"
        )


@dataclass(frozen=True)
class StartResult:
    """One start of the multi-start.

    status : IPOPT's return status, or the error that stopped the start.
    accepted : solved, all constraints within tolerance and (if required) stable.
    values : free quantities at the end of the start (SI, by name).
    objective : the study's objective there (SI metric or weighted sum; NaN if failed).
    """

    index: int
    materials: tuple[str | None, str | None]
    status: str
    success: bool
    accepted: bool
    objective: float
    values: dict[str, float]
    iterations: int
    seconds: float
    message: str = ""


@dataclass(frozen=True)
class StudyResult:
    """Outcome of :func:`solve_study` (picklable: plain data and a Design).

    feasible : some start was accepted; then ``design`` is the best one.
    objective : the study's objective of the best design (the metric in SI for one
        objective, the weighted sum of base-normalised metrics for several).
    metrics : workspace and design metrics of the best design (see METRICS). [SI]
    base_metrics : the same for the base design as given (its own tube moduli), by
        forward simulation.
    constraints : every constraint group at the best design.
    active : names of the active groups and free bounds (``bound.<name>.low/high``).
    conflicts : for an infeasible study, the groups that stay violated at the
        least-violating design, most violated first.
    limiting_bounds : the free quantities at a bound in that least-violating design.
    epsilon : the Pareto bounds imposed (SI).
    """

    study: str
    feasible: bool
    objective: float
    design: Design | None
    values: dict[str, float]
    materials: tuple[str | None, str | None]
    metrics: dict[str, float]
    base_metrics: dict[str, float]
    constraints: tuple[ConstraintState, ...]
    active: tuple[str, ...]
    starts: tuple[StartResult, ...]
    conflicts: tuple[Conflict, ...] = ()
    limiting_bounds: tuple[str, ...] = ()
    epsilon: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0

    def report(self) -> str:
        """A plain-text summary for the user (file units)."""
        lines = [f"study {self.study}: " + ("feasible" if self.feasible else "INFEASIBLE")]
        if self.feasible:
            lines.append(f"objective {self.objective:.6g}; materials {self.materials}")
            lines += [f"  {k} = {v:.6g}" for k, v in self.values.items()]
            lines.append("active: " + (", ".join(self.active) or "none"))
        for c in self.conflicts:
            lines.append("  conflict: " + c.describe())
        if self.limiting_bounds:
            lines.append("  with " + ", ".join(self.limiting_bounds))
        for s in self.starts:
            lines.append(
                f"  start {s.index} {s.materials}: {s.status}"
                + ("" if s.accepted else f" (rejected{': ' + s.message if s.message else ''})")
            )
        return "\n".join(lines)


@dataclass(frozen=True)
class Evaluation:
    """A design evaluated by forward simulation on the study's sampled configurations.

    objective : as in StudyResult; metrics : see METRICS [SI]; constraints : every group.
    converged, stable : all sampled equilibria converged / are stable.
    violation : sum over groups of the violation in file units (0 when feasible).
    """

    objective: float
    metrics: dict[str, float]
    constraints: tuple[ConstraintState, ...]
    converged: bool
    stable: bool
    violation: float


# ---------------------------------------------------------------------------- evaluation


def _structure(study: Study) -> Structure:
    return Structure(
        frozenset(study.effects),
        tuple(b.name for b in study.free),
        study.configurations,
        study.neutral_configurations,
    )


def _states(
    c: Core,
    g: np.ndarray,
    bounds: Mapping[str, tuple[float, float]],
    multipliers: np.ndarray | None = None,
) -> tuple[ConstraintState, ...]:
    rows = np.array(c.rows)
    out = []
    for name in dict.fromkeys(c.rows):
        lo, hi = bounds[name]
        if not (math.isfinite(lo) or math.isfinite(hi)):
            continue
        vals = g[rows == name]
        scale, unit, _ = GROUPS[name]
        margins = np.minimum(vals - lo, hi - vals)
        i = int(np.argmin(margins))
        limit = lo if vals[i] - lo <= hi - vals[i] else hi
        mult = 0.0 if multipliers is None else float(np.max(np.abs(multipliers[rows == name])))
        near = margins[i] / scale < ACTIVE_TOLERANCE or mult > 1e-7
        active = bool(near and name in c.variable_groups)
        out.append(
            ConstraintState(
                name, float(vals[i]), float(limit), float(margins[i]), active, mult, unit, scale
            )
        )
    return tuple(out)


def _violation(states: Sequence[ConstraintState]) -> float:
    """Sum of the groups' violations in file units, each beyond FEASIBILITY_TOLERANCE
    (absolute, plus the same relative to its limit)."""
    return float(
        sum(
            max(0.0, -s.margin / s.scale - FEASIBILITY_TOLERANCE * abs(s.limit) / s.scale)
            for s in states
        )
    )


@dataclass(frozen=True)
class _Norms:
    """Base-design values the objectives are divided by, and scales. [SI]"""

    disc: float
    area: float
    deflection: float
    metrics: dict[str, float]


def _metrics_dict(m: np.ndarray) -> dict[str, float]:
    return {k: float(x) for k, x in zip(METRICS, np.asarray(m).ravel(), strict=True)}


def _objective(study: Study, metrics: Mapping[str, float], norms: _Norms) -> float:
    if len(study.objective) == 1:
        return float(metrics[study.objective[0][0]])
    div = {"disc_radius": norms.disc, "area": norms.area, "reach_ratio": 1.0}
    return float(sum(w * metrics[n] / div[n] for n, w in study.objective))


def _forward(study: Study, design: Design) -> tuple[Core, np.ndarray, np.ndarray, Any]:
    """Forward equilibria of ``design`` at the study's configurations: (core, v, X, eq)."""
    c = core(_structure(study))
    p = parameter_vector(design)
    eq = solve_equilibria(c.model, p, c.commands[0], c.commands[1])
    return c, free_values(study, design), eq.unknowns.T.copy(), eq


@lru_cache(maxsize=32)
def _norms(study: Study) -> _Norms:
    cat, wire = material_combinations(study)[0]
    design = design_with(study, free_values(study, study.base), cat, wire)
    c, v, x, _ = _forward(study, design)
    x = np.nan_to_num(x)
    _, m, _, _, _ = c.evaluate(v, x, parameter_vector(design), 1.0)
    metrics = _metrics_dict(m)
    deflection = metrics["max_deflection"] if metrics["max_deflection"] > 0 else 1e-3
    disc = metrics["disc_radius"] if metrics["disc_radius"] > 1e-6 * deflection else deflection
    area = metrics["area"] if metrics["area"] > 0 else deflection**2
    return _Norms(disc, area, deflection, metrics)


def evaluate_design(
    study: Study,
    design: Design,
    materials: tuple[str | None, str | None] | None = None,
    epsilon: Mapping[str, float] | None = None,
) -> Evaluation:
    """Evaluate ``design`` by forward simulation (:func:`design.solve_equilibria`) on the
    study's sampled configurations, with the same metric and constraint expressions as
    the NLP. ``materials`` (catheter, wire) names pick the allowable strains (default:
    the study's first candidates)."""
    cat, wire = material_combinations(study)[0]
    if materials is not None:
        cat = material(materials[0]) if materials[0] else None
        wire = material(materials[1]) if materials[1] else None
    c, v, x, eq = _forward(study, design)
    converged = bool(eq.converged.all())
    norms = _norms(study)
    g, m, _, _, _ = c.evaluate(v, np.nan_to_num(x), parameter_vector(design), norms.deflection)
    g, metrics = np.asarray(g).ravel(), _metrics_dict(m)
    bounds = _group_bounds(study, cat, wire, epsilon)
    states = _states(c, g, bounds)
    violation = _violation(states)
    if not converged:
        violation = math.inf
    return Evaluation(
        _objective(study, metrics, norms),
        metrics,
        states,
        converged,
        bool(eq.stable.all()),
        violation,
    )


# ------------------------------------------------------------------------------ solving


def _start_points(study: Study, count: int) -> list[np.ndarray]:
    """Start 1: the base design (clipped into the bounds); others uniform in the bounds,
    redrawn (up to 100 times) until the rings fit the wire and the walls are positive."""
    lo = np.array([b.low for b in study.free])
    hi = np.array([b.high for b in study.free])
    base = np.clip(free_values(study, study.base), lo, hi)
    rng = np.random.default_rng(study.seed)
    names = [b.name for b in study.free]
    out = [base]
    for _ in range(count - 1):
        for _ in range(100):
            z = lo + (hi - lo) * rng.random(len(lo))
            vals = dict(zip(names, z, strict=True))
            d = design_with(study, vals)
            ok = (
                d.tip.magnet_inner_diameter < d.tip.magnet_outer_diameter
                and d.robot.catheter.inner_diameter < d.robot.catheter.outer_diameter
                and d.robot.wire.outer_diameter < d.robot.catheter.inner_diameter
                and d.robot.wire.outer_diameter <= d.tip.magnet_inner_diameter
            )
            if ok:
                break
        out.append(z)
    return out


@dataclass
class _Attempt:
    """One solve's raw outcome (internal)."""

    start: StartResult
    v: np.ndarray | None = None
    x: np.ndarray | None = None
    p: np.ndarray | None = None
    lam_g: np.ndarray | None = None
    lam_x: np.ndarray | None = None
    violation: float = math.inf
    g: np.ndarray | None = None
    metrics: dict[str, float] = field(default_factory=dict)


def _parameters(
    study: Study, start: np.ndarray, cat: Material | None, wire: Material | None, norms: _Norms
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(NLP parameter vector, warm-start z, warm-start x~ (n, K'), area sign)."""
    c = core(_structure(study))
    design = design_with(study, start, cat, wire)
    p = parameter_vector(design)
    _, _, x, _ = _forward(study, design)
    x = np.nan_to_num(x)
    n = c.model.n_unknowns
    xs = np.ones(n)
    for i in range(min(n, 4)):
        xs[i] = max(np.abs(x[i]).max(), 1e-9 * norms.deflection, 1e-300)
    _, _, _, _, area_signed = c.evaluate(free_values(study, design), x, p, norms.deflection)
    sign = 1.0 if float(area_signed) >= 0 else -1.0
    lo = np.array([b.low for b in study.free])
    hi = np.array([b.high for b in study.free])
    z0 = np.where(hi > lo, (start - lo) / np.where(hi > lo, hi - lo, 1.0), 0.0)
    weights = dict(study.objective)
    w = [weights.get("disc_radius", 0.0), weights.get("area", 0.0), weights.get("reach_ratio", 0.0)]
    params = np.concatenate(
        [p, xs, lo, hi, [norms.disc, norms.area, 1.0], [sign], w, [norms.deflection]]
    )
    return params, z0, x / xs[:, None], sign


def _bounds_vectors(
    prob: Problem, bounds: Mapping[str, tuple[float, float]], n_eq: int, n_epi: int
) -> tuple[np.ndarray, np.ndarray]:
    groups = list(prob.core.rows) + ["min_disc_radius", "min_reach_ratio"]
    lo = np.array([bounds[g][0] for g in groups]) / prob.row_scale
    hi = np.array([bounds[g][1] for g in groups]) / prob.row_scale
    lbg = np.concatenate([np.zeros(n_eq), np.zeros(n_epi), lo])
    ubg = np.concatenate([np.zeros(n_eq), np.full(n_epi, np.inf), hi])
    return lbg, ubg


def _reachable_start(
    study: Study,
    start: np.ndarray,
    anchor: np.ndarray,
    cat: Material | None,
    wire: Material | None,
    halvings: int = 5,
) -> np.ndarray:
    """``start``, or the first point on the way to ``anchor`` (halving the distance) whose
    sampled equilibria all converge and are stable by forward simulation (a warm start
    on the branch the NLP should follow)."""
    for _ in range(halvings):
        eq = _forward(study, design_with(study, start, cat, wire))[3]
        if eq.stable.all():
            return start
        start = anchor + 0.5 * (start - anchor)
    return start


def _solve_one(
    study: Study,
    index_: int,
    start: np.ndarray,
    cat: Material | None,
    wire: Material | None,
    epsilon: Mapping[str, float] | None,
    norms: _Norms,
) -> _Attempt:
    names = (cat.name if cat else None, wire.name if wire else None)
    t0 = time.perf_counter()
    st = _structure(study)
    prob = problem(st, study.max_iterations, study.tolerance, study.hessian)
    c = prob.core
    n, nf, k_all = c.model.n_unknowns, len(st.free), c.commands.shape[1]
    params, z0, xt0, _ = _parameters(study, start, cat, wire, norms)
    n_eq, n_epi = n * k_all, st.configurations + 2
    lbg, ubg = _bounds_vectors(prob, _group_bounds(study, cat, wire, epsilon), n_eq, n_epi)
    w0 = np.concatenate([z0, xt0.ravel(order="F"), [0.0, 0.0]])
    lbx = np.concatenate([np.zeros(nf), np.full(n * k_all, -np.inf), [0.0, 0.0]])
    ubx = np.concatenate([np.ones(nf), np.full(n * k_all, np.inf), [np.inf, 1.0]])
    sol = prob.solver(x0=w0, p=params, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    stats = prob.solver.stats()
    w = np.asarray(sol["x"]).ravel()
    lo, hi = params[len(NAMES) + n : len(NAMES) + n + nf], params[len(NAMES) + n + nf :][:nf]
    v = lo + (hi - lo) * np.clip(w[:nf], 0.0, 1.0)
    xs = params[len(NAMES) : len(NAMES) + n]
    x = w[nf : nf + n * k_all].reshape(n, k_all, order="F") * xs[:, None]
    p = params[: len(NAMES)]
    g, m, _, _, _ = c.evaluate(v, x, p, norms.deflection)
    g, metrics = np.asarray(g).ravel(), _metrics_dict(m)
    bounds = _group_bounds(study, cat, wire, epsilon)
    states = _states(c, g, bounds)
    violation = _violation(states)
    prm = np.asarray(c.params(v, p)).ravel()
    res = np.asarray(c.model.residual.map(k_all)(x, c.commands, np.tile(prm[:, None], k_all))[0])
    equilibrium = float(np.abs(res / xs[:, None]).max()) if res.size else 0.0
    minors = np.asarray(c.model.stability.map(k_all)(x, c.commands, np.tile(prm[:, None], k_all)))
    stable = bool(np.all(minors > 0))
    success = bool(stats.get("success", False))
    message = ""
    if not np.all(np.isfinite(w)):
        message = "non-finite solution"
    elif equilibrium > 1e-6:
        message = f"equilibrium not reached (scaled residual {equilibrium:.3g})"
    elif violation > 0:
        worst = max(states, key=lambda s: -s.margin / s.scale)
        message = f"violates {worst.describe()}"
    elif study.limits.stable and not stable:
        bad = np.flatnonzero(~np.all(minors > 0, axis=0))
        message = f"unstable equilibrium at configurations {bad.tolist()}"
    accepted = success and not message
    lam_g = np.asarray(sol["lam_g"]).ravel()
    result = StartResult(
        index=index_,
        materials=names,
        status=str(stats.get("return_status", "unknown")),
        success=success,
        accepted=accepted,
        objective=_objective(study, metrics, norms) if np.all(np.isfinite(w)) else math.nan,
        values={b.name: float(x_) for b, x_ in zip(study.free, v, strict=True)},
        iterations=int(stats.get("iter_count", 0)),
        seconds=time.perf_counter() - t0,
        message=message,
    )
    return _Attempt(
        result,
        v,
        x,
        p,
        lam_g[n_eq + n_epi : n_eq + n_epi + len(c.rows)],
        np.asarray(sol["lam_x"]).ravel()[:nf],
        violation,
        g,
        metrics,
    )


def _conflicts(
    study: Study,
    start: np.ndarray,
    cat: Material | None,
    wire: Material | None,
    epsilon: Mapping[str, float] | None,
    norms: _Norms,
) -> tuple[float, tuple[Conflict, ...], tuple[str, ...]]:
    """Minimum-violation problem (one slack per group, their sum minimised in the groups'
    file units): the groups whose slack stays > 0, and the free bounds that limit it."""
    st = _structure(study)
    prob = problem(st, study.max_iterations, study.tolerance, study.hessian)
    solver = restoration(st, max(study.max_iterations, 500), study.hessian)
    c = prob.core
    n, nf, k_all = c.model.n_unknowns, len(st.free), c.commands.shape[1]
    params, z0, xt0, _ = _parameters(study, start, cat, wire, norms)
    n_eq, n_epi = n * k_all, st.configurations + 2
    bounds = _group_bounds(study, cat, wire, epsilon)
    lbg, ubg = _bounds_vectors(prob, bounds, n_eq, n_epi)
    n_in = len(lbg) - n_eq - n_epi
    lo_in, hi_in = lbg[n_eq + n_epi :], ubg[n_eq + n_epi :]
    lbg2 = np.concatenate([lbg[: n_eq + n_epi], lo_in, np.full(n_in, -np.inf)])
    ubg2 = np.concatenate([ubg[: n_eq + n_epi], np.full(n_in, np.inf), hi_in])
    n_s = len(GROUPS)
    w0 = np.concatenate([z0, xt0.ravel(order="F"), [0.0, 0.0], np.full(n_s, 1.0)])
    lbx = np.concatenate([np.zeros(nf), np.full(n * k_all, -np.inf), [0.0, 0.0], np.zeros(n_s)])
    ubx = np.concatenate(
        [np.ones(nf), np.full(n * k_all, np.inf), [np.inf, 1.0], np.full(n_s, np.inf)]
    )
    sol = solver(x0=w0, p=params, lbx=lbx, ubx=ubx, lbg=lbg2, ubg=ubg2)
    if not solver.stats().get("success", False):
        raise RuntimeError(f"minimum-violation problem: {solver.stats().get('return_status')}")
    w = np.asarray(sol["x"]).ravel()
    slack = w[-n_s:]
    limiting = []
    for b, z in zip(study.free, w[:nf], strict=True):
        if b.high > b.low and z < 1e-6:
            limiting.append(f"{b.name} at its lower bound")
        elif b.high > b.low and z > 1 - 1e-6:
            limiting.append(f"{b.name} at its upper bound")
    lo_, hi_ = params[len(NAMES) + n : len(NAMES) + n + nf], params[len(NAMES) + n + nf :][:nf]
    v = lo_ + (hi_ - lo_) * np.clip(w[:nf], 0.0, 1.0)
    xs = params[len(NAMES) : len(NAMES) + n]
    x = w[nf : nf + n * k_all].reshape(n, k_all, order="F") * xs[:, None]
    g = np.asarray(c.evaluate(v, x, params[: len(NAMES)], norms.deflection)[0]).ravel()
    violated = {name for name, s in zip(GROUPS, slack, strict=True) if s > 1e-5}
    for state in _states(c, g, bounds):
        if state.name not in violated and state.active:
            limiting.append(
                f"{state.name} at its limit {state.limit / state.scale:.6g} {state.unit}"
            )
    out = []
    for name, s in zip(GROUPS, slack, strict=True):
        if s > 1e-5:
            scale, unit, meaning = GROUPS[name]
            lo, hi = bounds[name]
            limit = lo if math.isfinite(lo) else hi
            out.append(Conflict(name, float(s * scale), float(limit), unit, scale, meaning))
    ranked = tuple(sorted(out, key=lambda c_: -c_.violation / c_.scale))
    return float(slack.sum()), ranked, tuple(limiting)


def solve_study(
    study: Study,
    *,
    epsilon: Mapping[str, float] | None = None,
    starts: Sequence[Mapping[str, float]] | None = None,
) -> StudyResult:
    """Solve the study's design NLP from several starts; return the best accepted design.

    epsilon : Pareto bounds by quantity (PARETO_QUANTITIES: ``catheter_outer_diameter``
        and ``magnet_volume`` bounded above, ``external_distance`` below). [SI: m, m^3]
    starts : explicit start points (free quantities by name, SI; missing ones from the
        base design) instead of the study's seeded ones.
    Every material combination is solved from every start. If no start is accepted the
    result is infeasible and ``conflicts`` lists the constraint groups that stay violated
    at the least-violating design (or is empty if the starts failed for another reason).
    """
    t0 = time.perf_counter()
    norms = _norms(study)
    if starts is None:
        points = _start_points(study, study.starts)
    else:
        base = free_values(study, study.base)
        points = [
            np.array([float(s.get(b.name, base[i])) for i, b in enumerate(study.free)])
            for s in starts
        ]
    attempts: list[_Attempt] = []
    combos = material_combinations(study)
    for cat, wire in combos:
        for i, start in enumerate(points):
            try:
                if not np.all(np.isfinite(start)):
                    bad = [
                        b.name for b, x in zip(study.free, start, strict=True) if not np.isfinite(x)
                    ]
                    raise ValueError(f"start values are not finite: {', '.join(bad)}")
                if i > 0:
                    start = _reachable_start(study, start, points[0], cat, wire)
                attempts.append(_solve_one(study, i + 1, start, cat, wire, epsilon, norms))
            except Exception as exc:  # a failed start is an answer, not the end of the study
                names = (cat.name if cat else None, wire.name if wire else None)
                attempts.append(
                    _Attempt(
                        StartResult(
                            i + 1,
                            names,
                            f"error: {type(exc).__name__}",
                            False,
                            False,
                            math.nan,
                            {},
                            0,
                            0.0,
                            str(exc),
                        )
                    )
                )
    accepted = [a for a in attempts if a.start.accepted]
    start_results = tuple(a.start for a in attempts)
    if not accepted:
        conflicts: tuple[Conflict, ...] = ()
        limiting: tuple[str, ...] = ()
        best_total = math.inf
        for cat, wire in combos:
            try:
                total, found, bounds_ = _conflicts(study, points[0], cat, wire, epsilon, norms)
            except Exception:  # noqa: BLE001 - report what the starts said
                continue
            if total < best_total:
                best_total, conflicts, limiting = total, found, bounds_
        return StudyResult(
            study=study.name,
            feasible=False,
            objective=math.nan,
            design=None,
            values={},
            materials=(None, None),
            metrics={},
            base_metrics=evaluate_design(study, study.base).metrics,
            constraints=(),
            active=(),
            starts=start_results,
            conflicts=conflicts,
            limiting_bounds=limiting,
            epsilon=dict(epsilon or {}),
            seconds=time.perf_counter() - t0,
        )
    best = max(accepted, key=lambda a: a.start.objective)
    assert best.v is not None and best.g is not None
    cat_name, wire_name = best.start.materials
    cat = material(cat_name) if cat_name else None
    wire = material(wire_name) if wire_name else None
    c = core(_structure(study))
    states = _states(c, best.g, _group_bounds(study, cat, wire, epsilon), best.lam_g)
    active = [s.name for s in states if s.active]
    for b, value in zip(study.free, best.v, strict=True):
        width = b.high - b.low
        if width > 0 and (value - b.low) / width < 1e-6:
            active.append(f"bound.{b.name}.low")
        elif width > 0 and (b.high - value) / width < 1e-6:
            active.append(f"bound.{b.name}.high")
    design = design_with(study, best.v, cat, wire, name=f"{study.name}-optimum")
    design = replace(design, description=f"optimum of study {study.name!r} (ringpair optimize)")
    return StudyResult(
        study=study.name,
        feasible=True,
        objective=best.start.objective,
        design=design,
        values=dict(best.start.values),
        materials=best.start.materials,
        metrics=best.metrics,
        base_metrics=evaluate_design(study, study.base).metrics,
        constraints=states,
        active=tuple(active),
        starts=start_results,
        epsilon=dict(epsilon or {}),
        seconds=time.perf_counter() - t0,
    )


def pareto_values(study: Study, sweep: ParetoSweep) -> np.ndarray:
    """The epsilon bounds of one Pareto sweep, shape (points,), in increasing order. [SI]

    Without an explicit range, the sweep spans the free bounds of its quantity (for the
    magnet volume: the smallest and largest rings the ring bounds and the minimum wall
    allow, base values for the fixed ones). ValueError if the quantity cannot change in this study.
    """
    low, high = sweep.low, sweep.high
    if low is None or high is None:
        if sweep.against == "magnet_volume":
            tip = study.base.tip
            fixed = {
                "ring_outer_diameter": tip.magnet_outer_diameter,
                "ring_inner_diameter": tip.magnet_inner_diameter,
                "ring_length": tip.magnet_length,
            }
            rng = {}
            for name, value in fixed.items():
                b = study.bound(name)
                rng[name] = (b.low, b.high) if b else (value, value)
            od, idia, h = rng["ring_outer_diameter"], rng["ring_inner_diameter"], rng["ring_length"]
            bore = min(idia[1], od[0] - 2 * study.limits.min_wall)
            lo_ = 2 * ring_volume(od[0], max(bore, 0.0), h[0])
            hi_ = 2 * ring_volume(od[1], idia[0], h[1])
        else:
            b = study.bound(sweep.against)
            if b is None:
                raise ValueError(
                    f"pareto sweep against {sweep.against} needs free.{sweep.against}_mm "
                    "or an explicit range_mm"
                )
            lo_, hi_ = b.low, b.high
        low = lo_ if low is None else low
        high = hi_ if high is None else high
    if not high > low:
        raise ValueError(f"pareto sweep against {sweep.against} has an empty range")
    return np.linspace(low, high, sweep.points)
