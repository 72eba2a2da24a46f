"""The controllable workspace: the tip positions the robot can be steered to from its home
(:mod:`design.home`) without snapping, and the one disc number a design is judged by.

On the grid of ring angles (the torus (theta1, theta2), spacing ``step``) each node has
its state (:func:`design.equilibrium.solve_equilibria`). Two neighbouring nodes are
linked, one way, when driving the rings from one to the other
(:func:`design.equilibrium.drive`: the state continued in sub-steps, never across a fold)
ends in the other's state. The robot starts at its home: the rings antiparallel, the
grid's node at (pi, 0). The nodes reachable from there along links are the controllable
configurations; where a link is missing the robot snaps (or lands in another state than
the one it would reach on its own), and what lies behind only through such links is
reachable only by snapping.

Metrics:

- ``covered_disc_radius``: radius of the largest disc about the home inside the outer
  rim of the images of the grid cells whose four corners are controllable (rasterised at
  PIXELS across the tips' extent; holes enclosed by them, like the one inside the neutral
  loop, do not count), to the raster's ``resolution`` (the grid's chord and two pixels);
- ``disc_radius``, **the disc**: the disc about the home the robot can be steered over
  without a snap. Where the controllable cells cover the workspace's disc
  (:attr:`design.workspace.Workspace.disc_radius`, the loop's smooth curve about home) to
  the raster's resolution, that disc; else the covered disc. Never larger than the
  workspace's disc; the NLP's disc (which keeps its loops free of snaps) is the same
  measure, so the two agree where the optimum is steerable;
- ``fraction``: the share of the grid's configurations that are controllable.

SI units (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import label

from design.equilibrium import Equilibria, drive
from design.home import HOME_COMMAND
from design.model import RingPairModel
from design.workspace import Workspace, angle_grid, sweep

SAME = 1e-6
"""A driven state is a node's own when their unknowns agree to this, over their scale. [-]"""
PIXELS = 400
"""Raster across the controllable tips' extent for the disc radius."""


@dataclass(frozen=True)
class Controllable:
    """The controllable part of a grid of ring angles.

    angles : shape (G,), the grid's angles for either ring. [rad]
    controllable : shape (G, G), node (i, j) at (angles[i], angles[j]) is controllable.
    linked : shape (4, G, G), the link from each node towards +theta1, -theta1, +theta2,
        -theta2 holds.
    position : shape (G, G, 3), each node's tip (NaN without a state). [m]
    centre : shape (3,), the home's tip the discs are about. [m]
    covered_disc_radius : largest disc about the home covered by controllable cells. [m]
    resolution : how far the covered disc may fall short of a fully covered one (the
        grid's chord at the tips' extent and two raster pixels). [m]
    disc_radius : the disc (module docstring). [m]
    fraction : share of the grid's nodes that are controllable. [-]
    """

    angles: np.ndarray
    controllable: np.ndarray
    linked: np.ndarray
    position: np.ndarray
    centre: np.ndarray
    covered_disc_radius: float
    resolution: float
    disc_radius: float
    fraction: float


MOVES = ((1, 0), (-1, 0), (0, 1), (0, -1))
"""Neighbour offsets in (theta1, theta2) grid index: +theta1, -theta1, +theta2, -theta2."""


def controllable_workspace(
    model: RingPairModel,
    params: np.ndarray,
    grid: Equilibria,
    angles: np.ndarray,
    centre: np.ndarray,
    workspace_disc: float | None = None,
) -> Controllable:
    """The controllable configurations of ``grid``, the states at the angle pairs of
    ``angles`` x ``angles`` (meshgrid, 'ij' indexing, raveled, as
    :func:`design.workspace.sweep_workspace` solves them) (module docstring).
    centre : the home's tip, shape (3,) (:attr:`design.home.Home.position`). [m]
    workspace_disc : the workspace's disc about it (:attr:`Workspace.disc_radius`); without
        it the disc is the covered one. [m]"""
    g = len(angles)
    if len(grid) != g * g:
        raise ValueError(f"the grid has {len(grid)} states, expected {g} x {g}")
    params = np.asarray(params, float)
    x = grid.unknowns.reshape(g, g, -1)
    stable = grid.stable.reshape(g, g)
    index = np.indices((g, g))
    linked = np.zeros((4, g, g), bool)
    scale = model.unknown_scale(params)[:, None]
    for k, (di, dj) in enumerate(MOVES):
        ti, tj = (index[0] + di) % g, (index[1] + dj) % g
        both = stable & stable[ti, tj]
        a = np.flatnonzero(both)
        if a.size == 0:
            continue
        i, j = np.unravel_index(a, (g, g))
        start = np.vstack([angles[i], angles[j]])
        end = start + np.vstack([di, dj]) * (2 * np.pi / g)
        # The neighbour's state is at its angles (the command is periodic in 2 pi, the
        # unknowns are ring angles with torsion: shift them by the same turn).
        target = x[ti.ravel()[a], tj.ravel()[a]].T.copy()
        if model.n_unknowns > model.n_rod:
            target[model.n_rod :] += end - np.vstack([angles[ti.ravel()[a]], angles[tj.ravel()[a]]])
        driven, ok = drive(model, params, x[i, j].T, start, end)
        same = np.max(np.abs(driven - target) / scale, axis=0) <= SAME
        linked[k].ravel()[a] = ok & same
    controllable = _reached(linked, _home_node(angles) & stable)
    position = np.where(stable[:, :, None], grid.position.reshape(g, g, 3), np.nan)
    centre = np.asarray(centre, float)
    covered, pixel, extent = _covered_disc(position, controllable, centre)
    resolution = extent * (1 - np.cos(np.pi / g)) + 2 * pixel
    disc = covered
    if workspace_disc is not None and covered >= workspace_disc - resolution:
        disc = float(workspace_disc)
    return Controllable(
        angles=angles,
        controllable=controllable,
        linked=linked,
        position=position,
        centre=centre,
        covered_disc_radius=covered,
        resolution=float(resolution),
        disc_radius=float(min(disc, workspace_disc)) if workspace_disc is not None else disc,
        fraction=float(controllable.mean()),
    )


def _home_node(angles: np.ndarray) -> np.ndarray:
    """The grid's node nearest the home's command (theta1, theta2) = HOME_COMMAND."""
    g = len(angles)
    start = np.zeros((g, g), bool)
    turn = 2 * np.pi
    i, j = (int(np.argmin(np.abs((angles - a + np.pi) % turn - np.pi))) for a in HOME_COMMAND)
    start[i, j] = True
    return start


def _reached(linked: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Nodes reachable from ``start`` along ``linked`` (breadth first, on the torus)."""
    reached = start.copy()
    frontier = start.copy()
    while frontier.any():
        new = np.zeros_like(reached)
        for k, (di, dj) in enumerate(MOVES):
            new |= np.roll(frontier & linked[k], (di, dj), axis=(0, 1))
        frontier = new & ~reached
        reached |= new
    return reached


def _covered_disc(
    position: np.ndarray, controllable: np.ndarray, rest: np.ndarray
) -> tuple[float, float, float]:
    """Largest disc about ``rest`` (y, z) inside the outer rim of the images of the grid
    cells whose four corners are controllable: the distance from it to the nearest raster
    pixel that no such cell covers and that is open to the outside; the pixel; the
    raster's half-width. [m]"""
    ok = controllable & np.isfinite(position).all(axis=2)
    cell = ok & np.roll(ok, -1, 0) & np.roll(ok, -1, 1) & np.roll(ok, (-1, -1), (0, 1))
    if not cell.any():
        return 0.0, 0.0, 0.0
    tip = position[:, :, 1:] - rest[1:]
    corners = [tip, np.roll(tip, -1, 0), np.roll(tip, (-1, -1), (0, 1)), np.roll(tip, -1, 1)]
    quads = np.stack([c[cell] for c in corners], axis=1)  # (C, 4, 2)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    extent = np.abs(quads).max() * 1.05
    pixel = 2 * extent / PIXELS
    centres = (np.arange(PIXELS) + 0.5) * pixel - extent
    covered = np.zeros((PIXELS, PIXELS), bool)
    for a, b, c in triangles:
        lo = np.floor((np.minimum(np.minimum(a, b), c) + extent) / pixel).astype(int)
        hi = np.ceil((np.maximum(np.maximum(a, b), c) + extent) / pixel).astype(int)
        lo, hi = np.clip(lo, 0, PIXELS), np.clip(hi, 0, PIXELS)
        py, pz = np.meshgrid(centres[lo[0] : hi[0]], centres[lo[1] : hi[1]], indexing="ij")
        covered[lo[0] : hi[0], lo[1] : hi[1]] |= _inside(np.stack([py, pz], -1), a, b, c)
    # Uncovered pixels enclosed by covered ones (the hole inside the neutral loop) are not
    # the rim: like the workspace's disc radius, only what is open to the outside counts.
    pieces, _ = label(~covered)
    open_pieces = np.unique(np.concatenate([pieces[0], pieces[-1], pieces[:, 0], pieces[:, -1]]))
    outside = np.isin(pieces, open_pieces[open_pieces > 0])
    py, pz = np.meshgrid(centres, centres, indexing="ij")
    gap = np.hypot(py, pz)[outside]
    # rest lies on a pixel corner: an uncovered pixel there (at pixel / sqrt(2), which
    # rounding made 4e-20 m more than that) means no disc at all
    if not gap.size:
        disc = float(extent)
    else:
        disc = 0.0 if gap.min() < pixel else float(gap.min() - pixel / np.sqrt(2))
    return disc, float(pixel), float(extent)


def steerable(ws: Workspace, model: RingPairModel, params: np.ndarray) -> Controllable:
    """The controllable workspace of a swept workspace ``ws`` (its grid, about its home,
    capped by its disc): :func:`controllable_workspace`."""
    g = int(round(np.sqrt(len(ws.grid))))
    angles = angle_grid(2 * np.pi / g)
    return controllable_workspace(model, params, ws.grid, angles, ws.home.position, ws.disc_radius)


def controllable_disc_radius(
    model: RingPairModel, params: np.ndarray, free_length: float, step: float
) -> float:
    """The disc: the disc about the home that the robot can be steered over from home
    without a snap (module docstring), on a grid of ring angles of spacing ``step``
    [rad]; ``free_length`` [m] places the straight tip. [m]"""
    return steerable(sweep(model, params, free_length, step), model, params).disc_radius


def _inside(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Whether points p (..., 2) lie in the triangle abc (either orientation; edges count)."""

    def side(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return (v[0] - u[0]) * (p[..., 1] - u[1]) - (v[1] - u[1]) * (p[..., 0] - u[0])

    s1, s2, s3 = side(a, b), side(b, c), side(c, a)
    return ((s1 >= 0) & (s2 >= 0) & (s3 >= 0)) | ((s1 <= 0) & (s2 <= 0) & (s3 <= 0))
