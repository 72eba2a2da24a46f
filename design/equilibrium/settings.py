"""The equilibrium solver's tolerances and step controls, and why a row has no state.

Read as attributes of this module (``settings.TOLERANCE``) by every part of
:mod:`design.equilibrium`, so that a value changed here (a test's monkeypatch) changes it
everywhere. SI units (m or rad for unknowns; load factors dimensionless).
"""

from __future__ import annotations

import numpy as np

TOLERANCE = 1e-10
"""Convergence: infinity norm of the scaled residual below this. [m or rad]"""
RAMP_TOLERANCE = 1e-7
"""Convergence at the intermediate load factors of a ramp (only the branch is followed
there). [m or rad]"""
MAX_LOAD_STEP = 1.0
"""Largest step of the load factor lambda; the ramp's step adapts below it. [-]"""
MIN_LOAD_STEP = 2.0**-12
"""Below this step the branch is taken to end (a fold). [-]"""
CONTRACTION = 0.25
"""A ramp step is accepted only if each Newton correction is at most this fraction of the
one before (Deuflhard's contraction test: the corrector stays in the predictor's basin)."""
CORRECTION_RATIO = 0.5
MIN_CORRECTION = 0.01
"""...and if its first correction is at most CORRECTION_RATIO of the change the predictor
made, or MIN_CORRECTION (dimensionless): a corrector that lands far from the prediction
may have found another branch."""
MAX_CORRECTIONS = 8
"""Newton corrections per ramp step before the step is refused."""
LEAP_STEPS = 2
LEAP_CORRECTIONS = 4
"""Where the ramp of the linear rod needs at most LEAP_STEPS equal steps (the usual case
away from folds), its predictors, LEAP_CORRECTIONS Newton corrections per step and the
exact check at full load run in one compiled call (``leap1``, ``leap2``, ...), which
applies the ramp's own tests and returns only the verdict and the state; this halves the
time per configuration. (For the large-deflection rod the linear predictor misses by more
than half in most one-step ramps, so the adaptive ramp is as fast.)"""
TARGET_CONTRACTION = CONTRACTION / 2
"""The step control aims at this first contraction: the secant predictor's error grows
with the square of the step, and so does Newton's contraction, so the next step is the
last times sqrt(TARGET_CONTRACTION / contraction) (Deuflhard 2004, sec. 5.1.3), at most
GROWTH times larger and at least SHRINK times smaller."""
GROWTH = 4.0
SHRINK = 8.0
FIRST_DISPLACEMENT = 0.3
"""The first step of a ramp is at most so large that the tangent from rest predicts a
change of state of this much (dimensionless: unknowns over their scale, i.e. 0.3 of the
free length or 0.3 rad). [-]"""
SETTLE_OVERSHOOT = 2.0**-8
"""Past a fold the robot falls at this much more load (so that the fall has a direction).
[-]"""
RESTART_STEP = 2.0**-4
"""First ramp step after a fall. [-]"""
MAX_FALLS = 8
"""Falls (snap-throughs) per configuration before the ramp gives up."""
KICK = 1e-3
"""How far a falling robot is first moved along its softest mode (dimensionless: unknowns
over their scale). [-]"""
MODE_FLOOR = 1e-4
"""Smallest stiffness of a mode, relative to the elastic one, in the steps of a fall. [-]"""
TRUST = 0.05
"""Longest step of a fall (dimensionless). [-]"""
FALL_ITERATIONS = 400
"""Steps of one fall before it is given up."""
POLISH_ATTEMPTS = 3
"""Newton polishes of one fall that may fail to reach a stable state before it is given
up."""
POLISH_BELOW = 1e-3
POLISH_GRADIENT = 1e-3
"""A falling state is polished by Newton once its step or its downhill direction G^-1 g
is below these (dimensionless). [-]"""
HESSIAN_TOLERANCE = 1e-3
"""An eigenvalue of the large-deflection rod's energy Hessian (relative to the elastic
ones, which are of order one) below -HESSIAN_TOLERANCE is an unstable mode; closer to
zero, the constraint-like axial modes of a nearly straight rod (a single mode that has
just turned unstable shows in det dr/dx instead). [-]"""
TIE = 1e-6
"""Two falls whose distances differ by less than this fraction are a tie. [-]"""
DISTINCT = 1e-6
"""Two states differ when their unknowns differ by more than this, dimensionless. [-]"""
SUBSTEP = np.deg2rad(1.0)
"""Largest command increment per solve along a path. [rad]"""
SNAP_LAG_JUMP = 0.1
"""A change of a ring's lag (tip angle - command) larger than this within one sub-step is a
jump to another branch of equilibria (snap-through). [rad]"""
MAX_STRIDE = 4
SMOOTH_LAG_CHANGE = 0.02
"""Where the lags change by less than this per solve, the path is plainly smooth and is
followed in strides of up to MAX_STRIDE sub-steps; any larger change, instability or
failure sends it back to single sub-steps, where snaps are judged. [rad]"""
CHUNK = 4096
"""Columns per call of a mapped kernel at most. CasADi builds a map in about 4 us per
column and its first call on it pays for fresh buffers, so a batch that goes through many
sizes (a ramp's or Newton's shrinking batches) spends more building maps than solving
with large chunks; at this size a batch costs 3 % more CPU warm and the sizes built are
few (steering's benchmark: 1.6 -> 0.86 s CPU for 10,000 targets, 65,536 before)."""
GRAIN = 1024
PATH_CORRECTIONS = 4
"""Newton corrections per call of the path's corrector (``corrections``, one call in place
of as many from Python, whose overhead is most of a correction's cost: 1.2 us of the
baseline rod's 8.8 per evaluation); a path's sub-step mostly converges in three, and
another call goes on where it does not."""

FAILURES = {
    "fold": "the load ramp ended in a fold and the robot found no stable state to fall into",
    "falls": f"the robot snapped more than {MAX_FALLS} times on the load ramp",
    "unstable": "no stable state: the robot relaxed into none from its unstable equilibrium",
    "diverged": "the solver diverged (the tip pulled into the external magnet?)",
    "stalled": f"Newton's residual stalls above the tolerance ({TOLERANCE:g} m or rad)",
    "contact": "the rings touch the external magnet (contact is not modelled)",
    "pulled": "the robot is pulled into contact with the external magnet (contact is not modelled)",
}


def step_tolerance(lam: np.ndarray) -> np.ndarray:
    """A Newton step shorter than this (infinity norm, m or rad) is taken as the last: at
    full load the state after it is exact to rounding (quadratic convergence with the exact
    matrix of the linear rod; linear at the rate of the coarse matrix's error, about 1e-5,
    otherwise), so that states depend smoothly on the parameters (finite differences,
    fits); below full load, where only the branch is followed, 1e-6 m or rad."""
    return np.where(lam >= 1.0, 1e-9, 1e-6)
