"""Stability of states from the solver's monitors (the fold test along a branch, the
exact check anywhere), and the per-column scales and norms of the unknowns."""

from __future__ import annotations

import numpy as np

from design.equilibrium import settings
from design.model import RingPairModel


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
        good &= lowest > -settings.HESSIAN_TOLERANCE
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
