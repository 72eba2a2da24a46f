"""The CAD puts the ring magnets where the model has them: the centres of the placed ring
solids (cad.assembly) against the model's ring centres (design.model) on the unloaded,
straight robot, for designs unlike the demonstrator (other ring sizes, gaps and free
lengths)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from setups import random_design

from cad.assembly import ring_magnet, tip_locations
from cad.errors import CadError
from cad.mounting import MountingSpec, mounting_dims
from cad.process import FDM
from design.model import Symbols, model_for, ring_positions
from design.records import Design
from design.registry import parameter_vector
from design.units import MM


def model_ring_centres(design: Design, command: np.ndarray) -> np.ndarray:
    """(proximal, distal) ring centres of the baseline model's unloaded robot, shape
    (2, 3). [m]"""
    model = model_for(frozenset())
    params = parameter_vector(design)
    x0 = model.initial(command, params)
    position, frame, _ = model.pose(x0, command, params)
    rings = ring_positions(Symbols(ca.DM(params)), position, frame)
    return np.array([np.asarray(centre).ravel() for centre in rings])


def buildable_designs(count: int) -> list[Design]:
    """Random designs (tests/support/setups.py) whose mounting pieces can be built."""
    rng = np.random.default_rng(20261124)
    out = []
    while len(out) < count:
        design = random_design(rng)
        try:
            mounting_dims(design, FDM, MountingSpec())
        except CadError:
            continue
        out.append(design)
    return out


DESIGNS = buildable_designs(5)


@pytest.mark.parametrize("design", DESIGNS, ids=[f"design{i}" for i in range(len(DESIGNS))])
def test_placed_ring_centres_are_the_model_ring_centres(design: Design) -> None:
    dims = mounting_dims(design, FDM, MountingSpec())
    theta1, theta2 = 70.0, -20.0  # [deg]
    locations = tip_locations(design, dims, theta1, theta2)
    ring = ring_magnet(dims)
    placed = np.array(
        [
            ring.moved(locations[name]).Center().toTuple()
            for name in ("ring_magnet_proximal", "ring_magnet_distal")
        ]
    )
    expected = model_ring_centres(design, np.radians([theta1, theta2]))
    np.testing.assert_allclose(placed * MM, expected, rtol=0, atol=1e-9)


def test_designs_differ_from_the_demonstrator_and_each_other() -> None:
    tips = {(d.tip.magnet_outer_diameter, d.tip.magnet_length, d.tip.magnet_gap) for d in DESIGNS}
    lengths = {d.robot.free_length for d in DESIGNS}
    assert len(tips) == len(DESIGNS) and len(lengths) == len(DESIGNS)
    assert all(d.tip.magnet_gap > 0 and d.tip.magnet_length != 0.5e-3 for d in DESIGNS)
