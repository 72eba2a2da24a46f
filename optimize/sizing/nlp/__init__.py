"""Solving the design NLP of a study (:mod:`optimize.sizing.nlp_problem`) with IPOPT, with exact
derivatives through the model's own CasADi expressions; evaluating designs; the results.

Multi-start: start 1 is the base design, the others are drawn uniformly in the bounds
(seeded); a start that fails is recorded with IPOPT's status and does not stop the study.
If no start is feasible, a minimum-violation problem (one slack per constraint group)
tells which constraints conflict and by how much.

SI units are used for all inputs and outputs; file units only in reports.

Split by concept: :mod:`~optimize.sizing.nlp.evaluation` (forward evaluation, constraint
states, norms), :mod:`~optimize.sizing.nlp.branches` (is the optimum the robot's state,
can its loops be driven), :mod:`~optimize.sizing.nlp.solve` (multi-start IPOPT, the
minimum-violation problem), :mod:`~optimize.sizing.nlp.bounds` (Pareto bounds); this
package re-exports their names.
"""

from optimize.sizing.nlp.bounds import kept_optimum, pareto_values
from optimize.sizing.nlp.branches import (
    ARRIVAL_TOLERANCE,
    BRANCH_TOLERANCE,
    _loop_faults,
    _off_branch,
)
from optimize.sizing.nlp.evaluation import (
    ACTIVE_TOLERANCE,
    CONTROLLABLE,
    CONTROLLABLE_STEP,
    FEASIBILITY_TOLERANCE,
    _forward,
    _nlp_shape,
    _norms,
    controllable_disc_radius,
    evaluate_design,
    start_breaks,
)
from optimize.sizing.nlp.solve import _solve_one, optimize_design
from optimize.sizing.nlp_results import (
    Conflict,
    ConstraintState,
    Evaluation,
    OptimizationResult,
    StartResult,
)

__all__ = [
    "ACTIVE_TOLERANCE",
    "ARRIVAL_TOLERANCE",
    "BRANCH_TOLERANCE",
    "CONTROLLABLE",
    "CONTROLLABLE_STEP",
    "FEASIBILITY_TOLERANCE",
    "Conflict",
    "ConstraintState",
    "Evaluation",
    "OptimizationResult",
    "StartResult",
    "_forward",
    "_loop_faults",
    "_nlp_shape",
    "_norms",
    "_off_branch",
    "_solve_one",
    "controllable_disc_radius",
    "evaluate_design",
    "kept_optimum",
    "optimize_design",
    "pareto_values",
    "start_breaks",
]
