"""Workspace of the ring pair: sweep (theta1, theta2) and measure the reachable tip set.

Geometry of the reachable set. The configuration space is a torus (theta1, theta2). Along
the parallel line theta1 = theta2 the rings add, along the antiparallel line they cancel;
these two loops split the torus into two annuli with the same image boundary, so the tip
positions fill the region between the image of the parallel rings (the outer loop) and the
image of the antiparallel rings (the neutral loop, a point when the rings sit at the same
place, a small loop around the rest position when the spacing puts the distal ring in a
different field). Metrics:

- ``disc_radius``: radius of the largest disc around the rest position (the unloaded,
  straight tip) inside the outer loop: the distance from the rest position to the loop's
  nearest side (:func:`design.geometry.disc_radius`, the NLP's measure too).
  It measures size and symmetry in one number (an elongated or off-centre workspace has
  a small disc).
- ``neutral_deflection``: the largest tip deflection with antiparallel rings, i.e. how far
  from straight the robot stays when it is meant to be neutral.
- ``boundary_excess``: how far any grid configuration reaches beyond the outer loop
  (zero when the parallel rings do trace the boundary, as argued above).

SI units are used for all inputs and outputs; angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.equilibrium import Equilibria, solve_equilibria
from design.geometry import disc_radius, rest_position, winding_number
from design.model import RingPairModel
from design.records import Design

LOOP_SAMPLES = 720


@dataclass(frozen=True)
class Workspace:
    """Reachable tip set of one design and its metrics.

    grid : states of the (theta1, theta2) grid, theta1 varying slowest.
    parallel : equilibria with theta1 = theta2 over [0, 2 pi) (the outer loop).
    antiparallel : equilibria with theta1 = theta2 + pi over [0, 2 pi) (the neutral loop).
    rest_position : shape (3,), unloaded straight tip, base frame. [m]
    y_range, z_range : (min, max) deflection along y and z over the reachable set. [m]
    max_deflection : largest |tip - rest| over the reachable set. [m]
    max_direction : shape (3,), unit direction of that deflection, base frame. [-]
    max_angles : (theta1, theta2) of that configuration. [rad]
    disc_radius : largest disc around the rest position inside the outer loop. [m]
    neutral_deflection : largest deflection with antiparallel rings. [m]
    boundary_excess : reach of grid points beyond the outer loop (0 if none). [m]
    """

    grid: Equilibria
    parallel: Equilibria
    antiparallel: Equilibria
    rest_position: np.ndarray
    y_range: tuple[float, float]
    z_range: tuple[float, float]
    max_deflection: float
    max_direction: np.ndarray
    max_angles: tuple[float, float]
    disc_radius: float
    neutral_deflection: float
    boundary_excess: float

    @property
    def reachable(self) -> np.ndarray:
        """Tip positions of the grid configurations that have a state, shape (M, 3). [m]"""
        return self.grid.position[self.grid.stable]

    @property
    def n_without_state(self) -> int:
        """Grid configurations without a state (NaN, with a reason in ``grid.failure``)."""
        return int(np.count_nonzero(~self.grid.stable))

    @property
    def n_snapped(self) -> int:
        """Grid configurations whose load ramp ended in a fold (the robot snapped)."""
        return int(np.count_nonzero(self.grid.snapped))

    @property
    def n_multistable(self) -> int:
        """Grid configurations with another stable state at the same command."""
        return int(np.count_nonzero(self.grid.multistable))


def _loop_radius(loop: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Radius of a star-shaped closed loop (S, 2) around the origin in polar ``angles``."""
    phi = np.arctan2(loop[:, 1], loop[:, 0])
    order = np.argsort(phi)
    phi, r = phi[order], np.linalg.norm(loop, axis=1)[order]
    return np.interp(angles, phi, r, period=2 * np.pi)


def workspace_metrics(
    grid: Equilibria, parallel: Equilibria, antiparallel: Equilibria, rest_position: np.ndarray
) -> Workspace:
    """Measure a swept workspace (see the module docstring for the definitions)."""
    reach = grid.position[grid.stable] - rest_position
    if reach.shape[0] == 0:
        raise ValueError("no configuration of the grid reached a stable equilibrium")
    dist = np.linalg.norm(reach, axis=1)
    # Ties (an axisymmetric set-up) resolve to the first grid configuration, not to noise.
    i = int(np.flatnonzero(dist >= dist.max() * (1 - 1e-9))[0])
    stable_theta = grid.command[grid.stable]
    outer_ok = parallel.stable
    outer = (parallel.position[outer_ok] - rest_position)[:, 1:]
    disc = disc_radius(outer)
    excess = float("nan")
    if outer.shape[0] >= 3 and winding_number(outer) != 0:
        polar = np.arctan2(reach[:, 2], reach[:, 1])
        radial = np.linalg.norm(reach[:, 1:], axis=1)
        excess = float(max(0.0, np.max(radial - _loop_radius(outer, polar))))
    neutral = antiparallel.position[antiparallel.converged] - rest_position
    return Workspace(
        grid=grid,
        parallel=parallel,
        antiparallel=antiparallel,
        rest_position=rest_position,
        y_range=(float(reach[:, 1].min()), float(reach[:, 1].max())),
        z_range=(float(reach[:, 2].min()), float(reach[:, 2].max())),
        max_deflection=float(dist[i]),
        max_direction=reach[i] / max(dist[i], 1e-300),
        max_angles=(float(stable_theta[i, 0]), float(stable_theta[i, 1])),
        disc_radius=disc,
        neutral_deflection=float(np.linalg.norm(neutral, axis=1).max())
        if len(neutral)
        else float("nan"),
        boundary_excess=excess,
    )


def angle_grid(step: float) -> np.ndarray:
    """Angles 0, step, ... below 2 pi. [rad]"""
    n = max(int(round(2 * np.pi / step)), 1)
    return np.arange(n) * (2 * np.pi / n)


def sweep_workspace(
    design: Design,
    step: float = np.deg2rad(5.0),
    model: RingPairModel | None = None,
    multistable: bool = False,
) -> Workspace:
    """Solve the (theta1, theta2) grid with spacing ``step`` [rad] and both loops, each
    configuration's state as :func:`design.equilibrium.solve_equilibria` defines it;
    ``multistable``: also look for other stable states on the grid."""
    model = model or RingPairModel()
    params = model.parameters(design)
    angles = angle_grid(step)
    t1, t2 = np.meshgrid(angles, angles, indexing="ij")
    grid = solve_equilibria(model, params, t1.ravel(), t2.ravel(), multistable=multistable)
    loop = angle_grid(2 * np.pi / LOOP_SAMPLES)
    parallel = solve_equilibria(model, params, loop, loop)
    antiparallel = solve_equilibria(model, params, loop + np.pi, loop)
    rest = rest_position(design.robot.free_length)
    return workspace_metrics(grid, parallel, antiparallel, rest)
