"""The refit after an accepted effect: the parameters its effects make separable freed
too, kept if that pays as an effect must (:func:`_refine`). SI units.
"""

from __future__ import annotations

import math

from design.records import Design
from optimize.fitting.calibrate import EFFECT_SEPARATES, Priors
from optimize.fitting.diagnose.evidence import BIC_DROP, _cv_pays, _reason, _unphysical
from optimize.fitting.diagnose.fits import Progress, _cross_validated, _fit
from optimize.fitting.diagnose.result import Candidate, Fit
from optimize.fitting.measurements import Measurements


def _refine(
    design: Design,
    m: Measurements,
    current: Fit,
    tried: dict[str, Candidate],
    *,
    k: int,
    seed: int,
    sigma: float | None,
    say: Progress,
    priors: bool | Priors = True,
) -> Fit:
    """The current model refitted with the parameters its effects make separable
    (:data:`optimize.fitting.calibrate.EFFECT_SEPARATES`, e.g. the field's strength under
    gravity) also free, if that pays as an effect must (BIC, then cross-validated RMSE:
    a refit whose BIC does not pass is not cross-validated); else ``current``. The refit
    is recorded in ``tried`` either way."""
    free = current.calibration.names
    extra = [
        n for e in sorted(current.effects) for n in EFFECT_SEPARATES.get(e, ()) if n not in free
    ]
    if not extra:
        return current
    name = f"{current.name} ({', '.join(extra)} freed)"
    say(f"refitting {name}")
    try:
        fit = _fit(
            design,
            m,
            current.effects,
            k=k,
            seed=seed,
            cv=False,
            starts=[current.calibration],
            sigma=sigma,
            free=(*free, *extra),
            priors=priors,
        )
        change = fit.bic() - current.bic()
        why = f"not below -{BIC_DROP:g}" if not change < -BIC_DROP else _unphysical(fit)
        if why:  # (a BIC that passes needing parameters beyond their priors: not physical)
            why = why if why.startswith("not") else f"passes, but it {why}"
            verdict = f"rejected: BIC {change:+.1f}, {why} (not cross-validated)"
            tried[name] = Candidate(current.effects, current.name, fit, change, verdict)
            return current
        fit = _cross_validated(design, m, fit, k=k, seed=seed, sigma=sigma)
    except Exception as exc:  # reported; the final model stays
        tried[name] = Candidate(
            current.effects, current.name, None, math.nan, f"fit failed: {_reason(exc)}"
        )
        return current
    before, after = current.cv_rmse_mm, fit.cv_rmse_mm
    text = f"BIC {change:+.1f}, cross-validated RMSE {before:.3g} -> {after:.3g} mm"
    better = _cv_pays(before, after)
    verdict = f"accepted: {text}" if better else f"rejected: {text}"
    tried[name] = Candidate(current.effects, current.name, fit, change, verdict)
    return fit if better else current
