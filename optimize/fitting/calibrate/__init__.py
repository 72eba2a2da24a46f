"""Calibration: fit the model's uncertain physical parameters to measured tip positions.

One concept per module: the free-parameter policy (:mod:`.policy`), the result
(:mod:`.result`), the least-squares problem (:mod:`.problem`), the fit (:mod:`.fit`),
fits from several starts (:mod:`.starts`) and cross-validation
(:mod:`.cross_validation`); this package re-exports their public names.

Nonlinear least squares (``scipy.optimize.least_squares``, trust region reflective, with
bounds) on the position residuals weighted by their one-sigma uncertainty, with exact
Jacobians from the CasADi model by the implicit function theorem at each equilibrium
(:mod:`optimize.fitting.sensitivity`: dx/dp = -(dr/dx)^-1 dr/dp, through ``model.pose`` to the
tip, and through the friction play for ``hysteresis``).

Parameters are fitted in well-scaled units: scale factors, moduli and remanences by
their logarithm (relative change), lengths in millimetres, angles in degrees, masses in
grams (:data:`FREE_PARAMETERS`). Standard errors come from the Gauss-Newton covariance
(J^T J)^-1 s^2 with s^2 = chi^2 / (rows - parameters), mapped to SI by the delta method.
With priors (``priors=True``, :mod:`optimize.fitting.calibrate.priors`) the fit maximises
the posterior: one Gaussian residual per parameter, centred on the nominal design, with
the widths of :data:`FREE_PARAMETERS` or overrides; each estimate's pull (prior sigmas
moved) is :meth:`CalibrationResult.pulls`, and one beyond PULL_LIMIT is not physical.

Warm starts: the state of each configuration is the load ramp's
(:func:`design.equilibrium.solve_equilibria`, or the driven path's), but between two
evaluations of a fit the parameters change little, so each evaluation after the first
takes every row's state at the fit's current iterate (the lowest cost so far, never a
rejected trial step's) and solves once by Newton at the new parameters, with the
checks of :func:`design.equilibrium.drive` (contraction, the stable side of the folds,
clear of the magnet); rows that fail go through the ramp. A state the ramp reached by a
fall (``snapped``) is warm-started too: near a fold the ramp may fall elsewhere at the
new parameters, which the check of the answer below finds (solving such rows by the
ramp at every evaluation cost a third of the time of fits of the large-deflection rod,
for the same answers). Fits along a driven path are not warm-started (a
row's state there depends on where the path snapped: tried, such fits went elsewhere
often enough to cost more than they saved). The fit's answer is then solved by the
ramp itself, and where any fitted row's tip differs
from the warm-started one by more than WARM_TOLERANCE of its sigma, or has a state in one
and none in the other, the fit is made again from its start with those rows by the ramp
(WARM_RETRIES times, then every row by the ramp). Where that start sits on a symmetric
bifurcation (the magnet on the robot's axis, the offsets free at zero), every step of the
fit again may tip those rows to the other side, and it stays far above the first answer;
then it is also fitted from the first answer with one or two of its parameters back at the
start, from the one of these points where the ramp fits best, and the better fit is kept.
The returned result is always the ramp's.

Identifiability, said plainly: without gravity or torsion the baseline's tip pose
depends on the external remanence and the bending rigidity only through their ratio, so
``bending_rigidity_scale`` and ``external_remanence`` cannot both be free without priors
(their correlation is reported as +-1 and the fit says so in ``message``).

The paper's method (an exhaustive grid over a stiffness scale and a field scale) is kept
as :func:`grid_search_two_factors` (:mod:`optimize.fitting.paper_grid`, re-exported here). SI
units are used for all inputs and outputs; the ``*_mm`` figures of the results are
millimetres.
"""

from __future__ import annotations

from optimize.fitting.calibrate.cross_validation import (
    CrossValidation,
    _continued,
    configuration_folds,
    cross_validate,
    held_out_inflation,
)
from optimize.fitting.calibrate.fit import (
    WARM_RETRIES,
    WARM_TOLERANCE,
    UnsolvedStart,
    calibrate,
)
from optimize.fitting.calibrate.policy import (
    BASELINE_FREE,
    EFFECT_FREE,
    EFFECT_SEPARATES,
    FIELD_RELATIVE,
    FIELD_TOLERANCE,
    FREE_PARAMETERS,
    NESTED_START,
    SOFT_START,
    FreeParameter,
    default_free,
)
from optimize.fitting.calibrate.priors import (
    PRIORS_FILE,
    PULL_LIMIT,
    Priors,
    load_priors,
    parse_prior_options,
    parse_priors,
    prior_widths,
)
from optimize.fitting.calibrate.problem import TIP_ANGLE_SIGMA
from optimize.fitting.calibrate.result import (
    DEFAULT_SIGMA,
    CalibrationResult,
    row_sigma,
    straight_miss,
)
from optimize.fitting.calibrate.starts import (
    REPEAT_APART,
    calibrate_from_starts,
    path_matters,
    prior_starts,
    repeats_disagree,
    stiff_start,
)
from optimize.fitting.paper_grid import (
    PAPER_FIELD_GRID,
    PAPER_STIFFNESS_GRID,
    GridResult,
    grid_search_two_factors,
    two_factor_parameters,
)
from optimize.fitting.sensitivity import (
    SENSITIVE,
    Prediction,
    position_errors,
    predict,
    prediction_sensitivities,
    sensitivities,
    sensitivity_function,
)

__all__ = [
    "BASELINE_FREE",
    "EFFECT_FREE",
    "EFFECT_SEPARATES",
    "FIELD_RELATIVE",
    "FIELD_TOLERANCE",
    "FREE_PARAMETERS",
    "NESTED_START",
    "SOFT_START",
    "PAPER_FIELD_GRID",
    "PAPER_STIFFNESS_GRID",
    "SENSITIVE",
    "CalibrationResult",
    "UnsolvedStart",
    "CrossValidation",
    "FreeParameter",
    "GridResult",
    "Prediction",
    "calibrate",
    "PRIORS_FILE",
    "PULL_LIMIT",
    "Priors",
    "load_priors",
    "parse_prior_options",
    "parse_priors",
    "prior_widths",
    "held_out_inflation",
    "DEFAULT_SIGMA",
    "TIP_ANGLE_SIGMA",
    "WARM_RETRIES",
    "WARM_TOLERANCE",
    "_continued",
    "calibrate_from_starts",
    "stiff_start",
    "prior_starts",
    "repeats_disagree",
    "REPEAT_APART",
    "configuration_folds",
    "cross_validate",
    "default_free",
    "path_matters",
    "grid_search_two_factors",
    "position_errors",
    "predict",
    "prediction_sensitivities",
    "row_sigma",
    "straight_miss",
    "sensitivities",
    "sensitivity_function",
    "two_factor_parameters",
]
