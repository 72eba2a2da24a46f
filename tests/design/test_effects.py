"""Model effects: closed-form checks and limits that reduce each effect to the baseline."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from design.designfile import default_design
from design.equilibrium import solve_design, solve_equilibria, solve_sequence
from design.model import (
    DEFAULT_EFFECTS,
    EFFECTS,
    SWITCHES,
    RingPairModel,
    available_effects,
    parse_effects,
)
from design.records import Environment
from design.registry import index
from design.sections import bending_rigidity, tube_torsional_rigidity

DEMO = default_design()
L = DEMO.robot.free_length
EI = bending_rigidity(DEMO.robot)
THETA = np.deg2rad(np.arange(0.0, 181.0, 12.0))


def with_gravity(design, g=(0.0, 0.0, -9.81)):
    return dataclasses.replace(design, environment=Environment(gravity=g))


def set_params(params: np.ndarray, **values: float) -> np.ndarray:
    params = params.copy()
    for name, value in values.items():
        params[index(name)] = value
    return params


def test_parse_effects():
    assert parse_effects("none") == frozenset()
    assert parse_effects("all") == frozenset(available_effects()) | {"printed_tip"}
    assert frozenset(available_effects()) == frozenset(EFFECTS)  # printed_tip: a switch
    assert parse_effects("printed_tip,torsion") == {"printed_tip", "torsion"}
    assert parse_effects("default") == DEFAULT_EFFECTS < frozenset(SWITCHES)
    assert "printed_tip" in DEFAULT_EFFECTS  # the model for design work: the tip as built
    assert parse_effects("torsion, gravity") == {"torsion", "gravity"}
    assert parse_effects("default,torsion") == DEFAULT_EFFECTS | {"torsion"}
    with pytest.raises(ValueError, match="unknown model effect 'twist'"):
        parse_effects("torsion,twist")


def test_self_weight_deflection_is_w_L4_over_8EI():
    # Gere & Goodno, App. G case 1: uniform load w on a cantilever, tip deflection
    # w L^4 / (8 EI), tip slope w L^3 / (6 EI). Magnets and tip mass weightless and unmagnetised.
    model = RingPairModel(frozenset({"gravity"}))
    params = set_params(
        model.parameters(with_gravity(DEMO)), magnet_remanence=0.0, magnet_density=0.0
    )
    eq = solve_equilibria(model, params, 0.0, 0.0)
    c, w = DEMO.robot.catheter, DEMO.robot.wire
    weight = 9.81 * (
        c.density * np.pi / 4 * (c.outer_diameter**2 - c.inner_diameter**2)
        + w.density * np.pi / 4 * w.outer_diameter**2
    )
    assert -eq.position[0, 2] == pytest.approx(weight * L**4 / (8 * EI), rel=1e-12)
    slope = -eq.tangent[0, 2] / eq.tangent[0, 0]
    assert np.arctan(slope) == pytest.approx(weight * L**3 / (6 * EI), rel=1e-12)


def test_tip_mass_adds_F_L3_over_3EI():
    # Gere & Goodno, App. G case 4: tip force P deflects by P L^3 / (3 EI).
    model = RingPairModel(frozenset({"gravity"}))
    base = set_params(
        model.parameters(with_gravity(DEMO)), magnet_remanence=0.0, magnet_density=0.0
    )
    heavy = set_params(base, tip_mass=2e-3)
    z0 = solve_equilibria(model, base, 0.0, 0.0).position[0, 2]
    z1 = solve_equilibria(model, heavy, 0.0, 0.0).position[0, 2]
    assert z0 - z1 == pytest.approx(2e-3 * 9.81 * L**3 / (3 * EI), rel=1e-12)


def test_gravity_free_environment_is_the_baseline():
    weightless = dataclasses.replace(DEMO, environment=Environment())
    a = solve_design(weightless, THETA, 0.0)
    b = solve_design(weightless, THETA, 0.0, RingPairModel(frozenset({"gravity"})))
    np.testing.assert_array_equal(a.position, b.position)


def test_demonstrator_sags_under_its_own_weight():
    eq = solve_design(with_gravity(DEMO), THETA, 0.0, RingPairModel(frozenset({"gravity"})))
    weightless = solve_design(DEMO, THETA, 0.0)  # the baseline ignores gravity
    assert eq.converged.all() and eq.stable.all()
    sag = weightless.position[:, 2] - eq.position[:, 2]
    assert (sag > 5e-3).all()  # millimetres: a horizontal 150 mm PTFE catheter droops


def test_hysteresis_trails_the_command_by_the_friction_angle():
    # Play operator: driven forwards the ring trails by w, driven back it trails the
    # other way, so the same command gives two poses (Krasnosel'skii & Pokrovskii).
    w = np.deg2rad(6.0)
    wire = dataclasses.replace(DEMO.robot.wire, friction_angle=w)
    design = dataclasses.replace(DEMO, robot=dataclasses.replace(DEMO.robot, wire=wire))
    model = RingPairModel(frozenset({"hysteresis"}))
    path = np.deg2rad(np.r_[np.arange(0, 181, 12), np.arange(168, -1, -12)])
    eq = solve_design(design, path, 0.0, model, ordered=True)
    assert eq.converged.all()
    forward, backward = slice(1, 16), slice(16, 31)
    np.testing.assert_allclose(eq.tip_angles[forward, 0], path[forward] - w, atol=1e-12)
    np.testing.assert_allclose(eq.tip_angles[backward, 0], path[backward] + w, atol=1e-12)
    np.testing.assert_array_equal(eq.tip_angles[:, 1], 0.0)
    going = eq.position[1:15]
    coming = eq.position[29:15:-1]  # same commands on the way back
    assert np.abs(going - coming).max() > 1e-3


def test_frictionless_path_is_the_baseline():
    model = RingPairModel(frozenset({"hysteresis"}))
    a = solve_design(DEMO, THETA, 0.0)
    b = solve_design(DEMO, THETA, 0.0, model, ordered=True)
    np.testing.assert_allclose(b.position, a.position, atol=1e-13)
    assert not b.snapped.any()


def test_twist_of_each_transmission_in_a_uniform_transverse_field():
    # A ring commanded to theta_c in a uniform field B along +y (theta = 0, across the
    # straight robot) feels the axial torque -m B sin(theta) and its transmission twists
    # until theta - theta_c = -L m B sin(theta) / GJ (twist = torque L / GJ). The rings are
    # put 1 m apart so that their mutual coupling is negligible (~1e-12 of the field's).
    far = 1e5
    b = 0.05
    model = RingPairModel(frozenset({"torsion"}))
    from design.constants import MU0
    from design.dipole import K_DIPOLE

    moment = b * far**3 / (2 * K_DIPOLE)
    size = (moment * MU0 * 4 / np.pi) ** (1 / 3)
    params = set_params(
        model.parameters(DEMO),
        magnet_gap=1.0,
        external_remanence=1.0,
        external_diameter=size,
        external_length=size,
        external_center_x=L,
        external_center_y=-far,
        external_magnetization_x=0.0,
        external_magnetization_y=1.0,
    )
    from design.magnets import ring_moment

    m = ring_moment(
        DEMO.tip.magnet_outer_diameter,
        DEMO.tip.magnet_inner_diameter,
        DEMO.tip.magnet_length,
        DEMO.tip.magnet_remanence,
    )
    command = np.deg2rad(30.0)
    eq = solve_equilibria(model, params, command, command)
    assert eq.converged[0] and eq.stable[0]
    for i, tube in enumerate((DEMO.robot.wire, DEMO.robot.catheter)):
        gj = tube_torsional_rigidity(tube)
        expected = brentq(lambda t, gj=gj: t - command + L * m * b * np.sin(t) / gj, 0.0, command)
        assert expected < command - 0.05  # a real lag, several degrees
        assert eq.tip_angles[0, i] == pytest.approx(expected, rel=1e-6)


def test_torsionally_rigid_transmissions_are_the_baseline():
    model = RingPairModel(frozenset({"torsion"}))
    stiff = set_params(
        model.parameters(DEMO), wire_poisson_ratio=-1 + 1e-12, catheter_poisson_ratio=-1 + 1e-12
    )
    a = solve_design(DEMO, THETA, 0.0)
    b = solve_equilibria(model, stiff, THETA, 0.0)
    np.testing.assert_allclose(b.position, a.position, atol=1e-9)
    np.testing.assert_allclose(b.tip_angles, a.command, atol=1e-9)


@pytest.mark.parametrize("others", [(), ("gravity",), ("torsion", "near_field", "gravity")])
def test_small_loads_on_the_kirchhoff_rod_match_the_linear_model(others):
    # The linear cantilever is the Kirchhoff rod's linearisation (design/cantilever.py), so
    # with every load scaled down 1000x (deflections of ~20 um) the two models agree to
    # ~1e-3 relative: the first neglected term is quadratic in the load.
    linear = RingPairModel(frozenset(others))
    rod = RingPairModel(frozenset({"large_deflection", *others}))
    params = set_params(linear.parameters(with_gravity(DEMO)), load_scale=1e-3)
    a = solve_equilibria(linear, params, THETA, 0.0)
    b = solve_equilibria(rod, params, THETA, 0.0)
    assert a.converged.all() and b.converged.all()
    deflection = a.position - [L, 0.0, 0.0]
    error = np.linalg.norm(b.position - a.position, axis=1)
    assert error.max() < 1e-3 * np.linalg.norm(deflection, axis=1).max()
    np.testing.assert_allclose(b.tip_angles, a.tip_angles, atol=1e-6)


def test_large_deflection_moves_the_demonstrators_tip_towards_the_base():
    # An inextensible rod shortens along x as it bends (the linear one keeps x = L); at the
    # demonstrator's largest deflection (y ~ 0.14 L) the elastica's axial shortening is
    # about (2/3) (y/L)^2 L ~ 1-2 mm, and farther from the magnet the pull is weaker.
    a = solve_design(DEMO, 0.0, 0.0)
    b = solve_design(DEMO, 0.0, 0.0, RingPairModel(frozenset({"large_deflection"})))
    assert 0.5e-3 < L - b.position[0, 0] < 3e-3
    assert 0 < b.position[0, 1] < a.position[0, 1]


@pytest.mark.parametrize("rod", [(), ("large_deflection",)])
def test_snap_through_of_coupled_rings_at_the_closed_form_fold(rod):
    # Without an external field only the rings' coupling U = K12 cos(d) acts (d = tip angle
    # difference). The two transmissions twist in opposite directions, so
    # d = d_c + kappa sin d with kappa = K12 L (1/GJ_wire + 1/GJ_catheter). For kappa > 1 the
    # branch d > 0 ends at the fold cos d_f = 1/kappa, d_c,f = d_f - kappa sin d_f < 0: driving
    # d_c downwards the rings snap there, and on the way back at -d_c,f (hysteresis).
    from design.ring_coupling import coupling_coefficient

    t = DEMO.tip
    k12 = coupling_coefficient(
        t.magnet_outer_diameter,
        t.magnet_inner_diameter,
        t.magnet_length,
        t.spacing,
        t.magnet_remanence,
    )
    kappa = (
        k12
        * L
        * (
            1 / tube_torsional_rigidity(DEMO.robot.wire)
            + 1 / tube_torsional_rigidity(DEMO.robot.catheter)
        )
    )
    assert kappa > 1  # the demonstrator's rings cannot be held parallel (kappa ~ 1.9)
    d_f = np.arccos(1 / kappa)
    fold = d_f - kappa * np.sin(d_f)
    model = RingPairModel(frozenset({"torsion", *rod}))
    params = set_params(model.parameters(DEMO), external_remanence=0.0)
    down = np.deg2rad(np.arange(60.0, -60.5, -1.0))
    path = np.r_[down, down[::-1][1:]]
    eq = solve_sequence(model, params, path, 0.0)
    assert eq.converged.all() and eq.stable.all()
    snaps = np.rad2deg(path[eq.snapped])
    assert len(snaps) == 2
    assert snaps[0] == pytest.approx(np.rad2deg(fold), abs=1.0)  # going down
    assert snaps[1] == pytest.approx(-np.rad2deg(fold), abs=1.0)  # coming back
    d = eq.tip_angles[:, 0] - eq.tip_angles[:, 1]
    assert np.abs(d).min() > d_f - 0.02  # the rings never pass through parallel
    np.testing.assert_allclose(d - path, kappa * np.sin(d), atol=1e-9)


def test_strides_on_smooth_stretches_give_the_states_of_single_sub_steps(monkeypatch):
    """solve_sequence strides over plainly smooth stretches of the path; where the lags
    change faster it goes back to 1-degree sub-steps. On the bench path of a soft rod with
    twisting transmissions (which snaps), the states and the snaps are those of 1-degree
    steps all the way."""
    import design.equilibrium.settings as equilibrium_settings
    from optimize.fitting.synth import default_commands

    model = RingPairModel(frozenset({"torsion", "large_deflection"}))
    params = set_params(model.parameters(DEMO), bending_rigidity_scale=0.3)
    cmd = default_commands(60)
    strided = solve_sequence(model, params, cmd[:, 0], cmd[:, 1])
    monkeypatch.setattr(equilibrium_settings, "MAX_STRIDE", 1)
    single = solve_sequence(model, params, cmd[:, 0], cmd[:, 1])
    assert single.snapped.any() and single.stable.all()
    np.testing.assert_array_equal(strided.snapped, single.snapped)
    np.testing.assert_allclose(strided.position, single.position, rtol=0, atol=1e-12)
