"""Where each ring's north goes (issue 52: an assembly key that indexes each ring's
magnetisation): the solids carry angle 0, the ring's north at theta = 0 (local +X of its
piece, :mod:`cad.mounting`), as the instructions say (docs/tutorial.md, the bill of
materials): the distal piece's stop key is centred on it, and the proximal piece's notch
edge that the key bears on with the rings parallel lies half the key's width before it.
Real solids probed on the demonstrator and on tips drawn from the whole range the CAD
accepts (rings from 1 mm across, every process, wall, fit and stop angle)."""

from __future__ import annotations

import csv
import math

import cadquery as cq
import pytest
from tips import drawn_tip

from cad.build import CadReport
from cad.mounting import MountingSpec, build_mounting_pieces
from design.records import Design


def _at(radius: float, angle_deg: float, z: float) -> cq.Vector:
    a = math.radians(angle_deg)
    return cq.Vector(radius * math.cos(a), radius * math.sin(a), z)


def assert_angle_zero_is_marked(design: Design, spec: MountingSpec, why: str) -> None:
    pieces = build_mounting_pieces(design, None, spec)
    d = pieces.dims
    half = d.key_angle_deg / 2
    step = min(1.0, half / 4)  # probe a degree (or a quarter of the half key) either side
    # distal piece: the key on the shoulder, centred on local +X
    r = (d.key_inner_diameter + d.outer_diameter) / 4
    z = d.journal_length - d.key_height / 2
    key = pieces.distal
    for angle in (0.0, half - step, -half + step):
        assert key.isInside(_at(r, angle, z)), f"{why}: no key at {angle:.2f} deg"
    for angle in (half + step, -half - step):
        assert not key.isInside(_at(r, angle, z)), f"{why}: key beyond {angle:.2f} deg"
    # proximal piece: the notch's edge the key bears on at theta1 = theta2, half a key
    # before +X (material before it, the notch after it)
    r = (d.sleeve_bore + d.outer_diameter) / 4
    z = d.proximal_length - d.notch_depth / 2
    sleeve = pieces.proximal
    assert sleeve.isInside(_at(r, -half - step, z)), f"{why}: the notch starts early"
    assert not sleeve.isInside(_at(r, -half + step, z)), f"{why}: the notch starts late"
    assert not sleeve.isInside(_at(r, 0.0, z)), f"{why}: the key cannot reach angle 0"


def test_the_demonstrators_key_and_notch_mark_each_rings_north(demonstrator: Design) -> None:
    assert_angle_zero_is_marked(demonstrator, MountingSpec(), "demonstrator")


@pytest.mark.parametrize("seed", range(5401, 5409))
def test_drawn_tips_key_and_notch_mark_each_rings_north(demonstrator: Design, seed: int) -> None:
    design, spec, why = drawn_tip(demonstrator, seed)
    assert_angle_zero_is_marked(design, spec, why)


def test_the_bill_of_materials_says_where_north_goes(fdm_build: CadReport) -> None:
    """The ring magnets' row names the key and the angle from the notch's edge that the
    solids have (the half key of the pieces built)."""
    with open(fdm_build.out_dir / "bom.csv", newline="", encoding="utf-8") as f:
        rows = {r["item"]: r for r in csv.DictReader(ln for ln in f if not ln.startswith("#"))}
    note = rows["ring_magnet"]["note"]
    assert fdm_build.assembly is not None
    half = fdm_build.assembly.mounting.dims.key_angle_deg / 2
    assert "stop key's centre line" in note and f"{half:.1f} deg past the notch's edge" in note
