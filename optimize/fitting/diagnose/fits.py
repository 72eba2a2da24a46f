"""One fit of a candidate model as the search uses it (:func:`_fit`): from several starts,
along the bench's path where that matters, the best kept, optionally cross-validated
(:func:`_cross_validated`). SI units.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any, Literal

import numpy as np

from design.model import model_for
from design.records import Design
from optimize.fitting.calibrate import (
    CalibrationResult,
    Priors,
    UnsolvedStart,
    calibrate,
    cross_validate,
    default_free,
    path_matters,
    straight_miss,
)
from optimize.fitting.diagnose.result import Fit
from optimize.fitting.diagnose.scans import UNSOLVED_OFFSETS, _parameters, _scan
from optimize.fitting.diagnose.starts import _leveled_start, _prefix_start, _stiffer
from optimize.fitting.measurements import Measurements

SCREEN_EVALUATIONS = 12
"""Model evaluations of a screening fit (a candidate's BIC before it is fitted in full)."""
MIN_SOLVED = 0.5
"""A screening fit skips a start where fewer than this fraction of the rows have a state
(:class:`optimize.fitting.calibrate.UnsolvedStart`). [-]"""
FOLD_ANCHOR = 3.0
"""A fold of the cross-validation fits its parameters under a Gaussian penalty centred on
the fit of all the data, this many of its standard errors wide. Without it, a fold of a
few configurations can wander along a direction the full data barely fix (e.g. the
magnet's height seen from above) to where its held-out configurations lie on another
branch of a multistable robot, and the held-out error then measures that jump, not the
model. [-]"""
FOLD_EVALUATIONS = 25
"""Model evaluations of a fold's fit at most (it starts at the fit of all the data)."""

Progress = Callable[[str], None]
Fitted = tuple[CalibrationResult, bool | Literal["driven"]]
"""A calibration and the solve mode it was fitted with (see :func:`predict`)."""


def _fit(
    design: Design,
    m: Measurements,
    effects: frozenset[str],
    *,
    k: int,
    seed: int,
    cv: bool,
    starts: Sequence[CalibrationResult | Mapping[str, float] | None],
    sigma: float | None,
    max_nfev: int | None = None,
    free: Sequence[str] = (),
    priors: bool | Priors = True,
    within: float | None = None,
) -> Fit:
    """Calibrate ``effects`` from each start (None: the nominal design; a fit: its
    estimates, and its states if it is of this model; a mapping: these values, the others
    nominal), keep the best, and
    cross-validate it if ``cv``. ``free``: the free parameters (default: the effects'
    :func:`default_free`). ``priors`` (:mod:`optimize.fitting.calibrate.priors`: True, the
    defaults; a mapping, widths overridden; False, none) do not pull the fit, a least
    squares fit as without them: they judge its estimates (their pulls) and, with
    ``within``, bound each parameter to its nominal value +- that many prior sigmas."""
    free = tuple(free) or default_free(effects)
    model = model_for(effects)
    mode: bool | Literal["driven"] = "hysteresis" in effects

    # the priors judge and (``within``) bound the fit; the diagnosis fits by least squares
    options: dict[str, Any] = {
        "sigma": sigma,
        "max_nfev": max_nfev,
        "priors": priors,
        "posterior": False,
    }
    if within is not None:  # the prior-bounded fit (calibrate's ``within``)
        options["within"] = within
    if max_nfev is not None:  # a screen: skip starts where most rows have no state
        options["min_solved"] = MIN_SOLVED

    def fit(
        start: Mapping[str, float] | None,
        path: bool | Literal["driven"],
        states: np.ndarray | None = None,
    ) -> Fitted:
        cal = calibrate(
            design, m, effects, free, initial=start, ordered=path, states=states, **options
        )
        return cal, path

    # From each start: the fast fit, refitted along the path if the path matters at its
    # estimate; and a fit along the path from the start itself if the path matters there
    # (the fast fit can run into a region where it no longer does, e.g. a stiff rod).
    fits: list[Fitted] = []
    skipped: list[UnsolvedStart] = []
    for s in starts:
        values = {} if s is None else s if isinstance(s, Mapping) else s.estimate
        initial = {n: v for n, v in values.items() if n in free} or None
        leveled = _leveled_start(model, design, m, initial, free, mode, unset=values)
        # A fit of this model starts from its own states (the first evaluation warm).
        same = isinstance(s, CalibrationResult) and s.effects == model.effects and not leveled
        initial = leveled or initial
        # where the robot is pulled onto the magnet at most rows, also from a stiffer rod
        attempts = [initial, *_stiffer(model, design, initial, free)]
        for attempt in attempts:
            states = s.states if same and attempt is initial else None  # type: ignore[union-attr]
            try:
                cal, path = fit(attempt, mode, states)
                break
            except UnsolvedStart as exc:
                skipped.append(exc)
        else:
            continue
        initial = attempt
        if path_matters(model, cal.params, m, mode):
            cal, path = fit({n: cal.estimate[n] for n in free}, "driven")
        fits.append((cal, path))
        if path_matters(model, _parameters(model, design, initial), m, mode):
            fits.append(fit(initial, "driven"))
    if not fits:
        raise skipped[0]
    # A fit that solves every row first; among fits that all leave rows, the least misfit.
    cal, path = min(fits, key=lambda f: (f[0].unconverged > 0, f[0].chi2))
    if m.sequence is not None and max_nfev is None:  # full fits of data with a path
        start = _prefix_start(design, m, effects, free, cal, sigma, priors)
        if start is not None:
            early, _ = fit(start, "driven")
            if early.unconverged == 0 and early.chi2 < cal.chi2:
                cal, path = early, "driven"
        start = _scan(model, m, cal.params, free)
        if start is not None:
            scanned, _ = fit(start, "driven")
            if scanned.unconverged == 0 and scanned.chi2 < cal.chi2:
                cal, path = scanned, "driven"
    if cal.unconverged:
        # A row without a state costs the straight robot's miss wherever it has none: the
        # fit sees no slope back to where it has one, and stops just past the edge.
        start = _scan(
            model, m, cal.params, free, ordered=path, factors=(), offsets=UNSOLVED_OFFSETS
        )
        if start is not None:
            rescued, rescued_path = fit(start, path)
            if rescued.unconverged == 0 and rescued.chi2 < cal.chi2:
                cal, path = rescued, rescued_path
    solved = np.isfinite(cal.errors)
    unsolved = int(np.count_nonzero(m.seen & ~solved))
    coordinates = int(m.measured.sum())
    # Rows without a state cost what the fit's objective charged them: the straight robot's
    # miss. An infinite misfit would make every model that solves them win by -inf BIC,
    # whatever it does on the others.
    rss = float(np.nansum(cal.residuals[solved] ** 2))
    rss += float(np.sum(straight_miss(cal.params, m)[m.seen & ~solved] ** 2))
    result = Fit(effects, cal, math.nan, rss, coordinates, path, unsolved)
    return _cross_validated(design, m, result, k=k, seed=seed, sigma=sigma) if cv else result


def _cross_validated(
    design: Design, m: Measurements, fit: Fit, *, k: int, seed: int, sigma: float | None
) -> Fit:
    """``fit`` with its k-fold cross-validated RMSE; each fold starts at the fit of all the
    data, solves the configurations as it did, and is kept near it (FOLD_ANCHOR)."""
    cal = fit.calibration
    scale = math.sqrt(cal.chi2 / cal.dof) if cal.chi2 > 0 else 1.0
    error = cal.standard_error
    anchor = {
        n: (cal.estimate[n], FOLD_ANCHOR * error[n] / scale)
        for n in cal.names
        if np.isfinite(error[n]) and error[n] > 0
    }
    priors = dict(cal.prior_width) or False
    held_out = cross_validate(
        design,
        m,
        fit.effects,
        cal.names,
        k=k,
        seed=seed,
        initial=cal.estimate,
        full=cal,
        sigma=sigma,
        max_nfev=FOLD_EVALUATIONS,
        ordered=fit.ordered,
        anchor=anchor,
        priors=priors,
        posterior=cal.priors,
        within=cal.within,
    )
    return replace(fit, cv_rmse_mm=held_out.rmse_mm, cv_expected_ratio=held_out.expected_ratio)
