"""The design NLP with the model for design work and the printed tip (issue 16): on set-ups
drawn from the whole design space (ring sizes, free length, tube stiffness, magnet shape,
distance and off-axis position, gravity direction), the optimiser's prediction of every
reported metric equals forward simulation of its optimum (:func:`design.solve_equilibria`
at the same sampled configurations, an independent solve: the load ramp from the unloaded
robot, not IPOPT) within 0.1 mm, and the optimum can be driven around its loops without a
snap (the NLP's acceptance test, checked here by driving them again at a finer step)."""

from __future__ import annotations

import numpy as np
import pytest
import tomli_w
from setups import random_design

from design.admissible import WIRE_CLEARANCE
from design.controllable import steerable
from design.designfile import design_to_dict
from design.equilibrium import solve_sequence
from design.geometry import curve_disc_radius, external_distance
from design.home import solve_home
from design.model import RingPairModel
from design.process import RESIN
from design.registry import parameter_vector
from design.workspace import sweep_workspace
from optimize.sizing.nlp import evaluate_design, optimize_design
from optimize.sizing.nlp_problem import METRICS
from optimize.sizing.studyfile import loads_study

LENGTHS = (
    "disc_radius",
    "reach_y",
    "reach_z",
    "neutral_deflection",
    "max_deflection",
    "sag",
    "droop",
    "straight_disc_radius",
)
"""The metrics in metres (the others are an area, a ratio, a volume and design sizes)."""
AGREE = 1e-4
"""Prediction and forward simulation agree within this. [m]"""
SEEDS = tuple(range(11, 23))
"""Drawn set-ups, tried in order until CASES had a feasible optimum."""
CASES = 3
FIT = RESIN.fit_allowance
"""The fit allowance on the wire bore of the drawn designs' (resin) tip pieces. [m]"""

STUDY = """
name = "faithful-drawn"
base_design = "base.toml"
effects = "default,printed_tip"
objective = "disc_radius"
[free]
magnet_inner_diameter_mm = [{bore_low:.4f}, {bore_high:.4f}]
magnet_length_mm = [0.3, 3.0]
magnet_gap_mm = [0.0, 3.0]
external_distance_mm = [{low:.3f}, {high:.3f}]
[materials]
catheter = ["pebax_7233"]
wire = ["niti"]
[constraints]
max_outer_diameter_mm = 60.0
twist_limit_deg = 90.0
neutral_tolerance_mm = 200.0
magnet_clearance_mm = 2.0
[solver]
starts = 1
configurations = 24
neutral_configurations = 4
"""


def _study(seed: int, folder):
    """The drawn set-up's study; its ring bore free between what the printed pieces need
    (the rings rest on the pockets' floors: bore above the wire bore and the catheter's
    passage) and a 0.15 mm wall, or None where the drawn rings leave no such bore."""
    design = random_design(np.random.default_rng(seed))
    (folder / "base.toml").write_text(tomli_w.dumps(design_to_dict(design)))
    d0 = float(external_distance(design.robot.free_length, np.array(design.external_magnet.center)))
    floor = (
        max(design.robot.wire.outer_diameter + FIT, design.robot.catheter.inner_diameter)
        + 2 * WIRE_CLEARANCE
    )
    top = design.tip.magnet_outer_diameter - 0.3e-3
    if floor >= top:
        return None
    text = STUDY.format(
        low=0.9 * d0 * 1e3, high=1.5 * d0 * 1e3, bore_low=floor * 1e3, bore_high=top * 1e3
    )
    return loads_study(text, folder=folder)


@pytest.fixture(scope="module")
def optima(tmp_path_factory):
    """(seed, study, result) of the first CASES drawn set-ups with a feasible optimum."""
    out, tried = [], []
    for seed in SEEDS:
        study = _study(seed, tmp_path_factory.mktemp(f"seed{seed}"))
        if study is None:
            tried.append((seed, "no ring bore fits the printed pieces"))
            continue
        result = optimize_design(study)
        tried.append((seed, result.starts[0].message or result.starts[0].status))
        if result.feasible:
            out.append((seed, study, result))
        if len(out) == CASES:
            return out
    pytest.fail(f"fewer than {CASES} drawn set-ups had a feasible optimum: {tried}")


def test_faithful_nlp_predictions_equal_forward_simulation_on_drawn_setups(optima):
    for seed, study, result in optima:
        forward = evaluate_design(study, result.design, result.materials)
        assert forward.converged and forward.stable, f"seed {seed}"
        for name in LENGTHS:
            predicted, simulated = result.metrics[name], forward.metrics[name]
            assert abs(predicted - simulated) <= AGREE, (
                f"seed {seed}: {name} predicted {predicted * 1e3:.4f} mm, "
                f"forward {simulated * 1e3:.4f} mm"
            )
        assert set(result.metrics) == set(METRICS)
        for state in result.constraints:
            other = next(s for s in forward.constraints if s.name == state.name)
            assert abs(state.value - other.value) / state.scale <= 0.1, (
                f"seed {seed}: {state.name} {state.describe()} vs {other.describe()}"
            )


def test_faithful_optimum_loop_driven_finely_never_snaps(optima):
    """The parallel-ring loop of every optimum, driven in 0.5-degree steps by the path
    solver (which lets the robot fall where a branch ends and flags it), never snaps, and
    the disc about home of its states at the NLP's sampled directions is the NLP's within
    0.1 mm (the driven robot is on the NLP's branch)."""
    for seed, study, result in optima:
        model = RingPairModel(study.effects)
        phi = np.deg2rad(np.arange(0.0, 360.0 + 1e-9, 0.5))
        eq = solve_sequence(model, parameter_vector(result.design), phi, phi)
        assert not eq.snapped.any(), f"seed {seed}: snaps at {np.rad2deg(phi[eq.snapped])}"
        assert eq.converged.all(), f"seed {seed}"
        every = (len(phi) - 1) // study.configurations
        p = parameter_vector(result.design)
        home = solve_home(model, p, result.design.robot.free_length)
        loop = eq.position[: len(phi) - 1 : every] - home.position
        driven = float(curve_disc_radius(loop[:, 1:]))
        assert abs(driven - result.metrics["disc_radius"]) <= AGREE, (
            f"seed {seed}: driven {driven * 1e3:.4f} mm, "
            f"NLP {result.metrics['disc_radius'] * 1e3:.4f} mm"
        )


def test_nlp_disc_about_home_is_the_forward_workspaces_the_one_disc(optima):
    """Issue 49: the NLP's disc (about home, on the study's default 24 samples of the loop;
    on 16, seed 13 differs by 0.11 mm) equals the disc
    ``ringpair workspace`` reports for the optimum (the forward sweep's 720-sample loop
    about the forward home, capped by what can be steered to from home on a 10-degree grid)
    within 0.1 mm; the cells steerable from home never cover a disc larger than the
    workspace's beyond the raster's resolution."""
    for seed, study, result in optima:
        model = RingPairModel(study.effects)
        ws = sweep_workspace(result.design, np.deg2rad(10.0), model)
        ctl = steerable(ws, model, parameter_vector(result.design))
        assert ws.home.stable, f"seed {seed}"
        assert abs(ws.droop - result.metrics["droop"]) <= AGREE, f"seed {seed}"
        assert abs(ctl.disc_radius - result.metrics["disc_radius"]) <= AGREE, (
            f"seed {seed}: NLP {result.metrics['disc_radius'] * 1e3:.4f} mm, workspace "
            f"{ctl.disc_radius * 1e3:.4f} mm (loop {ws.disc_radius * 1e3:.4f} mm, covered "
            f"{ctl.covered_disc_radius * 1e3:.4f} mm, {100 * ctl.fraction:.0f} % steerable)"
        )
        assert ctl.disc_radius <= ws.disc_radius
        assert ctl.covered_disc_radius <= ws.disc_radius + ctl.resolution, f"seed {seed}"


STOPS = """
name = "stops"
effects = "torsion,printed_tip"
[free]
magnet_gap_mm = [0.0, 3.0]
stop_angle_deg = [1.0, 180.0]
external_distance_mm = [70.0, 200.0]
[materials]
catheter = ["pebax_7233"]
wire = ["niti"]
[constraints]
max_outer_diameter_mm = 10.0
twist_limit_deg = 30.0
neutral_tolerance_mm = 2.0
[solver]
starts = 1
"""


@pytest.mark.parametrize("pretwist", [False, True], ids=["stop_angle", "stop_angle+pretwist"])
def test_stops_free_in_the_nlp_with_torsion(pretwist):
    """The mounting pieces' stop angle, and with it the pre-twist, as free variables (the
    demonstrator, whose touching rings are multistable under torsion alone): the optimum
    is accepted (its loops driven without a snap, no multistable state) and forward
    simulation reproduces its metrics within 0.1 mm. With the pre-twist free, the optimiser
    used to leave it at zero, the rings touching their stop without pressing on it, a
    state that the loop check rightly rejected; the ``ring_stiffness`` rows now count the
    stop's hold (tests/optimize/sizing/test_ring_stiffness.py)."""
    text = STOPS.replace("[materials]", "pretwist_deg = [-30.0, 30.0]\n[materials]")
    study = loads_study(text if pretwist else STOPS)
    result = optimize_design(study)
    assert result.feasible, result.report()
    assert "stop_angle" in result.values
    assert ("pretwist" in result.values) == pretwist
    forward = evaluate_design(study, result.design, result.materials)
    assert forward.converged and forward.stable
    for name in LENGTHS:
        assert abs(result.metrics[name] - forward.metrics[name]) <= AGREE, name
