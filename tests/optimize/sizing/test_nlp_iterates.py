"""The stall stop of the design NLP (optimize/sizing/nlp_iterates.py), on problems whose
answers are known in closed form."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from optimize.sizing.nlp_iterates import STALL_ITERATIONS, BestIterate


def _solve(f, g, x0, lbg, ubg, stop: bool):
    """IPOPT with limited-memory Hessians (as the design NLP) on min f s.t. lbg <= g <=
    ubg, with or without the stall stop: (status, iterations, x, callback)."""
    x = ca.SX.sym("x", len(x0))
    best = BestIterate(len(x0), 1, 1e-8)
    options = {
        "ipopt.print_level": 0,
        "print_time": 0,
        "ipopt.max_iter": 1000,
        "ipopt.hessian_approximation": "limited-memory",
    }
    if stop:
        options["iteration_callback"] = best
    solver = ca.nlpsol("kink", "ipopt", {"x": x, "f": f(x), "g": g(x)}, options)
    best.reset(np.array([lbg]), np.array([ubg]))
    sol = solver(x0=x0, lbg=lbg, ubg=ubg)
    stats = solver.stats()
    return stats["return_status"], stats["iter_count"], np.asarray(sol["x"]).ravel(), best


def test_a_kinked_minimum_is_kept_once_the_solve_wanders_about_it():
    # min |x0 - 0.3| + |x1 + 0.2| s.t. -1 <= x0 + x1 <= 1: the minimum (0.3, -0.2), f = 0,
    # sits on two kinks, as the disc radius (a minimum over the workspace's sides) does.
    # IPOPT's quasi-Newton steps circle it for hundreds of iterations before certifying.
    def f(x):
        return ca.fabs(x[0] - 0.3) + ca.fabs(x[1] + 0.2)

    def g(x):
        return x[0] + x[1]

    status, plain, _, _ = _solve(f, g, [2.0, 1.0], -1.0, 1.0, stop=False)
    assert status == "Solve_Succeeded" and plain > 4 * STALL_ITERATIONS
    status, stopped, _, best = _solve(f, g, [2.0, 1.0], -1.0, 1.0, stop=True)
    assert status == "User_Requested_Stop" and best.stalled
    assert stopped < plain / 2
    x, objective = best.best
    assert objective == pytest.approx(0.0, abs=1e-9)
    assert x == pytest.approx([0.3, -0.2], abs=1e-9)


def test_a_converging_solve_through_infeasible_iterates_is_not_touched():
    # min (x0 - 3)^2 + (x1 - 1)^2 s.t. x0 * x1 <= 1 from a feasible start far off: the
    # iterates leave the feasible set on the way; the answer is the tangency of the circle
    # about (3, 1) with the hyperbola x0 x1 = 1, found here by a separate 1-D solve. (The
    # long way, 25 improving infeasible iterates from a feasible start, is the known-distance
    # study of test_nlp.py, whose optimum is a closed form.)
    def f(x):
        return (x[0] - 3.0) ** 2 + (x[1] - 1.0) ** 2

    def g(x):
        return x[0] * x[1]

    plain = _solve(f, g, [0.0, -5.0], -np.inf, 1.0, stop=False)
    stopped = _solve(f, g, [0.0, -5.0], -np.inf, 1.0, stop=True)
    assert stopped[0] == plain[0] == "Solve_Succeeded" and not stopped[3].stalled
    assert stopped[1] == plain[1]
    # on x1 = 1/x0, d/dx0 [(x0-3)^2 + (1/x0-1)^2] = 0: x0^4 - 3 x0^3 + x0 - 1 = 0
    roots = np.roots([1.0, -3.0, 0.0, 1.0, -1.0])
    real = roots[np.isreal(roots)].real
    distance = [(r - 3) ** 2 + (1 / r - 1) ** 2 for r in real]
    x0 = real[int(np.argmin(distance))]
    assert stopped[2] == pytest.approx([x0, 1 / x0], abs=1e-6)


# The default study's Pareto point at a 1.46 mm catheter, from the optimum (nylon 12):
# IPOPT stalls on it. An interior-point iterate's multipliers are the barrier's, nonzero
# on every row; read as KKT multipliers they made every constraint "active" in the front's
# CSV. The answer's active rows are the rows at their limits, and only they.
@pytest.mark.slow
def test_a_best_feasible_iterate_names_as_active_only_the_rows_at_their_limits():
    from dataclasses import replace

    from optimize.sizing.nlp import optimize_design
    from optimize.sizing.nlp.evaluation import ACTIVE_TOLERANCE
    from optimize.sizing.studyfile import default_study

    study = replace(default_study(), catheter_materials=("nylon_12",))
    optimum = {  # the study's optimum as its run found it (results.json, SI)
        "catheter_outer_diameter": 1.6382860344667862e-3,
        "catheter_inner_diameter": 0.600000000033558e-3,
        "wire_outer_diameter": 0.3922135669205517e-3,
        "magnet_outer_diameter": 1.3499999999847767e-3,
        "magnet_inner_diameter": 0.650000000059601e-3,
        "magnet_length": 1.4548988279027573e-3,
        "magnet_gap": 5.108386107657104e-14,
        "external_distance": 60.00000000059083e-3,
    }
    result = optimize_design(
        study, epsilon={"catheter_outer_diameter": 1.46e-3}, starts=[optimum], conflicts=False
    )
    assert result.feasible
    if not result.starts[0].status.startswith("Best_Feasible_Iterate"):
        pytest.skip(f"IPOPT converged on this machine ({result.starts[0].status})")
    at_limit = {c.name for c in result.constraints if c.margin / c.scale < ACTIVE_TOLERANCE}
    assert {a for a in result.active if not a.startswith("bound.")} == at_limit
    assert len(at_limit) < len(result.constraints) / 2, result.active
