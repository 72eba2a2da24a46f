"""The set-up render (issue 52: the external magnet appeared in no render): the robot and
its field sources to scale, in the base frame. The sources' surfaces are checked against
the design (each body's extent is the source's size at its centre) and the picture is
rendered offscreen and read back: the magnets' north and south colours and a coil's
copper are on it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from PIL import Image

from cad.actuator import build_actuator
from cad.assembly import build_assembly
from cad.mounting import build_mounting_pieces
from cad.process import FDM
from cad.render import render_all
from cad.sources import COPPER, NORTH, SOUTH, bodiless, source_meshes
from design.records import Design, Source
from design.units import MM


def _with_sources(design: Design) -> Design:
    coil = Source(
        "coil", radius=60 * MM, turns=100, current=5.0, center=(150 * MM, 0.0, 70 * MM),
        axis=(0.0, 0.0, 1.0),
    )  # fmt: skip
    sphere = Source(
        "sphere", diameter=20 * MM, remanence=1.3, center=(150 * MM, 60 * MM, 0.0),
        magnetization=(0.0, -1.0, 0.0),
    )  # fmt: skip
    block = Source(
        "cuboid", dimensions=(10 * MM, 30 * MM, 20 * MM), remanence=1.3,
        center=(150 * MM, -60 * MM, 0.0), magnetization=(0.0, 1.0, 0.0),
    )  # fmt: skip
    uniform = Source("uniform", b=(0.0, 0.0, 0.01))
    return replace(design, sources=(coil, sphere, block, uniform))


def test_source_surfaces_have_the_sources_sizes(demonstrator: Design):
    d = _with_sources(demonstrator)
    meshes = source_meshes(d)
    ext = d.external_magnet
    # external magnet: two halves along -x, together its length and diameter
    (north, c1), (south, c2) = meshes[:2]
    assert (c1, c2) == (NORTH, SOUTH)
    both = np.array([north.bounds, south.bounds])
    lo, hi = both[:, 0::2].min(axis=0), both[:, 1::2].max(axis=0)
    centre = np.array(ext.center) / MM
    np.testing.assert_allclose(
        hi - lo, [ext.length / MM, ext.diameter / MM, ext.diameter / MM], rtol=2e-3
    )
    np.testing.assert_allclose((hi + lo) / 2, centre, atol=1e-6)
    assert north.center[0] < south.center[0]  # magnetised along -x: north faces the robot
    coil = next(m for m, c in meshes if c == COPPER)
    b = np.array(coil.bounds).reshape(3, 2)
    assert abs((b[0, 1] - b[0, 0]) / 2 - 60 - coil_tube(b)) < 0.5  # radius + tube
    block_halves = meshes[-2:]
    b = np.array([m.bounds for m, _ in block_halves])
    np.testing.assert_allclose(
        b[:, 1::2].max(axis=0) - b[:, 0::2].min(axis=0), [10, 30, 20], atol=1e-6
    )
    assert bodiless(d) == ["uniform field 0, 0, 10 mT"]


def coil_tube(bounds: np.ndarray) -> float:
    """The tube radius drawn round a coil: its thickness along the axis over two. [mm]"""
    return (bounds[2, 1] - bounds[2, 0]) / 2


def test_setup_render_shows_the_magnets_and_coil(demonstrator: Design, tmp_path):
    d = _with_sources(demonstrator)
    assembly = build_assembly(d, build_actuator(d, FDM), build_mounting_pieces(d))
    files = render_all(assembly, tmp_path, design=d)
    setup = tmp_path / "setup.png"
    assert setup in files
    img = np.asarray(Image.open(setup).convert("RGB")).astype(float) / 255
    for colour, least in ((NORTH, 2000), (SOUTH, 2000), (COPPER, 300)):
        # shading darkens a colour: compare hue by the direction of the RGB vector
        rgb = img.reshape(-1, 3)
        norm = np.linalg.norm(rgb, axis=1) + 1e-9
        cos = rgb @ np.array(colour) / norm / np.linalg.norm(colour)
        assert (cos > 0.995).sum() > least, colour
