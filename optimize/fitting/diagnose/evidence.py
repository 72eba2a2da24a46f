"""How the search decides and says why: the thresholds (BIC_DROP, CV_GAIN, NOISE_P,
HELD_OUT_RATIO), each verdict's wording, an accepted cause's evidence and what the
final model leaves unexplained. SI units; the ``*_mm`` figures are millimetres.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from scipy import stats

from design.records import Design
from design.sections import tube_torsional_rigidity
from design.units import MM
from optimize.fitting.calibrate import (
    EFFECT_FREE,
    FIELD_RELATIVE,
    FIELD_TOLERANCE,
    PULL_LIMIT,
)
from optimize.fitting.diagnose.result import (
    Candidate,
    Cause,
    Fit,
    parameter_values,
    report_key,
)
from optimize.fitting.likelihood import Interval
from optimize.fitting.measurements import Measurements
from optimize.fitting.structure import (
    STRUCTURE_P,
    ResidualDependence,
)

BIC_DROP = 10.0
"""Accept an effect only if the BIC falls by more than this (Kass & Raftery: > 10 is very
strong evidence)."""
CV_GAIN = 0.03
"""... and its cross-validated RMSE falls by more than this fraction."""
NOISE_P = 1e-3
"""With stated sigmas, residuals whose chi-square p-value is above this are noise."""
HELD_OUT_RATIO = 2.0
"""The final model does not generalise where its cross-validated RMSE exceeds its
in-sample RMSE by more than this factor times the ratio a right model would give with
the same configurations and folds (:func:`optimize.fitting.calibrate.held_out_inflation`:
about 1.3 for 16 rows seen from above and 8 free parameters, several where a few
configurations alone fix a parameter, e.g. a far magnet seen from above); e.g. folds that
land on another branch of the robot than the data's, or a missing effect. [-]"""


def _cv_pays(before: float, after: float) -> bool:
    """The cross-validated RMSE falls by more than CV_GAIN (or becomes defined)."""
    return after < (1 - CV_GAIN) * before or (not np.isfinite(before) and np.isfinite(after))


def _noise_consistent(fit: Fit, m: Measurements) -> bool:
    """With stated sigmas: the weighted residual is consistent with them (chi-square)."""
    if not np.isfinite(m.sigma).any():
        return False
    return bool(stats.chi2.sf(fit.calibration.chi2, fit.calibration.dof) > NOISE_P)


def _cause(
    design: Design,
    name: str,
    before: Fit,
    after: Fit,
    s0: Sequence[ResidualDependence],
    s1: Sequence[ResidualDependence],
    final: Fit,
    profiles: Mapping[str, Interval],
    field_fixed: bool,
    profile_failure: str = "",
) -> Cause:
    """The accepted effect ``name`` (``before`` -> ``after``, structure ``s0`` -> ``s1``),
    its parameters as the ``final`` model estimates them, with their ``profiles``
    (``profile_failure``: why they are NaN, if they could not be found);
    ``field_fixed``: the field's strength was not fitted (those of its parameters in
    FIELD_RELATIVE are then relative to it, and their profiles include its tolerance)."""
    params: dict[str, float] = {}
    intervals: dict[str, tuple[float, float]] = {}
    for p in EFFECT_FREE[name]:
        key, factor = report_key(p)
        params[key] = final.calibration.estimate[p] * factor
        intervals[key] = (profiles[p].lower * factor, profiles[p].upper * factor)
        if p.endswith("_torsion_scale"):  # the physical quantity behind the factor
            tube = p.removesuffix("_torsion_scale")
            gj = tube_torsional_rigidity(getattr(design.robot, tube))
            params[f"{tube}_torsional_rigidity_n_m2"] = params[key] * gj
            intervals[f"{tube}_torsional_rigidity_n_m2"] = (
                intervals[key][0] * gj,
                intervals[key][1] * gj,
            )
    r2_after = {s.feature: s.r2 for s in s1}
    drops = [(s.r2 - r2_after.get(s.feature, 0.0), s) for s in s0 if s.p_value < STRUCTURE_P]
    text = f"{name}: "
    if drops:
        drop, s = max(drops, key=lambda t: t[0])
        text += (
            f"the residuals' dependence on {s.feature} (R^2 {s.r2:.2f} -> "
            f"{r2_after.get(s.feature, 0.0):.2f}) goes away"
        )
    else:
        text += "the residuals shrink without a single dominant pattern"
    text += (
        f" and the cross-validated RMSE falls from {before.cv_rmse_mm:.3g} to "
        f"{after.cv_rmse_mm:.3g} mm (BIC {after.bic() - before.bic():+.0f})"
    )
    if final is not after and not math.isclose(final.cv_rmse_mm, after.cv_rmse_mm, rel_tol=0.05):
        # refitted later (from another candidate's estimates, or with more effects)
        text += f" ({final.cv_rmse_mm:.3g} mm in the final model, {final.name})"

    def sigma(key: str) -> str:
        lower, upper = intervals[key]
        if math.isfinite(lower) and math.isfinite(upper):
            return f"1 sigma {lower:.3g} to {upper:.3g}"
        return "1 sigma unknown" + (f": {profile_failure}" if profile_failure else "")

    if params:
        text += ", with " + ", ".join(f"{k} = {v:.4g} ({sigma(k)})" for k, v in params.items())
    if field_fixed and set(EFFECT_FREE[name]) & set(FIELD_RELATIVE):
        text += (
            f" (relative to the field's strength, which these data cannot separate from "
            f"them: a field x % stronger than the design's remanences means them about x % "
            f"higher; the intervals include the remanences' tolerance, "
            f"{100 * FIELD_TOLERANCE:.1f} % one sigma)"
        )
    return Cause(name, after, params, intervals, text + ".")


def _not_applicable(design: Design, m: Measurements, effect: str) -> str:
    """Why ``effect`` cannot be told from these data at all ('' if it can)."""
    if effect == "hysteresis" and m.sequence is None:
        return "hysteresis needs the order of acquisition (a sequence column)"
    if effect == "gravity" and design.environment.gravity is None:
        return "the design file states no gravity (environment.gravity_m_s2)"
    return ""


def _reason(exc: Exception) -> str:
    """An exception as one line: its type and message."""
    text = " ".join(str(exc).split()) or "no message"
    return f"{type(exc).__name__}: {text}"


def _bic_order(c: Candidate) -> float:
    """Most negative BIC change first; failed fits (NaN) last."""
    return math.inf if np.isnan(c.bic_change) or c.fit is None else c.bic_change


def _bic_verdict(c: Candidate) -> str:
    text = f"rejected: BIC {c.bic_change:+.1f} on top of {c.on_top_of}, not below -{BIC_DROP:g}"
    if c.fit is not None and c.fit.unsolved:
        text += f" (it leaves {c.fit.unsolved} row(s) without an equilibrium)"
    return text


def _unphysical(fit: Fit, bounded: Fit | None = None) -> str:
    """'' where every estimate of ``fit`` lies within PULL_LIMIT prior sigmas of its
    nominal value (or it was given no priors), or where ``bounded``, the same model fitted
    within PULL_LIMIT prior sigmas, fits the data as well within the noise
    (:func:`_bound_costs`: the data do not need the departure); else what it needs, as
    'needs <parameter> = <value> (<pull> prior sigmas), ...'. [-]"""
    cal = fit.calibration
    if not cal.prior_width:
        return ""
    beyond = cal.beyond_prior()
    if not beyond or (bounded is not None and not _bound_costs(fit, bounded)):
        return ""
    shown = parameter_values(cal)
    parts = []
    for name, value in sorted(beyond.items(), key=lambda kv: -abs(kv[1])):
        key, _ = report_key(name)
        parts.append(f"{key} = {shown[key]:.4g} ({value:+.1f} prior sigmas)")
    return f"needs {', '.join(parts)}: beyond {PULL_LIMIT:g} prior sigmas, not physical"


def _bound_costs(fit: Fit, bounded: Fit) -> bool:
    """Whether holding the fit within PULL_LIMIT prior sigmas (``bounded``) costs more than
    PULL_LIMIT^2 in chi-square, the noise taken from ``fit``'s own residuals: the
    nonlinear form of the prior-data conflict, which at an estimate that wandered along a
    direction the data barely fix (null data, a far magnet: its centre 10 prior sigmas out
    at 0.274 mm RMS, and held within them 0.277 mm) judged the data's standard errors
    there and called a departure needed. [-]"""
    rms, held = fit.calibration.rmse_mm, bounded.calibration.rmse_mm
    count = int(np.isfinite(np.asarray(fit.calibration.residuals, float)).sum())
    if not (np.isfinite(rms) and np.isfinite(held)) or rms <= 0:
        return True
    return count * (held**2 / rms**2 - 1.0) > PULL_LIMIT**2


def _outside_priors(fit: Fit) -> bool:
    """Whether an estimate of ``fit`` lies beyond PULL_LIMIT prior sigmas, needed by the
    data or not (a fit that wandered along a direction they leave free): such a fit is
    no physical start, and the search fits within the priors from then on. [-]"""
    return bool(fit.calibration.prior_width and fit.calibration.outside_prior())


def _unexplained(
    m: Measurements, fit: Fit, s: Sequence[ResidualDependence], bounded: Fit | None = None
) -> str:
    """What the final model leaves unexplained, and how large it is ('' if nothing); a
    final model that needs a parameter beyond its prior (:func:`_unphysical`, ``bounded``
    the same model fitted within its priors, where made) does not explain the data
    either."""
    left = [d for d in s if d.p_value < STRUCTURE_P]
    size = f"{fit.calibration.rmse_mm:.3g} mm RMS, {fit.cv_rmse_mm:.3g} mm cross-validated"
    stated = np.isfinite(m.sigma)
    if stated.any():
        axes = m.measured.sum(axis=1).mean()
        noise = float(np.median(m.sigma[stated]) * math.sqrt(axes) / MM)
        size += f"; the stated noise alone would give {noise:.3g} mm"
    unphysical = _unphysical(fit, bounded)
    if unphysical:
        return (
            f"{fit.name} fits ({size}) only with parameters the bench rules out: it "
            f"{unphysical}; a prior is violated (the set-up is not as the design file says, "
            "or an effect no candidate models is absorbed by them)"
        )
    if left:
        return (
            "structure remains that no candidate explains: the residuals still depend on "
            + ", ".join(f"{d.feature} (R^2 {d.r2:.2f})" for d in left[:3])
            + f" ({size})"
        )
    if stated.any() and not _noise_consistent(fit, m):
        return (
            "the residual exceeds the stated noise without a pattern any candidate explains "
            f"({size})"
        )
    expected = fit.cv_expected_ratio if np.isfinite(fit.cv_expected_ratio) else 1.0
    if fit.cv_rmse_mm > HELD_OUT_RATIO * expected * fit.calibration.rmse_mm:
        return (
            f"the final model does not predict configurations it was not fitted to: the "
            f"cross-validated RMSE is {fit.cv_rmse_mm / fit.calibration.rmse_mm:.1f}x the "
            f"in-sample one, where a right model would give about {expected:.1f}x with these "
            f"configurations ({size}); a missing effect, or fits that land on another "
            "branch of the robot"
        )
    return ""
