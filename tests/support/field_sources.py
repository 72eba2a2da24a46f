"""Numeric evaluation of the field kernels, and their magpylib twins, for the tests."""

from __future__ import annotations

import casadi as ca
import magpylib as magpy
import numpy as np
from scipy.spatial.transform import Rotation

from design.fields.sources import KINDS, source_field, split_parameters


def block(kind: str, q: dict) -> np.ndarray:
    """The parameter block of a source of ``kind`` with quantities ``q`` (SI)."""
    return np.concatenate([np.ravel(q[k.name]).astype(float) for k in KINDS[kind]])


def evaluate(kind: str, q: dict, points: np.ndarray, exact: bool = True, fieldmap=None):
    """B (n, 3) [T] and G (n, 3, 3) [T/m] of one source at points (n, 3) [m]."""
    values = block(kind, q)
    prm = ca.SX.sym("q", len(values))
    p = ca.SX.sym("p", 3)
    b, g = source_field(kind, split_parameters(kind, prm), p, exact, fieldmap)
    fn = ca.Function("f", [p, prm], [b, g])
    n = len(points)
    flux, grad = fn.map(n)(np.asarray(points, float).T, values)
    return np.array(flux).T, np.array(grad).reshape(3, n, 3).transpose(1, 0, 2)


def rotation_to(axis: np.ndarray) -> Rotation:
    """A rotation taking the local z axis to ``axis``."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    rot, _ = Rotation.align_vectors([axis], [[0.0, 0.0, 1.0]])
    return rot


def magpylib_source(kind: str, q: dict):
    """magpylib's object for the source (magpylib >= 5 is SI: polarization in T,
    dimensions in m, currents in A)."""
    if kind == "cuboid":
        return magpy.magnet.Cuboid(
            polarization=q["remanence"] * np.asarray(q["magnetization"]),
            dimension=q["dimensions"],
            position=q["center"],
        )
    if kind == "sphere":
        return magpy.magnet.Sphere(
            polarization=q["remanence"] * np.asarray(q["magnetization"]),
            diameter=q["diameter"],
            position=q["center"],
        )
    if kind == "cylinder":
        return magpy.magnet.Cylinder(
            polarization=(0, 0, q["remanence"]),
            dimension=(q["diameter"], q["length"]),
            position=q["center"],
            orientation=rotation_to(q["magnetization"]),
        )
    if kind == "coil":
        return magpy.current.Circle(
            current=q["turns"] * q["current"],
            diameter=2 * q["radius"],
            position=q["center"],
            orientation=rotation_to(q["axis"]),
        )
    raise ValueError(kind)


def unit(rng) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def draw_source(kind: str, rng) -> dict:
    """A source of ``kind`` drawn from the whole design space: sizes from 1 mm to 0.2 m
    (a cuboid's sides within 10x of each other: for flatter plates far away the rounding
    of the eight corner terms, ~1e-10 of B in ringpair and magpylib alike, makes the
    differences of magpylib's B no reference at 1e-8), remanences to 1.5 T, currents to
    5000 A turns, any direction, centre within 0.3 m."""
    size = lambda: 10 ** rng.uniform(-3, np.log10(0.2))  # noqa: E731
    centre = rng.uniform(-0.3, 0.3, 3)
    if kind == "uniform":
        return {"b": rng.normal(size=3) * 10 ** rng.uniform(-3, 0.5)}
    if kind == "coil":
        return {
            "radius": size(), "turns": float(rng.integers(1, 500)),
            "current": rng.uniform(-10, 10), "center": centre, "axis": unit(rng),
        }  # fmt: skip
    q = {"remanence": rng.uniform(0.1, 1.5), "center": centre, "magnetization": unit(rng)}
    if kind == "cuboid":  # block magnets: sides within 10x of each other
        q["dimensions"] = size() * 10 ** rng.uniform(-1, 0, 3)
    else:
        q["diameter"] = size()
    if kind == "cylinder":
        q["length"] = size()
    return q


def extent(kind: str, q: dict) -> float:
    """The source's largest dimension. [m]"""
    if kind == "cuboid":
        return float(np.linalg.norm(q["dimensions"]))
    if kind == "coil":
        return 2 * q["radius"]
    return float(np.hypot(q["diameter"], q.get("length", 0.0)))


def outside_points(kind: str, q: dict, rng, n: int) -> np.ndarray:
    """Points (n, 3) from the source's surface out to 5 extents, none within a thousandth
    of an extent of the magnet's body (of a coil's wire)."""
    size = extent(kind, q)
    out = np.empty((0, 3))
    while len(out) < n:
        direction = rng.normal(size=(2 * n, 3))
        direction /= np.linalg.norm(direction, axis=1)[:, None]
        pts = q["center"] + direction * size * rng.uniform(0.02, 5, (2 * n, 1))
        out = np.vstack([out, pts[clear(kind, q, pts) > 1e-3 * size]])
    return out[:n]


def clear(kind: str, q: dict, pts: np.ndarray) -> np.ndarray:
    """Distance of points (n, 3) to the body (the wire of a coil). [m]"""
    offset = pts - q["center"]
    if kind == "cuboid":
        return np.linalg.norm(np.maximum(np.abs(offset) - q["dimensions"] / 2, 0), axis=1)
    if kind == "sphere":
        return np.linalg.norm(offset, axis=1) - q["diameter"] / 2
    axis = np.asarray(q.get("magnetization", q.get("axis")))
    z = offset @ axis
    rho = np.linalg.norm(offset - z[:, None] * axis, axis=1)
    if kind == "coil":
        return np.hypot(z, rho - q["radius"])
    return np.hypot(
        np.maximum(np.abs(z) - q["length"] / 2, 0), np.maximum(rho - q["diameter"] / 2, 0)
    )


def richardson_gradient(get_b, points: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """dB_i/dp_j (n, 3, 3) of ``get_b`` (points (n, 3) -> B (n, 3)) by central differences
    at steps h, h / 2 and h / 4, twice Richardson-extrapolated (truncation ~ h^6)."""
    out = np.empty((len(points), 3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1.0

        def central(h, e=e):
            return (get_b(points + h * e) - get_b(points - h * e)) / (2 * h)

        d1, d2, d4 = central(steps), central(steps / 2), central(steps / 4)
        first, second = (4 * d2 - d1) / 3, (4 * d4 - d2) / 3
        out[:, :, j] = (16 * second - first) / 15
    return out
