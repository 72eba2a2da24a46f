"""Batch equilibrium: closed-form equilibria and stability limits, flags, batching."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import design.equilibrium as equilibrium
from design.constants import MU0
from design.designfile import default_design
from design.dipole import K_DIPOLE
from design.equilibrium import solve_design, solve_equilibria, stable_states
from design.magnets import ring_moment
from design.model import RingPairModel
from design.registry import index
from design.sections import bending_rigidity

MODEL = RingPairModel()
DEMO = default_design()
L = DEMO.robot.free_length
EI = bending_rigidity(DEMO.robot)
M_RING = ring_moment(
    DEMO.tip.magnet_outer_diameter,
    DEMO.tip.magnet_inner_diameter,
    DEMO.tip.magnet_length,
    DEMO.tip.magnet_remanence,
)
FAR = 1e5  # [m]: a dipole this far away makes a uniform field (gradient 3 B / FAR)


def uniform_field_params(b: float, direction: str) -> np.ndarray:
    """Demonstrator parameters with the rings at zero spacing and an external dipole so far
    away that its field at the tip is uniform, B = b along +x or along -y."""
    params = MODEL.parameters(DEMO)
    moment = b * FAR**3 / (2 * K_DIPOLE)  # on a dipole's axis B = 2 k m / r^3
    # A cylinder with D = length = FAR / 10 (far clear of the robot) has this moment at
    # remanence B_r = moment mu0 / volume.
    size = FAR / 10
    values = {
        "magnet_gap": -DEMO.tip.magnet_length,  # centre spacing 0
        "external_remanence": moment * MU0 / (np.pi / 4 * size**3),
        "external_diameter": size,
        "external_length": size,
    }
    if direction == "+x":  # on the x axis beyond the tip, magnetised along +x
        values |= {
            "external_center_x": L + FAR,
            "external_center_y": 0.0,
            "external_magnetization_x": 1.0,
            "external_magnetization_y": 0.0,
        }
    else:  # on the y axis at +FAR, magnetised along -y: B along -y at the tip
        values |= {
            "external_center_x": L,
            "external_center_y": FAR,
            "external_magnetization_x": 0.0,
            "external_magnetization_y": -1.0,
        }
    for name, value in values.items():
        params[index(name)] = value
    return params


def test_tip_moment_in_uniform_field_matches_closed_form():
    # Rings along y_tip in a uniform field b x: the tip turns by psi with
    # EI psi / L = 2 m b cos(psi) (linear cantilever under a rotating tip moment), and
    # deflects by L^2 / (2 EI) * 2 m b cos(psi) (Gere & Goodno, App. G case 6).
    for lam in (0.2, 1.0, 2.5):
        b = lam * EI / (2 * M_RING * L)
        eq = solve_equilibria(MODEL, uniform_field_params(b, "+x"), 0.0, 0.0)
        psi = brentq(lambda x, lam=lam: x - lam * np.cos(x), 0, np.pi / 2)
        assert eq.converged[0] and eq.stable[0]
        assert -eq.unknowns[0, 3] == pytest.approx(psi, rel=1e-5)
        moment = 2 * M_RING * b * np.cos(psi)
        assert -eq.position[0, 1] == pytest.approx(L**2 / (2 * EI) * moment, rel=1e-5)
        tangent = eq.tangent[0]
        assert np.arctan2(-tangent[1], tangent[0]) == pytest.approx(psi, rel=1e-5)


@pytest.mark.parametrize("lam", [0.2, 2.5, 10.0])
def test_large_deflection_tip_moment_in_uniform_field_is_the_circular_arc(lam):
    # A pure tip moment bends the Kirchhoff rod into a circular arc with tip angle
    # psi = M L / EI (Euler's elastica; Timoshenko & Gere, Theory of Elastic Stability, 1.11)
    # so EI psi / L = 2 m b cos(psi) holds exactly, and the tip sits at
    # x = L sin(psi) / psi, y = -L (1 - cos(psi)) / psi. lam = 10: deflection 0.61 L.
    model = RingPairModel(frozenset({"large_deflection"}))
    b = lam * EI / (2 * M_RING * L)
    eq = solve_equilibria(model, uniform_field_params(b, "+x"), 0.0, 0.0)
    psi = brentq(lambda x: x - lam * np.cos(x), 0, np.pi / 2)
    assert eq.converged[0] and eq.stable[0]
    tangent = eq.tangent[0]
    # The far dipole is uniform to ~1e-6 over the robot (gradient 3 B / FAR).
    assert np.arctan2(-tangent[1], tangent[0]) == pytest.approx(psi, rel=1e-5)
    arc = np.array([np.sin(psi), -(1 - np.cos(psi)), 0.0]) * L / psi
    np.testing.assert_allclose(eq.position[0], arc, atol=1e-5 * L)
    if lam == 10.0:
        assert -eq.position[0, 1] > 0.6 * L


@pytest.mark.parametrize("effects", [(), ("large_deflection",)])
def test_antialigned_rings_lose_stability_at_2mB_equal_EI_over_L(effects):
    # Straight robot, both rings antiparallel to a uniform field: the tangent stiffness of
    # the (dy, phi_z) plane, [[12EI/L^3, -6EI/L^2], [-6EI/L^2, 4EI/L - 2mB]], loses
    # definiteness at 2 m B = EI / L (derived in design/cantilever.py's stiffness). The
    # straight state is the same for the Kirchhoff rod, whose linearisation there is the
    # linear cantilever, so its check must switch at the same load.
    model = RingPairModel(frozenset(effects))
    critical = EI / (2 * M_RING * L)
    along_plus_y = np.zeros(2)  # rings along +y, field along -y
    below = uniform_field_params(0.95 * critical, "-y")
    above = uniform_field_params(1.05 * critical, "-y")
    for params, stable in ((below, True), (above, False)):
        # The equilibrium next to the straight state (the far dipole's tiny gradient moves
        # it by some um near the critical field), found by plain Newton from the straight
        # robot.
        x = np.zeros(model.n_unknowns)
        for _ in range(8):
            r, jac = model.residual(x, along_plus_y, params)
            x = x - np.linalg.solve(np.asarray(jac), np.asarray(r).ravel())
        assert np.abs(x[:2]).max() < 1e-4 * L
        assert stable_states(model, params, x[:, None], along_plus_y[:, None])[0] == stable
    # Solved on its own, the robot above the critical field buckles on the load ramp: it
    # falls off the straight state (a symmetric bifurcation) into a bent stable one.
    eq = solve_equilibria(model, above, 0.0, 0.0)
    assert eq.stable[0] and eq.snapped[0]
    assert np.abs(eq.position[0, 1:]).max() > 1e-2 * L
    held = solve_equilibria(model, below, 0.0, 0.0)
    assert held.stable[0] and not held.snapped[0]
    assert np.abs(held.position[0, 1:]).max() < 1e-3 * L  # (the far dipole's tiny gradient)
    aligned = solve_equilibria(model, above, np.pi, np.pi)
    assert aligned.stable[0] and not aligned.snapped[0]


def test_unconverged_configurations_are_flagged_and_never_numbers(demonstrator, monkeypatch):
    # An unattainable tolerance: nothing may be reported as converged, every pose is NaN.
    monkeypatch.setattr(equilibrium.settings, "TOLERANCE", 0.0)
    eq = solve_design(demonstrator, np.linspace(0, 3, 5), 0.0)
    assert not eq.converged.any() and not eq.stable.any()
    assert np.isnan(eq.position).all() and np.isnan(eq.frame).all()


def test_batch_equals_one_by_one_across_chunks(demonstrator, monkeypatch):
    monkeypatch.setattr(equilibrium.settings, "CHUNK", 7)  # several chunks and a padded last one
    rng = np.random.default_rng(3)
    t1, t2 = rng.uniform(0, 2 * np.pi, (2, 23))
    batch = solve_design(demonstrator, t1, t2)
    for k in (0, 6, 7, 22):
        one = solve_design(demonstrator, t1[k], t2[k])
        np.testing.assert_allclose(one.position[0], batch.position[k], atol=1e-15)
        np.testing.assert_allclose(one.frame[0], batch.frame[k], atol=1e-15)
    assert batch.converged.all() and batch.stable.all()


@pytest.mark.parametrize("effects", [(), ("torsion",), ("large_deflection", "near_field")])
def test_states_on_threaded_maps_equal_serial_ones(effects, monkeypatch):
    """Workers run their maps on one thread (design.compiled.use_threads), the parent on
    two: on set-ups drawn from the whole design space, 40-200 configurations (maps of 32
    columns and more, which are threaded), the states must be the same to the last bit."""
    import design.compiled as compiled
    from design.model import model_for
    from optimize.fitting.setups import random_design

    seed = int(np.random.SeedSequence().entropy % 2**32)
    rng = np.random.default_rng(seed)
    model = model_for(frozenset(effects))
    monkeypatch.setattr(compiled, "_threads", compiled.THREADS)
    for _ in range(10):  # a set-up where most configurations have a state
        params = model.parameters(random_design(rng))
        t1, t2 = rng.uniform(-np.pi, np.pi, (2, int(rng.integers(40, 201))))
        threaded = solve_equilibria(model, params, t1, t2)
        if threaded.converged.mean() >= 0.5:
            break
    monkeypatch.setattr(compiled, "_threads", 1)
    runs = [threaded, solve_equilibria(model, params, t1, t2)]
    assert compiled.map_threads(64) == 1 and compiled.THREADS > 1
    assert threaded.converged.mean() >= 0.5, f"seed {seed}: no set-up with states drawn"
    for name in ("unknowns", "position", "converged", "stable", "snapped"):
        np.testing.assert_array_equal(
            getattr(runs[0], name), getattr(runs[1], name), err_msg=f"seed {seed}: {name}"
        )


def test_tip_frame_is_orthonormal_and_right_handed(demonstrator):
    eq = solve_design(demonstrator, np.linspace(0, 6, 11), np.linspace(1, 2, 11))
    for frame in eq.frame:
        np.testing.assert_allclose(frame.T @ frame, np.eye(3), atol=1e-14)
        assert np.linalg.det(frame) == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(eq.tangent, eq.frame[:, :, 0])


def test_demonstrator_parallel_rings_deflect_towards_plus_y(demonstrator):
    # Both rings along +y: the field of the -x magnetised cylinder (B along -x at the tip)
    # turns them towards +y... and its gradient pulls them the same way (dBy/dy > 0).
    eq = solve_design(demonstrator, 0.0, 0.0)
    assert eq.position[0, 1] > 0.015
    assert abs(eq.position[0, 2]) < 1e-12
