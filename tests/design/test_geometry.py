"""Geometry of the set-up (design.geometry) against closed forms: the distance to a solid
cylinder, the ring centres and their spacing, the external magnet's distance from the rest
tip, the rings' clearance to the magnet and the workspace loop's disc radius; numpy and
CasADi branches alike, on set-ups from the whole design space (tests/support/setups.py).
The seed of each random case is in its test id."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from setups import random_design

from design.geometry import (
    SMOOTH,
    cylinder_distance,
    disc_radius,
    external_distance,
    magnet_centre_at,
    magnet_spacing,
    rest_position,
    ring_centres,
    ring_clearance,
    ring_radius,
    segment_distances,
    winding_number,
)
from design.units import MM

SEEDS = range(9000, 9020)


def unit(v):
    return v / np.linalg.norm(v)


def magnet_cylinder(seed):
    """A random design's external magnet: (centre, unit axis, a unit vector normal to the
    axis, radius, half length) [m], and the rng for further draws."""
    rng = np.random.default_rng(seed)
    ext = random_design(rng).external_magnet
    axis = np.asarray(ext.magnetization, float)
    normal = unit(np.cross(axis, rng.normal(size=3)))
    return np.asarray(ext.center, float), axis, normal, ext.diameter / 2, ext.length / 2, rng


def evaluate(function, symbols, values):
    """``function`` of CasADi ``symbols`` evaluated at numbers ``values``, as numpy."""
    outputs = function(*symbols)
    outputs = list(outputs) if isinstance(outputs, tuple) else [outputs]
    result = ca.Function("f", list(symbols), outputs)(*values)
    result = result if isinstance(result, tuple) else (result,)
    return [np.asarray(r, float).ravel() for r in result]


# --- cylinder_distance: hypot(max(|a| - h, 0), max(rho - R, 0)) in the cylinder's axial and
# radial coordinates a, rho (the distance to the nearer face, rim or mantle).


@pytest.mark.parametrize("seed", SEEDS)
def test_cylinder_distance_on_the_axis_beyond_a_face_is_the_axial_excess(seed):
    _, axis, _, radius, half, rng = magnet_cylinder(seed)
    for side in (1, -1):
        a = side * (half + rng.uniform(1, 50) * MM)
        assert cylinder_distance(a * axis, axis, radius, half) == pytest.approx(
            abs(a) - half, rel=1e-12
        ), f"seed {seed}"


@pytest.mark.parametrize("seed", SEEDS)
def test_cylinder_distance_in_the_mid_plane_outside_is_the_radial_excess(seed):
    _, axis, normal, radius, half, rng = magnet_cylinder(seed)
    rho = radius + rng.uniform(1, 50) * MM
    assert cylinder_distance(rho * normal, axis, radius, half) == pytest.approx(
        rho - radius, rel=1e-12
    ), f"seed {seed}"


@pytest.mark.parametrize("seed", SEEDS)
def test_cylinder_distance_off_a_rim_edge_is_the_hypotenuse_of_both_excesses(seed):
    _, axis, normal, radius, half, rng = magnet_cylinder(seed)
    axial, radial = rng.uniform(1, 50, 2) * MM
    for side in (1, -1):
        offset = side * (half + axial) * axis + (radius + radial) * normal
        assert cylinder_distance(offset, axis, radius, half) == pytest.approx(
            np.hypot(axial, radial), rel=1e-12
        ), f"seed {seed}"


@pytest.mark.parametrize("seed", SEEDS)
def test_cylinder_distance_is_zero_inside(seed):
    _, axis, normal, radius, half, rng = magnet_cylinder(seed)
    a = rng.uniform(-0.99, 0.99, 50)[:, None] * half
    rho = rng.uniform(0, 0.99, 50)[:, None] * radius
    turn = rng.uniform(0, 2 * np.pi, 50)[:, None]  # about the axis
    normals = np.cos(turn) * normal + np.sin(turn) * np.cross(axis, normal)
    inside = a * axis + rho * normals
    assert np.all(cylinder_distance(inside, axis, radius, half) == 0.0), f"seed {seed}"


def test_cylinder_distance_is_the_same_on_casadi_symbols():
    # 20 magnets of the design space x 10 points in a box of half-side radius + half length
    # about the centre, inside and out; the symbolic branch floors its square roots by SMOOTH.
    symbols = ca.SX.sym("offset", 3), ca.SX.sym("axis", 3), ca.SX.sym("r"), ca.SX.sym("h")
    inside = 0
    for seed in range(9100, 9120):
        _, axis, _, radius, half, rng = magnet_cylinder(seed)
        points = rng.uniform(-1, 1, (10, 3)) * (radius + half)
        numeric = cylinder_distance(points, axis, radius, half)  # broadcast over points
        symbolic = [
            evaluate(cylinder_distance, symbols, (p, axis, radius, half))[0][0] for p in points
        ]
        np.testing.assert_allclose(
            symbolic, numeric, rtol=1e-12, atol=2 * SMOOTH, err_msg=f"seed {seed}"
        )
        inside += np.count_nonzero(numeric == 0)
    assert 10 < inside < 190  # points inside and outside


# --- ring centres: the proximal ring on the rod tip, the distal one a spacing (ring length
# plus face-to-face gap) further along the tip tangent (module docstring).


@pytest.mark.parametrize("seed", SEEDS)
def test_ring_centres_are_a_ring_length_plus_gap_apart_along_the_tangent(seed):
    rng = np.random.default_rng(seed)
    tip = random_design(rng).tip
    spacing = magnet_spacing(tip.magnet_length, tip.magnet_gap)
    assert spacing == tip.magnet_length + tip.magnet_gap, f"seed {seed}"
    position, tangent = rng.normal(size=3) * 0.1, unit(rng.normal(size=3))
    proximal, distal = ring_centres(position, tangent, spacing)
    np.testing.assert_array_equal(proximal, position, err_msg=f"seed {seed}")
    np.testing.assert_allclose(distal - proximal, spacing * tangent, rtol=1e-15, atol=1e-15)
    assert np.linalg.norm(distal - proximal) == pytest.approx(spacing, rel=1e-14)
    symbols = ca.SX.sym("p", 3), ca.SX.sym("t", 3), ca.SX.sym("s")
    np.testing.assert_allclose(
        np.stack(evaluate(ring_centres, symbols, (position, tangent, spacing))),
        np.stack([proximal, distal]),
        rtol=1e-15,
        atol=1e-18,
        err_msg=f"seed {seed}",
    )


@pytest.mark.parametrize("seed", SEEDS)
def test_ring_centres_of_the_straight_rod_are_at_free_length_and_one_spacing_on(seed):
    design = random_design(np.random.default_rng(seed))
    length, spacing = design.robot.free_length, design.tip.magnet_length + design.tip.magnet_gap
    proximal, distal = ring_centres(rest_position(length), np.array([1.0, 0, 0]), spacing)
    np.testing.assert_array_equal(proximal, [length, 0, 0], err_msg=f"seed {seed}")
    np.testing.assert_array_equal(distal, [length + spacing, 0, 0], err_msg=f"seed {seed}")
    symbolic = evaluate(rest_position, [ca.SX.sym("L")], [length])[0]
    np.testing.assert_array_equal(symbolic, [length, 0, 0], err_msg=f"seed {seed}")


# --- external magnet's distance: |c - (L, 0, 0)|, the centre c moved along the ray from the
# rest tip.


@pytest.mark.parametrize("seed", SEEDS)
def test_magnet_centre_at_and_external_distance_are_inverse(seed):
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    length, centre = design.robot.free_length, np.asarray(design.external_magnet.center)
    rest = np.array([length, 0.0, 0.0])
    distance = external_distance(length, centre)
    assert distance == pytest.approx(np.linalg.norm(centre - rest), rel=1e-15), f"seed {seed}"
    back = magnet_centre_at(length, centre, distance)
    np.testing.assert_allclose(back, centre, rtol=1e-14, atol=1e-15, err_msg=f"seed {seed}")
    wanted = distance * rng.uniform(0.3, 3.0)
    moved = magnet_centre_at(length, centre, wanted)
    assert external_distance(length, moved) == pytest.approx(wanted, rel=1e-14), f"seed {seed}"
    # on the same ray from the rest tip
    np.testing.assert_allclose(
        (moved - rest) / wanted,
        (centre - rest) / distance,
        rtol=1e-13,
        atol=1e-14,
        err_msg=f"seed {seed}",
    )
    symbols = ca.SX.sym("L"), ca.SX.sym("c", 3), ca.SX.sym("D")
    args = (length, centre, wanted)
    symbolic = evaluate(magnet_centre_at, symbols, args)[0]
    np.testing.assert_allclose(symbolic, moved, rtol=1e-14, atol=1e-15, err_msg=f"seed {seed}")
    symbolic = evaluate(lambda L, c, _: external_distance(L, c), symbols, args)[0]
    assert symbolic[0] == pytest.approx(distance, rel=1e-14), f"seed {seed}"


# --- ring clearance: the least distance of a ring centre to the magnet less the radius of
# the sphere that holds a ring, hypot(outer diameter / 2, length / 2).


def nearest_point_on_cylinder(point, centre, axis, radius, half):
    """The point of the solid cylinder nearest ``point``: the cylinder is a segment along the
    axis times a disc across it, so its projection clamps each part on its own."""
    offset = point - centre
    a = offset @ axis
    across = offset - a * axis
    rho = np.linalg.norm(across)
    scale = min(1.0, radius / rho) if rho > 0 else 0.0
    return centre + np.clip(a, -half, half) * axis + scale * across


def cylinder_surface(centre, axis, radius, half, n=240):
    """Points covering the cylinder's mantle and faces, (m, 3), and the farthest any point
    of the surface lies from them (half a grid cell's diagonal). [m]"""
    u = unit(np.cross(axis, [0.3, -0.5, 0.8]))
    v = np.cross(axis, u)
    phi = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v  # (n, 3)
    a = np.linspace(-half, half, n)
    mantle = centre + radius * ring[:, None, :] + a[None, :, None] * axis
    r = np.linspace(0, radius, n // 2)
    disc = r[None, :, None] * ring[:, None, :]
    faces = [centre + side * half * axis + disc for side in (1, -1)]
    points = np.concatenate([p.reshape(-1, 3) for p in (mantle, *faces)])
    arc, steps = 2 * np.pi * radius / n, (a[1] - a[0], r[1] - r[0])
    return points, np.hypot(arc, max(steps)) / 2


@pytest.mark.parametrize("seed", range(9200, 9230))
def test_ring_clearance_is_the_nearest_ring_centre_to_the_magnet_less_the_ring_sphere(seed):
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    tip, ext = design.tip, design.external_magnet
    centre, axis = np.asarray(ext.center), np.asarray(ext.magnetization)
    radius, half = ext.diameter / 2, ext.length / 2
    sphere = np.hypot(tip.magnet_outer_diameter / 2, tip.magnet_length / 2)
    surface, resolution = cylinder_surface(centre, axis, radius, half)
    symbols = [ca.SX.sym(n, 3) for n in "pdcm"] + [ca.SX.sym(n) for n in ("od", "h", "D", "H")]
    symbolic_clearance = ca.Function(
        "f", symbols, [ring_clearance(symbols[:2], *symbols[4:6], *symbols[2:4], *symbols[6:])]
    )
    # The straight rod and four deflected tips (up to 60 degrees, 40 mm off the rest tip).
    poses = [(rest_position(design.robot.free_length), np.array([1.0, 0, 0]))]
    for _ in range(4):
        tilt = np.deg2rad(rng.uniform(0, 60)) * unit(rng.normal(size=2))
        tangent = unit(np.array([1.0, np.tan(tilt[0]), np.tan(tilt[1])]))
        poses.append((poses[0][0] + rng.uniform(-40, 40, 3) * MM, tangent))
    for position, tangent in poses:
        centres = ring_centres(position, tangent, tip.magnet_length + tip.magnet_gap)
        nearest = [
            np.linalg.norm(c - nearest_point_on_cylinder(c, centre, axis, radius, half))
            for c in centres
        ]
        for c, d in zip(centres, nearest, strict=True):  # the projection is the nearest point
            if d > 1e-9:  # outside, where the solid and its surface agree
                sampled = np.linalg.norm(surface - c, axis=1).min()
                assert d - 1e-12 <= sampled <= d + resolution, f"seed {seed}"
        sizes = (tip.magnet_outer_diameter, tip.magnet_length)
        clearance = ring_clearance(centres, *sizes, centre, axis, ext.diameter, ext.length)
        assert clearance == pytest.approx(min(nearest) - sphere, rel=1e-12, abs=1e-15), (
            f"seed {seed}"
        )
        symbolic = symbolic_clearance(*centres, centre, axis, *sizes, ext.diameter, ext.length)
        assert float(symbolic) == pytest.approx(clearance, rel=1e-12, abs=2 * SMOOTH), (
            f"seed {seed}"
        )


@pytest.mark.parametrize("seed", SEEDS)
def test_ring_radius_is_the_distance_to_the_rim_corners(seed):
    # A ring's farthest points from its centre are its outer rim circles, at
    # hypot(outer diameter / 2, length / 2); sampled over the whole outer surface.
    tip = random_design(np.random.default_rng(seed)).tip
    od, length = tip.magnet_outer_diameter, tip.magnet_length
    phi, x = np.meshgrid(np.linspace(0, 2 * np.pi, 60), np.linspace(-length / 2, length / 2, 31))
    surface = np.stack([x, od / 2 * np.cos(phi), od / 2 * np.sin(phi)], axis=-1)
    farthest = np.linalg.norm(surface, axis=-1).max()
    assert ring_radius(od, length) == pytest.approx(farthest, rel=1e-14), f"seed {seed}"
    symbolic = evaluate(ring_radius, [ca.SX.sym("od"), ca.SX.sym("h")], [od, length])[0]
    assert symbolic[0] == pytest.approx(farthest, rel=1e-14), f"seed {seed}"


# --- disc radius of the workspace loop (moved from test_workspace.py).


def test_disc_radius_of_a_square_loop_is_its_half_side():
    # The nearest points are the sides' midpoints (2), not the corners (2 sqrt 2).
    square = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], float) * 2.0
    np.testing.assert_allclose(segment_distances(square), 2.0, rtol=1e-15)
    assert disc_radius(square) == pytest.approx(2.0, rel=1e-15)
    assert winding_number(square) == 1 and winding_number(square[::-1]) == -1
    assert disc_radius(square[::-1]) == pytest.approx(2.0, rel=1e-15)  # clockwise
    assert winding_number(square + [5.0, 0.0]) == 0
    assert disc_radius(square + [5.0, 0.0]) == 0.0  # not around the origin


@pytest.mark.parametrize("sides", [3, 7, 24])
def test_disc_radius_of_a_regular_polygon_is_its_apothem(sides):
    # A regular polygon of circumradius R has the apothem R cos(pi / n); moved by c, the
    # origin lies R cos(pi / n) + c . n_i from side i (outward normal n_i).
    phi = 0.3 + 2 * np.pi * np.arange(sides) / sides
    polygon = 1.5 * np.column_stack([np.cos(phi), np.sin(phi)])
    apothem = 1.5 * np.cos(np.pi / sides)
    assert disc_radius(polygon) == pytest.approx(apothem, rel=1e-14)
    centre = np.array([0.2, -0.1])
    normal = phi + np.pi / sides
    expected = np.min(apothem + np.column_stack([np.cos(normal), np.sin(normal)]) @ centre)
    assert disc_radius(polygon + centre) == pytest.approx(expected, rel=1e-13)


def test_disc_radius_is_the_same_on_casadi_symbols():
    rng = np.random.default_rng(3)
    phi = np.sort(rng.uniform(0, 2 * np.pi, 40))
    loop = (1 + 0.3 * rng.random(40))[:, None] * np.column_stack([np.cos(phi), np.sin(phi)])
    symbol = ca.SX.sym("loop", 40, 2)
    outputs = [segment_distances(symbol), winding_number(symbol), disc_radius(symbol)]
    sides, winding, disc = (
        np.asarray(v).ravel() for v in ca.Function("f", [symbol], outputs)(loop)
    )
    np.testing.assert_allclose(sides, segment_distances(loop), rtol=1e-12)
    assert winding == pytest.approx(1.0, abs=1e-12)
    assert disc == pytest.approx(disc_radius(loop), rel=1e-12)
    outside = ca.Function("f", [symbol], [disc_radius(symbol)])(loop + [3.0, 0.0])
    assert float(outside) == 0.0


def test_external_distance_parameterisation_broadcasts_over_batches():
    # A batch of centres and distances gives each its own answer, as one at a time does.
    rng = np.random.default_rng(11)
    centres = rng.uniform([0.2, -0.05, -0.05], [0.4, 0.05, 0.05], (7, 3))
    distances = rng.uniform(0.02, 0.2, 7)
    batch = magnet_centre_at(0.15, centres, distances)
    for k in range(7):
        one = magnet_centre_at(0.15, centres[k], distances[k])
        assert np.allclose(batch[k], one, rtol=0, atol=1e-15), f"point {k}"
    assert np.allclose(external_distance(0.15, batch), distances, rtol=1e-12)
