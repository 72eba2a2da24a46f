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
from design.registry import index
from optimize.fitting.calibrate.fit import calibrate
from optimize.fitting.calibrate.policy import NESTED_START, SOFT_START, default_free
from optimize.fitting.calibrate.result import CalibrationResult
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
    noise's RMS); where the path matters already at the start, the fit is also driven
    from there ('along the path from the start': a fit from rest can settle where the
    path no longer matters, in the wrong states; null as-built set of seed 18 in
    tests/optimize/fitting/test_priors.py, chi-square 15,323 -> 3.0). Returns the best
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
    nominal = fits["nominal"]
    start = nominal.params.copy()
    for name, value in {**nominal.nominal, **(options.get("initial") or {})}.items():
        start[index(name)] = value
    if path_matters(model, start, m, mode):
        # the fit from rest may have left the path's states for good on its way
        fits["along the path from the start"] = calibrate(design, m, effects, names, **driven)
    best = best_fit()
    if best is not fits.get("along the path from the start") and path_matters(
        model, best.params, m, mode
    ):
        fits["along the path"] = calibrate(
            design, m, effects, names, **{**driven, "initial": best.estimate}
        )
    return best_fit(), fits
