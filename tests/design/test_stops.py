"""Rotational stops and pre-twist (issue 16, item 3; design.stops) against closed forms.

The paper (Sayres & Pittiglio, Sec. III-A): the mounting pieces "impose relative rotational
limits on the magnets, allowing us to 'lock' the magnets in a high-potential-energy state
by twisting the tube/wire enough so that any torsional strain is compensated".

Closed forms, no external field: the transmissions are torsion springs of compliance
C_i = L / GJ_i in series, C = C_wire + C_catheter, and the rings couple with
T_1 = -T_2 = K12 sin(rho), rho = theta1 - theta2 (design.ring_coupling).

- Held at a stop (rho = 0 or S, where K12 sin(rho) = 0): both rings turn by the commanded
  relative angle's excess e = rho_c + p - rho_stop shared in proportion to the compliances,
  theta2 = c2 + e C_catheter / C, theta1 = theta2 + rho_stop; the stop carries -e / C.
- Within the stops, the pre-twist that holds rho: rho - rho_c - p = C K12 sin(rho), so
  p = rho - rho_c - C K12 sin(rho), and theta2 = c2 - C_catheter K12 sin(rho).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import RingPairModel
from design.registry import index
from design.ring_coupling import coupling_coefficient
from design.sections import tube_torsional_rigidity
from design.stops import STOP_STIFFNESS
from tests.support.setups import random_design

STOPS = frozenset({"torsion", "printed_tip"})
DEMO = default_design()


def _compliances(design) -> tuple[float, float]:
    """(C_wire, C_catheter) = L / GJ. [rad / (N m)]"""
    length = design.robot.free_length
    return (
        length / tube_torsional_rigidity(design.robot.wire),
        length / tube_torsional_rigidity(design.robot.catheter),
    )


def _k12(design) -> float:
    t = design.tip
    return float(
        coupling_coefficient(
            t.magnet_outer_diameter,
            t.magnet_inner_diameter,
            t.magnet_length,
            t.spacing,
            t.magnet_remanence,
        )
    )


def _field_free(model: RingPairModel, design, pretwist_deg: float) -> np.ndarray:
    p = model.parameters(design)
    p[index("external_remanence")] = 0.0
    p[index("pretwist")] = np.deg2rad(pretwist_deg)
    return p


@pytest.mark.parametrize("pretwist_deg", [-5.0, -40.0, -200.0])
def test_rings_held_at_the_lower_stop_share_the_excess_twist(pretwist_deg):
    # Parallel command with a negative pre-twist: the distal ring is pressed against the
    # stop at rho = 0 (the paper's "locked" parallel rings).
    model = RingPairModel(STOPS)
    params = _field_free(model, DEMO, pretwist_deg)
    c = np.deg2rad([0.0, 30.0, 150.0, 300.0])
    eq = solve_equilibria(model, params, c, c)
    assert eq.converged.all() and eq.stable.all()
    c_wire, c_cath = _compliances(DEMO)
    excess = np.deg2rad(pretwist_deg)  # rho_c + p - 0
    theta2 = c + excess * c_cath / (c_wire + c_cath)
    penetration = abs(excess) / STOP_STIFFNESS  # the penalty's give
    np.testing.assert_allclose(eq.tip_angles[:, 1], theta2, atol=2 * penetration + 1e-6)
    rho = eq.tip_angles[:, 0] - eq.tip_angles[:, 1]
    np.testing.assert_allclose(rho, 0.0, atol=2 * penetration + 1e-6)


@pytest.mark.parametrize("stop_deg", [180.0, 120.0])
def test_rings_held_at_the_upper_stop(stop_deg):
    # Command beyond the upper stop S (with a positive pre-twist): rho = S. With S = 180
    # deg the coupling vanishes there; at 120 deg it adds K12 sin(S) to the stop's load,
    # which the rings' angles do not see while they are held.
    mounting = dataclasses.replace(DEMO.tip.mounting, stop_angle=np.deg2rad(stop_deg))
    design = dataclasses.replace(DEMO, tip=dataclasses.replace(DEMO.tip, mounting=mounting))
    model = RingPairModel(STOPS)
    params = _field_free(model, design, 25.0)
    c2 = np.deg2rad([0.0, 90.0, 200.0])
    c1 = c2 + np.deg2rad(stop_deg)
    eq = solve_equilibria(model, params, c1, c2)
    assert eq.converged.all() and eq.stable.all()
    c_wire, c_cath = _compliances(design)
    stop = np.deg2rad(stop_deg)
    coupling = _k12(design) * np.sin(stop)  # on ring 1, carried by the stop too
    excess = np.deg2rad(25.0) + c_wire * coupling + (-c_cath) * (-coupling)
    theta2 = c2 + excess * c_cath / (c_wire + c_cath) - c_cath * coupling
    tol = 2 * abs(excess) / STOP_STIFFNESS + 1e-6
    np.testing.assert_allclose(eq.tip_angles[:, 1], theta2, atol=tol)
    np.testing.assert_allclose(eq.tip_angles[:, 0] - eq.tip_angles[:, 1], stop, atol=tol)


@pytest.mark.parametrize("rho_deg", [60.0, 100.0, 150.0])
def test_pretwist_needed_to_hold_a_relative_angle(rho_deg):
    # Rings 1 mm apart (K12 C < 1: one state per command), parallel command: the pre-twist
    # p = rho - C K12 sin(rho) holds them at rho, inside the stops.
    design = dataclasses.replace(DEMO, tip=dataclasses.replace(DEMO.tip, magnet_gap=1e-3))
    c_wire, c_cath = _compliances(design)
    k12 = _k12(design)
    assert (c_wire + c_cath) * k12 < 1
    rho = np.deg2rad(rho_deg)
    pretwist = rho - (c_wire + c_cath) * k12 * np.sin(rho)
    model = RingPairModel(STOPS)
    params = _field_free(model, design, np.rad2deg(pretwist))
    c = np.deg2rad([0.0, 45.0, 250.0])
    eq = solve_equilibria(model, params, c, c)
    assert eq.converged.all() and eq.stable.all()
    np.testing.assert_allclose(eq.tip_angles[:, 0] - eq.tip_angles[:, 1], rho, atol=1e-9)
    np.testing.assert_allclose(eq.tip_angles[:, 1], c - c_cath * k12 * np.sin(rho), atol=1e-9)


def test_demonstrator_rings_held_parallel_as_in_the_paper():
    # The demonstrator's touching rings (K12 L (1/GJ_wire + 1/GJ_catheter) = 1.9) part to
    # about 96 deg when driven parallel on torsion alone; the stop at 0 with a pre-twist of
    # -40 deg holds them parallel all round the loop, in the external field.
    theta = np.deg2rad(np.arange(0.0, 360.0, 30.0))
    free = RingPairModel(frozenset({"torsion"}))
    parted = solve_equilibria(free, free.parameters(DEMO), theta, theta)
    rho_free = parted.tip_angles[:, 0] - parted.tip_angles[:, 1]
    assert (np.abs(rho_free) > np.deg2rad(45.0)).all()
    model = RingPairModel(STOPS)
    params = model.parameters(DEMO)
    params[index("pretwist")] = np.deg2rad(-40.0)
    held = solve_equilibria(model, params, theta, theta)
    assert held.converged.all() and held.stable.all()
    rho = held.tip_angles[:, 0] - held.tip_angles[:, 1]
    assert np.abs(rho).max() < np.deg2rad(0.1)


def test_relative_command_is_taken_within_a_turn_about_the_stops():
    # 350 deg against 0 deg is -10 deg of relative command, not 350.
    model = RingPairModel(STOPS)
    params = _field_free(model, DEMO, 0.0)
    a = solve_equilibria(model, params, np.deg2rad([350.0]), 0.0)
    b = solve_equilibria(model, params, np.deg2rad([-10.0]), 0.0)
    np.testing.assert_allclose(a.tip_angles, b.tip_angles, atol=1e-12)


@pytest.mark.parametrize("seed", range(1700, 1712))
def test_stops_hold_the_relative_angle_on_random_setups(seed):
    # Property: random designs (tests/support/setups.py), stop angles, pre-twists and
    # commands, in the field: every state found keeps rho within [0, S] up to the
    # penalty's give, the contact torque over k = STOP_STIFFNESS / C: 2e-3 rad allows
    # contact torques up to 20 times the loop's torque at one radian of twist.
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    stop = np.deg2rad(rng.uniform(30.0, 270.0))
    pretwist = np.deg2rad(rng.uniform(-90.0, 90.0))
    mounting = dataclasses.replace(design.tip.mounting, stop_angle=stop, pretwist=pretwist)
    design = dataclasses.replace(design, tip=dataclasses.replace(design.tip, mounting=mounting))
    model = RingPairModel(STOPS | {"large_deflection"} if rng.random() < 0.5 else STOPS)
    theta1, theta2 = rng.uniform(0.0, 2 * np.pi, (2, 16))
    eq = solve_equilibria(model, model.parameters(design), theta1, theta2)
    ok = eq.converged  # (near a strong magnet some set-ups have no state at all)
    rho = eq.tip_angles[ok, 0] - eq.tip_angles[ok, 1]
    give = 20.0 / STOP_STIFFNESS
    assert (rho >= -give).all() and (rho <= stop + give).all(), f"seed {seed}: {rho}"


def test_rings_held_from_rest_are_not_snapped():
    # Held at the stop from the unloaded robot on: no branch ends on the way (no snap).
    model = RingPairModel(STOPS)
    params = _field_free(model, DEMO, -40.0)
    eq = solve_equilibria(model, params, np.zeros(2), np.zeros(2))
    assert eq.stable.all()
    assert not eq.snapped.any()
