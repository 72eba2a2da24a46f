"""Workspace of the ring pair: sweep (theta1, theta2) and measure the reachable tip set.

Geometry of the reachable set. The configuration space is a torus (theta1, theta2). Along
the parallel line theta1 = theta2 the rings add, along the antiparallel line they cancel;
these two loops split the torus into two annuli with the same image boundary, so the tip
positions fill the region between the image of the parallel rings (the outer loop) and the
image of the antiparallel rings (the neutral loop, a point when the rings sit at the same
place, a small loop around the home when the spacing puts the distal ring in a
different field). The measures are taken about the robot's home (:mod:`design.home`: the
state with the rings antiparallel, theta1 = pi, theta2 = 0, gravity and the printed tip
included), where it sits when it is meant to be neutral:

- ``disc_radius``: radius of the largest disc about the home inside the outer loop: the
  distance from the home to the nearest arc of the smooth curve through the loop's
  samples (:func:`design.geometry.curve_disc_radius`, the NLP's measure too, so that its
  few samples and the sweep's many agree). It measures size and symmetry in one number
  (an elongated or off-centre workspace has a small disc). :mod:`design.controllable`
  caps it by what can be steered to from home without a snap, the one disc number a
  design is judged by.
- ``droop``: the home's distance from the straight, weightless tip.
- ``reach``: how far the reachable tips extend beyond the home towards +y, -y, +z, -z.
- ``straight_disc_radius``: the same disc about the straight, weightless tip (the measure
  before the home; for a robot hanging along gravity the two agree).
- ``neutral_deflection``: the largest deflection of an antiparallel-ring tip from the
  straight tip, i.e. how far from straight the robot stays when it is meant to be
  neutral (the droop and the neutral loop's spread together).
- ``boundary_excess``: how far any grid configuration reaches beyond the outer loop
  (zero when the parallel rings do trace the boundary, as argued above).

SI units are used for all inputs and outputs; angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.equilibrium import Equilibria, solve_equilibria
from design.geometry import curve_disc_radius, winding_number
from design.home import Home, solve_home
from design.model import RingPairModel
from design.records import Design

LOOP_SAMPLES = 720


@dataclass(frozen=True)
class Workspace:
    """Reachable tip set of one design and its metrics.

    grid : states of the (theta1, theta2) grid, theta1 varying slowest.
    parallel : equilibria with theta1 = theta2 over [0, 2 pi) (the outer loop).
    antiparallel : equilibria with theta1 = theta2 + pi over [0, 2 pi) (the neutral loop).
    home : the robot's home (:mod:`design.home`).
    rest_position : shape (3,), the straight, weightless tip, base frame. [m]
    y_range, z_range : (min, max) deflection from the straight tip along y and z over the
        reachable set. [m]
    max_deflection : largest |tip - straight tip| over the reachable set. [m]
    max_direction : shape (3,), unit direction of that deflection, base frame. [-]
    max_angles : (theta1, theta2) of that configuration. [rad]
    disc_radius : largest disc about the home inside the outer loop. [m]
    straight_disc_radius : the same about the straight tip. [m]
    reach : (+y, -y, +z, -z) extent of the reachable set beyond the home. [m]
    neutral_deflection : largest deflection with antiparallel rings (from the straight
        tip). [m]
    boundary_excess : reach of grid points beyond the outer loop (0 if none). [m]
    """

    grid: Equilibria
    parallel: Equilibria
    antiparallel: Equilibria
    home: Home
    rest_position: np.ndarray
    y_range: tuple[float, float]
    z_range: tuple[float, float]
    max_deflection: float
    max_direction: np.ndarray
    max_angles: tuple[float, float]
    disc_radius: float
    straight_disc_radius: float
    reach: tuple[float, float, float, float]
    neutral_deflection: float
    boundary_excess: float

    @property
    def droop(self) -> float:
        """The home's distance from the straight, weightless tip. [m]"""
        return self.home.droop

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


class NoWorkspace(ValueError):
    """A design whose sweep has nothing to measure: no grid configuration has a stable
    state, or the robot has no home. The message says which and why."""


def _common_failure(eq: Equilibria) -> str:
    """The most frequent reason in ``eq.failure`` of the rows without a state."""
    reasons = [str(r) for r in eq.failure[~eq.stable] if r]
    return max(set(reasons), key=reasons.count) if reasons else "no reason recorded"


def _loop_radius(loop: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Radius of a star-shaped closed loop (S, 2) around the origin in polar ``angles``."""
    phi = np.arctan2(loop[:, 1], loop[:, 0])
    order = np.argsort(phi)
    phi, r = phi[order], np.linalg.norm(loop, axis=1)[order]
    return np.interp(angles, phi, r, period=2 * np.pi)


def workspace_metrics(
    grid: Equilibria, parallel: Equilibria, antiparallel: Equilibria, home: Home
) -> Workspace:
    """Measure a swept workspace about ``home`` (module docstring for the definitions);
    :class:`NoWorkspace` where there is nothing to measure."""
    rest_position = home.straight
    reach = grid.position[grid.stable] - rest_position
    if reach.shape[0] == 0:
        raise NoWorkspace(
            f"none of the {len(grid)} configurations of the grid has a stable state (most "
            f"often: {_common_failure(grid)})"
        )
    if not np.isfinite(home.position).all():
        raise NoWorkspace(f"the robot has no home state: {home.state.failure[0]}")
    dist = np.linalg.norm(reach, axis=1)
    # Ties (an axisymmetric set-up) resolve to the first grid configuration, not to noise.
    i = int(np.flatnonzero(dist >= dist.max() * (1 - 1e-9))[0])
    stable_theta = grid.command[grid.stable]
    outer_ok = parallel.stable
    outer = (parallel.position[outer_ok] - rest_position)[:, 1:]
    centre = (home.position - rest_position)[1:]
    excess = float("nan")
    if outer.shape[0] >= 3 and winding_number(outer - centre) != 0:
        about = reach[:, 1:] - centre
        polar = np.arctan2(about[:, 1], about[:, 0])
        radial = np.linalg.norm(about, axis=1)
        excess = float(max(0.0, np.max(radial - _loop_radius(outer - centre, polar))))
    neutral = antiparallel.position[antiparallel.converged] - rest_position
    around = reach[:, 1:] - centre
    return Workspace(
        grid=grid,
        parallel=parallel,
        antiparallel=antiparallel,
        home=home,
        rest_position=rest_position,
        y_range=(float(reach[:, 1].min()), float(reach[:, 1].max())),
        z_range=(float(reach[:, 2].min()), float(reach[:, 2].max())),
        max_deflection=float(dist[i]),
        max_direction=reach[i] / max(dist[i], 1e-300),
        max_angles=(float(stable_theta[i, 0]), float(stable_theta[i, 1])),
        disc_radius=curve_disc_radius(outer - centre),
        straight_disc_radius=curve_disc_radius(outer),
        reach=(
            float(around[:, 0].max()),
            float(-around[:, 0].min()),
            float(around[:, 1].max()),
            float(-around[:, 1].min()),
        ),
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
    return sweep(model, model.parameters(design), design.robot.free_length, step, multistable)


def _torus(g: int) -> np.ndarray:
    """Each node's four neighbours on the g x g grid of ring angles (periodic), shape
    (g * g, 4)."""
    index = np.arange(g * g).reshape(g, g)
    moves = [np.roll(index, s, axis=a).ravel() for a in (0, 1) for s in (1, -1)]
    return np.stack(moves, axis=1)


def sweep(
    model: RingPairModel,
    params: np.ndarray,
    free_length: float,
    step: float,
    multistable: bool = False,
) -> Workspace:
    """:func:`sweep_workspace` of the robot with parameter vector ``params`` in ``model``,
    ``free_length`` [m] placing the straight tip."""
    angles = angle_grid(step)
    t1, t2 = np.meshgrid(angles, angles, indexing="ij")
    grid = solve_equilibria(
        model,
        params,
        t1.ravel(),
        t2.ravel(),
        multistable=multistable,
        neighbours=_torus(len(angles)),
    )
    loop = angle_grid(2 * np.pi / LOOP_SAMPLES)
    parallel = solve_equilibria(model, params, loop, loop)
    antiparallel = solve_equilibria(model, params, loop + np.pi, loop)
    home = solve_home(model, params, free_length)
    return workspace_metrics(grid, parallel, antiparallel, home)
