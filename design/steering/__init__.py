"""Steering: the ring angles that put the tip where the user wants it.

The forward map is the state (:func:`design.equilibrium.solve_equilibria`: each
configuration's stable equilibrium reached by the load ramp) and its tip. Steering
inverts the tip's lateral position (y, z), base frame, as a function of the two ring
angles: two angles, two coordinates, so a target inside the workspace has isolated
solutions, in general more than one (the rings' moments add as two vectors, and the
same sum is reached with them mirrored about it).

Where the state is a regular stable equilibrium, the tip is a smooth function of the
angles with the exact derivative of the implicit function theorem,
d tip / d theta = dP/dtheta - dP/dx (dr/dx)^-1 dr/dtheta (r the model's residual, P its
pose; :func:`_sensitivity`, compiled from the model's own expressions).

For a batch of targets: the state and its tip are solved on a grid of ring angles
(SEED_STEP), each cell split into two triangles, and the grid's piecewise-linear map is
inverted: every triangle whose image holds a target gives a start, the angles and the
state interpolated (:func:`_interpolated_seeds`). From there Newton on the state and the
angles together (the model's residual and the tip's distance to the target: n + 2
equations in n + 2 unknowns, exact Jacobian compiled from the model's own expressions,
:func:`_inverse_step`) converges in a few steps, the whole batch in one mapped call per
step, each start leaving the batch as it converges or joins another. The map from the
angles (a torus) to the plane has degree zero, so a target's regular solutions come in
pairs of opposite orientation (the sign of det d tip / d theta): where one is missing,
each solution's angles swapped start once more (alike rings swapped give nearly the same
net moment: the pair of solutions that merges at the workspace's rim, too close together
for the grid). A target is settled where its solutions pair up, each one solved on its
own as every caller solves it (the load ramp) lands on it, and the grid resolves the map
about it (no corner nearby without a state or after a snap).

The other targets (out of reach, snaps, the map unresolved) are searched: every local
minimum of the distance to the target on the grid (the angles are periodic) seeds a
Levenberg-Marquardt iteration on the angles (Nocedal & Wright, *Numerical Optimization*,
2006, sec. 10.3), each trial angle pair solved for its state as every caller solves it;
so do the rim's closest points, offset to either side of parallel rings
(:func:`_rim_seeds`), and each result's angles swapped.
Solutions whose angles agree to SAME_ANGLE are one. A solution reaches its target when the
tip is within REACHED of it; a target that no seed reaches gets the closest point found,
flagged ``reached = False`` (out of reach, or only reached through a snap).

Each solution carries its state's flags (``snapped``: the ramp to it passed a fold;
``multistable``: another stable state exists at those angles) and its **fold margin**: the
smallest real part of an eigenvalue of K^-1 dr/dx, K the unloaded robot's dr/dx (1 for the
unloaded robot, 0 at a fold, where the robot snaps). SI units throughout (m, rad).

The package: :mod:`~design.steering.settings`, :mod:`~design.steering.grid` (the forward
map on a grid of ring angles and its inverse), :mod:`~design.steering.newton` (Newton on
state and angles) and :mod:`~design.steering.search` (the search and :func:`steer`).
"""

from __future__ import annotations

from design.steering.search import Steering, steer
from design.steering.settings import (
    CONVERGED,
    EDGE,
    FOLD_BAND,
    MAX_DAMPING,
    MAX_ITERATIONS,
    MAX_SEEDS,
    MAX_TURN,
    MERGE,
    NEWTON_ITERATIONS,
    REACHED,
    RIM_OFFSET,
    RIM_SEEDS,
    RIM_STEP,
    SAME_ANGLE,
    SEED_MERGE,
    SEED_STEP,
    SEEDS,
    SWAP_NEAR,
)

__all__ = [
    "CONVERGED",
    "EDGE",
    "FOLD_BAND",
    "MAX_DAMPING",
    "MAX_ITERATIONS",
    "MAX_SEEDS",
    "MAX_TURN",
    "MERGE",
    "NEWTON_ITERATIONS",
    "REACHED",
    "RIM_OFFSET",
    "RIM_SEEDS",
    "RIM_STEP",
    "SAME_ANGLE",
    "SEEDS",
    "SEED_MERGE",
    "SEED_STEP",
    "SWAP_NEAR",
    "Steering",
    "steer",
]
