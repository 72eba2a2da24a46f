"""The tip as built (effect ``printed_tip``, design.mounting): the rigid segment and the
pieces' weight against closed-form cantilever results, on both rod models.

Closed forms (Gere & Goodno, Mechanics of Materials, App. G, cases 1, 4 and 6): a
cantilever of length l and bending rigidity EI under a tip force F, a tip moment M and a
uniform load w deflects at its end by F l^3 / 3EI + M l^2 / 2EI + w l^4 / 8EI and turns by
F l^2 / 2EI + M l / EI + w l^3 / 6EI; a rigid segment carries a point at a from the rod's
end by delta + a phi (small rotations).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import RingPairModel
from design.mounting import design_tip_geometry
from design.records import Environment
from design.registry import index
from design.sections import bending_rigidity
from tests.support.setups import random_design

G = 9.81
SMALL = 0.01
"""Gravity scale for the linear closed forms: the tip turns by ~3 mrad, so the model's
finite rotations of the tip frame differ from the small-rotation formulas by ~1e-5."""


def _params(model: RingPairModel, design, **values: float) -> np.ndarray:
    p = model.parameters(design)
    for name, value in values.items():
        p[index(name)] = value
    return p


def _weight_per_length(design) -> float:
    c, w = design.robot.catheter, design.robot.wire
    return G * (
        c.density * np.pi / 4 * (c.outer_diameter**2 - c.inner_diameter**2)
        + w.density * np.pi / 4 * (w.outer_diameter**2 - w.inner_diameter**2)
    )


def _sag(design, tip_mass: float = 0.0, g_scale: float = 1.0) -> float:
    """Closed-form sag of the tracked point (proximal ring centre) under gravity (-z):
    rod of length L - a, the rings, the tip mass and both pieces as point weights on the
    rigid segment. [m]"""
    g = design_tip_geometry(design)
    t = design.tip
    ring = t.density * np.pi / 4 * (t.magnet_outer_diameter**2 - t.magnet_inner_diameter**2)
    ring *= t.magnet_length
    a = g.rigid_offset
    points = [
        (a, ring),
        (a + t.spacing, ring),
        (a, tip_mass),
        (g.proximal_arm, g.proximal_mass),
        (g.distal_arm, g.distal_mass),
    ]
    force = g_scale * G * sum(m for _, m in points)
    moment = g_scale * G * sum(arm * m for arm, m in points)
    w = g_scale * _weight_per_length(design)
    length, ei = design.robot.free_length - a, bending_rigidity(design.robot)
    deflection = (
        force * length**3 / (3 * ei) + moment * length**2 / (2 * ei) + w * length**4 / (8 * ei)
    )
    rotation = force * length**2 / (2 * ei) + moment * length / ei + w * length**3 / (6 * ei)
    return deflection + a * rotation


def _weighed(design, g_scale: float = 1.0):
    gravity = (0.0, 0.0, -g_scale * G)
    return dataclasses.replace(design, environment=Environment(gravity=gravity))


def test_printed_tip_sags_as_a_cantilever_with_a_rigid_weighted_end():
    # Linear rod: unmagnetised rings, weak gravity -z; the sag of the tracked point is the
    # closed form above.
    design = _weighed(default_design(), SMALL)
    model = RingPairModel(frozenset({"gravity", "printed_tip"}))
    params = _params(model, design, magnet_remanence=0.0, tip_mass=0.3e-3)
    eq = solve_equilibria(model, params, 0.0, 0.0)
    assert -eq.position[0, 2] == pytest.approx(_sag(design, 0.3e-3, SMALL), rel=1e-4)
    # the linear rod's end stays at x = L - a; the segment turns with the tip frame
    assert eq.position[0, 0] == pytest.approx(design.robot.free_length, rel=1e-6)


@pytest.mark.parametrize("seed", range(1600, 1612))
def test_printed_tip_sag_on_random_setups(seed):
    # Property: random designs across the design space (tests/support/setups.py), stiffened
    # so the sag stays small (< 0.2 % of L): the large-deflection rod with the printed tip
    # agrees with the linear closed form to 1 % of the sag.
    rng = np.random.default_rng(seed)
    design = _weighed(random_design(rng))
    model = RingPairModel(frozenset({"gravity", "printed_tip", "large_deflection"}))
    params = _params(model, design, magnet_remanence=0.0)
    sag = _sag(design)
    scale = max(1.0, sag / (2e-3 * design.robot.free_length))
    params[index("bending_rigidity_scale")] = scale
    eq = solve_equilibria(model, params, 0.0, 0.0)
    assert eq.converged[0], f"seed {seed}"
    assert -eq.position[0, 2] == pytest.approx(sag / scale, rel=0.01, abs=1e-12), f"seed {seed}"


def test_baseline_has_no_rigid_segment():
    # The paper's model: the rings on the rod's end; the printed tip changes the response
    # to the same loads (a shorter, stiffer rod and an arm).
    design = default_design()
    theta = np.deg2rad([0.0, 60.0])
    base = RingPairModel()
    tip = RingPairModel(frozenset({"printed_tip"}))
    a = solve_equilibria(base, base.parameters(design), theta, 0.0)
    b = solve_equilibria(tip, tip.parameters(design), theta, 0.0)
    assert a.converged.all() and b.converged.all()
    assert np.abs(a.position - b.position).max() > 1e-4


def test_rest_position_is_the_free_length_with_and_without_the_printed_tip():
    design = default_design()
    for effects in (
        frozenset(),
        frozenset({"printed_tip"}),
        frozenset({"printed_tip", "large_deflection"}),
    ):
        model = RingPairModel(effects)
        params = _params(model, design, load_scale=0.0)
        x0 = model.initial(np.zeros(2), params)
        position = np.asarray(model.pose(x0, np.zeros(2), params)[0]).ravel()
        np.testing.assert_allclose(position, [design.robot.free_length, 0, 0], atol=1e-15)
