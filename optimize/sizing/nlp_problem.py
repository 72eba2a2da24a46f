"""The design NLP's formulation: variables, equilibrium constraints, objectives and
constraint groups of one study, built as CasADi expressions (solved by :mod:`optimize.sizing.nlp`).

Formulation (one material combination, one start):

- Variables: the free quantities, scaled to [0, 1] by their bounds; the model's unknowns
  x_k at K parallel-ring configurations (theta1 = theta2 = phi_j, phi_j = 2 pi j / K: the
  boundary of the reachable set, :mod:`design.workspace`) and at K_n antiparallel ones
  (theta1 = phi_j + pi, theta2 = phi_j: the neutral loop), K_n with the rings at right
  angles, and the robot at rest with the field off (:func:`field_off`), each scaled by its
  size at the warm start; epigraph variables rho (disc radius) and t (reach ratio).
- Equilibrium: ``RingPairModel.residual(x_k, command_k, params) = 0`` for every k, where
  ``params`` is the base design's parameter vector with the free entries replaced. Any
  model the study names (``effects``): the baseline, the model for design work, torsion
  with the printed tip's stops (stop angle and pre-twist may be free). Each
  configuration's residual, pose and internal loads are one function of the model,
  compiled with its Jacobian (:mod:`design.compiled`) and mapped over the configurations.
- Objectives (maximised; several are weighted after division by their base-design value):
  ``disc_radius``: rho <= the distance from the robot's home (:mod:`design.home`: the
  first antiparallel sample, theta1 = pi, theta2 = 0, solved with the others) to each arc
  of the smooth curve through the parallel loop's samples seen along x
  (:func:`design.geometry.curve_distances`; the largest disc about home inside the loop,
  :func:`design.geometry.curve_disc_radius`, as the forward workspace measures it on its
  720 samples); ``area``: the shoelace
  area of the parallel loop (seen along x); ``reach_ratio``: t <= w_z / w_y and
  t <= w_y / w_z with the y and z widths of the loop (smooth maxima in the NLP, exact
  sample maxima when reported).
- Constraints (named groups, reported by name): bending strain at the clamp and at the
  rod's end (|M| / EI x outer radius, M from the model's ``internal`` function) of each
  tube within its material's allowable strain; twist of each transmission (L / GJ times
  the axial torque on its ring, from the same function: the solved twist with
  ``torsion``, its first-order estimate without) within the limit at every configuration;
  with ``torsion`` the rings' rotational stiffness (:func:`ring_stiffness`: a stop counts
  by how hard it is pressed, so a free pre-twist presses the rings against it); rings on
  the wire and the wire in the catheter with clearance (at least
  :data:`design.admissible.WIRE_CLEARANCE`), and the ring bore over the printed pieces' wire
  bore and passage (``ring_seat``); walls (these five: the margins of
  :mod:`design.admissible`, bounded by :meth:`~design.admissible.Rule.bound`); the largest
  outer diameter (the printed tip's and the catheter's; the printed pieces' rows whatever
  the model: the study builds them); clearance
  of both rings to the external magnet at every configuration (the model's
  :func:`design.geometry.ring_clearance`: true distance to the cylinder less the ring's
  bounding sphere); the neutral deflection within tolerance (each antiparallel tip's
  distance from the tip at rest with the field off: how well the rings cancel; the sag
  under the robot's own weight is the ``sag`` metric; the disc is about the home, which
  sags with the loop); optional lower bounds on
  disc radius and reach ratio; epsilon bounds (Pareto) on the catheter diameter, the
  magnet distance and the magnet volume. After the solve every sampled equilibrium must
  be the state the robot reaches there (:func:`design.solve_equilibria`: stable and
  connected to the unloaded robot by the load ramp); where IPOPT followed another branch,
  it starts once more from that design with the robot's states, and an optimum still on
  another branch is rejected; so is one whose loops cannot be driven from sample to
  sample without a snap, or with a multistable sampled state (``stable = true``, the
  default; :func:`optimize.sizing.nlp._loop_faults`).

SI units are used for all inputs and outputs; file units only in reports.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from design.admissible import RULES
from design.compiled import compile_functions
from design.geometry import (
    curve_disc_radius,
    curve_distances,
    external_distance,
    magnet_centre_at,
    rest_position,
)
from design.home import HOME_COMMAND
from design.magnets import ring_volume
from design.model import RingPairModel, Symbols, magnet_clearance
from design.registry import NAMES, index
from design.stops import stop_stiffness, stop_torque
from optimize.sizing.nlp_iterates import BestIterate
from optimize.sizing.studyfile import DEG, MM, MM3

SMOOTH_MAX_SHARPNESS = 200.0
"""Sharpness of the log-sum-exp maximum used for the reach widths, in units of the
deflection scale (bias at most log(K) / 200 of that scale)."""
TINY = 1e-20
"""Floor under square roots of squared norms, keeping them smooth at zero. [m or -]"""
EQUILIBRIUM_TOLERANCE = 1e-6
"""Largest scaled equilibrium residual of an accepted optimum (the unknowns over their
scale at the start). [-]"""

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
    "sag",
    "droop",
    "straight_disc_radius",
)
"""Workspace and design metrics reported for every solution, SI (m, m^2, -, m^3).
``disc_radius``: the largest disc about the robot's home (:mod:`design.home`: the first
antiparallel sample, theta1 = pi, theta2 = 0) inside the smooth curve through the
parallel loop's samples (:func:`design.geometry.curve_disc_radius`, the forward
workspace's measure); ``neutral_deflection``: the largest distance of an antiparallel-ring
tip from the tip at rest with the field off (how well the rings cancel); ``sag``: that
rest tip's distance from the straight robot's (its own weight); ``droop``: the home's
distance from the straight robot's tip; ``straight_disc_radius``: the disc about the
straight tip (the measure before issue 49)."""

# group: (file-unit scale, unit label, meaning)
GROUPS: dict[str, tuple[float, str, str]] = {
    "strain.catheter": (1e-2, "%", "bending strain of the catheter"),
    "strain.wire": (1e-2, "%", "bending strain of the wire"),
    "twist.wire": (DEG, "deg", "twist of the wire (distal ring)"),
    "twist.catheter": (DEG, "deg", "twist of the catheter (proximal ring)"),
    "neutral": (MM, "mm", "tip deflection with antiparallel rings"),
    "magnet_clearance": (MM, "mm", "rings to the external magnet's surface"),
    "ring_stiffness": (1.0, "-", "rings' rotational stiffness over the transmissions'"),
    "ring_on_wire": (MM, "mm", RULES["ring_on_wire"].meaning),
    "wire_in_catheter": (MM, "mm", RULES["wire_in_catheter"].meaning),
    "ring_wall": (MM, "mm", RULES["ring_wall"].meaning),
    "catheter_wall": (MM, "mm", RULES["catheter_wall"].meaning),
    "ring_diameter": (MM, "mm", "outer diameter of the printed tip"),
    "ring_seat": (MM, "mm", RULES["ring_seat"].meaning),
    "catheter_diameter": (MM, "mm", "catheter outer diameter"),
    "epsilon.catheter_outer_diameter": (MM, "mm", "catheter OD (Pareto bound)"),
    "epsilon.external_distance": (MM, "mm", "external magnet distance (Pareto bound)"),
    "epsilon.magnet_volume": (MM3, "mm^3", "volume of both rings (Pareto bound)"),
    "min_disc_radius": (MM, "mm", "disc radius (lower bound)"),
    "min_reach_ratio": (1.0, "-", "reach ratio (lower bound)"),
}
"""Constraint groups: scale from SI to the unit they are reported in, unit, meaning."""


@dataclass(frozen=True)
class NlpShape:
    """What fixes the NLP's shape: its variables and rows (one compiled solver per shape)."""

    effects: frozenset[str]
    free: tuple[str, ...]
    configurations: int
    neutral_configurations: int


def commands(shape: NlpShape) -> np.ndarray:
    """Sampled commands, shape (2, K + 2 K_n): K parallel (the boundary), K_n antiparallel
    (neutral), then K_n with the rings at right angles (theta1 = theta2 + pi/2, where the
    rings' mutual torque, and so the twist, is largest). [rad]"""
    k, kn = shape.configurations, shape.neutral_configurations
    phi = 2 * np.pi * np.arange(k) / k
    psi = 2 * np.pi * np.arange(kn) / kn
    out = np.vstack(
        [np.concatenate([phi, psi + np.pi, psi + np.pi / 2]), np.concatenate([phi, psi, psi])]
    )
    assert tuple(out[:, k]) == HOME_COMMAND  # the first antiparallel sample is the home
    return out


def _params_expression(free: tuple[str, ...], v: ca.SX, base: ca.SX) -> ca.SX:
    """Model parameter vector with the free entries replaced by ``v`` (SI)."""
    entries = list(ca.vertsplit(base))
    for i, name in enumerate(free):
        if name == "external_distance":
            ids = [index(f"external_center_{a}") for a in "xyz"]
            centre = ca.vertcat(*[base[j] for j in ids])
            new = magnet_centre_at(entries[index("free_length")], centre, v[i])
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


FIELD_OFF = ("magnet_remanence", "external_remanence")
"""Parameters set to zero for the robot with the field off (the magnets unmagnetised: no
field, no ring moments, no ring coupling), which leaves only its own weight."""


def field_off(params: np.ndarray) -> np.ndarray:
    """The parameter vector(s) ``params`` (..., len(NAMES)) with the field off (FIELD_OFF
    zero). [SI]"""
    out = np.array(params, float)
    for name in FIELD_OFF:
        out[..., index(name)] = 0.0
    return out


@dataclass(frozen=True)
class Core:
    """The study's metrics and constraint rows as CasADi functions of (v, X, P).

    v : free quantities (SI), shape (n_free,); X : unknowns at :attr:`commands`, shape
    (n, K + 2 K_n + 1); P : model parameter vector of the start design, shape
    (len(NAMES),). The last configuration is the robot at rest with the field off
    (:func:`field_off`; straight without gravity), the reference of the neutral loop.
    ``rows`` lists the constraint group of every row of ``g``. Each configuration's
    equilibrium residual, pose and internal loads come from one function of the model
    (``column``), mapped over the configurations, so that the NLP's compiled code holds
    one copy of the model.
    """

    shape: NlpShape
    model: RingPairModel
    commands: np.ndarray
    params: ca.Function  # (v, P) -> prm
    column: ca.Function  # (x, command, prm) -> r, rows, tip deflection from straight
    compiled: ca.Function  # the same in native code, with its Jacobian (first derivatives)
    evaluate: ca.Function  # (v, X, P, scale) -> g, metrics, side distances, widths, area
    exact: ca.Function  # the same from ``column``, twice differentiable (exact Hessians)
    outcome: ca.Function  # (prm, mapped rows, mapped deflections, scale) -> evaluate's outputs
    rows: tuple[str, ...]
    variable_groups: frozenset[str]
    """Groups that depend on the free quantities (the others cannot be active)."""

    def configuration_params(self, params: np.ndarray) -> np.ndarray:
        """The parameter vector of every configuration, one per column, shape
        (len(NAMES), K'): ``params``, the last with the field off. [SI]"""
        out = np.tile(np.asarray(params, float), (self.commands.shape[1], 1))
        out[-1] = field_off(out[-1])
        return out.T


COLUMN_ROWS = (
    "strain.catheter",
    "strain.wire",
    "strain.catheter",
    "strain.wire",
    "twist.wire",
    "twist.catheter",
    "magnet_clearance",
)
"""Constraint rows of one configuration: bending strain at the clamp, then at the rod's
end, the transmissions' twist, the rings' clearance to the external magnet (with
``torsion`` then ``ring_stiffness``, :func:`ring_stiffness`)."""

RING_STIFFNESS_MARGIN = 0.05
"""Least rotational stiffness of the rings at a sampled state, over the transmissions'
(``ring_stiffness`` rows, with ``torsion``; :func:`ring_stiffness`). [-]"""
HOLD_ANGLE = np.deg2rad(1.0)
"""Relative rotation of the rings that a state held against a stop must survive
(:func:`ring_stiffness`). [rad]"""


def column_rows(model: RingPairModel) -> tuple[str, ...]:
    """The constraint group of each of ``model``'s rows of one configuration."""
    torsion = model.n_unknowns > model.n_rod
    return COLUMN_ROWS + (("ring_stiffness",) if torsion else ())


def ring_stiffness(model: RingPairModel, r: ca.SX, x: ca.SX, s: Symbols) -> ca.SX:
    """The rings' lowest rotational stiffness at fixed pose, over the transmissions': the
    least eigenvalue of the symmetric part of K_t^-1/2 H K_t^-1/2, K_t the transmissions'
    stiffness GJ / L and H = K_t - dtau/dtheta, tau the axial torques on the rings from the
    field and each other. H is a principal block of the Hessian of the total potential, so
    a stable state has it positive definite; the touching rings' mutual torque (kappa > 1)
    makes it indefinite.

    With the stops (``printed_tip``), a ring pair held against a stop by the contact torque
    lambda is stable as long as that torque exceeds the others' pull over a disturbance of
    HOLD_ANGLE: the stop adds its secant stiffness |lambda| / HOLD_ANGLE on the relative
    angle, not its contact stiffness (a stop touched without pressing, the pre-twist
    free, holds nothing). [-]

    r : the model's residual at x, whose rows from n_rod on are theta - command - tau L /
    GJ (rad), the stops' torque in tau: dr/dtheta = K_t^-1 (K_t - dtau/dtheta)."""
    n_rod = model.n_rod
    theta = x[n_rod:]
    compliance = s["free_length"] / s.torsional_rigidity
    j = ca.jacobian(r[n_rod:], theta)
    if "printed_tip" in model.effects:
        k = stop_stiffness(compliance)
        lam = stop_torque(theta[0] - theta[1], s["stop_angle"], k)
        relative = ca.DM([[1.0, -1.0], [-1.0, 1.0]])
        tangent = ca.jacobian(lam, theta[0])  # d lambda / d rho
        held = ca.fabs(lam) / HOLD_ANGLE
        # replace the contact's tangent stiffness (-tangent) by its secant one (held)
        j = j + ca.diag(compliance) @ ((tangent + held) * relative)
    w = ca.sqrt(compliance)
    m = j * ((1 / w) @ w.T)  # K_t^1/2 (K_t^-1 H) K_t^-1/2
    a, d, b = m[0, 0], m[1, 1], (m[0, 1] + m[1, 0]) / 2
    return (a + d) / 2 - ca.sqrt(((a - d) / 2) ** 2 + b**2 + TINY**2)


def _column(model: RingPairModel) -> ca.Function:
    """One configuration: (x, command, prm) -> (equilibrium residual, :func:`column_rows`, tip
    deflection from the straight robot's tip (3)). [SI]"""
    x = ca.SX.sym("x", model.n_unknowns)
    c = ca.SX.sym("command", 2)
    prm = ca.SX.sym("params", len(NAMES))
    s = Symbols(prm)
    r, _ = model.residual(x, c, prm)
    position, frame, _ = model.pose(x, c, prm)
    base_moment, end_moment, twist = model.internal(x, c, prm)
    rows = []
    for moment in (base_moment[1:3], end_moment):
        curvature = ca.sqrt(ca.sumsqr(moment) + TINY**2) / s.bending_rigidity
        rows += [
            curvature * s["catheter_outer_diameter"] / 2,
            curvature * s["wire_outer_diameter"] / 2,
        ]
    rows += [twist[0], twist[1], magnet_clearance(s, position, frame)]
    if model.n_unknowns > model.n_rod:
        rows.append(ring_stiffness(model, r, x, s))
    deflection = position - rest_position(s["free_length"])
    return ca.Function(
        "study_column",
        [x, c, prm],
        [r, ca.vertcat(*rows), deflection],
        ["x", "command", "params"],
        ["r", "rows", "deflection"],
        {"cse": True},
    )


@lru_cache(maxsize=1)
def _design_rows() -> tuple[tuple[str, ...], ca.Function]:
    """The rows that depend on the design alone, and prm -> (those rows, magnet volume,
    external distance, catheter OD). [SI]

    The tip's outer diameter and the rings' seat are the printed pieces' (design.mounting)
    whatever model the study designs with: the study builds those pieces."""
    prm = ca.SX.sym("params", len(NAMES))
    s = Symbols(prm)
    q = dict(s) | {"wire_bore": s.tip.wire_bore, "passage_diameter": s.tip.passage_diameter}
    volume = 2 * ring_volume(
        s["magnet_outer_diameter"], s["magnet_inner_diameter"], s["magnet_length"]
    )
    distance = external_distance(s["free_length"], s.external_center)
    admissible = ("ring_on_wire", "wire_in_catheter", "ring_wall", "catheter_wall")
    rows = [(name, RULES[name].margin(q)) for name in admissible]
    rows += [
        ("ring_diameter", s.tip.outer_diameter),
        ("catheter_diameter", s["catheter_outer_diameter"]),
    ]
    # the rings rest on the pieces' pocket floors (cad.mounting refuses anything else)
    rows.append(("ring_seat", RULES["ring_seat"].margin(q)))
    rows += [
        ("epsilon.catheter_outer_diameter", s["catheter_outer_diameter"]),
        ("epsilon.external_distance", distance),
        ("epsilon.magnet_volume", volume),
    ]
    fn = ca.Function(
        "study_design",
        [prm],
        [ca.vertcat(*[r for _, r in rows]), volume, distance, s["catheter_outer_diameter"]],
    )
    return tuple(g for g, _ in rows), fn


def design_values(prm: np.ndarray) -> dict[str, float]:
    """The rows that depend on the design alone (the rings' fit, the diameters, the seat,
    the Pareto quantities: :func:`_design_rows`) at the parameter vector ``prm``, by
    group. [SI]"""
    groups, fn = _design_rows()
    return dict(zip(groups, np.asarray(fn(prm)[0]).ravel().tolist(), strict=True))


@lru_cache(maxsize=8)
def core(shape: NlpShape) -> Core:
    """Build the metric and constraint expressions of a shape (cached)."""
    model = RingPairModel(shape.effects)
    nf = len(shape.free)
    cmd = np.hstack([commands(shape), np.zeros((2, 1))])  # the last: at rest, field off
    v_sx, base_sx = ca.SX.sym("v", nf), ca.SX.sym("P", len(NAMES))
    params = ca.Function(
        "study_params", [v_sx, base_sx], [_params_expression(shape.free, v_sx, base_sx)],
        ["v", "P"], ["params"],
    )  # fmt: skip
    column = _column(model)
    compiled = compile_functions([column, column.jacobian()])[0]
    design = _design_rows()
    rows = column_rows(model)
    outcome = _outcome(shape, cmd.shape[1], len(rows), design, rows)
    evaluate, free_groups = _evaluation(shape, cmd, params, compiled, outcome)
    exact = _evaluation(shape, cmd, params, column, outcome)[0]
    return Core(
        shape, model, cmd, params, column, compiled, evaluate, exact, outcome[0], outcome[1],
        free_groups,
    )  # fmt: skip


def _configuration_params(prm: ca.MX, count: int) -> ca.MX:
    """The parameter vector of each of ``count`` configurations, the last with the field
    off (:func:`field_off`), shape (len(NAMES), count)."""
    mask = np.ones(len(NAMES))
    mask[[index(name) for name in FIELD_OFF]] = 0.0
    return ca.horzcat(ca.repmat(prm, 1, count - 1), prm * ca.DM(mask))


def _evaluation(
    shape: NlpShape,
    cmd: np.ndarray,
    params: ca.Function,
    column: ca.Function,
    outcome: tuple[ca.Function, tuple[str, ...]],
) -> tuple[ca.Function, frozenset[str]]:
    """The study's rows and metrics from ``column`` mapped over the configurations:
    (v, X, P, scale) -> (g, metrics, side distances, widths, signed area), ``outcome``
    (:func:`_outcome`) of the mapped rows and deflections; the groups that depend on the
    free quantities or the unknowns."""
    n, nf, k_all = column.size1_in(0), len(shape.free), cmd.shape[1]
    v = ca.MX.sym("v", nf)
    big_x = ca.MX.sym("X", n, k_all)
    base = ca.MX.sym("P", len(NAMES))
    scale = ca.MX.sym("scale")
    prm = params(v, base)
    _, rows_k, deflection = column.map(k_all)(big_x, ca.DM(cmd), _configuration_params(prm, k_all))
    outputs: list[ca.MX] = list(outcome[0](prm, rows_k, deflection, scale))
    evaluate = ca.Function(
        "study_metrics",
        [v, big_x, base, scale],
        outputs,
        ["v", "X", "P", "scale"],
        ["g", "metrics", "side_distances", "widths", "area_signed"],
    )
    g, unknowns = outputs[0], ca.vertcat(v, ca.vec(big_x))
    free_groups = frozenset(
        grp for grp, k in zip(outcome[1], range(g.numel()), strict=True)
        if ca.depends_on(g[k], unknowns)
    )  # fmt: skip
    return evaluate, free_groups


def _outcome(
    shape: NlpShape,
    k_all: int,
    n_rows: int,
    design: tuple[tuple[str, ...], ca.Function],
    column_groups: tuple[str, ...],
) -> tuple[ca.Function, tuple[str, ...]]:
    """The study's rows and metrics from the mapped column's rows and deflections (whose
    rows are of ``column_groups``), without the model (cheap to differentiate):
    (prm, rows (n_rows, K'), deflection (3, K'), scale) -> (g, metrics, side distances,
    widths, signed area); the group of every row of g."""
    k_par, kn = shape.configurations, shape.neutral_configurations
    design_groups, design_rows = design
    prm = ca.SX.sym("params", len(NAMES))
    rows_k = ca.SX.sym("rows", n_rows, k_all)
    deflection = ca.SX.sym("deflection", 3, k_all)
    scale = ca.SX.sym("scale")
    rest = deflection[:, -1]  # the robot at rest, field off
    neutral = deflection[:, k_par : k_par + kn] - ca.repmat(rest, 1, kn)
    neutral_distance = ca.sqrt(ca.sum1(neutral * neutral) + TINY**2).T
    g_design, volume, distance, catheter = design_rows(prm)
    g = ca.vertcat(ca.vec(rows_k[:, : k_all - 1]), neutral_distance, g_design)
    groups = column_groups * (k_all - 1) + ("neutral",) * kn + design_groups

    home = deflection[:, k_par]  # the first antiparallel sample: HOME_COMMAND
    straight = deflection[1:, :k_par]  # (2, K), y and z of the parallel loop
    d = straight - ca.repmat(home[1:], 1, k_par)  # about home
    dist = ca.sqrt(ca.sum1(straight * straight) + TINY**2).T
    sides = curve_distances(d.T)
    area_signed = 0.5 * ca.sum2(
        d[0, :] * ca.horzcat(d[1, 1:], d[1, 0]) - ca.horzcat(d[0, 1:], d[0, 0]) * d[1, :]
    )
    reach_y = (ca.mmax(d[0, :]) - ca.mmin(d[0, :])) / 2
    reach_z = (ca.mmax(d[1, :]) - ca.mmin(d[1, :])) / 2
    metrics = ca.vertcat(
        curve_disc_radius(d.T),
        ca.fabs(area_signed),
        reach_y,
        reach_z,
        ca.fmin(reach_y, reach_z) / ca.fmax(ca.fmax(reach_y, reach_z), 1e-300),
        ca.mmax(neutral_distance),
        ca.mmax(dist),
        volume,
        distance,
        catheter,
        ca.sqrt(ca.sumsqr(rest) + TINY**2),
        ca.sqrt(ca.sumsqr(home) + TINY**2),
        curve_disc_radius(straight.T),
    )
    widths = ca.vertcat(
        _smooth_max(d[0, :].T, scale) + _smooth_max(-d[0, :].T, scale),
        _smooth_max(d[1, :].T, scale) + _smooth_max(-d[1, :].T, scale),
    )
    outcome = ca.Function(
        "study_outcome",
        [prm, rows_k, deflection, scale],
        [g, metrics, sides, widths, area_signed],
        ["params", "rows", "deflection", "scale"],
        ["g", "metrics", "side_distances", "widths", "area_signed"],
    )
    return outcome, groups


@dataclass(frozen=True)
class Problem:
    """The NLP of a shape and its IPOPT ``solver``.

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
    best: BestIterate  # the solver's best feasible iterate (reset before each solve)


def _ipopt_options(max_iterations: int, tolerance: float, hessian: str) -> dict[str, Any]:
    return {
        "ipopt.hessian_approximation": hessian,
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "print_time": False,
        "ipopt.max_iter": max_iterations,
        "ipopt.tol": tolerance,
        "ipopt.acceptable_tol": max(tolerance * 100, 1e-6),
        # IPOPT's defaults accept equilibria violated by 1e-4 (1e-2 at its acceptable
        # level); an optimum is judged by residuals below EQUILIBRIUM_TOLERANCE
        "ipopt.constr_viol_tol": EQUILIBRIUM_TOLERANCE / 10,
        "ipopt.acceptable_constr_viol_tol": EQUILIBRIUM_TOLERANCE / 10,
        # the free quantities stay within their bounds (by default IPOPT relaxes them by
        # 1e-8, which a stop's contact stiffness turns into 1e-4 rad of ring angle)
        "ipopt.bound_relax_factor": 0.0,
        "error_on_fail": False,
        # a trial point where the model has no value (NaN) is IPOPT's to step back from;
        # CasADi's warning for each reached the user's console as raw C++ log lines
        "show_eval_warnings": False,
    }


def _symbolic_nlp(
    c: Core, relaxed: bool, exact: bool
) -> tuple[dict[str, ca.MX], np.ndarray, list[str]]:
    """NLP expressions. Variables (z, x~, rho~, t[, slacks]); returns (nlp, row scales of the
    inequality part, group of each inequality row). ``exact``: from the model's own
    expressions, twice differentiable (exact Hessians), else from their compiled twin with
    its Jacobian (:mod:`design.compiled`; about 20x faster per evaluation)."""
    st = c.shape
    n, nf, k_all = c.model.n_unknowns, len(st.free), c.commands.shape[1]
    z = ca.MX.sym("z", nf)
    xt = ca.MX.sym("xt", n, k_all)
    rho_t = ca.MX.sym("rho")
    t = ca.MX.sym("t")
    p_base = ca.MX.sym("P", len(NAMES))
    xs = ca.MX.sym("xs", n)
    lo, hi = ca.MX.sym("lo", nf), ca.MX.sym("hi", nf)
    norms = ca.MX.sym("norms", 3)
    area_sign, scale = ca.MX.sym("area_sign"), ca.MX.sym("dscale")
    weights = ca.MX.sym("weights", 3)
    v = lo + (hi - lo) * z
    big_x = xt * ca.repmat(xs, 1, k_all)
    prm = c.params(v, p_base)
    column = c.column if exact else c.compiled
    # the model mapped once: its derivatives are most of an iteration's work
    mapped = column.map(k_all)(big_x, ca.DM(c.commands), _configuration_params(prm, k_all))
    r_all, rows_k, deflection = mapped
    g_rows, _, sides, widths, area_signed = c.outcome(prm, rows_k, deflection, scale)
    rho = rho_t * norms[0]
    equilibrium = [ca.vec(r_all / ca.repmat(xs, 1, k_all))]
    groups = list(c.rows) + ["min_disc_radius", "min_reach_ratio"]
    row_scale = np.array([GROUPS[g][0] for g in groups])
    ineq = ca.vertcat(g_rows, rho, t) / ca.DM(row_scale)
    epigraph = ca.vertcat(sides - rho, widths[1] - t * widths[0], widths[0] - t * widths[1]) / scale
    objective = -(
        weights[0] * rho_t + weights[1] * area_sign * area_signed / norms[1] + weights[2] * t
    )
    variables = [z, ca.vec(xt), rho_t, t]
    params = ca.vertcat(p_base, xs, lo, hi, norms, area_sign, weights, scale)
    if relaxed:
        names = list(GROUPS)
        slack = ca.MX.sym("slack", len(names))
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
    shape: NlpShape, max_iterations: int, tolerance: float, hessian: str = "limited-memory"
) -> Problem:
    """The IPOPT solver of a shape (cached per process). ``hessian``: IPOPT's
    ``hessian_approximation``, "exact" (second derivatives of the model) or
    "limited-memory" (L-BFGS from the exact gradients)."""
    c = core(shape)
    nlp, row_scale, _ = _symbolic_nlp(c, relaxed=False, exact=hessian == "exact")
    options = _ipopt_options(max_iterations, tolerance, hessian)
    best = BestIterate(nlp["x"].numel(), nlp["g"].numel(), options["ipopt.constr_viol_tol"])
    options["iteration_callback"] = best
    solver = ca.nlpsol("design_nlp", "ipopt", nlp, options)
    return Problem(c, solver, nlp["x"].numel(), nlp["g"].numel(), row_scale, best)


@lru_cache(maxsize=8)
def restoration(
    shape: NlpShape, max_iterations: int, hessian: str = "limited-memory"
) -> ca.Function:
    """The minimum-violation NLP of a shape (one slack per constraint group)."""
    nlp, _, _ = _symbolic_nlp(core(shape), relaxed=True, exact=hessian == "exact")
    options = _ipopt_options(max_iterations, 1e-8, hessian)
    return ca.nlpsol("design_restoration", "ipopt", nlp, options)
