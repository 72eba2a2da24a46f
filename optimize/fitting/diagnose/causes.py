"""The causes a diagnosis names: each accepted effect with its evidence and its
parameters as the final model estimates them, with profile-likelihood intervals
(:func:`accepted_causes`). SI units; the ``*_mm`` figures are millimetres.
"""

from __future__ import annotations

import math
from dataclasses import replace

from design.records import Design
from optimize.fitting.calibrate import EFFECT_FREE, FIELD_RELATIVE, FIELD_TOLERANCE
from optimize.fitting.diagnose.evidence import _cause, _reason
from optimize.fitting.diagnose.fits import Progress
from optimize.fitting.diagnose.result import Cause, Fit
from optimize.fitting.likelihood import Interval, profile_intervals, widened
from optimize.fitting.measurements import Measurements
from optimize.fitting.structure import ResidualDependence

Step = tuple[list[str], Fit, Fit, tuple[ResidualDependence, ...], tuple[ResidualDependence, ...]]
"""One accepted addition: the effects added, the model before and after, and the residual
structure of each."""


def accepted_causes(
    design: Design,
    m: Measurements,
    current: Fit,
    steps: list[Step],
    sigma: float | None,
    say: Progress,
) -> list[Cause]:
    """The causes of ``steps`` (the accepted additions, in order), their parameters as
    ``current`` (the final model) estimates them, with profile-likelihood intervals: the
    linearised errors are too small where parameters trade off along a curved valley
    (:mod:`optimize.fitting.likelihood`). sigma : as given to the diagnosis. [m]
    say : progress messages."""
    own = [p for step in steps for e in step[0] for p in EFFECT_FREE[e]]
    profiles: dict[str, Interval] = {}
    profile_failure = ""
    if own:
        say("profile-likelihood intervals of " + ", ".join(own))
        try:
            profiles = profile_intervals(
                design,
                m,
                current.calibration,
                own,
                ordered=current.ordered,
                sigma=sigma,
            )
        except Exception as exc:  # the intervals are then null (JSON), the evidence says why
            profiles = {p: Interval(math.nan, math.nan, 0) for p in own}
            profile_failure = f"the profile likelihood failed ({_reason(exc)})"
    field_fixed = "external_remanence" not in current.calibration.names
    if field_fixed:  # then the data fix these only relative to the field's strength
        estimate = current.calibration.estimate
        for p in set(own) & set(FIELD_RELATIVE):
            profiles[p] = widened(p, estimate[p], profiles[p], FIELD_TOLERANCE)
    causes = []
    for added, before, after, s0, s1 in steps:
        for name in added:
            cause = _cause(
                design,
                name,
                before,
                after,
                s0,
                s1,
                current,
                profiles,
                field_fixed,
                profile_failure,
            )
            if len(added) > 1:
                others = ", ".join(a for a in added if a != name)
                evidence = cause.evidence[:-1] + f" (accepted together with {others}: "
                evidence += "no single addition paid)."
                cause = replace(cause, evidence=evidence)
            causes.append(cause)
    return causes
