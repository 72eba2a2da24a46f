"""Tip stiffness: how far the tip's tracked point gives under a force pressed on it.

At an equilibrium r(x, F) = 0 (:mod:`design.model`, F the force applied at the tracked
point, the registry's ``applied_force_*``, 0 in a design) the implicit function theorem
gives the state's derivative dx/dF = -(dr/dx)^-1 dr/dF, and the tracked point P(x) moves by
the compliance

    C = dP/dF = (dP/dx) (dr/dx)^-1 (-dr/dF),   a 3x3 matrix, base frame [m/N],

compiled from the model's own expressions (:func:`_compliance`): dr/dx holds every load's
dependence on the pose, so the magnetic stiffness of the field and its gradient (the
force and torque change as the rings move through a non-uniform field), gravity and the
rings' torsion are in it, exactly as in the equilibrium itself. The stiffness is its
inverse, K = C^-1 [N/m = mN/mm]. For conservative loads C is symmetric; its symmetric
part's eigenvalues c_i (ascending stiffness 1 / c_i) and eigenvectors are the principal
stiffnesses and directions. An inextensible rod does not shorten under an axial push to
first order: along a direction whose compliance is below RIGID times the largest the tip
is rigid in the model (infinite stiffness); those are counted (``rigid``), not reported
as numbers. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from design.compiled import compile_function
from design.equilibrium import Equilibria, kernels
from design.model import RingPairModel
from design.registry import index

RIGID = 1e-9
"""A principal compliance below this fraction of the largest is a rigid direction. [-]"""


@dataclass(frozen=True)
class TipStiffness:
    """The tip's translational stiffness at N states (NaN where a row has no state).

    compliance : shape (N, 3, 3), dP/dF at the tracked point, base frame. [m/N]
    stiffness : shape (N, 3), principal stiffnesses, ascending; inf along rigid
        directions. [N/m, numerically mN/mm]
    directions : shape (N, 3, 3), the principal directions as columns, base frame. [-]
    rigid : shape (N,), directions along which the model's tip does not give (an
        inextensible rod's axis).
    asymmetry : shape (N,), |C - C^T| / |C| (Frobenius): 0 for conservative loads. [-]
    """

    compliance: np.ndarray
    stiffness: np.ndarray
    directions: np.ndarray
    rigid: np.ndarray
    asymmetry: np.ndarray

    @property
    def lowest(self) -> np.ndarray:
        """The smallest principal stiffness, shape (N,). [N/m]"""
        return self.stiffness[:, 0]

    @property
    def highest(self) -> np.ndarray:
        """The largest finite principal stiffness, shape (N,) (NaN without one). [N/m]"""
        finite = np.where(np.isfinite(self.stiffness), self.stiffness, -np.inf).max(axis=1)
        return np.where(np.isfinite(finite), finite, np.nan)


@lru_cache(maxsize=16)
def _compliance(model: RingPairModel) -> ca.Function:
    """(x, command, params) -> C (9, column-major) at an equilibrium x, compiled."""
    x = ca.SX.sym("x", model.n_unknowns)
    command = ca.SX.sym("command", 2)
    prm = ca.SX.sym("params", model.residual.size1_in(2))
    r, dr_dx = model.residual.call([x, command, prm])
    position = model.pose.call([x, command, prm])[0]
    first = index("applied_force_x")
    force = prm[first : first + 3]
    dx_df = -ca.solve(dr_dx, ca.jacobian(r, force))
    c = ca.jacobian(position, x) @ dx_df + ca.jacobian(position, force)
    return compile_function(ca.Function("compliance", [x, command, prm], [ca.densify(ca.vec(c))]))


def tip_stiffness(
    model: RingPairModel,
    params: np.ndarray,
    eq: Equilibria,
    held: np.ndarray | None = None,
) -> TipStiffness:
    """The tip stiffness of each state of ``eq`` (of ``model`` with ``params``, shape (k,)
    or (k, N)). ``held`` (N, 3): where finite, the unit normal of a frictionless obstacle
    the tip presses on; the tip then moves only along it, C_held = C - C n n^T C /
    (n^T C n), which is rigid along n (the compliance at the tracked point stands for the
    contact point's).

    The model's Jacobians do not depend on the commanded angles beyond the tip angles (the
    transmissions' twist is linear in the command), so the states' tip angles are passed
    as the command: right with ``hysteresis`` too, whose effective command is not kept.
    """
    params = np.asarray(params, float)
    n = len(eq)
    compliance = np.full((n, 3, 3), np.nan)
    ok = np.asarray(eq.stable, bool) & np.isfinite(eq.unknowns).all(axis=1)
    if ok.any():
        p = params if params.ndim == 1 else params[:, ok]
        c = kernels(model).run(_compliance(model), [eq.unknowns[ok].T, eq.tip_angles[ok].T], p)
        compliance[ok] = c[0].T.reshape(-1, 3, 3).transpose(0, 2, 1)
    if held is not None:
        pressed = np.isfinite(held).all(axis=1) & np.isfinite(compliance).all(axis=(1, 2))
        if pressed.any():
            c, nu = compliance[pressed], held[pressed]
            cn, ncv = c @ nu[:, :, None], nu[:, None, :] @ c
            compliance[pressed] = c - cn @ ncv / (ncv @ nu[:, :, None])
    stiffness = np.full((n, 3), np.nan)
    directions = np.full((n, 3, 3), np.nan)
    rigid = np.zeros(n, int)
    asymmetry = np.full(n, np.nan)
    good = np.isfinite(compliance).all(axis=(1, 2))
    if good.any():
        c = compliance[good]
        sym = 0.5 * (c + c.transpose(0, 2, 1))
        values, vectors = np.linalg.eigh(sym)  # ascending compliance
        values, vectors = values[:, ::-1], vectors[:, :, ::-1]  # ascending stiffness
        floor = RIGID * np.abs(values).max(axis=1, keepdims=True)
        stiff = values <= floor
        with np.errstate(divide="ignore"):
            stiffness[good] = np.where(stiff, np.inf, 1.0 / np.where(stiff, 1.0, values))
        directions[good] = vectors
        rigid[good] = stiff.sum(axis=1)
        scale = np.linalg.norm(c, axis=(1, 2))
        asymmetry[good] = np.linalg.norm(c - c.transpose(0, 2, 1), axis=(1, 2)) / np.where(
            scale > 0, scale, 1.0
        )
    return TipStiffness(compliance, stiffness, directions, rigid, asymmetry)
