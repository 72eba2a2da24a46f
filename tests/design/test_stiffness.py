"""Tip stiffness (design.stiffness): beam theory's closed forms with the field off, and the
implicit-function compliance against finite differences of the solved state under a small
force applied at the tracked point, over random set-ups from the whole design space."""

from __future__ import annotations

import numpy as np
import pytest
from setups import random_design

from design.equilibrium import solve_equilibria
from design.model import PRINTED_TIP, model_for
from design.mounting import design_tip_geometry
from design.registry import index
from design.stiffness import tip_stiffness

FORCE = index("applied_force_x")


def _tube_ei(tube) -> float:
    """E pi (D^4 - d^4) / 64 of one tube (Gere & Timoshenko, *Mechanics of Materials*,
    the hollow circle's second moment of area). [N m^2]"""
    return tube.youngs_modulus * np.pi * (tube.outer_diameter**4 - tube.inner_diameter**4) / 64


def _field_off(params: np.ndarray) -> np.ndarray:
    p = params.copy()
    p[index("external_remanence")] = 0.0
    return p


@pytest.mark.parametrize("printed", [False, True])
def test_field_free_cantilever_stiffness_is_beam_theory(printed):
    """With the field off the robot is a cantilever; a lateral force F at the tracked
    point, a rigid segment a beyond the flexible length l, deflects it by
    F (l^3 / 3 + a l^2 + a^2 l) / EI (tip force and the moment F a on the flexible part,
    plus the segment's rotation; a = 0: F L^3 / (3 EI)). The inextensible rod is rigid
    along its axis."""
    rng = np.random.default_rng(51)
    design = random_design(rng)
    effects = frozenset({PRINTED_TIP}) if printed else frozenset()
    model = model_for(effects)
    params = _field_off(model.parameters(design))
    eq = solve_equilibria(model, params, [0.3, 2.0], [1.1, 4.0])
    st = tip_stiffness(model, params, eq)
    ei = _tube_ei(design.robot.catheter) + _tube_ei(design.robot.wire)
    length = design.robot.free_length
    a = design_tip_geometry(design).rigid_offset if printed else 0.0
    flexible = length - a
    expected = ei / (flexible**3 / 3 + a * flexible**2 + a**2 * flexible)
    np.testing.assert_allclose(st.stiffness[:, :2], expected, rtol=1e-9)
    assert (st.rigid == 1).all() and np.isinf(st.stiffness[:, 2]).all()
    np.testing.assert_allclose(np.abs(st.directions[:, 0, 2]), 1.0, atol=1e-12)  # the axis


@pytest.mark.parametrize(
    "seed, effects",
    [
        (5100, ()),
        (5101, ("near_field", "torsion")),
        (5102, ("gravity", PRINTED_TIP)),
        (5103, ("large_deflection", "near_field")),
    ],
)
def test_compliance_is_the_finite_difference_of_the_state_under_a_tip_force(seed, effects):
    """C = dP/dF from the implicit function theorem (magnetic stiffness included) against
    central differences of the solved state (the load ramp with a force +-h applied at the
    tracked point), every column, in the field of a random set-up."""
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    model = model_for(frozenset(effects))
    params = model.parameters(design)
    command = rng.uniform(0, 2 * np.pi, 2)
    eq = solve_equilibria(model, params, command[0], command[1])
    if not eq.stable[0]:
        pytest.skip(f"seed {seed}: no stable state drawn")
    st = tip_stiffness(model, params, eq)
    c = st.compliance[0]
    h = 1e-4 / np.abs(c).max()  # a 0.1 mm push at most
    pushed = np.tile(params[:, None], (1, 6))
    for i in range(3):
        pushed[FORCE + i, 2 * i] += h
        pushed[FORCE + i, 2 * i + 1] -= h
    moved = solve_equilibria(model, pushed, np.full(6, command[0]), np.full(6, command[1]))
    assert moved.stable.all(), f"seed {seed}"
    fd = (moved.position[0::2] - moved.position[1::2]).T / (2 * h)
    # (central differences: error ~ h^2 P''' ~ 1e-6 of C at a 0.1 mm push)
    np.testing.assert_allclose(c, fd, atol=1e-5 * np.abs(c).max(), err_msg=f"seed {seed}")
    if "large_deflection" in effects:  # (the linear rod's loads: conservative to 1st order)
        assert st.asymmetry[0] < 1e-6, f"seed {seed}: conservative loads, symmetric C"
    assert np.all(st.stiffness[0] > 0), f"seed {seed}: a stable state is stiff"
