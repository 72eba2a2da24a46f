"""The design NLP: a known optimum, an optimum re-checked by independent forward
simulation of its saved design file, an infeasible study's conflict report, a failing
start, a Pareto (epsilon) bound, picklable results."""

from __future__ import annotations

import math
import pickle
from dataclasses import replace

import numpy as np
import pytest
import tomli_w
from scipy.optimize import minimize_scalar
from studies import SMALL

from design.constants import MU0
from design.designfile import default_design, design_to_dict, load_design, save_design
from design.equilibrium import solve_design
from design.geometry import curve_disc_radius
from design.model import RingPairModel
from design.mounting import design_tip_geometry
from design.ring_coupling import coupling_coefficient, coupling_torques
from design.sections import bending_rigidity, tube_torsional_rigidity
from design.workspace import LOOP_SAMPLES, Workspace, sweep_workspace
from optimize.sizing.materials import material
from optimize.sizing.nlp import evaluate_design, optimize_design, pareto_values
from optimize.sizing.studyfile import Study, default_study, loads_study

L_MM = 150.0
BETA = math.radians(45.0)


def study_disc_radius(ws: Workspace, study: Study) -> float:
    """The disc about home (design.geometry.curve_disc_radius) of a forward-swept
    workspace's parallel loop taken at the study's K directions, phi_j = 2 pi j / K (every
    LOOP_SAMPLES / K-th loop sample), as the NLP measures it. [m]"""
    every, rest = divmod(LOOP_SAMPLES, study.configurations)
    assert rest == 0
    loop = ws.parallel.position[::every] - ws.home.position
    return curve_disc_radius(loop[:, 1:])


@pytest.fixture(scope="module")
def known_study(tmp_path_factory):
    """Demonstrator with the external magnet on a line at BETA from the rod axis (in the
    x-y plane), its axis pointing at the rest tip; point-like rings (10^-7 mm long, so
    the spacing and the deflection, about 1e-12 m, are negligible) and a weak magnet."""
    doc = design_to_dict(default_design())
    doc.pop("environment")
    u = [math.cos(BETA), math.sin(BETA), 0.0]
    d0 = 250.0
    doc["tip"]["magnet_length_mm"] = 1e-7
    doc["external_magnet"]["remanence_t"] = 0.0145
    doc["external_magnet"]["center_mm"] = [L_MM + d0 * u[0], d0 * u[1], 0.0]
    doc["external_magnet"]["magnetization"] = [-u[0], -u[1], 0.0]
    folder = tmp_path_factory.mktemp("known")
    (folder / "base.toml").write_text(tomli_w.dumps(doc))
    text = """
name = "known-distance"
base_design = "base.toml"
[free]
external_distance_mm = [100.0, 400.0]
[constraints]
catheter_max_strain = 0.05
wire_max_strain = 0.06
[solver]
starts = 2
tolerance = 1e-12
"""
    return loads_study(text, folder=folder)


def known_optimum(study: Study):
    """The known study's optimum by the closed form of
    :func:`test_distance_maximising_the_disc_radius_closed_form`: (magnet distance [m],
    disc radius of the K-sample polygon [m], d -> the loop's semi-axes (a_y, a_z) [m])."""
    design = study.base
    k = MU0 / (4 * math.pi)
    ext = design.external_magnet
    m_e = ext.remanence / MU0 * math.pi / 4 * ext.diameter**2 * ext.length
    tip = design.tip
    m = (
        tip.magnet_remanence
        / MU0
        * math.pi
        / 4
        * (tip.magnet_outer_diameter**2 - tip.magnet_inner_diameter**2)
        * tip.magnet_length
    )
    ei, length = bending_rigidity(design.robot), design.robot.free_length

    def semi_axes(d: float) -> tuple[float, float]:
        torque = length**2 * math.cos(BETA) / d**3
        scale = 2 * k * m_e * m / ei  # two rings
        return (
            scale * (torque + length**3 * (1 - 3 * math.sin(BETA) ** 2) / d**4),
            scale * (torque + length**3 / d**4),
        )

    step = 2 * math.pi / study.configurations

    phi = step * np.arange(study.configurations)

    def polygon_disc(d: float) -> float:
        """The disc inside the smooth curve through the ellipse's K samples (the NLP's
        measure, design.geometry.curve_disc_radius, on numbers here)."""
        a_y, a_z = semi_axes(d)
        return curve_disc_radius(np.c_[a_y * np.cos(phi), a_z * np.sin(phi)])

    best = minimize_scalar(
        lambda d: -polygon_disc(d), bounds=(0.1, 0.4), method="bounded", options={"xatol": 1e-13}
    )
    return best.x, polygon_disc(best.x), semi_axes


@pytest.mark.parametrize("hessian", ["limited-memory", "exact"])
def test_distance_maximising_the_disc_radius_closed_form(known_study, hessian):
    """Linear dipole baseline, small-load limit. The external dipole m_e sits at distance d
    along u = (cos b, sin b, 0) from the rest tip, magnetised towards it (m_e = -|m_e| u),
    so the tip is on its axis: B = -2 k |m_e| / d^3 u and dB/dp = 3 k |m_e| / d^4 (I - 3 u u^T)
    (k = mu0 / 4 pi). Parallel rings at angle phi, m = |m| (0, cos phi, sin phi):

    - phi = 0 (m along y): f = 3 k |m_e| |m| / d^4 (y - 3 sin b u), so f_y = 3 k |m_e||m|
      (1 - 3 sin^2 b) / d^4, f_z = 0; torque m x B = 2 k |m_e||m| cos b / d^3 z.
      Tip deflection (F L^3 / 3EI, T L^2 / 2EI): delta_y = (k |m_e||m| / EI)
      (L^2 cos b / d^3 + L^3 (1 - 3 sin^2 b) / d^4), delta_z = 0.
    - phi = 90 deg (m along z): delta_z = (k |m_e||m| / EI) (L^2 cos b / d^3 + L^3 / d^4),
      delta_y = 0.

    The parallel loop is the ellipse with these semi-axes, centred on the rest position, so
    the disc radius is the smaller, delta_y (sin^2 b > 1/3 makes the force term oppose the
    torque term). d(delta_y)/dd = 0 gives
        d* = 4 L (3 sin^2 b - 1) / (3 cos b),
    for b = 45 deg: d* = 2 sqrt(2) L / 3 = 141.42136 mm. The NLP measures the loop about
    the robot's home (here the straight tip, to 1e-12: point-like rings, no gravity) by the
    smooth curve through its K samples at phi_j = 2 pi j / K
    (design.geometry.curve_disc_radius), computed again on the ellipse's samples here;
    the minor axis' end is a sample, so that disc is a_y and its optimum d*. The model's
    equilibrium adds corrections of relative size deflection / d ~ 1e-14 and spacing / d
    ~ 1e-12.
    """
    d_star = 4 * L_MM * (3 * math.sin(BETA) ** 2 - 1) / (3 * math.cos(BETA)) * 1e-3
    distance, disc, semi_axes = known_optimum(known_study)
    assert distance == pytest.approx(d_star, rel=1e-4)  # the continuous loop's optimum
    result = optimize_design(replace(known_study, hessian=hessian))
    assert result.feasible
    assert all(s.accepted for s in result.starts)
    assert result.values["external_distance"] == pytest.approx(distance, rel=1e-6)
    assert result.objective == pytest.approx(disc, rel=1e-6)
    assert result.objective == pytest.approx(semi_axes(d_star)[0], rel=2e-4)


def test_epsilon_bound_moves_the_optimum_onto_it(known_study):
    # Beyond d* the disc shrinks with distance, so external_distance >= 160 mm binds.
    result = optimize_design(known_study, epsilon={"external_distance": 0.160})
    assert result.values["external_distance"] == pytest.approx(0.160, rel=1e-7)
    assert "epsilon.external_distance" in result.active
    back = pickle.loads(pickle.dumps(result))
    assert back.values == result.values and back.design == result.design


def test_pareto_front_against_magnet_distance_is_monotone(known_study):
    # Requiring the magnet farther away can only cost disc radius; below d* it is free.
    eps = [0.12, 0.15, 0.2, 0.3]
    radius = [optimize_design(known_study, epsilon={"external_distance": e}).objective for e in eps]
    free = optimize_design(known_study).objective
    assert radius[0] == pytest.approx(free, rel=1e-9)
    assert all(a > b for a, b in zip(radius, radius[1:], strict=False))


def test_pareto_values_span_the_free_bounds():
    study = default_study()
    od, dist, vol = (pareto_values(study, replace(p, low=None, high=None)) for p in study.pareto)
    assert od[0] == pytest.approx(1.2e-3) and od[-1] == pytest.approx(2.5e-3)
    assert dist[0] == pytest.approx(0.060) and dist[-1] == pytest.approx(0.200)
    # an explicit range (the default study's distance and volume sweeps) is taken as given
    given = study.pareto[1]
    assert given.low is not None and given.high is not None
    span = pareto_values(study, given)
    assert (span[0], span[-1]) == pytest.approx((given.low, given.high))
    # Both rings at the largest OD, the smallest bore and the longest length. [m^3]
    od_hi = study.bound("magnet_outer_diameter").high
    bore_lo = study.bound("magnet_inner_diameter").low
    length_hi = study.bound("magnet_length").high
    assert vol[-1] == pytest.approx(2 * math.pi / 4 * (od_hi**2 - bore_lo**2) * length_hi)
    assert len(od) == study.pareto[0].points


def test_a_failing_start_does_not_stop_the_study(known_study, monkeypatch):
    import optimize.sizing.nlp.solve as nlp

    # A start that cannot be evaluated is rejected with its reason; the next one solves.
    result = optimize_design(known_study, starts=[{"external_distance": math.nan}, {}])
    first, second = result.starts
    assert not first.accepted and "not finite: external_distance" in first.message
    assert second.accepted and result.feasible
    assert result.values["external_distance"] == pytest.approx(
        known_optimum(known_study)[0], rel=1e-6
    )

    # A start whose solver breaks down is recorded with the error, the others carry on.
    real = nlp._solve_one
    calls = []

    def flaky(*args, **kwargs):
        calls.append(args[1])
        if len(calls) == 1:
            raise RuntimeError("IPOPT crashed")
        return real(*args, **kwargs)

    monkeypatch.setattr(nlp, "_solve_one", flaky)
    result = optimize_design(known_study)
    assert calls == [1, 2]
    assert result.starts[0].status == "error: RuntimeError"
    assert result.starts[0].message == "IPOPT crashed"
    assert result.feasible and result.starts[1].accepted


def _dipole_field(offset, moment):
    """Oracle: point-dipole flux density, B = mu0/4pi (3 P (P.m) / |P|^5 - m / |P|^3). [T]"""
    r = np.linalg.norm(offset)
    return MU0 / (4 * np.pi) * (3 * offset * (offset @ moment) / r**5 - moment / r**3)


def test_optimum_rechecked_by_forward_simulation_of_its_design_file(tmp_path):
    study = loads_study(SMALL)
    result = optimize_design(study)
    assert result.feasible, result.report()
    path = tmp_path / "best.toml"
    save_design(result.design, path)
    design = load_design(path)  # the saved file is a valid design file

    # Objective: the workspace's disc radius on the forward loop at the study's directions.
    ws = sweep_workspace(design, np.deg2rad(15.0))
    assert ws.n_without_state == 0 and ws.n_snapped == 0
    assert ws.parallel.stable.all()
    assert study_disc_radius(ws, study) == pytest.approx(result.objective, rel=1e-4)
    # 720 loop samples: the smooth curve through the NLP's samples follows the loop
    assert abs(ws.disc_radius - result.objective) <= 1e-4
    assert ws.disc_radius > 1.05 * sweep_workspace(study.base, np.deg2rad(15.0)).disc_radius
    # Neutral pose (720 antiparallel samples).
    lim = study.limits
    assert ws.neutral_deflection <= lim.neutral_tolerance * (1 + 1e-3)

    # Geometry.
    tip, robot = design.tip, design.robot
    assert tip.magnet_inner_diameter >= robot.wire.outer_diameter + lim.wire_clearance - 1e-9
    assert robot.catheter.inner_diameter >= robot.wire.outer_diameter + lim.wire_clearance
    printed = design_tip_geometry(design).outer_diameter  # the pieces the CAD builds
    assert max(printed, tip.magnet_outer_diameter, robot.catheter.outer_diameter) <= (
        lim.max_outer_diameter + 1e-12
    )

    # Bending strain (independent: curvature of the clamped beam's Hermite shape from the
    # tip displacement and slope, kappa(0) = 6 delta / L^2 - 2 theta / L, kappa(L) =
    # -6 delta / L^2 + 4 theta / L; Gere & Goodno, App. G).
    length = robot.free_length
    q = ws.parallel.unknowns
    slope_y, slope_z = q[:, 3], -q[:, 2]
    curv = []
    for delta, theta in ((q[:, 0], slope_y), (q[:, 1], slope_z)):
        curv.append(
            np.stack(
                [
                    6 * delta / length**2 - 2 * theta / length,
                    -6 * delta / length**2 + 4 * theta / length,
                ]
            )
        )
    kappa = np.hypot(curv[0], curv[1]).max()
    assert kappa * robot.catheter.outer_diameter / 2 <= material("ptfe").allowable_strain
    assert kappa * robot.wire.outer_diameter / 2 <= material("niti").allowable_strain

    # Twist (rigid transmissions: |axial torque| L / GJ), rings at right angles and parallel,
    # from an oracle dipole field and the rings' coupling coefficient.
    phi = np.deg2rad(np.arange(0.0, 360.0, 15.0))
    k12 = coupling_coefficient(
        tip.magnet_outer_diameter,
        tip.magnet_inner_diameter,
        tip.magnet_length,
        tip.spacing,
        tip.magnet_remanence,
    )
    ext = design.external_magnet
    m_e = np.asarray(ext.magnetization) * ext.remanence / MU0 * np.pi / 4 * ext.diameter**2
    m_e = m_e * ext.length
    m_ring = (
        tip.magnet_remanence
        / MU0
        * np.pi
        / 4
        * (tip.magnet_outer_diameter**2 - tip.magnet_inner_diameter**2)
        * tip.magnet_length
    )
    gj = (tube_torsional_rigidity(robot.wire), tube_torsional_rigidity(robot.catheter))
    worst = 0.0
    for t1, t2 in ((phi + np.pi / 2, phi), (phi, phi)):
        eq = solve_design(design, t1, t2)
        for i in range(len(phi)):
            frame = eq.frame[i]
            torques = list(coupling_torques(t1[i], t2[i], k12))
            for j, (angle, centre) in enumerate(
                (
                    (t1[i], eq.position[i] + tip.spacing * frame[:, 0]),
                    (t2[i], eq.position[i]),
                )
            ):
                m = m_ring * (np.cos(angle) * frame[:, 1] + np.sin(angle) * frame[:, 2])
                b = _dipole_field(centre - np.asarray(ext.center), m_e)
                torques[j] += np.cross(m, b) @ frame[:, 0]
            for j in range(2):
                worst = max(worst, abs(torques[j]) * length / gj[j])
    assert worst <= lim.twist_limit * (1 + 1e-3)

    # Clearance of both rings to the magnet's surface over the whole swept grid.
    axis = np.asarray(ext.magnetization)
    bound_radius = math.hypot(tip.magnet_outer_diameter / 2, tip.magnet_length / 2)
    for pos, frame in zip(ws.grid.position, ws.grid.frame, strict=True):
        for centre in (pos, pos + tip.spacing * frame[:, 0]):
            off = centre - np.asarray(ext.center)
            a = off @ axis
            radial = np.sqrt(max(off @ off - a * a, 0.0))
            gap = math.hypot(max(abs(a) - ext.length / 2, 0.0), max(radial - ext.diameter / 2, 0))
            assert gap - bound_radius >= lim.magnet_clearance - 1e-9

    # The package's own forward evaluation agrees with the NLP.
    ev = evaluate_design(study, design)
    assert ev.converged and ev.stable and ev.violation == 0
    assert ev.objective == pytest.approx(result.objective, rel=1e-6)
    assert {s.name for s in result.constraints if s.active} <= set(result.active)


def test_infeasible_study_reports_the_conflict():
    # The rings' bore can be at most 0.6 mm, the wire at least 0.4 mm, but the bore must
    # clear the wire by 0.5 mm: short by exactly 0.3 mm.
    text = """
name = "impossible"
[free]
magnet_inner_diameter_mm = [0.5, 0.6]
wire_outer_diameter_mm = [0.4, 0.6]
[materials]
catheter = ["ptfe"]
wire = ["niti"]
[constraints]
wire_clearance_mm = 0.5
twist_limit_deg = 180.0
[solver]
starts = 2
"""
    result = optimize_design(loads_study(text))
    assert not result.feasible
    assert result.design is None
    assert all(not s.accepted for s in result.starts)
    conflicts = {c.name: c for c in result.conflicts}
    # the rings' seat on the printed pieces (bore over the pieces' wire bore and the
    # catheter's passage) cannot be met either: the bore is what both need
    assert set(conflicts) == {"ring_on_wire", "ring_seat"}
    conflict = conflicts["ring_on_wire"]
    assert conflict.violation == pytest.approx(0.3e-3, rel=1e-4)
    assert "magnet_inner_diameter at its upper bound" in result.limiting_bounds
    assert "wire_outer_diameter at its lower bound" in result.limiting_bounds
    report = result.report()
    assert "INFEASIBLE" in report
    assert "ring_on_wire (ring bore minus wire OD) misses its limit 0.5 mm by 0.3 mm" in report


def test_torsion_study_optimum_holds_in_forward_simulation():
    # With the torsion effect the twist is the solved tip-angle lag itself.
    study = loads_study(SMALL.replace('objective = "disc_radius"', 'effects = "torsion"'))
    result = optimize_design(study)
    assert result.feasible, result.report()
    model = RingPairModel(study.effects)
    ws = sweep_workspace(result.design, np.deg2rad(15.0), model=model)
    assert ws.n_without_state == 0 and ws.n_snapped == 0
    assert study_disc_radius(ws, study) == pytest.approx(result.objective, rel=1e-4)
    phi = np.deg2rad(np.arange(0.0, 360.0, 15.0))
    for t1 in (phi, phi + np.pi / 2, phi + np.pi):
        eq = solve_design(result.design, t1, phi, model=model)
        lag = np.angle(np.exp(1j * (eq.tip_angles - eq.command)))
        assert np.abs(lag).max() <= study.limits.twist_limit * (1 + 1e-3)


def test_controllable_objective_picks_the_start_with_the_largest_steerable_disc():
    """objective = "controllable_disc_radius": every accepted start is scored by the disc
    the robot can be steered over from home without a snap, as ``ringpair workspace``
    measures it (design.controllable on the study's model), and the best one wins."""
    from design.controllable import steerable

    study = replace(loads_study(SMALL), objective=(("controllable_disc_radius", 1.0),), starts=3)
    result = optimize_design(study)
    assert result.feasible, result.report()
    accepted = [s.objective for s in result.starts if s.accepted]
    assert result.objective == max(accepted)
    model = RingPairModel(study.effects)
    ws = sweep_workspace(result.design, np.deg2rad(10.0), model)
    disc = steerable(ws, model, model.parameters(result.design)).disc_radius
    assert result.metrics["controllable_disc_radius"] == pytest.approx(disc, rel=1e-9)
    assert result.objective == pytest.approx(disc, rel=1e-9)
    # the one disc: the NLP's own measure of it agrees within 0.1 mm (issue 49)
    assert abs(result.metrics["disc_radius"] - disc) <= 1e-4
