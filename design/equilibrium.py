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
(a search, so a lower bound on multistability).

Batches run through compiled CasADi functions mapped over columns; the per-column ramp
logic is vectorised in numpy. SI units are used for all inputs and outputs.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from functools import cache, lru_cache

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from design.compiled import (
    BufferEvaluator,
    ColumnEvaluator,
    compile_functions,
    map_threads,
    mapped,
)
from design.friction import play
from design.model import RingPairModel
from design.records import Design
from design.registry import index

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


@dataclass(frozen=True)
class Equilibria:
    """Steady states of N configurations. Rows without a state hold NaN in every pose array.

    command : shape (N, 2), ring angles commanded at the base (theta1 distal, theta2). [rad]
    tip_angles : shape (N, 2), ring angles at the tip (differ with torsion/hysteresis). [rad]
    position : shape (N, 3), rod tip (proximal ring centre), base frame. [m]
    tangent : shape (N, 3), unit tip tangent, base frame. [-]
    frame : shape (N, 3, 3), tip frame, columns (tangent, y_tip, z_tip), base frame. [-]
    unknowns : shape (N, n), the model's unknowns x at equilibrium. [SI]
    converged : shape (N,), a state was found (residual below TOLERANCE).
    stable : shape (N,), converged and stable (every returned state is).
    residual : shape (N,), infinity norm of the final residual. [m or rad]
    snapped : shape (N,), the robot jumped to another branch on its way here (a fold of the
        load ramp, or along a path).
    multistable : shape (N,), another stable state exists at the same command (only looked
        for on request; False otherwise).
    failure : shape (N,), why a row has no state ('' where it has one).
    """

    command: np.ndarray
    tip_angles: np.ndarray
    position: np.ndarray
    tangent: np.ndarray
    frame: np.ndarray
    unknowns: np.ndarray
    converged: np.ndarray
    stable: np.ndarray
    residual: np.ndarray
    snapped: np.ndarray
    multistable: np.ndarray
    failure: np.ndarray

    def __len__(self) -> int:
        return len(self.converged)


# ----------------------------------------------------------------------- compiled kernels


class _Kernels:
    """The compiled functions of one model that the solver calls, the loads scaled by the
    load factor lambda: ``newton`` (x, command, lambda, params) -> (r, Newton step,
    dx/dlambda, monitor, clearance), ``relaxation`` and ``descent`` as
    :class:`design.model.RingPairModel`'s;
    ``check`` (x, command, lambda, params) -> (r, exact monitor, position, frame (9,
    column-major), tip angles, clearance to the external magnet);
    ``leap<m>`` (command, params) -> (the tangent at rest dx/dlambda, taken, the state at
    full load, ``check``'s outputs there): the ramp in m equal steps in one call, with
    the ramp's acceptance tests (:meth:`_leap`); ``corrections``: PATH_CORRECTIONS Newton
    corrections at full load in one call (:meth:`_corrections`)."""

    def __init__(self, model: RingPairModel) -> None:
        self.model = model
        x = ca.SX.sym("x", model.n_unknowns)
        command = ca.SX.sym("command", 2)
        lam = ca.SX.sym("load_factor")
        prm = ca.SX.sym("params", model.residual.size1_in(2))
        load = index("load_scale")
        scaled = ca.vertcat(prm[:load], prm[load] * lam, prm[load + 1 :])
        r_lam, step, load_tangent, monitor_lam, clearance = model.newton.call([x, command, scaled])
        newton = ca.Function(
            "newton",
            [x, command, lam, prm],
            [r_lam, step, load_tangent * prm[load], monitor_lam, clearance],  # dx / dlambda
        )
        relaxation, descent = (
            ca.Function(
                name, [x, command, lam, prm], getattr(model, name).call([x, command, scaled])
            )
            for name in ("relaxation", "descent")
        )
        r, monitor, position, frame, angles, clearance = model.check.call([x, command, scaled])
        check = ca.Function(
            "check",
            [x, command, lam, prm],
            [r, monitor, position, ca.reshape(frame, 9, 1), angles, clearance],
        )
        leaps = [
            self._leap(model, newton, relaxation, check, command, prm, count)
            for count in range(1, LEAP_STEPS + 1)
            if model.linear_rod
        ]
        compiled = compile_functions([newton, relaxation, descent, check, *leaps])
        self.newton, self.relaxation, self.descent, self.check = compiled[:4]
        for leap in compiled[4:]:  # run by name: "leap1", "leap2", ...
            setattr(self, leap.name(), leap)
        self.corrections = self._corrections(model, self.newton)
        self._maps: dict[tuple[str, int, int], ColumnEvaluator] = {}
        self._tiles: dict[tuple[bytes, int], np.ndarray] = {}
        self._lock = threading.Lock()

    @staticmethod
    def _leap(
        model: RingPairModel,
        newton: ca.Function,
        relaxation: ca.Function,
        check: ca.Function,
        command: ca.SX,
        prm: ca.SX,
        count: int,
    ) -> ca.Function:
        """``leap<count>`` (command, params) -> (the tangent at rest dx/dlambda, taken (1 or
        0), the state at full load, ``check``'s outputs there): the ramp in ``count`` equal
        steps, taken exactly where :func:`_ramp` would accept each step: the first
        predicts a change of at most FIRST_DISPLACEMENT; in each, the first correction
        stays within :func:`_near` of the prediction and each later one contracts by
        CONTRACTION up to the first that converges (residual below the tolerance at the
        step's load, or a step below :func:`_step_tolerance`; later ones only polish the
        state to rounding); below full load no fold is crossed and at full load the state
        passes the exact check; the rings stay clear of the external magnet. For the
        linear rod (the only one with leaps) both the fold monitor and the exact one are
        the Sylvester minors of the stiffness form, all positive where stable."""
        probe = np.zeros(prm.size1())
        probe[index("free_length")] = 2.0
        length = prm[index("free_length")]
        scale = ca.vertcat(*[length if v == 2.0 else 1 for v in model.unknown_scale(probe)])

        def norm(v: ca.SX) -> ca.SX:
            return ca.mmax(ca.fabs(v) / scale)

        def positive(v: ca.SX) -> ca.SX:
            return ca.mmin(v) > 0

        x = model.initial.call([command, prm])[0]
        # The tangent at rest: (dr/dx)^-1 = K^-1 there, and r is linear in the load (but
        # for the rings' mutual torque, which goes with its square), so it is minus the
        # relaxation direction at full load.
        tangent = -relaxation.call([x, command, 1, prm])[0]
        ok = norm(tangent) <= count * FIRST_DISPLACEMENT
        before, rest_tangent = None, tangent
        h = 1.0 / count
        for k in range(1, count + 1):
            move = h * tangent
            if before is not None:  # the ramp's second-order predictor
                move += 0.5 * h * (tangent - before)
            x = x + move
            lam = k * h
            tol = TOLERANCE if lam >= 1.0 else RAMP_TOLERANCE
            small = float(_step_tolerance(model, np.array([lam]))[0])
            going, converged = ca.SX(1), ca.SX(0)
            bound = ca.fmax(CORRECTION_RATIO * norm(move), MIN_CORRECTION)  # _near
            for _ in range(LEAP_CORRECTIONS):
                r, step, load_tangent, monitor, clearance = newton.call([x, command, lam, prm])
                done = ca.logic_or(ca.mmax(ca.fabs(r)) < tol, ca.mmax(ca.fabs(step)) < small)
                converged = ca.logic_or(converged, ca.logic_and(going, done))
                size = norm(step)
                going = ca.logic_and(going, ca.logic_and(ca.logic_not(done), size <= bound))
                bound = CONTRACTION * size
                x = x - step
            ok = ca.logic_and(ok, converged)
            if k < count:
                ok = ca.logic_and(ok, ca.logic_and(positive(monitor), clearance[0] >= 0))
            before, tangent = tangent, load_tangent
        checked = check.call([x, command, 1, prm])
        r, monitor, clearance = checked[0], checked[1], checked[5]
        exact = ca.logic_and(ca.mmax(ca.fabs(r)) < TOLERANCE, positive(monitor))
        ok = ca.logic_and(ok, ca.logic_and(exact, clearance[0] >= 0))
        # NaN anywhere fails every comparison in numpy, not in C's fmax: say it here.
        ok = ca.logic_and(ok, ca.sum1(ca.fabs(ca.vertcat(x, r))) < np.inf)
        return ca.Function(f"leap{count}", [command, prm], [rest_tangent, ok, x, *checked])

    @staticmethod
    def _corrections(model: RingPairModel, newton: ca.Function) -> ca.Function:
        """``corrections`` (x, command, params, scale) -> (the state after each of
        PATH_CORRECTIONS Newton corrections from x at full load, (n, K); per correction
        its size max |step| / scale, max |step|, max |r| and sum |step| (C's fmax skips
        NaN, a sum does not), (4, K); the monitor and the clearance where each was taken,
        (m, K) and (1, K)). The compiled ``newton`` called K times in CasADi's virtual
        machine: nothing to compile, and the decisions (:func:`solve_sequence`) are
        those of the corrections made one by one, to the last bit."""
        x0 = ca.MX.sym("x", model.n_unknowns)
        command = ca.MX.sym("command", 2)
        prm = ca.MX.sym("params", newton.size1_in(3))
        scale = ca.MX.sym("scale", model.n_unknowns)
        x, states, sizes, monitors, clearances = x0, [], [], [], []
        for _ in range(PATH_CORRECTIONS):
            r, step, _tangent, monitor, clearance = newton.call([x, command, 1.0, prm])
            magnitude = ca.fabs(step)
            sizes.append(
                ca.vertcat(
                    ca.mmax(magnitude / scale),
                    ca.mmax(magnitude),
                    ca.mmax(ca.fabs(r)),
                    ca.sum1(magnitude),
                )
            )
            monitors.append(monitor)
            clearances.append(clearance[0])
            x = x - step
            states.append(x)
        return ca.Function(
            "corrections",
            [x0, command, prm, scale],
            [
                ca.horzcat(*states),
                ca.horzcat(*sizes),
                ca.horzcat(*monitors),
                ca.horzcat(*clearances),
            ],
        )

    def _mapped(self, function: ca.Function, size: int) -> ColumnEvaluator:
        key = (function.name(), size, map_threads(size))
        with self._lock:
            if key not in self._maps:
                self._maps[key] = mapped(function, size)
            return self._maps[key]

    def _shared(self, params: np.ndarray, size: int) -> np.ndarray:
        """``params`` (k,) as the (k, size) column-major input of a map, kept for reuse (a
        shared input of a threaded map is far slower in CasADi, and copying it for each
        call costs about as much as a Newton step of the linear rod)."""
        key = (params.tobytes(), size)
        with self._lock:
            if key not in self._tiles:
                if len(self._tiles) >= 8:
                    self._tiles.clear()
                self._tiles[key] = np.tile(params, size).reshape(size, params.size).T
            return self._tiles[key]

    def run(
        self, which: str | ca.Function, args: list[np.ndarray], params: np.ndarray
    ) -> list[np.ndarray]:
        """Evaluate ``which`` (a kernel's name, or another function of the model whose last
        input is the parameters, e.g. :mod:`design.steering`'s) on the columns of ``args``
        (each (rows, N)) with ``params`` shared, shape (k,), or per column, (k, N); in
        chunks of CHUNK columns, the last one padded to a power of two below GRAIN and to a
        multiple of GRAIN above (few distinct map sizes, at most half the work wasted).
        Returns each output as (rows, N)."""
        f = getattr(self, which) if isinstance(which, str) else which
        n = args[0].shape[1]
        if n == 0:
            return [np.zeros((f.size1_out(i), 0)) for i in range(f.n_out())]
        outs: list[list[np.ndarray]] = []
        for start in range(0, n, CHUNK):
            stop = min(start + CHUNK, n)
            count = stop - start
            size = min(CHUNK, -(-count // GRAIN) * GRAIN, 1 << (count - 1).bit_length())
            chunk = [a[:, start:stop] for a in args]
            if params.ndim == 2:
                chunk.append(params[:, start:stop])
            if size > count:  # padded with the last column (np.pad's cost: a fit's 10 %)
                edge = np.minimum(np.arange(size), count - 1)
                chunk = [c[:, edge] for c in chunk]
            if params.ndim == 1:
                chunk.append(self._shared(params, size))
            results = self._mapped(f, size)(chunk)
            outs = outs or [[] for _ in results]
            for acc, out in zip(outs, results, strict=True):
                acc.append(out[:, :count])
        return [acc[0] if len(acc) == 1 else np.concatenate(acc, axis=1) for acc in outs]


@cache
def kernels(model: RingPairModel) -> _Kernels:
    """The compiled solver functions of ``model`` (built and compiled once per process,
    kept for every model: there is one per set of effects, and a diagnosis fits up to all
    32 of them; the shared library is cached on disk by :mod:`design.compiled`)."""
    return _Kernels(model)


# ------------------------------------------------------------------------------ stability


def _matrices(model: RingPairModel, monitor: np.ndarray) -> np.ndarray:
    """The column-major matrices stacked in each column of ``monitor`` as (N, k, n, n),
    transposed (which changes neither determinant nor eigenvalues)."""
    n = model.n_unknowns
    return monitor.T.reshape(monitor.shape[1], monitor.shape[0] // (n * n), n, n)


def _fold_free(model: RingPairModel, monitor: np.ndarray) -> np.ndarray:
    """Whether each column's Newton monitor is on the stable side of every fold seen
    from rest: all Sylvester minors positive (linear rod), det dr/dx > 0 (large-deflection
    rod: along a branch followed continuously from rest, where it is the elastic
    stiffness, the lowest eigenvalue of the second variation can only reach zero where
    dr/dx is singular)."""
    if model.linear_rod:  # (the method, not np.all: this runs ~10^5 times a fit)
        return np.asarray((monitor > 0).all(axis=0))
    with np.errstate(invalid="ignore"):
        return np.linalg.det(_matrices(model, monitor)[:, 0]) > 0


def _stable(model: RingPairModel, monitor: np.ndarray) -> np.ndarray:
    """Exact stability of each column from the ``check`` monitor, wherever the state came
    from: all Sylvester minors positive (linear rod; the Hessian of the total potential),
    or for the large-deflection rod det J(s_k) > 0 at every node (Jacobi's condition on
    nested variations), no eigenvalue of the energy's Hessian below -HESSIAN_TOLERANCE
    and, with torsion, J(0)'s angle block with eigenvalues of positive real part
    (:class:`design.model.RingPairModel`)."""
    if model.linear_rod:
        return np.all(monitor > 0, axis=0)
    m = _matrices(model, monitor)
    ok = np.isfinite(m).all(axis=(1, 2, 3))
    out = np.zeros(len(m), bool)
    if ok.any():
        hessian = m[ok][:, -1]
        good = (np.linalg.det(m[ok][:, :-1]) > 0).all(axis=1)
        lowest = np.linalg.eigvalsh(0.5 * (hessian + hessian.transpose(0, 2, 1)))[:, 0]
        good &= lowest > -HESSIAN_TOLERANCE
        if model.n_unknowns > model.n_rod:
            angles = m[ok][:, 0, model.n_rod :, model.n_rod :]
            good &= (np.linalg.eigvals(angles).real > 0).all(axis=1)
        out[ok] = good
    return out


def _columns(params: np.ndarray, idx: np.ndarray) -> np.ndarray:
    return params if params.ndim == 1 else params[:, idx]


def _scale(model: RingPairModel, params: np.ndarray, n: int) -> np.ndarray:
    """Scale of the unknowns per column, (n_unknowns, n)."""
    scale = model.unknown_scale(params)
    return np.broadcast_to(scale[:, None], (model.n_unknowns, n)) if scale.ndim == 1 else scale


def _norm(values: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Dimensionless infinity norm of each column (NaN stays NaN)."""
    return np.max(np.abs(values) / scale, axis=0)


# --------------------------------------------------------------------- Newton and falls
#
# The helpers below work on the columns they are given: params (k,) shared or (k, m), one
# per column; command (2, m); states x (n, m); load factors lam (m,).


def _step_tolerance(model: RingPairModel, lam: np.ndarray) -> np.ndarray:
    """A Newton step shorter than this (infinity norm, m or rad) is taken as the last: at
    full load the state after it is exact to rounding (quadratic convergence with the exact
    matrix of the linear rod; linear at the rate of the coarse matrix's error, about 1e-5,
    otherwise), so that states depend smoothly on the parameters (finite differences,
    fits); below full load, where only the branch is followed, 1e-6 m or rad."""
    return np.where(lam >= 1.0, 1e-9, 1e-6)


class _Checks:
    """The ``check`` outputs (r, monitor, position, frame, tip angles, clearance) of states
    at full load, kept per column of a solve (NaN where not checked)."""

    def __init__(self, n: int) -> None:
        self.outs: list[np.ndarray] | None = None
        self.done = np.zeros(n, bool)

    def put(self, idx: np.ndarray, outs: list[np.ndarray]) -> None:
        if self.outs is None:
            self.outs = [np.full((o.shape[0], self.done.size), np.nan) for o in outs]
        for acc, o in zip(self.outs, outs, strict=True):
            acc[:, idx] = o
        self.done[idx] = True


def _check(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The exact check of states at load factors lam (default full load): (converged to
    TOLERANCE, stable, check outputs)."""
    lam = np.ones(x.shape[1]) if lam is None else lam
    outs = kernels(model).run("check", [x, command, lam[None, :]], params)
    converged = np.max(np.abs(outs[0]), axis=0) < TOLERANCE
    return converged, _stable(model, outs[1]), outs


def _judge(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray,
    monitor: np.ndarray,
    clearance: np.ndarray,
    checks: _Checks,
    where: np.ndarray,
    exact: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Judge candidate states x (n, m) at load factors lam, given the solver's monitor and
    clearance at (or within a last Newton step of) each: (converged, acceptable). At full
    load, or anywhere if ``exact`` (states not reached along a branch from rest), the
    exact check decides (full-load outputs are put in ``checks`` at columns ``where``);
    below full load a candidate is converged by construction and, along a branch, the
    monitor must show no fold crossed. A state whose rings are inside the external magnet
    is never acceptable."""
    converged = np.ones(lam.size, bool)
    ok = np.zeros(lam.size, bool)
    full = lam >= 1.0
    test = full | exact
    if test.any():
        done, ok[test], outs = _check(
            model, _columns(params, test), command[:, test], x[:, test], lam[test]
        )
        converged[full] = done[full[test]]
        ok[full] &= converged[full]
        at_full = full[test]
        checks.put(where[full], [o[:, at_full] for o in outs])
    ok[~test] = _fold_free(model, monitor[:, ~test])
    return converged, ok & (clearance.ravel() >= 0)


def _newton(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray,
    checks: _Checks,
    where: np.ndarray,
    iterations: int = 2 * MAX_CORRECTIONS,
    exact: bool = False,
    known: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Newton from x at load factors lam (no contraction required): (states, converged,
    acceptable as :func:`_judge` judges, ``exact`` passed on; checks of full-load states
    go to ``checks`` at columns ``where``). A column whose iterate comes within DISTINCT of
    its ``known`` state (n, m), a regular root, stops unconverged: it would end there."""
    kern = kernels(model)
    xs = x.copy()
    ok = np.zeros(lam.size, bool)
    done = np.zeros(lam.size, bool)
    running = np.isfinite(xs).all(axis=0)
    for _ in range(iterations):
        if known is not None:
            a = np.flatnonzero(running)
            near = _norm(xs[:, a] - known[:, a], _scale(model, _columns(params, a), a.size))
            running[a[near <= DISTINCT]] = False
        a = np.flatnonzero(running)
        if a.size == 0:
            break
        r, step, _, monitor, clearance = kern.run(
            "newton", [xs[:, a], command[:, a], lam[None, a]], _columns(params, a)
        )
        rn, sn = np.max(np.abs(r), axis=0), np.max(np.abs(step), axis=0)
        lost = ~np.isfinite(sn)
        running[a[lost]] = False
        candidate = ~lost & ((rn < TOLERANCE) | (sn < _step_tolerance(model, lam[a])))
        xs[:, a[~lost]] -= step[:, ~lost]  # (a converged state takes its last step too)
        c = a[candidate]
        if c.size:
            converged, good = _judge(
                model,
                _columns(params, c),
                command[:, c],
                xs[:, c],
                lam[c],
                monitor[:, candidate],
                clearance[:, candidate],
                checks,
                where[c],
                exact,
            )
            ok[c], done[c] = good, converged
            running[c[converged]] = False
    return xs, done, ok


def _fall(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    lam: np.ndarray,
    checks: _Checks,
    where: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stable states the robot falls into from x at load factors lam (a fold, or an
    unstable equilibrium).

    The robot goes down its total potential energy. In the modes of M = G^-1 H (H the
    energy's Hessian in the unknowns, G a metric: :class:`design.model.RingPairModel`
    ``descent``; eigenvectors v, eigenvalues mu, the stiffness of each mode relative to
    the elastic one) the downhill direction -G^-1 g has components -a; each mode moves by
    -a / |mu| (with |mu| at least MODE_FLOOR): Newton's step in the stable modes, and in
    an unstable mode the same
    distance downhill instead of up to the saddle ("saddle-free Newton": Dauphin et al.,
    NeurIPS 2014), the whole step at most TRUST long. It starts kicked by KICK both ways
    along the softest mode, so that a symmetric bifurcation is left too, and is polished by
    Newton once no mode is unstable and its step or pull is small, judged by the exact
    check (a polish that lands on an unstable equilibrium kicks the column off again). A
    way on which the rings reach the external magnet ends there (contact, which is not
    modelled). Of the two ways the stable state nearer x is taken (the first where they
    tie to TIE: at a symmetric bifurcation the states are mirror images).
    Returns (states, found, touched: no state found and the fall reached the magnet)."""
    kern = kernels(model)
    n, m = x.shape
    both = np.concatenate([np.arange(m), np.arange(m)])
    p2, c2, lam2 = _columns(params, both), command[:, both], lam[both]
    scale = _scale(model, p2, 2 * m)
    xs = np.concatenate([x, x], axis=1)
    sign = np.concatenate([np.ones(m), -np.ones(m)])
    found = np.zeros(2 * m, bool)
    touched = np.zeros(2 * m, bool)
    alive = np.isfinite(xs).all(axis=0)
    kicked = np.zeros(2 * m, bool)
    polishes = np.zeros(2 * m, int)
    scratch = _Checks(2 * m)
    for _ in range(FALL_ITERATIONS):
        a = np.flatnonzero(alive & ~found)
        if a.size == 0:
            break
        direction, modes, clearance = kern.run(
            "descent", [xs[:, a], c2[:, a], lam2[None, a]], _columns(p2, a)
        )
        matrices = modes.T.reshape(-1, n, n).transpose(0, 2, 1)
        inside = ~(clearance[0] >= 0)
        touched[a[inside]] = True
        good = np.isfinite(matrices).all(axis=(1, 2)) & np.isfinite(direction).all(axis=0)
        good &= ~inside
        alive[a[~good]] = False
        a, direction, matrices = a[good], direction[:, good], matrices[good]
        if a.size == 0:
            continue
        values, vectors = np.linalg.eig(matrices)
        fresh = ~kicked[a]
        if fresh.any():  # leave along the softest mode, both ways
            soft = vectors[np.flatnonzero(fresh), :, np.argmin(values.real[fresh], axis=1)].real
            relative = soft.T / scale[:, a[fresh]]
            # (a mode's sign is arbitrary: its first component of at least half the largest
            # magnitude counts positive, so that a symmetric mode's sign, and the side the
            # robot falls to at a symmetric bifurcation, does not depend on rounding)
            size = np.abs(relative)
            first = np.argmax(size >= 0.5 * size.max(axis=0), axis=0)
            lead = relative[first, np.arange(relative.shape[1])]
            big = size.max(axis=0)
            kick = KICK * np.sign(lead) / np.where(big > 0, big, 1.0)
            xs[:, a[fresh]] += sign[a[fresh]] * kick * soft.T
            kicked[a[fresh]] = True
        components = np.linalg.solve(vectors, direction.T[:, :, None].astype(complex))[:, :, 0]
        magnitude = np.maximum(np.abs(values.real), MODE_FLOOR)
        step = np.einsum("kij,kj->ki", vectors, components / magnitude).real.T
        size = _norm(step, scale[:, a])
        step *= np.minimum(1.0, TRUST / np.maximum(size, 1e-300))
        xs[:, a] -= step
        # Polished where no mode is unstable (within MODE_FLOOR: near a straight rod the
        # axial force and moment are constraint-like, the energy hardly depends on them and
        # the steps along them need not shrink) and the step or the pull is small.
        pull = _norm(direction, scale[:, a])
        settled = (values.real > -MODE_FLOOR).all(axis=1)
        ready = a[settled & ((size < POLISH_BELOW) | (pull < POLISH_GRADIENT))]
        if ready.size:
            polished, _, ok = _newton(
                model,
                _columns(p2, ready),
                c2[:, ready],
                xs[:, ready],
                lam2[ready],
                scratch,
                ready,
                exact=True,
            )
            xs[:, ready[ok]] = polished[:, ok]
            found[ready[ok]] = True
            polishes[ready[~ok]] += 1
            kicked[ready[~ok]] = False  # near an unstable equilibrium: leave it again
            alive[ready[polishes[ready] > POLISH_ATTEMPTS]] = False
    distance = np.where(found, _norm(xs - x[:, both], scale), np.inf)
    second = distance[m:] < distance[:m] * (1 - TIE)
    pick = np.where(second, np.arange(m) + m, np.arange(m))
    if scratch.outs is not None:
        full = found[pick] & scratch.done[pick]
        checks.put(where[full], [o[:, pick[full]] for o in scratch.outs])
    contact = ~found[pick] & (touched[:m] | touched[m:])
    return xs[:, pick], found[pick], contact


# -------------------------------------------------------------------------- the load ramp

_RUN, _DONE, _FOLD, _FAIL = range(4)


def _initial(model: RingPairModel, params: np.ndarray, command: np.ndarray) -> np.ndarray:
    """The unloaded robot for each column (:attr:`RingPairModel.initial`: straight, the
    tip angles the commands, or with stops the rings against them)."""
    if model.n_unknowns == model.n_rod:
        return np.zeros((model.n_unknowns, command.shape[1]))
    return kernels(model).run(model.initial, [command], params)[0]


def _near(predicted: np.ndarray) -> np.ndarray:
    """How far a ramp step's first correction may go for a predicted change of state
    ``predicted`` (dimensionless): CORRECTION_RATIO of it, or MIN_CORRECTION."""
    return np.maximum(CORRECTION_RATIO * predicted, MIN_CORRECTION)


def _leap(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    count: int,
    checks: _Checks,
    where: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ramp in ``count`` equal steps, from the compiled ``leap<count>``
    (:meth:`_Kernels._leap`): (the tangent at rest (n, N), which columns it takes to full
    load, their states). The checks of the columns taken are put in ``checks`` at
    ``where``; other columns are left to the ramp's adaptive steps."""
    outs = kernels(model).run(f"leap{count}", [command], params)
    tangent, taken, x, checked = outs[0], outs[1][0] > 0.5, outs[2], outs[3:]
    idx = np.flatnonzero(taken)
    checks.put(where[idx], [o[:, idx] for o in checked])
    return tangent, idx, x[:, idx]


def _ramp(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    checks: _Checks,
    max_step: float = MAX_LOAD_STEP,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Follow each column from the unloaded robot (lambda = 0) to full load (lambda = 1)
    (module docstring). Returns (x (n, N), reached full load, snapped, failure reasons);
    the states reached are checked (in ``checks``).

    Predictor: the state's tangent dx/dlambda = -(dr/dx)^-1 dr/dlambda (from the solver's
    last evaluation), with the curvature of the branch from the change of the tangent
    since the step before (a second-order predictor); from rest the tangent alone."""
    kern = kernels(model)
    n_cols = command.shape[1]
    x = _initial(model, params, command)
    scale = _scale(model, params, n_cols)
    lam = np.zeros(n_cols)
    lam_prev = np.full(n_cols, -1.0)
    h = np.full(n_cols, max_step)
    target = np.zeros(n_cols)
    xs = x.copy()
    corrections = np.zeros(n_cols, int)
    last = np.full(n_cols, np.inf)
    contraction = np.zeros(n_cols)  # the corrector's first contraction in this step
    predicted = np.zeros(n_cols)  # the predictor's change of state in this step
    phase = np.full(n_cols, _RUN)
    falls = np.zeros(n_cols, int)
    refused = np.zeros(n_cols, bool)  # the current step was refused before
    failure = np.full(n_cols, "", dtype=object)
    # The first step is sized so that the tangent at rest predicts a change of state of at
    # most FIRST_DISPLACEMENT; where that step is the whole ramp, it is taken by ``leap``.
    if max_step >= 1.0 and model.linear_rod:
        tangent = np.zeros_like(x)
        left = np.arange(n_cols)
        for count in range(1, LEAP_STEPS + 1):
            if left.size == 0:
                break
            p = _columns(params, left)
            t, idx, states = _leap(model, p, command[:, left], count, checks, left)
            if count == 1:
                tangent[:] = t
            x[:, left[idx]], lam[left[idx]], phase[left[idx]] = states, 1.0, _DONE
            left = np.delete(left, idx)
            left = left[_norm(tangent[:, left], scale[:, left]) <= (count + 1) * FIRST_DISPLACEMENT]
    else:
        tangent = -kern.run("relaxation", [x, command, np.ones((1, n_cols))], params)[0]
    tangent_prev = np.zeros_like(tangent)
    with np.errstate(divide="ignore", invalid="ignore"):
        h[:] = np.clip(FIRST_DISPLACEMENT / _norm(tangent, scale), MIN_LOAD_STEP, max_step)
    h[~np.isfinite(h)] = max_step
    tangent_xs = np.zeros_like(tangent)  # the tangent at the current iterate

    def predict(cols: np.ndarray) -> None:
        """Targets and predictions for the next step of columns ``cols``."""
        if cols.size == 0:  # (most iterations: the loop runs on a few columns)
            return
        target[cols] = np.minimum(lam[cols] + h[cols], 1.0)
        step = (target[cols] - lam[cols])[None, :]
        xs[:, cols] = x[:, cols] + step * tangent[:, cols]
        curved = lam_prev[cols] >= 0
        if curved.any():
            c = cols[curved]
            bend = (tangent[:, c] - tangent_prev[:, c]) / (lam[c] - lam_prev[c])
            xs[:, c] += 0.5 * step[:, curved] ** 2 * bend
        predicted[cols] = _norm(xs[:, cols] - x[:, cols], scale[:, cols])
        corrections[cols] = 0
        last[cols] = np.inf
        contraction[cols] = 0.0

    def fall(f: np.ndarray) -> None:
        """Columns f end in a fold at lam: they fall, a little further loaded."""
        lam_fall = np.minimum(lam[f] + np.maximum(SETTLE_OVERSHOOT, h[f]), 1.0)
        fallen, found, contact = _fall(
            model, _columns(params, f), command[:, f], x[:, f], lam_fall, checks, f
        )
        ok, lost = f[found], f[~found]
        phase[lost] = _FAIL
        failure[lost] = np.where(contact[~found], FAILURES["pulled"], FAILURES["fold"])
        x[:, ok] = fallen[:, found]
        lam[ok] = lam_fall[found]
        lam_prev[ok] = -1.0
        if ok.size:  # the branch's tangent at the state fallen into: the next predictor
            tangent[:, ok] = kern.run(
                "newton", [x[:, ok], command[:, ok], lam[None, ok]], _columns(params, ok)
            )[2]
        falls[ok] += 1
        h[ok] = RESTART_STEP
        phase[ok[lam[ok] >= 1.0]] = _DONE
        rest = ok[lam[ok] < 1.0]
        phase[rest] = _RUN
        predict(rest)
        too_many = ok[falls[ok] > MAX_FALLS]
        phase[too_many] = _FAIL
        failure[too_many] = FAILURES["falls"]

    predict(np.flatnonzero(phase == _RUN))
    while True:
        a = np.flatnonzero(phase == _RUN)
        if a.size == 0:
            f = np.flatnonzero(phase == _FOLD)
            if f.size == 0:
                break
            fall(f)
            continue
        r, step, load_tangent, monitor, clearance = kern.run(
            "newton", [xs[:, a], command[:, a], target[None, a]], _columns(params, a)
        )
        tangent_xs[:, a] = load_tangent
        rn, sn = np.max(np.abs(r), axis=0), _norm(step, scale[:, a])
        tol = np.where(target[a] >= 1.0, TOLERANCE, RAMP_TOLERANCE)
        conv = rn < tol
        small = np.max(np.abs(step), axis=0) < _step_tolerance(model, target[a])
        candidate = conv | small
        moved = np.isfinite(sn)  # every finite step is taken, a candidate's last one too
        xs[:, a[moved]] -= step[:, moved]
        # The corrector must stay near the prediction (its first correction at most
        # CORRECTION_RATIO of the predicted change, or MIN_CORRECTION), and contract.
        near = _near(predicted[a])
        contracting = np.where(corrections[a] == 0, sn <= near, sn <= CONTRACTION * last[a])
        give_up = ~candidate & (
            ~np.isfinite(sn) | ~contracting | (corrections[a] >= MAX_CORRECTIONS)
        )
        refuse = give_up.copy()
        accept = np.zeros(a.size, bool)
        cand = a[candidate]
        if cand.size:
            converged, good = _judge(
                model,
                _columns(params, cand),
                command[:, cand],
                xs[:, cand],
                target[cand],
                monitor[:, candidate],
                clearance[:, candidate],
                checks,
                cand,
            )
            accept[candidate] = converged & good
            refuse[candidate] = converged & ~good
            stalled = cand[~converged & (corrections[cand] >= MAX_CORRECTIONS)]
            if stalled.size:
                phase[stalled] = _FAIL
                failure[stalled] = FAILURES["stalled"]
                accept[np.isin(a, stalled)] = False

        acc = a[accept]
        if acc.size:  # (most iterations accept or refuse nothing: skip their bookkeeping)
            lam_prev[acc] = np.where(tangent[:, acc].any(axis=0), lam[acc], -1.0)
            tangent_prev[:, acc] = tangent[:, acc]
            x[:, acc], lam[acc], tangent[:, acc] = xs[:, acc], target[acc], tangent_xs[:, acc]
            factor = np.sqrt(TARGET_CONTRACTION / np.maximum(contraction[acc], 1e-12))
            growth = np.where(refused[acc], 1.0, GROWTH)  # no growth right after a refusal
            h[acc] = np.minimum(h[acc] * np.clip(factor, 1 / SHRINK, growth), max_step)
            refused[acc] = False
            phase[acc[lam[acc] >= 1.0]] = _DONE
            predict(acc[lam[acc] < 1.0])

        running = phase[a] == _RUN
        refusing = refuse & running
        if refusing.any():
            ref = a[refusing]
            refused[ref] = True
            with np.errstate(invalid="ignore", divide="ignore"):
                # Newton's contraction; for a first correction that missed the prediction,
                # how far it missed (the predictor's error grows with the step's square).
                theta = np.where(
                    corrections[ref] == 0,
                    TARGET_CONTRACTION * sn[refusing] / near[refusing],
                    np.where(np.isfinite(last[ref]), sn[refusing] / last[ref], np.inf),
                )
                theta = np.where(np.isfinite(theta), theta, np.inf)
            factor = np.sqrt(TARGET_CONTRACTION / np.maximum(theta, 1e-12))
            h[ref] *= np.clip(factor, 1 / SHRINK, 0.5)
            phase[ref[h[ref] < MIN_LOAD_STEP]] = _FOLD
            predict(ref[h[ref] >= MIN_LOAD_STEP])

        carry_on = ~accept & ~refuse & running
        go = a[carry_on]
        first = corrections[go] == 1
        contraction[go[first]] = sn[carry_on][first] / last[go[first]]
        last[go] = sn[carry_on]
        corrections[go] += 1
    return x, phase == _DONE, falls > 0, failure


# ------------------------------------------------------------------------ final states


def _finish(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    reached: np.ndarray,
    snapped: np.ndarray,
    failure: np.ndarray,
    checks: _Checks,
    multistable: bool = False,
) -> Equilibria:
    """Check the states reached at full load (an unstable one falls once more), poses, and
    the optional search for other stable states."""
    n_cols = command.shape[1]
    x = np.where(reached, x, np.nan)
    todo = np.flatnonzero(~checks.done)
    if todo.size or checks.outs is None:
        todo = todo if checks.outs is not None else np.arange(n_cols)
        checks.put(todo, _check(model, _columns(params, todo), command[:, todo], x[:, todo])[2])
    outs = checks.outs
    assert outs is not None
    stable = reached & (np.max(np.abs(outs[0]), axis=0) < TOLERANCE) & _stable(model, outs[1])
    fall = np.flatnonzero(reached & ~stable)
    if fall.size:
        fallen, found, contact = _fall(
            model,
            _columns(params, fall),
            command[:, fall],
            x[:, fall],
            np.ones(fall.size),
            checks,
            fall,
        )
        x[:, fall] = np.where(found, fallen, np.nan)
        snapped[fall[found]] = True
        stable[fall] = found
        failure[fall[~found]] = np.where(contact[~found], FAILURES["pulled"], FAILURES["unstable"])
    failure[~stable & (failure == "")] = FAILURES["diverged"]
    touching = stable & ~(outs[5][0] >= 0)
    stable &= ~touching
    failure[touching] = FAILURES["contact"]
    multi = np.zeros(n_cols, bool)
    if multistable and stable.any():
        multi = _other_stable_states(model, params, command, x, stable)
    r, _, position, frame, angles, _ = outs
    nan = np.where(stable, 1.0, np.nan)
    frames = frame.T.reshape(n_cols, 3, 3).transpose(0, 2, 1) * nan[:, None, None]
    return Equilibria(
        command=command.T.copy(),
        tip_angles=angles.T * nan[:, None],
        position=position.T * nan[:, None],
        tangent=frames[:, :, 0].copy(),
        frame=frames,
        unknowns=x.T * nan[:, None],
        converged=stable.copy(),
        stable=stable,
        residual=np.max(np.abs(r), axis=0),
        snapped=snapped & stable,
        multistable=multi,
        failure=np.where(stable, "", failure).astype(object),
    )


def _mirror(model: RingPairModel, x: np.ndarray) -> np.ndarray:
    """The unknowns of the state turned by pi about the robot's axis (a start)."""
    m = x.copy()
    if model.linear_rod:
        m[:4] = -x[:4]
    else:
        m[[1, 2, 4, 5]] = -x[[1, 2, 4, 5]]
    return m


def _other_stable_states(
    model: RingPairModel,
    params: np.ndarray,
    command: np.ndarray,
    x: np.ndarray,
    stable: np.ndarray,
) -> np.ndarray:
    """Whether another stable state exists at each command: Newton (then, if it lands on
    an unstable equilibrium, a fall from there) from the straight robot at full load, from
    the mirror image of the state and, with torsion, from the state with the rings' lags
    mirrored."""
    n_cols = command.shape[1]
    starts = [_initial(model, params, command), _mirror(model, x)]
    if model.n_unknowns > model.n_rod:
        lagged = x.copy()
        lagged[model.n_rod :] = 2 * command - x[model.n_rod :]
        starts.append(lagged)
    scale = _scale(model, params, n_cols)
    found = np.zeros(n_cols, bool)
    for start in starts:
        todo = np.flatnonzero(stable & ~found)
        if todo.size == 0:
            break
        p, c, ones = _columns(params, todo), command[:, todo], np.ones(todo.size)
        scratch = _Checks(todo.size)
        local = np.arange(todo.size)
        states, converged, good = _newton(
            model, p, c, start[:, todo], ones, scratch, local, known=x[:, todo]
        )
        unstable = np.flatnonzero(converged & ~good)
        if unstable.size:
            fallen, ok, _ = _fall(
                model,
                _columns(p, unstable),
                c[:, unstable],
                states[:, unstable],
                ones[unstable],
                scratch,
                unstable,
            )
            states[:, unstable] = fallen
            good[unstable] = ok
        distinct = _norm(states - x[:, todo], scale[:, todo]) > DISTINCT
        found[todo[good & distinct]] = True
    return found


# ------------------------------------------------------------------------------ entries


def _commands(theta1: ArrayLike, theta2: ArrayLike) -> np.ndarray:
    t1, t2 = np.broadcast_arrays(
        np.asarray(theta1, float).ravel(), np.asarray(theta2, float).ravel()
    )
    return np.vstack([t1, t2])


def solve_equilibria(
    model: RingPairModel,
    params: np.ndarray,
    theta1: ArrayLike,
    theta2: ArrayLike,
    *,
    multistable: bool = False,
    max_load_step: float = MAX_LOAD_STEP,
) -> Equilibria:
    """The state of each configuration on its own (commanded ring angles (theta1[i],
    theta2[i]) [rad]): the stable equilibrium connected to the unloaded robot by the load
    ramp (module docstring).

    params : model parameter vector, shape (k,), from ``model.parameters(design)``, or one
        per configuration, shape (k, N). [SI]
    multistable : also look for other stable states at each command (costs a few more
        solves per configuration).
    max_load_step : largest step of the load ramp (smaller: a finer ramp, for checks).
    ``hysteresis`` needs an order, so here it is ignored (the commands are taken as reached
    from the centre of the play); use :func:`solve_sequence` for ordered commands.
    """
    params = np.asarray(params, float)
    command = _commands(theta1, theta2)
    checks = _Checks(command.shape[1])
    x, reached, snapped, failure = _ramp(model, params, command, checks, max_load_step)
    return _finish(model, params, command, x, reached, snapped, failure, checks, multistable)


def stable_states(
    model: RingPairModel, params: np.ndarray, unknowns: np.ndarray, command: np.ndarray
) -> np.ndarray:
    """Whether each given state is a converged, stable equilibrium (the exact check).

    unknowns : shape (n, N). command : shape (2, N). [SI]
    """
    converged, stable, _ = _check(model, np.asarray(params, float), command, unknowns)
    return converged & stable


# -------------------------------------------------------------------------- driven paths


def drive(
    model: RingPairModel,
    params: np.ndarray,
    x: np.ndarray,
    start: np.ndarray,
    end: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Each column's state x (n, N) at commands ``start`` (2, N), driven to ``end`` (2, N)
    [rad] in equal sub-steps of at most SUBSTEP, each solved by Newton from the state
    before (contracting by CONTRACTION, ending on the stable side of every fold seen from
    rest, :func:`_fold_free`, with the rings clear of the external magnet): (the states
    at ``end``, whether every sub-step did; NaN where not). The batch form of
    :func:`solve_sequence`'s continuation, without falls: a column that would snap
    fails."""
    kern = kernels(model)
    n_cols = x.shape[1]
    scale = _scale(model, params, n_cols)
    x = x.copy()
    ok = np.isfinite(x).all(axis=0)
    n_sub = max(1, int(np.ceil(np.max(np.abs(end - start), initial=0.0) / SUBSTEP)))
    ones = np.ones((1, n_cols))
    tolerance = float(_step_tolerance(model, np.ones(1))[0])
    for k in range(1, n_sub + 1):
        command = start + (end - start) * (k / n_sub)
        running = ok.copy()
        done = np.zeros(n_cols, bool)
        last = np.full(n_cols, np.inf)
        for _ in range(MAX_CORRECTIONS + 2):
            a = np.flatnonzero(running)
            if a.size == 0:
                break
            r, step, _, monitor, clearance = kern.run(
                "newton", [x[:, a], command[:, a], ones[:, a]], _columns(params, a)
            )
            size = _norm(step, scale[:, a])
            contracting = np.isfinite(size) & (size <= CONTRACTION * last[a])
            x[:, a] -= np.where(np.isfinite(step), step, 0.0)
            small = (np.max(np.abs(step), axis=0) < tolerance) | (
                np.max(np.abs(r), axis=0) < TOLERANCE
            )
            fine = _fold_free(model, monitor) & (clearance[0] >= 0)
            finished = small & np.isfinite(size)
            done[a[finished & fine]] = True
            failed = (finished & ~fine) | (~finished & ~contracting)
            running[a[finished | failed]] = False
            last[a] = size
        ok &= done
    x[:, ~ok] = np.nan
    return x, ok


@lru_cache(maxsize=128)
def _path_evaluator(model: RingPairModel, thread: int) -> BufferEvaluator:
    """The path's Newton corrections of ``model`` (``corrections``) on reusable buffers,
    one per thread (the buffers are not shared between threads)."""
    return BufferEvaluator(kernels(model).corrections)


def solve_sequence(
    model: RingPairModel, params: np.ndarray, theta1: ArrayLike, theta2: ArrayLike
) -> Equilibria:
    """Equilibria along an ordered path of commanded angles, as the robot is driven. [rad]

    The first command's state is that of the configuration on its own (the load ramp of
    :func:`solve_equilibria`: the robot enters its loads as on a bench). Each later command
    is reached in sub-steps of at most SUBSTEP, each Newton solve starting from the
    previous state, so the robot stays on its branch. With ``hysteresis`` the commands
    first pass through each transmission's play (:func:`design.friction.play`). Where the
    branch ends (Newton stops contracting or the state crosses a fold) the robot falls into
    the stable state it relaxes to, and where that or a plain step changes a ring's lag by
    more than SNAP_LAG_JUMP, ``snapped`` is set for that command.
    """
    params = np.asarray(params, float)
    command = _commands(theta1, theta2)
    effective = command
    if "hysteresis" in model.effects:
        width = np.array(
            [params[index("wire_friction_angle")], params[index("catheter_friction_angle")]]
        )
        effective = play(command, width)
    corrections = _path_evaluator(model, threading.get_ident())
    scale = model.unknown_scale(params)
    corrections.fix(2, params)  # the same along the whole path
    corrections.fix(3, scale)
    n_rod = model.n_rod
    torsion = model.n_unknowns > n_rod
    step_tolerance = float(_step_tolerance(model, np.ones(1))[0])

    def newton(x0: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, bool]:
        """Newton from x0 at the command c; (state, converged on the stable side)."""
        x, last, k = x0, math.inf, 0
        while True:
            # (views of the evaluator's buffers, and plain floats: this loop runs ~10^5
            # times a fit)
            states, sizes, monitors, clearances = corrections.views(x, c)
            for j, (size, largest, residual, total) in enumerate(zip(*sizes.tolist(), strict=True)):
                finite = math.isfinite(size) and math.isfinite(total)
                if not finite or (k > 0 and size > CONTRACTION * last):
                    return x, False
                if largest < step_tolerance or residual < TOLERANCE:
                    ok = _fold_free(model, monitors[:, j : j + 1])[0] and clearances[0, j] >= 0
                    return states[:, j].copy(), bool(ok)
                x, last, k = states[:, j].copy(), size, k + 1
                if k == MAX_CORRECTIONS + 2:
                    return x, False

    def lags(x: np.ndarray, c: np.ndarray) -> np.ndarray:
        return x[n_rod:] - c if torsion else np.zeros(2)

    def fall(x: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, str]:
        """The state the robot falls into from x at c, or NaN and why not."""
        fallen, found, contact = _fall(
            model, params, c[:, None], x[:, None], np.ones(1), _Checks(1), np.arange(1)
        )
        if found[0]:
            return fallen[:, 0], ""
        return np.full_like(x, np.nan), FAILURES["pulled" if contact[0] else "unstable"]

    def alone(c: np.ndarray) -> tuple[np.ndarray, bool, str]:
        """The state at c as a configuration on its own: (state or NaN, snapped, failure)."""
        x, ok, snap, why = _ramp(model, params, c[:, None], _Checks(1))
        return (x[:, 0] if ok[0] else np.full(model.n_unknowns, np.nan)), bool(snap[0]), why[0]

    snapped = np.zeros(command.shape[1], bool)
    failure = np.full(command.shape[1], "", dtype=object)
    first, snapped[0], failure[0] = alone(effective[:, 0])
    states = [first]
    stride = 1
    for k in range(1, command.shape[1]):
        prev = states[-1]
        a, b = effective[:, k - 1], effective[:, k]
        if not np.isfinite(prev).all():  # lost: start again as a configuration on its own
            x, snapped[k], failure[k] = alone(b)
            states.append(x)
            continue
        n_sub = max(1, int(np.ceil(np.abs(b - a).max() / SUBSTEP)))
        path = a[:, None] + np.outer(b - a, np.arange(n_sub + 1) / n_sub)  # (2, n_sub + 1)
        lag = lags(prev, a)
        j = 0
        while j < n_sub:
            step = min(stride, n_sub - j)
            c = path[:, j + step]
            out, ok = newton(prev, c)
            jump = float(np.abs(lags(out, c) - lag).max()) if ok else np.inf
            if step > 1 and not (ok and jump < SMOOTH_LAG_CHANGE):
                stride = 1  # not plainly smooth: look again in single sub-steps
                continue
            if not ok:
                snapped[k] = True
                out, why = fall(out if np.isfinite(out).all() else prev, c)
                if why:
                    prev = out
                    failure[k] = why
                    break
                jump = float(np.abs(lags(out, c) - lag).max())
            if jump > SNAP_LAG_JUMP:
                snapped[k] = True
            stride = min(2 * stride, MAX_STRIDE) if jump < SMOOTH_LAG_CHANGE / 2 else 1
            prev, lag = out, lags(out, c)
            j += step
        states.append(prev)
    x = np.column_stack(states)
    reached = np.isfinite(x).all(axis=0)
    eq = _finish(model, params, effective, x, reached, snapped, failure, _Checks(x.shape[1]))
    return Equilibria(**{**eq.__dict__, "command": command.T.copy()})


def solve_design(
    design: Design,
    theta1: ArrayLike,
    theta2: ArrayLike,
    model: RingPairModel | None = None,
    ordered: bool = False,
    multistable: bool = False,
) -> Equilibria:
    """The states of ``design`` (baseline model unless given) for commanded angles. [rad]

    ordered : follow the commands as a path (:func:`solve_sequence`) instead of solving
        each on its own; required for ``hysteresis`` and to see snap-through along a path.
    multistable : look for other stable states (configurations on their own only).
    """
    model = model or RingPairModel()
    if ordered:
        return solve_sequence(model, model.parameters(design), theta1, theta2)
    return solve_equilibria(
        model, model.parameters(design), theta1, theta2, multistable=multistable
    )
