"""Branch diagrams: the state along the load ramp and the other branches of equilibria."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from design.branches import branches, load_path, scaled_loads
from design.designfile import default_design
from design.equilibrium import solve_equilibria, stable_states
from design.model import model_for
from design.registry import index
from design.ring_coupling import coupling_coefficient
from design.sections import tube_torsional_rigidity

TORSION = frozenset({"torsion"})


def field_off(params: np.ndarray) -> np.ndarray:
    """Parameters with the external magnet's remanence 1e9 times smaller: the rings' mutual
    torque is the only load that matters."""
    params = params.copy()
    params[index("external_remanence")] *= 1e-9
    return params


def test_touching_rings_snap_apart_at_one_over_sqrt_kappa():
    # Rings held parallel by their transmissions, coupled by U = K12 cos(theta1 - theta2)
    # (design/ring_coupling.py) scaled by lambda^2 on the load ramp: the relative angle phi
    # sees the transmissions in series, k = 1 / (L / GJ_wire + L / GJ_catheter), so the
    # energy k phi^2 / 2 + lambda^2 K12 cos(phi) is stable at phi = 0 until
    # lambda^2 K12 = k, i.e. lambda = 1 / sqrt(kappa), kappa = K12 L (1/GJ_w + 1/GJ_c); then
    # the rings fall apart to phi = kappa lambda^2 sin(phi). The demonstrator's touching
    # rings have kappa = 1.9 (README).
    design = default_design()
    model = model_for(TORSION)
    params = field_off(model.parameters(design))
    t, r = design.tip, design.robot
    k12 = coupling_coefficient(
        t.magnet_outer_diameter,
        t.magnet_inner_diameter,
        t.magnet_length,
        t.spacing,
        t.magnet_remanence,
    )
    kappa = (
        k12
        * r.free_length
        * (1 / tube_torsional_rigidity(r.wire) + 1 / tube_torsional_rigidity(r.catheter))
    )
    assert kappa == pytest.approx(1.9, abs=0.05)
    critical = 1 / np.sqrt(kappa)
    lam = np.linspace(0.0, 1.0, 401)
    path = load_path(model, params, np.deg2rad([40.0, 40.0]), lam)
    assert path.stable.all()
    phi = path.tip_angles[:, 0] - path.tip_angles[:, 1]
    before, after = lam < critical - 0.003, lam > critical + 0.003
    assert np.abs(phi[before]).max() < 1e-6
    assert not path.snapped[before].any() and path.snapped[after].all()
    expected = [
        brentq(lambda x, s=s: x - kappa * s**2 * np.sin(x), 1e-9, np.pi) for s in lam[after]
    ]
    np.testing.assert_allclose(np.abs(phi[after]), expected, atol=1e-6)
    # One side, the same at every load factor (a symmetric bifurcation: either side is a
    # state; the choice must not depend on rounding).
    assert np.all(np.sign(phi[after]) == np.sign(phi[after][0]))


def test_the_load_path_ends_in_the_state_and_branches_are_equilibria():
    design = default_design()
    model = model_for(frozenset({"near_field", "torsion", "large_deflection", "gravity"}))
    params = model.parameters(design)
    command = np.deg2rad([30.0, 30.0])
    lam = np.linspace(0.0, 1.0, 41)
    path, others = branches(model, params, command, lam)
    state = solve_equilibria(model, params, command[0], command[1])
    np.testing.assert_allclose(path.position[-1], state.position[0], atol=1e-12)
    # With gravity the rings' pitchfork is imperfect: the state turns smoothly, another
    # stable branch and an unstable one appear together at a fold (multistable).
    assert not path.snapped.any()
    assert len(others) == 2 and sorted(b.stable[-1] for b in others) == [False, True]
    for branch in others:
        exists = np.isfinite(branch.unknowns).all(axis=1)
        assert exists[-1] and not exists[0]  # born at a fold, not connected to rest
        columns = scaled_loads(model, params, lam)
        for k in np.flatnonzero(exists):
            r, _ = model.residual(branch.unknowns[k], command, columns[:, k])
            assert np.abs(np.asarray(r)).max() < 1e-8
        c = np.repeat(command[:, None], exists.sum(), axis=1)
        verdict = stable_states(model, columns[:, exists], branch.unknowns[exists].T, c)
        np.testing.assert_array_equal(verdict, branch.stable[exists])
