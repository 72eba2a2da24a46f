"""A field sampled on a regular grid (a bench measurement, a COMSOL grid export),
interpolated by smooth splines, on CasADi symbols.

The file (docs/formats.md) has the columns x_mm, y_mm, z_mm, bx_t, by_t, bz_t: positions
in millimetres, flux density in tesla, one row per grid node of a rectilinear grid (every
combination of the distinct x, y and z values present once, in any order), comma or
whitespace separated; a header row of those names and lines starting with ``%`` or ``#``
(COMSOL's export header) are skipped. Each component is interpolated by a tensor-product
cubic B-spline through the nodes (CasADi's ``bspline``), so B is twice
continuously differentiable and its gradient and the solvers' second derivatives exist;
the gradient is the spline's exact derivative. The spline's error for a smooth field falls
like h^4 in B and h^3 in the gradient with the grid spacing h (tests/design/fields).
Outside the grid the field is NaN, never extrapolated; :meth:`FieldMap.outside` names the
first point outside. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

import hashlib
import math
import os
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import casadi as ca
import numpy as np

from design.units import MM

__all__ = ["COLUMNS", "FieldMap", "FieldMapError", "map_field", "read_field_map"]

COLUMNS = ("x_mm", "y_mm", "z_mm", "bx_t", "by_t", "bz_t")
MIN_NODES = 4
"""Nodes per axis a cubic spline needs."""


class FieldMapError(ValueError):
    """A field-map file that cannot be read as a grid; the message names the line."""


@dataclass(frozen=True, eq=False)
class FieldMap:
    """B sampled on the grid ``axes`` (three increasing arrays of node positions, base
    frame [m]), ``flux`` of shape (nx, ny, nz, 3) [T]; ``source`` names the file. Equal
    (and hashed) by content."""

    axes: tuple[np.ndarray, np.ndarray, np.ndarray]
    flux: np.ndarray
    source: str = "<array>"
    digest: str = field(init=False)

    def __post_init__(self) -> None:
        h = hashlib.sha256()
        for a in (*self.axes, self.flux):
            h.update(np.ascontiguousarray(a, float).tobytes())
        object.__setattr__(self, "digest", h.hexdigest()[:16])

    def __eq__(self, other: object) -> bool:
        return isinstance(other, FieldMap) and other.digest == self.digest

    def __hash__(self) -> int:
        return hash(self.digest)

    @property
    def lower(self) -> np.ndarray:
        """The grid's lowest corner, base frame. [m]"""
        return np.array([a[0] for a in self.axes])

    @property
    def upper(self) -> np.ndarray:
        """The grid's highest corner, base frame. [m]"""
        return np.array([a[-1] for a in self.axes])

    @property
    def spacing(self) -> float:
        """The largest node spacing along any axis. [m]"""
        return float(max(np.diff(a).max() for a in self.axes))

    @cached_property
    def interpolant(self) -> ca.Function:
        """position (3,) [m] -> B (3,) [T], the splines (extrapolating: see
        :func:`map_field`), a call node in SX graphs. Their coefficients interpolate the
        nodes with not-a-knot ends, solved axis by axis (scipy's ``make_interp_spline``:
        the tensor product's system separates), so a 50^3 grid takes about a second."""
        from scipy.interpolate import make_interp_spline  # 0.5 s to import: maps only

        coefficients, knots = np.asarray(self.flux, float), []
        for axis, nodes in enumerate(self.axes):
            spline = make_interp_spline(nodes, coefficients, k=3, axis=axis)
            coefficients = np.moveaxis(spline.c, 0, axis)
            knots.append([float(t) for t in spline.t])
        flat = coefficients.transpose(3, 0, 1, 2).ravel(order="F").tolist()
        spline_fn = ca.Function.bspline(f"field_map_{self.digest}", knots, flat, [3, 3, 3], 3)
        p = ca.MX.sym("p", 3)
        return ca.Function(
            f"field_map_{self.digest}_call", [p], [spline_fn(p)], {"never_inline": True}
        )

    def outside(self, points: np.ndarray) -> np.ndarray | None:
        """The first of ``points`` (n, 3) [m] outside the grid, or None."""
        points = np.atleast_2d(points)
        bad = ((points < self.lower) | (points > self.upper)).any(axis=1)
        return points[np.argmax(bad)] if bad.any() else None


def map_field(offset: ca.SX, fieldmap: FieldMap) -> tuple[ca.SX, ca.SX]:
    """B (3,) [T] and G = dB/dp (3, 3) [T/m] of ``fieldmap`` at ``offset`` (3,) [m], the
    field point in the map's frame (the base frame moved by the map's centre); NaN
    outside the grid."""
    spline = fieldmap.interpolant
    p = ca.SX.sym("p", 3)
    b = spline(p)
    inside = 1
    for i in range(3):
        inside = ca.logic_and(
            inside, ca.logic_and(p[i] >= fieldmap.lower[i], p[i] <= fieldmap.upper[i])
        )
    nan = ca.DM.nan()
    g = ca.jacobian(b, p)
    fn = ca.Function(
        "map_field", [p], [ca.if_else(inside, b, nan * ca.DM.ones(3)),
                           ca.if_else(inside, g, nan * ca.DM.ones(3, 3))],
    )  # fmt: skip
    flux, grad = fn(offset)
    return flux, grad


def _rows(text: str, source: str) -> tuple[np.ndarray, list[int]]:
    """The numeric rows and their line numbers (1-based)."""
    rows, lines = [], []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped[0] in "%#":
            continue
        cells = [c for c in stripped.replace(",", " ").split() if c]
        if [c.lower() for c in cells] == list(COLUMNS):
            continue
        if len(cells) != len(COLUMNS):
            raise FieldMapError(
                f"{source} line {number}: expected {len(COLUMNS)} columns "
                f"({', '.join(COLUMNS)}); got {len(cells)}: {stripped[:60]!r}"
            )
        try:
            values = [float(c) for c in cells]
        except ValueError:
            raise FieldMapError(
                f"{source} line {number}: expected numbers; got {stripped[:60]!r}"
            ) from None
        if not all(math.isfinite(v) for v in values):
            raise FieldMapError(
                f"{source} line {number}: expected finite numbers; got {stripped[:60]!r}"
            )
        rows.append(values)
        lines.append(number)
    if not rows:
        raise FieldMapError(f"{source}: no rows of {', '.join(COLUMNS)}")
    return np.array(rows), lines


def parse_field_map(text: str, source: str = "<string>") -> FieldMap:
    """A :class:`FieldMap` from file text (columns :data:`COLUMNS`); FieldMapError names
    the line of a bad row, a node given twice or the first node missing."""
    data, lines = _rows(text, source)
    axes = [np.unique(data[:, i]) for i in range(3)]
    for name, a in zip("xyz", axes, strict=True):
        if len(a) < MIN_NODES:
            raise FieldMapError(
                f"{source}: the grid needs at least {MIN_NODES} distinct {name}_mm values "
                f"(a cubic spline); got {len(a)}"
            )
    index = [np.searchsorted(a, data[:, i]) for i, a in enumerate(axes)]
    shape = tuple(len(a) for a in axes)
    flux = np.full((*shape, 3), np.nan)
    seen = np.full(shape, -1)
    for row, (i, j, k) in enumerate(zip(*index, strict=True)):
        if seen[i, j, k] >= 0:
            raise FieldMapError(
                f"{source} line {lines[row]}: node ({data[row, 0]:g}, {data[row, 1]:g}, "
                f"{data[row, 2]:g}) mm is also on line {lines[seen[i, j, k]]}"
            )
        seen[i, j, k] = row
        flux[i, j, k] = data[row, 3:]
    missing = np.argwhere(seen < 0)
    if len(missing):
        i, j, k = missing[0]
        raise FieldMapError(
            f"{source}: the grid has no row for the node ({axes[0][i]:g}, {axes[1][j]:g}, "
            f"{axes[2][k]:g}) mm ({len(missing)} of {seen.size} nodes missing); a regular "
            "grid needs every combination of its x, y and z values"
        )
    return FieldMap((axes[0] * MM, axes[1] * MM, axes[2] * MM), flux, source)


def read_field_map(path: str | os.PathLike[str]) -> FieldMap:
    """Read a field-map file (:func:`parse_field_map`); FieldMapError if it cannot be
    read."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FieldMapError(f"field map {p} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise FieldMapError(f"field map {p} cannot be read: {exc}") from None
    return parse_field_map(text, str(p))


def write_field_map(path: str | os.PathLike[str], axes, flux: np.ndarray, digits: int = 17) -> None:
    """Write B (nx, ny, nz, 3) [T] on the grid ``axes`` [m] as a field-map file, each
    number to ``digits`` significant digits (17: exactly)."""
    from design.atomic import write_text

    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3) / MM
    rows = np.c_[grid, np.asarray(flux).reshape(-1, 3)]
    body = "\n".join(",".join(f"{v:.{digits}g}" for v in row) for row in rows)
    write_text(path, ",".join(COLUMNS) + "\n" + body + "\n")
