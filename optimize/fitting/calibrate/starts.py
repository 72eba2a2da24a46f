"""Fits from several starts: whether the bench's path matters (:func:`path_matters`),
the start with stiff transmissions (:func:`stiff_start`) and the best of the fits from
the nominal design, stiff and soft transmissions and along the path
(:func:`calibrate_from_starts`). SI units.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Literal

import numpy as np

from design.model import RingPairModel, model_for
from design.records import Design
from design.registry import PARAMETERS
from optimize.fitting.calibrate.fit import calibrate
from optimize.fitting.calibrate.policy import (
    FREE_PARAMETERS,
    NESTED_START,
    SOFT_START,
    default_free,
)
from optimize.fitting.calibrate.priors import Priors, prior_widths
from optimize.fitting.calibrate.result import CalibrationResult, row_sigma
from optimize.fitting.measurements import Measurements
from optimize.fitting.sensitivity import predict


def path_matters(
    model: RingPairModel,
    params: np.ndarray,
    m: Measurements,
    ordered: bool | Literal["driven"] | None = None,
) -> bool:
    """Whether driving the bench's path (the data's ``sequence``) ends in other states
    than solving ``m`` as ``ordered`` (:func:`predict`) at ``params``. Twisting
    transmissions, or a strong magnet near the tip, can make the robot multistable; then
    its state depends on the path driven, and the fast solve (each configuration on its
    own, or the played commands in one batch) is exact only where the two agree. False
    without a sequence."""
    if m.sequence is None:
        return False
    fast = predict(model, params, m, ordered=ordered).equilibria.position
    driven = predict(model, params, m, ordered="driven").equilibria.position
    same_solved = np.array_equal(np.isnan(fast), np.isnan(driven))
    return not (same_solved and np.nanmax(np.abs(fast - driven), initial=0.0) < 1e-6)


REPEAT_APART = 5.0
"""Two rows of one command measured further apart than this many sigmas of their
difference show a state that depends on the path the bench drove. [-]"""


def repeats_disagree(m: Measurements, sigma: float | None = None) -> bool:
    """Whether two rows of one command were measured more than REPEAT_APART sigmas apart
    (their difference's, over the coordinates both measured; rows' sigmas by
    :func:`row_sigma`): the robot on the bench was multistable there, whatever the model
    says at the nominal design."""
    s = row_sigma(m, sigma)
    _, group = np.unique(m.command, axis=0, return_inverse=True)
    for g in np.unique(group):
        rows = np.flatnonzero(group.ravel() == g)
        for a, i in enumerate(rows):
            for j in rows[a + 1 :]:
                both = m.measured[i] & m.measured[j]
                apart = np.linalg.norm((m.position[i] - m.position[j])[both])
                if apart > REPEAT_APART * np.hypot(s[i], s[j]):
                    return True
    return False


def prior_starts(
    design: Design, free: Sequence[str], priors: bool | Priors = True
) -> dict[str, dict[str, float]]:
    """Starts one prior sigma (``priors``' widths, the registry's where a width is
    infinite or priors are off) either side of the nominal design along each free
    parameter, the others nominal, inside the fit's bounds; by label, e.g.
    'bending_rigidity_scale +1 sigma'. [SI]"""
    widths = prior_widths(priors if isinstance(priors, Mapping) else None)
    starts = {}
    for name in free:
        spec = FREE_PARAMETERS[name]
        width = widths[name] if np.isfinite(widths[name]) else spec.prior
        p0 = PARAMETERS[name].value(design)
        for sign in (-1, 1):
            low, high = max(spec.lower, p0 - spec.span), min(spec.upper, p0 + spec.span)
            value = float(np.clip(spec.physical(sign * width, p0), low, high))
            starts[f"{name} {sign:+d} sigma"] = {name: value}
    return starts


def stiff_start(
    design: Design,
    m: Measurements,
    effects: Iterable[str],
    free: Sequence[str],
    initial: Mapping[str, float] | None = None,
    **options: Any,
) -> dict[str, float] | None:
    """Where a fit of ``effects`` with ``free`` torsion scales also starts: the other free
    parameters fitted (from ``initial``, ``options`` of :func:`calibrate`) with the
    transmissions held nearly rigid (NESTED_START, the baseline's assumption), and the
    transmissions there; None where no torsion scale is free."""
    stiff = {n: v for n, v in NESTED_START.items() if n in free}
    if not stiff:
        return None
    others = [n for n in free if n not in stiff]
    held = {n: v for n, v in (initial or {}).items() if n in others}
    if others:
        fit = calibrate(design, m, effects, others, fixed=stiff, initial=held or None, **options)
        held = fit.estimate
    return {**held, **stiff}


def calibrate_from_starts(
    design: Design,
    m: Measurements,
    effects: Iterable[str] = (),
    free: Sequence[str] | None = None,
    **options: Any,
) -> tuple[CalibrationResult, dict[str, CalibrationResult]]:
    """:func:`calibrate` (``options`` are its own) from the nominal design and, where
    torsion scales are free, also from stiff and from soft transmissions: a local fit
    cannot cross a snap-through of the rings, and which side of one the nominal design
    lies on is chance. 'stiff': :func:`stiff_start`; 'soft': the nominal design with
    SOFT_START. Magnet on the robot's axis, torsion data drawn from the design space
    (``optimize.fitting.planted``, 15 sets): from the nominal design alone 5 fits ended at
    1.7-15 times the noise's RMS, from these three starts (and along the path, below) 2 at
    1.7 and 9 times.
    Where the data have a sequence and driving their path ends in other states than the
    fit's solve at the best estimate (:func:`path_matters`), the best is also fitted along
    the path ('along the path'; on-axis torsion set [99, 9], 15 rows: 1.7 -> 0.9x the
    noise's RMS); where the data have a sequence, the fit is also driven from the start
    ('along the path from the start': a fit from rest can settle where the path no
    longer matters, in the wrong states, null as-built set of seed 18 in
    tests/optimize/fitting/test_priors.py, chi-square 15,323 -> 3.0; and the path may
    matter at neither the nominal design nor the fit from rest while the robot measured is
    multistable, seed 2051170903 there, RMS 13.9 -> 0.54 mm). Returns the best
    (every fitted row solved, then the least chi-square) and the fit from each start by name."""
    names = default_free(effects) if free is None else tuple(free)
    fits = {"nominal": calibrate(design, m, effects, names, **options)}
    stiff = stiff_start(design, m, effects, names, **options)
    if stiff is not None:
        fits["stiff"] = calibrate(design, m, effects, names, initial=stiff, **options)
        soft = {n: SOFT_START[n] for n in NESTED_START if n in names}
        fits["soft"] = calibrate(design, m, effects, names, initial=soft, **options)

    def best_fit() -> CalibrationResult:
        return min(fits.values(), key=lambda f: (f.unconverged > 0, f.chi2))

    ordered = options.get("ordered")
    mode = "hysteresis" in set(effects) if ordered is None else ordered
    if mode == "driven":
        return best_fit(), fits
    model = model_for(frozenset(effects))
    driven = {**options, "ordered": "driven"}
    if m.sequence is not None:
        # the fit from rest may leave the path's states for good on its way, and where the
        # path matters at neither the start nor the fit's best (a robot measured with a
        # stronger magnet than the nominal one is multistable, the nominal one is not),
        # only a fit along the path reaches the states the bench drove to
        fits["along the path from the start"] = calibrate(design, m, effects, names, **driven)
    best = best_fit()
    if m.sequence is not None and (repeats_disagree(m, options.get("sigma")) or best.unconverged):
        # a fit starts in one basin of the misfit; which basin holds the bench's states
        # is not known where the robot is multistable or the best fit leaves rows unsolved
        for label, start in prior_starts(design, names, options.get("priors", False)).items():
            fits[f"along the path from {label}"] = calibrate(
                design, m, effects, names, **{**driven, "initial": start}
            )
        best = best_fit()
    along = [f for label, f in fits.items() if label.startswith("along the path")]
    if not any(best is f for f in along) and path_matters(model, best.params, m, mode):
        fits["along the path"] = calibrate(
            design, m, effects, names, **{**driven, "initial": best.estimate}
        )
    return best_fit(), fits
