"""The one tip geometry (design.mounting): numbers and CasADi alike, the radial stack-up,
the grooves' readout, and the model's use of it (the solids: tests/cad/test_cad_mounting.py)."""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np
import pytest

from design.designfile import default_design
from design.model import Symbols
from design.mounting import (
    PITCH_PER_WIDTH,
    TipGeometry,
    design_tip_geometry,
    geometry_values,
)
from design.process import FDM, RESIN
from design.records import Mounting
from design.registry import NAMES, parameter_vector
from tests.support.setups import random_design


@pytest.mark.parametrize("seed", range(1800, 1820))
def test_symbolic_geometry_equals_the_numeric_one(seed):
    # The model evaluates tip_geometry on CasADi symbols of the registry (design.model
    # Symbols.tip); for random designs and both processes it gives the numbers the CAD uses.
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    process = "fdm" if rng.random() < 0.5 else "resin"
    mounting = Mounting.printed_by(process, stop_angle=math.radians(rng.uniform(30, 270)))
    design = dataclasses.replace(design, tip=dataclasses.replace(design.tip, mounting=mounting))
    prm = ca.SX.sym("p", len(NAMES))
    tip = Symbols(prm).tip
    names = [f.name for f in dataclasses.fields(TipGeometry)]
    values = ca.Function("tip", [prm], [ca.vertcat(*[getattr(tip, n) for n in names])])
    got = np.asarray(values(parameter_vector(design))).ravel()
    want = geometry_values(design_tip_geometry(design))
    for name, value in zip(names, got, strict=True):
        assert value == pytest.approx(want[name], rel=1e-12), f"seed {seed}: {name}"


@pytest.mark.parametrize("process", [RESIN, FDM], ids=["resin", "fdm"])
def test_outer_diameter_stacks_walls_and_clearances_on_the_ring(process):
    # Ring + fit | journal wall | running clearance | sleeve wall | groove depth (w / 2),
    # each wall 1.25 x the process minimum: D = D_m + fit + 2 w + c + 2 (w + w / 2).
    design = default_design()
    mounting = Mounting.printed_by(process.name)
    design = dataclasses.replace(design, tip=dataclasses.replace(design.tip, mounting=mounting))
    g = design_tip_geometry(design)
    w = 1.25 * process.min_wall
    expected = 4e-3 + process.fit_allowance + 2 * w + process.running_clearance + 3 * w
    assert g.outer_diameter == pytest.approx(expected, rel=1e-12)


def test_resin_makes_the_smallest_tip():
    design = default_design()  # resin by default
    fdm = dataclasses.replace(
        design, tip=dataclasses.replace(design.tip, mounting=Mounting.printed_by("fdm"))
    )
    small, big = design_tip_geometry(design), design_tip_geometry(fdm)
    assert small.outer_diameter < big.outer_diameter
    assert small.rigid_length < big.rigid_length
    assert small.proximal_mass + small.distal_mass < big.proximal_mass + big.distal_mass


@pytest.mark.parametrize("range_deg", [180.0, 240.0, 360.0])
def test_grooves_read_the_range_at_a_readable_pitch(range_deg):
    g = design_tip_geometry(default_design(), groove_range=math.radians(range_deg))
    for visible, pitch, readout in (
        (g.proximal_length - g.notch_depth, g.proximal_pitch, g.proximal_readout),
        (g.body_length, g.distal_pitch, g.distal_readout),
    ):
        travel = visible - g.groove_width - 2 * g.wall  # the groove stops a wall short
        assert readout * math.radians(range_deg) == pytest.approx(travel, rel=1e-12)
        assert readout == pytest.approx(pitch / (2 * math.pi))
        assert pitch >= PITCH_PER_WIDTH * g.groove_width * (1 - 1e-12)


def test_rigid_segment_holds_the_rings_and_the_pieces():
    g = design_tip_geometry(default_design())
    spacing = g.magnet_length + g.gap
    assert 0 < g.rigid_offset < g.rigid_offset + spacing < g.rigid_length
    assert 0 < g.proximal_arm < g.distal_arm < g.rigid_length
