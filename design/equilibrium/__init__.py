"""Equilibrium of the ring-pair robot: *the state* it reaches, in batch or along a path.

The magnetic wrench depends on the tip pose, so a steady state solves r(x) = 0
(:mod:`design.model`). Near a strong magnet or with a soft rod r = 0 has several
solutions, stable and unstable, and which one a real robot sits in depends on how it got
there. The state has one definition, used by every caller (simulation, workspace, NLP
samples, calibration and each cross-validation fold, Monte Carlo):

- **A configuration on its own** (:func:`solve_equilibria`): the stable equilibrium
  connected to the unloaded robot by a quasi-static load ramp. The ring angles are held
  and every load (the field, gravity, the rings' mutual torque) is scaled by lambda from 0
  (the straight, unloaded robot) to 1; the branch of equilibria is followed by
  natural-parameter continuation: a predictor from the branch's tangent and curvature,
  Newton corrections, and a step in lambda accepted only where the corrector lands near
  the prediction and contracts (each correction at most CONTRACTION of the one before;
  Deuflhard, *Newton Methods for Nonlinear Problems*, 2004, sec. 5.1) and the
  state stays stable. The step grows where Newton converges fast and shrinks where it does
  not. Where the branch ends in a fold (the step falls below MIN_LOAD_STEP: a pull-in
  towards the magnet, the rings' snap), the robot falls: it goes down its total
  potential energy from the last state, a little further loaded (:func:`_fall`), into the
  stable state it reaches, which is flagged ``snapped``, and the ramp goes on from there;
  a fall that brings the rings to the external magnet ends in NaN (contact is not
  modelled).
- **A driven path** (:func:`solve_sequence`): the first command as above, then each
  command from the previous state in sub-steps of at most SUBSTEP, so the robot stays on
  its branch as a real one does; friction play (``hysteresis``) acts on the commands, and
  where the branch ends the robot falls as above (``snapped``).

Never an unstable state as an answer: a returned state is converged (infinity norm of the
scaled residual below TOLERANCE), stable by the model's exact check (:func:`_stable`:
linear rod, the Sylvester minors of the Hessian of the total potential; large-deflection
rod, Jacobi's condition det J(s) > 0 on nested variations and the inertia of the energy's
Hessian) and clear of the external magnet. Anything else is NaN, with the reason in
``failure``. On request (``multistable=True``) other stable states at the same command
are looked for, from the straight robot at full load, from the mirror image of the state
and, with torsion, from the rings' lags mirrored; ``multistable`` flags where one is found
(a search, so a lower bound on multistability); on a grid of commands (``neighbours``)
a state found at one node is driven to its neighbours, following its branch.

Batches run through compiled CasADi functions mapped over columns; the per-column ramp
logic is vectorised in numpy. SI units are used for all inputs and outputs.

The package, one concept per module: :mod:`~design.equilibrium.settings` (tolerances and
step controls), :mod:`~design.equilibrium.kernels` (the compiled functions),
:mod:`~design.equilibrium.stability`, :mod:`~design.equilibrium.newton`,
:mod:`~design.equilibrium.fall`, :mod:`~design.equilibrium.ramp` (the load ramp),
:mod:`~design.equilibrium.finish` (final states), :mod:`~design.equilibrium.drive`
(states driven in batch), :mod:`~design.equilibrium.paths` (driven paths) and
:mod:`~design.equilibrium.solve` (the entries). The names below are re-exported here; the
settings are read from :mod:`design.equilibrium.settings` (change them there).
"""

from __future__ import annotations

from design.equilibrium import settings
from design.equilibrium.drive import drive
from design.equilibrium.finish import Equilibria
from design.equilibrium.kernels import kernels
from design.equilibrium.paths import solve_sequence
from design.equilibrium.settings import (
    CHUNK,
    CONTRACTION,
    CORRECTION_RATIO,
    DISTINCT,
    FAILURES,
    FALL_ITERATIONS,
    FIRST_DISPLACEMENT,
    GRAIN,
    GROWTH,
    HESSIAN_TOLERANCE,
    KICK,
    LEAP_CORRECTIONS,
    LEAP_STEPS,
    MAX_CORRECTIONS,
    MAX_FALLS,
    MAX_LOAD_STEP,
    MAX_STRIDE,
    MIN_CORRECTION,
    MIN_LOAD_STEP,
    MODE_FLOOR,
    PATH_CORRECTIONS,
    POLISH_ATTEMPTS,
    POLISH_BELOW,
    POLISH_GRADIENT,
    RAMP_TOLERANCE,
    RESTART_STEP,
    SETTLE_OVERSHOOT,
    SHRINK,
    SMOOTH_LAG_CHANGE,
    SNAP_LAG_JUMP,
    SUBSTEP,
    TARGET_CONTRACTION,
    TIE,
    TOLERANCE,
    TRUST,
)
from design.equilibrium.solve import solve_design, solve_equilibria, stable_states

__all__ = [
    "CHUNK",
    "CONTRACTION",
    "CORRECTION_RATIO",
    "DISTINCT",
    "Equilibria",
    "FAILURES",
    "FALL_ITERATIONS",
    "FIRST_DISPLACEMENT",
    "GRAIN",
    "GROWTH",
    "HESSIAN_TOLERANCE",
    "KICK",
    "LEAP_CORRECTIONS",
    "LEAP_STEPS",
    "MAX_CORRECTIONS",
    "MAX_FALLS",
    "MAX_LOAD_STEP",
    "MAX_STRIDE",
    "MIN_CORRECTION",
    "MIN_LOAD_STEP",
    "MODE_FLOOR",
    "PATH_CORRECTIONS",
    "POLISH_ATTEMPTS",
    "POLISH_BELOW",
    "POLISH_GRADIENT",
    "RAMP_TOLERANCE",
    "RESTART_STEP",
    "SETTLE_OVERSHOOT",
    "SHRINK",
    "SMOOTH_LAG_CHANGE",
    "SNAP_LAG_JUMP",
    "SUBSTEP",
    "TARGET_CONTRACTION",
    "TIE",
    "TOLERANCE",
    "TRUST",
    "drive",
    "kernels",
    "settings",
    "solve_design",
    "solve_equilibria",
    "solve_sequence",
    "stable_states",
]
