"""Steering's grid spacings, seeds, tolerances and iteration limits. SI units (m, rad)."""

from __future__ import annotations

import numpy as np

SEED_STEP = np.deg2rad(5.0)
"""Spacing of the grid of ring angles whose interpolated map starts Newton (and whose
local minima of the distance to a target seed the search). [rad]"""
SEEDS = 6
MAX_SEEDS = 24
"""Grid seeds per target: the SEEDS closest local minima, and more (up to MAX_SEEDS) where
they are closer than the grid resolves."""
RIM_STEP = np.deg2rad(2.0)
RIM_SEEDS = 2
RIM_OFFSET = np.deg2rad(1.0)
"""The rim of the workspace (the rings parallel) is sampled every RIM_STEP; its RIM_SEEDS
closest local minima to a target (within the seed grid's resolution of it) seed iterations
at RIM_OFFSET and 4 RIM_OFFSET to either side of parallel. [rad]"""
REACHED = 1e-9
"""A target is reached when the tip is this close to it. [m]"""
SAME_ANGLE = 1e-6
"""Two solutions are one when both ring angles agree to this. [rad]"""
MAX_TURN = 0.3
"""Largest change of a ring angle per iteration (keeps the iteration near its branch).
[rad]"""
SWAP_NEAR = np.deg2rad(5.0)
"""A solution's swapped angles seed one more iteration unless they are this close to a
solution already found (alike rings: the swap is nearly the mirror solution). [rad]"""
SEED_MERGE = np.deg2rad(1.0)
"""Grid seeds of one target that one Newton step brings this close are one. [rad]"""
MERGE = 1e-3
"""Iterations of one target whose angles come this close are merged (they go on to the
same solution). [rad]"""
MAX_ITERATIONS = 80
"""Levenberg-Marquardt iterations per seed at most."""
MAX_DAMPING = 1e8
"""Damping beyond which no step lowers the distance: the closest point is found."""

NEWTON_ITERATIONS = 12
"""Newton iterations on (state, angles) per seed at most (from an interpolated start they
converge in three to five)."""
CONVERGED = 1e-12
"""Newton on (state, angles) has converged where every residual (the model's, m or rad,
and the tip's distance to the target, m) is below this."""
EDGE = 1e-9
"""A target on a grid triangle's edge (barycentric coordinate down to -EDGE) is in it."""
FOLD_BAND = 4.0
"""Safety factor on the estimated reach of the map beyond a folded grid triangle's image
(where a target's solutions may lie between the grid's points)."""
