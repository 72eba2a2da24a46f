"""The best feasible iterate of an IPOPT solve, and the stop once it stalls.

Near a fold of the robot's equilibria or a kink of the disc radius (a minimum over the
workspace's sides), IPOPT with limited-memory Hessians can reach the optimum's design,
feasible, within a few dozen iterations, and then never certify it: its dual
infeasibility stays at 1e-3 to 1e-1 while its steps wander off feasibility and back, until
the iteration limit (measured on the default study's magnet-volume sweep: the objective
settled to 1e-6 by iteration 34 of 300, the last iterate 0.7 off its equilibria). The
callback here, called by IPOPT at every iteration, keeps the iterate with the best
objective among those that meet the constraints (to the solve's ``constr_viol_tol``),
and stops the solve once that has not improved by more than :data:`STALL_GAIN`
(relative) for :data:`STALL_ITERATIONS` iterations in which the solve came back to the
feasible set :data:`STALL_RETURNS` times: it wanders about the optimum it has. A solve
still on its way (infeasible iterates whose objective improves, as on the way from a
feasible start to a far optimum) is not stopped, nor is one that converges: its iterates
improve until IPOPT's own test stops it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

STALL_ITERATIONS = 30
"""Iterations without a gain after which a solve with a feasible iterate is stopped."""
STALL_RETURNS = 5
"""Feasible iterates without a gain, within those iterations, that make it a stall."""
STALL_GAIN = 1e-6
"""Relative objective gain that counts as progress. [-]"""


class BestIterate(ca.Callback):  # type: ignore[misc]
    """IPOPT's iteration callback (CasADi ``iteration_callback``): the best feasible
    iterate of the current solve. nx, ng : the NLP's numbers of variables and rows.
    feasible : largest violation of any row (the NLP's scaled rows) of a kept iterate.
    Call :meth:`reset` with the solve's row bounds before each solve; after it,
    :attr:`best` is (x, f) or None and :attr:`stalled` says whether this
    callback stopped it."""

    def __init__(self, nx: int, ng: int, feasible: float) -> None:
        ca.Callback.__init__(self)
        self.nx, self.ng, self.feasible = nx, ng, feasible
        self.reset(np.full(ng, -np.inf), np.full(ng, np.inf))
        self.construct("best_iterate", {})

    def reset(self, lbg: np.ndarray, ubg: np.ndarray) -> None:
        """Forget the last solve; ``lbg``, ``ubg``: the next solve's row bounds."""
        self.lbg, self.ubg = np.asarray(lbg, float), np.asarray(ubg, float)
        self.best: tuple[np.ndarray, float] | None = None
        self.since = self.returns = 0
        self.stalled = False

    def get_n_in(self) -> int:
        return int(ca.nlpsol_n_out())

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return str(ca.nlpsol_out(i))

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nx)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.ng)
        return ca.Sparsity(0, 0)

    def eval(self, arg: Sequence[ca.DM]) -> list[Any]:
        x, f, g = (np.asarray(a, float).ravel() for a in arg[:3])
        objective = float(f[0])
        violation = np.max(np.maximum(self.lbg - g, g - self.ubg), initial=0.0)
        if violation <= self.feasible and np.isfinite(objective) and np.isfinite(x).all():
            if self.best is None or objective < self.best[1] - STALL_GAIN * abs(self.best[1]):
                self.best = (x.copy(), objective)
                self.since = self.returns = 0
                return [0]
            if objective < self.best[1]:
                self.best = (x.copy(), objective)
            self.returns += 1
        if self.best is not None:
            self.since += 1
            if self.since >= STALL_ITERATIONS and self.returns >= STALL_RETURNS:
                self.stalled = True
                return [1]  # IPOPT: User_Requested_Stop
        return [0]
