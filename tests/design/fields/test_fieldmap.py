"""Field maps (design.fields.fieldmap): a map sampled from an analytic source reproduces
its field and gradient inside the grid at the splines' order in the grid spacing, COMSOL
data of a real magnet through the map reader, points outside refused, bad files named by
line."""

from __future__ import annotations

import os
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from field_sources import evaluate

from design.fields.fieldmap import (
    FieldMap,
    FieldMapError,
    map_field,
    parse_field_map,
    read_field_map,
    write_field_map,
)

SEED = int(os.environ.get("RINGPAIR_SEED", np.random.SeedSequence().entropy % 2**32))
DATA = Path(
    os.environ.get("RINGPAIR_SHARED_DATA", Path(__file__).parents[3] / ".." / "shared" / "data")
)
COIL = {"radius": 0.05, "turns": 100.0, "current": 2.0, "center": np.zeros(3),
        "axis": np.array([0.3, 0.0, 0.9539392014169456])}  # fmt: skip


def grid(lower, upper, n):
    return tuple(np.linspace(lo, hi, n) for lo, hi in zip(lower, upper, strict=True))


def sampled(kind, q, axes) -> FieldMap:
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    flux, _ = evaluate(kind, q, nodes)
    return FieldMap(axes, flux.reshape(*(len(a) for a in axes), 3))


def map_evaluate(fieldmap, points):
    p = ca.SX.sym("p", 3)
    b, g = map_field(p, fieldmap)
    flux, grad = ca.Function("f", [p], [b, g]).map(len(points))(points.T)
    n = len(points)
    return np.array(flux).T, np.array(grad).reshape(3, n, 3).transpose(1, 0, 2)


# Cubic B-splines through the nodes: B's error falls like h^4 and the gradient's like h^3
# (de Boor, A Practical Guide to Splines, 2001, ch. XVII); measured on a coil's field in a
# box of 0.6 radii about its centre at 9, 17 and 33 nodes per axis (h = 3.75, 1.9, 0.94 mm).
def test_map_of_a_coil_converges_at_the_splines_order_in_the_grid_spacing():
    rng = np.random.default_rng(SEED)
    print(f"seed {SEED}")
    lower, upper = np.full(3, -0.015), np.full(3, 0.015)
    points = rng.uniform(lower, upper, (300, 3))
    exact_b, exact_g = evaluate("coil", COIL, points)
    errors = []
    for n in (9, 17, 33):
        flux, grad = map_evaluate(sampled("coil", COIL, grid(lower, upper, n)), points)
        errors.append(
            (np.abs(flux - exact_b).max() / np.abs(exact_b).max(),
             np.abs(grad - exact_g).max() / np.abs(exact_g).max())
        )  # fmt: skip
    errors = np.array(errors)
    order = np.log2(errors[:-1] / errors[1:])
    overall = np.log2(errors[0] / errors[-1]) / 2
    print("relative errors (B, G) at h = 3.75, 1.875, 0.94 mm:", errors, "orders", order)
    # cubic splines: B converges as h^4, its gradient as h^3. The largest error over random
    # points makes one halving's order noisy (16 seeds: B 3.3-5.1, G 2.7-4.0), the order
    # over both halvings less so (B 3.7-4.7, G 3.1-3.9): every halving at least h^2, both
    # together near the theory
    assert (order > 2).all()
    assert overall[0] > 3.5 and overall[1] > 2.8
    # at h = a / 53 (0.94 mm for a 50 mm coil): B to 2e-6, G to 2e-4 of their largest
    # value (measured 6e-7 and 7e-5)
    assert errors[-1, 0] < 2e-6 and errors[-1, 1] < 2e-4


def test_points_outside_the_grid_are_nan_and_named():
    axes = grid([-0.01] * 3, [0.01] * 3, 5)
    fieldmap = sampled("coil", COIL, axes)
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0105, 0.0], [0.01, 0.01, 0.01]])
    flux, grad = map_evaluate(fieldmap, points)
    assert np.isfinite(flux[[0, 2]]).all() and np.isnan(flux[1]).all()
    assert np.isnan(grad[1]).all()
    np.testing.assert_array_equal(fieldmap.outside(points), points[1])
    assert fieldmap.outside(points[[0, 2]]) is None


def test_written_map_reads_back_and_bad_files_name_their_line(tmp_path):
    axes = grid([-0.01] * 3, [0.01] * 3, 4)
    fieldmap = sampled("coil", COIL, axes)
    path = tmp_path / "field.csv"
    write_field_map(path, axes, fieldmap.flux)
    again = read_field_map(path)
    assert again == fieldmap
    lines = path.read_text().splitlines()
    with pytest.raises(FieldMapError, match=r"no row for the node \(10, 10, 10\) mm"):
        parse_field_map("\n".join(lines[:-1]), "f.csv")
    with pytest.raises(FieldMapError, match="f.csv line 66: node .* also on line 2"):
        parse_field_map("\n".join([*lines, lines[1]]), "f.csv")
    bad = lines.copy()
    bad[7] = bad[7].rsplit(",", 1)[0] + ",nan"
    with pytest.raises(FieldMapError, match="f.csv line 8: expected finite numbers"):
        parse_field_map("\n".join(bad), "f.csv")
    bad[7] = "1,2,3"
    with pytest.raises(FieldMapError, match="f.csv line 8: expected 6 columns"):
        parse_field_map("\n".join(bad), "f.csv")
    with pytest.raises(FieldMapError, match="at least 4 distinct z_mm"):
        parse_field_map("\n".join(r for r in lines if r.split(",")[2] != "10"), "f.csv")


def _comsol(name):
    folder = DATA / "kim2022-4inch-n52"
    if not folder.is_dir():
        pytest.skip(f"third-party data not found at {folder.resolve()}")
    data = np.loadtxt(folder / name, comments="%")
    keep = data[:, 0] <= 100.0  # beyond ~150 mm COMSOL's outer boundary bends the field
    return data[keep, 0] * 1e-3, data[keep, 1]


# Kim et al., Sci. Robot. 7, eabg9907 (2022), supplementary data S1: COMSOL on-axis |B|
# [mT] and |dB_z/dz| [T/m] of an N52 cylinder 101.6 mm x 101.6 mm. A grid about its axis
# (sampled from the exact cylinder of 1 T, written with a COMSOL-style header), read by
# the map reader and scaled by one least-squares remanence, reproduces both: |B| within
# 0.5 % to 80 mm, 1 % to 100 mm, the gradient within 1 %.
def test_comsol_field_of_a_4inch_n52_magnet_through_the_map_reader(tmp_path):
    distance, b_mt = _comsol("Flux_Density_B.txt")
    distance_g, g_tm = _comsol("Gradient_Bz_z_South.txt")
    size = 0.1016
    q = {"diameter": size, "length": size, "remanence": 1.0, "center": np.zeros(3),
         "magnetization": np.array([0.0, 0.0, 1.0])}  # fmt: skip
    axes = (np.linspace(-0.01, 0.01, 5), np.linspace(-0.01, 0.01, 5),
            np.arange(size / 2, size / 2 + 0.1025, 0.0025))  # fmt: skip
    path = tmp_path / "comsol.txt"
    write_field_map(path, axes, sampled("cylinder", q, axes).flux)
    path.write_text("% Model: exported grid\n% Dimension: 3\n" + path.read_text())
    fieldmap = read_field_map(path)
    points = np.c_[0 * distance, 0 * distance, size / 2 + distance]
    shape = np.linalg.norm(map_evaluate(fieldmap, points)[0], axis=1)
    remanence = shape @ (b_mt * 1e-3) / (shape @ shape)
    assert 1.43 < remanence < 1.45
    error = np.abs(remanence * shape / (b_mt * 1e-3) - 1)
    assert error.max() < 0.01 and error[distance <= 0.08].max() < 0.005
    points = np.c_[0 * distance_g, 0 * distance_g, size / 2 + distance_g]
    _, grad = map_evaluate(fieldmap, points)
    assert np.abs(remanence * np.abs(grad[:, 2, 2]) / g_tm - 1).max() < 0.01
