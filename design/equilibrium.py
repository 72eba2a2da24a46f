"""Batch equilibrium of the ring-pair robot: Newton's method from the straight robot.

The magnetic wrench depends on the tip pose, so the steady state solves r(q) = 0
(:mod:`design.model`). For N configurations at once, a fixed number of Newton steps is
unrolled into one compiled function and mapped over the batch; configurations whose
residual is not below tolerance afterwards are re-solved by load continuation (the ring
moments ramped from zero), and any still unconverged are flagged and returned as NaN.
An equilibrium is stable when the symmetric part of the tangent stiffness K - dQ/dq is
positive definite (Sylvester's criterion on its diagonally scaled form).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from design.compiled import compile_function
from design.model import N_COORDINATES, RingPairModel
from design.params import Design

NEWTON_STEPS = 6
TOLERANCE = 1e-10
"""Convergence: infinity norm of the residual q - C Q(q) below this. [m or rad]"""
CHUNK = 65536
THREADS = 2
CONTINUATION_STEPS = (4, 16, 64)


@dataclass(frozen=True)
class Equilibria:
    """Steady states of N configurations. Unconverged rows hold NaN in every pose array.

    theta : shape (N, 2), ring angles at the tip (theta1 distal, theta2 proximal). [rad]
    position : shape (N, 3), rod tip (proximal ring centre), base frame. [m]
    tangent : shape (N, 3), unit tip tangent, base frame. [-]
    frame : shape (N, 3, 3), tip frame, columns (tangent, y_tip, z_tip), base frame. [-]
    coordinates : shape (N, 4), cantilever coordinates (dy, dz, phi_y, phi_z). [m, rad]
    converged : shape (N,), residual below TOLERANCE.
    stable : shape (N,), converged and the tangent stiffness is positive definite.
    residual : shape (N,), infinity norm of the final residual. [m or rad]
    """

    theta: np.ndarray
    position: np.ndarray
    tangent: np.ndarray
    frame: np.ndarray
    coordinates: np.ndarray
    converged: np.ndarray
    stable: np.ndarray
    residual: np.ndarray

    def __len__(self) -> int:
        return len(self.converged)


@lru_cache(maxsize=8)
def newton_function(model: RingPairModel) -> ca.Function:
    """Compiled single-configuration solver:
    (q0, theta, params) -> (q, |r|_inf, leading minors of scaled sym(H), position, frame)."""
    q0 = ca.SX.sym("q0", N_COORDINATES)
    theta = ca.SX.sym("theta", 2)
    prm = ca.SX.sym("params", len(model.parameter_names))
    q = q0
    for _ in range(NEWTON_STEPS):
        r, jac, _h = model.residual(q, theta, prm)
        q = q - ca.solve(jac, r)
    r, _jac, h = model.residual(q, theta, prm)
    hs = 0.5 * (h + h.T)
    # Diagonal scaling (a congruence, so definiteness is unchanged) makes the minors O(1).
    k_scale = 1 / ca.sqrt(ca.fmax(ca.fabs(ca.diag(hs)), 1e-300))
    hn = hs * (k_scale @ k_scale.T)
    minors = ca.vertcat(*[ca.det(hn[:k, :k]) for k in range(1, N_COORDINATES + 1)])
    position, frame = model.pose(q, prm)
    fn = ca.Function(
        "newton", [q0, theta, prm], [q, ca.norm_inf(r), minors, position, ca.reshape(frame, 9, 1)]
    )
    return compile_function(fn)


@lru_cache(maxsize=16)
def _mapped(model: RingPairModel, size: int) -> ca.Function:
    return newton_function(model).map(size, "thread", THREADS)


def _evaluate(function: ca.Function, args: list[np.ndarray]) -> list[np.ndarray]:
    """Evaluate a mapped function on column-major buffers without DM conversions (which
    would cost more than the solve itself). Returns each output as (rows, size)."""
    buf, trigger = function.buffer()
    flat = [np.asfortranarray(a).ravel(order="F") for a in args]
    outs = [np.empty(function.nnz_out(i)) for i in range(function.n_out())]
    for i, a in enumerate(flat):
        buf.set_arg(i, memoryview(a))  # type: ignore[call-arg, arg-type]
    for i, o in enumerate(outs):
        buf.set_res(i, memoryview(o))  # type: ignore[call-arg, arg-type]
    trigger()
    return [o.reshape(function.size2_out(i), function.size1_out(i)).T for i, o in enumerate(outs)]


def _run(
    model: RingPairModel, q0: np.ndarray, theta: np.ndarray, params: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Run the compiled solver on columns (q0, theta, params), in fixed-size chunks.

    params : shape (n,) shared by all columns, or (n, N) one per column.
    """
    n = theta.shape[1]
    size = min(CHUNK, n)
    if params.ndim == 1:
        params = np.broadcast_to(params[:, None], (params.size, n))
    outs: list[list[np.ndarray]] = [[] for _ in range(5)]
    for start in range(0, n, size):
        stop = min(start + size, n)
        pad = size - (stop - start)
        args = [a[:, start:stop] for a in (q0, theta, params)]
        if pad:
            args = [np.pad(a, ((0, 0), (0, pad)), mode="edge") for a in args]
        for acc, out in zip(outs, _evaluate(_mapped(model, size), args), strict=True):
            acc.append(out[:, : stop - start])
    return tuple(np.concatenate(acc, axis=1) for acc in outs)


def solve_equilibria(
    model: RingPairModel,
    params: np.ndarray,
    theta1: ArrayLike,
    theta2: ArrayLike,
) -> Equilibria:
    """Equilibria for ring angles (theta1[i], theta2[i]) at the tip. [rad]

    params : model parameter vector, shape (n,), from ``model.parameters(design)``. [SI]
    theta1, theta2 : broadcastable arrays of tip angles. [rad]
    """
    t1, t2 = np.broadcast_arrays(
        np.asarray(theta1, float).ravel(), np.asarray(theta2, float).ravel()
    )
    theta = np.vstack([t1, t2])
    n = theta.shape[1]
    params = np.asarray(params, dtype=float)
    q, res, minors, pos, frame = _run(model, np.zeros((N_COORDINATES, n)), theta, params)
    bad = ~(res[0] < TOLERANCE)
    ring = model.parameter_names.index("ring_moment")
    for steps in CONTINUATION_STEPS:
        idx = np.flatnonzero(bad)
        if idx.size == 0:
            break
        qc = np.zeros((N_COORDINATES, idx.size))
        sub = theta[:, idx]
        for lam in np.linspace(0.0, 1.0, steps + 1)[1:]:
            prm = np.repeat(params[:, None], idx.size, axis=1)
            prm[ring] *= lam
            out = _run(model, qc, sub, prm)
            qc = np.where(np.isfinite(out[0]), out[0], qc)
        for arr, new in zip((q, res, minors, pos, frame), out, strict=True):
            arr[:, idx] = new
        bad = ~(res[0] < TOLERANCE)
    converged = ~bad
    stable = converged & np.all(minors > 0, axis=0)
    nan = np.where(converged, 1.0, np.nan)
    frames = frame.T.reshape(n, 3, 3).transpose(0, 2, 1) * nan[:, None, None]
    return Equilibria(
        theta=theta.T.copy(),
        position=pos.T * nan[:, None],
        tangent=frames[:, :, 0].copy(),
        frame=frames,
        coordinates=q.T * nan[:, None],
        converged=converged,
        stable=stable,
        residual=res[0].copy(),
    )


def solve_design(
    design: Design, theta1: ArrayLike, theta2: ArrayLike, model: RingPairModel | None = None
) -> Equilibria:
    """Equilibria of ``design`` (baseline model unless given) for tip angles. [rad]"""
    model = model or RingPairModel()
    return solve_equilibria(model, model.parameters(design), theta1, theta2)
