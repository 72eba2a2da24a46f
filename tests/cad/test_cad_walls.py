"""The absolute wall check (issue 52): it finds knife edges, and the parts have none.

The check (:func:`cad.checks.wall_thickness`) is anchored to solids whose thinnest wall is
known in closed form: a tube (its radial wall), a slab (its thickness) and a wedge sharper
than :data:`cad.checks.KNIFE_ANGLE_DEG` (its thickness falls to nothing at the edge, so
the check must find a wall far below the limit), while a box's 90 deg corners are no wall.
Then the tip pieces, drawn from the whole range of mountings the design file accepts
(process, wall, fits, stop angle, groove range) about drawn rings, from the smallest that
fit over the wire up (seeds printed), have no
wall under their process minimum: the helical grooves end a wall short of every face.
"""

from __future__ import annotations

import math

import cadquery as cq
import numpy as np
import pytest
import trimesh
from tips import drawn_tip

from cad.checks import KNIFE_ANGLE_DEG, wall_thickness
from cad.meshing import tessellate
from cad.mounting import build_mounting_pieces
from cad.solids import box, tube
from design.records import Design

SEEDS = tuple(range(5231, 5261))  # 5245 and 5259 found the web by the glue port


def _mesh(solid: cq.Shape, tolerance: float = 0.01) -> trimesh.Trimesh:
    v, t = tessellate(solid, tolerance, 0.2)
    return trimesh.Trimesh(v, t, process=True)


def _thinnest(solid: cq.Shape) -> float:
    return float(np.min(wall_thickness(_mesh(solid))))


def test_tube_and_slab_walls_are_measured_exactly() -> None:
    assert _thinnest(tube(10.0, 9.0, 0.0, 20.0)) == pytest.approx(0.5, abs=0.01)  # chords
    assert _thinnest(box((0.0, 20.0), (0.0, 15.0), (0.0, 0.7))) == pytest.approx(0.7, abs=1e-6)
    # A cube's corners are 90 deg: no ray leaves by a face turned back, its wall is its side.
    assert _thinnest(box((0.0, 3.0), (0.0, 3.0), (0.0, 3.0))) == pytest.approx(3.0, abs=1e-6)


@pytest.mark.parametrize("angle_deg", [10.0, 40.0])
def test_a_wedge_sharper_than_the_knife_angle_is_a_knife_edge(angle_deg: float) -> None:
    # A 10 mm long wedge of the given angle: thickness t(x) = x tan(angle) from its edge.
    assert angle_deg < KNIFE_ANGLE_DEG
    tip = 10.0 * math.tan(math.radians(angle_deg))
    wedge = cq.Workplane("XZ").polyline([(0, 0), (10, 0), (10, tip)]).close().extrude(-5.0).val()
    t = wall_thickness(_mesh(wedge))
    # the ray from the slanted face's centroids crosses the wedge where it is thinnest
    assert np.min(t) < 0.5 * tip
    assert np.min(t) > 0.0


@pytest.mark.parametrize("seed", SEEDS)
def test_drawn_tip_pieces_have_no_wall_under_the_process_minimum(
    demonstrator: Design, seed: int
) -> None:
    design, spec, why = drawn_tip(demonstrator, seed)
    print(why)
    pieces = build_mounting_pieces(design, None, spec)
    limit = pieces.process.min_wall_mm
    for name, solid in (("proximal", pieces.proximal), ("distal", pieces.distal)):
        proc = pieces.process
        mesh = _mesh(solid, proc.linear_deflection_mm)
        thinnest = float(np.min(wall_thickness(mesh)))
        assert thinnest >= limit, f"seed {seed}: {name} piece wall {thinnest:.3f} mm < {limit}"
