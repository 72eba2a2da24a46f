"""Diagnosis: what the simulation gets wrong on measured data, the physical cause, and the gain.

Method (the result format is spec/formats.md's diagnosis JSON):

1. Calibrate the baseline (:func:`optimize.fitting.calibrate.calibrate`, its default free
   parameters) and cross-validate it over held-out configurations.
2. Look for structure in its residuals: regress them on smooth functions of each candidate
   cause's signature (each ring angle and their difference as two-harmonic Fourier series,
   the deflection and the distance to the external magnet as quadratics, the acquisition
   order as a cubic, the direction of travel as a sign) and F-test each against the
   residual noise (:func:`residual_structure`).
3. Greedy forward selection: fit every candidate effect added to the current model (its
   own parameters freed, :data:`optimize.fitting.calibrate.EFFECT_FREE`); take the candidates in
   order of the Bayesian information criterion, n ln(RSS'/RSS) + k' ln n, and accept the
   first whose BIC falls by more than BIC_DROP (very strong evidence, Kass & Raftery 1995)
   and whose cross-validated RMSE falls by more than CV_GAIN; repeat while one is accepted
   and the residual is not yet consistent with the stated noise (chi-square test, when the
   data give sigma).
4. Name each accepted cause with its evidence (the residual structure it removes, the
   cross-validated gain, its parameters as the final model estimates them with 1-sigma
   profile-likelihood intervals, :mod:`optimize.fitting.likelihood`), and say whether structure
   remains.

Data with an acquisition order are fitted along the bench's path wherever that changes
the states (a multistable robot), and each full fit of such data also scans the misfit
along the path around its estimate (:func:`_scan`): snap-throughs make it jump, which a
local least-squares fit cannot see.

The candidates are only ever judged through the data: the same fits, the same thresholds
for each. SI units inside; the ``*_mm`` figures are millimetres.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy import stats

from design.geometry import rest_position
from design.model import EFFECTS, RingPairModel, model_for
from design.records import Design
from design.registry import index
from design.sections import tube_torsional_rigidity
from optimize.fitting.calibrate import (
    EFFECT_FREE,
    FREE_PARAMETERS,
    CalibrationResult,
    calibrate,
    cross_validate,
    default_free,
    predict,
    row_sigma,
)
from optimize.fitting.likelihood import Interval, profile_intervals
from optimize.fitting.measurements import Measurements

BIC_DROP = 10.0
"""Accept an effect only if the BIC falls by more than this (Kass & Raftery: > 10 is very
strong evidence)."""
CV_GAIN = 0.03
"""... and its cross-validated RMSE falls by more than this fraction."""
NESTED_START = {"wire_torsion_scale": 10.0, "catheter_torsion_scale": 10.0}
"""A candidate is also started where it all but reduces to the current model (here:
transmissions 10 times stiffer than nominal, nearly rigid, the baseline's assumption; the
nominal value can lie beyond a snap-through of the rings from the data's branch, where
a local fit cannot come back from)."""
SCAN_FACTORS = (0.6, 0.7, 0.8, 0.9, 1.1, 1.25, 1.5)
"""Factors on each positive (log-fitted) parameter, alone and with the others of its
effect, at which a fit along the path looks for a better basin (see :func:`_scan`)."""
SCREEN_EVALUATIONS = 12
"""Model evaluations of a screening fit (a candidate's BIC before it is fitted in full)."""
STRUCTURE_P = 1e-3
"""A residual dependence on a feature is reported as structure below this p-value."""
NOISE_P = 1e-3
"""With stated sigmas, residuals whose chi-square p-value is above this are noise."""

Progress = Callable[[str], None]
Fitted = tuple[CalibrationResult, bool | Literal["driven"]]
"""A calibration and the solve mode it was fitted with (see :func:`predict`)."""


@dataclass(frozen=True)
class ResidualDependence:
    """Residual dependence on one feature.

    feature : what the residuals were regressed on. r2 : fraction of the residual variance
    the regression explains. p_value : F-test of the regression against pure noise.
    """

    feature: str
    r2: float
    p_value: float


@dataclass(frozen=True)
class Fit:
    """One calibrated model with its cross-validated error."""

    effects: frozenset[str]
    calibration: CalibrationResult
    cv_rmse_mm: float
    rss: float
    n: int
    ordered: bool | Literal["driven"] = False
    """How the fit solved the configurations (see :func:`optimize.fitting.calibrate.predict`)."""

    @property
    def name(self) -> str:
        return "+".join(sorted(self.effects)) or "baseline"

    def bic(self) -> float:
        """n ln(RSS / n) + k ln n over the measured coordinates. [-]"""
        k = len(self.calibration.names)
        return self.n * math.log(self.rss / self.n) + k * math.log(self.n)

    def summary(self) -> dict[str, object]:
        """The spec's model block: rmse_mm, max_abs_mm, cv_rmse_mm, params (report units)."""
        return {
            "effects": sorted(self.effects),
            "rmse_mm": self.calibration.rmse_mm,
            "max_abs_mm": self.calibration.max_abs_mm,
            "cv_rmse_mm": self.cv_rmse_mm,
            "params": parameter_values(self.calibration),
            "uncertainty": parameter_values(self.calibration, standard_error=True),
        }


@dataclass(frozen=True)
class Cause:
    """An accepted effect.

    fit : the model it was accepted with (its cv_rmse_mm is the cause's).
    params : its own parameters in the final model, report units (``name_<unit>``), with
        the physical quantity behind each scale factor (e.g. the wire's torsional rigidity).
    intervals : 1-sigma profile-likelihood interval of each of ``params``, report units.
    evidence : one sentence: the structure it removed, the gain, the parameters.
    """

    name: str
    fit: Fit
    params: dict[str, float]
    intervals: dict[str, tuple[float, float]]
    evidence: str


@dataclass(frozen=True)
class Diagnosis:
    """What the data say about the model (spec/formats.md, diagnosis result).

    baseline, final : the calibrated baseline and the selected model.
    causes : accepted effects, in the order they were added (strongest first).
    structure_before, structure_after : residual structure of the baseline and the final
        model, strongest first.
    unexplained : the final residual still shows structure (or exceeds the stated noise)
        that no candidate explains.
    candidates : every fit tried: effect set -> (BIC, cross-validated RMSE or NaN). [-, mm]
    time_s : wall time. [s]
    """

    baseline: Fit
    final: Fit
    causes: tuple[Cause, ...]
    structure_before: tuple[ResidualDependence, ...]
    structure_after: tuple[ResidualDependence, ...]
    unexplained: str
    candidates: dict[str, tuple[float, float]] = field(default_factory=dict)
    time_s: float = 0.0

    def to_json(self) -> dict[str, object]:
        """The diagnosis JSON of spec/formats.md, with optional extra keys."""
        base, final = self.baseline.summary(), self.final.summary()
        final["interval"] = {k: list(v) for c in self.causes for k, v in c.intervals.items()}
        ratio = self.final.cv_rmse_mm / self.baseline.cv_rmse_mm
        return {
            "baseline": base,
            "causes": [
                {
                    "name": c.name,
                    "params": c.params,
                    "interval": {k: list(v) for k, v in c.intervals.items()},
                    "cv_rmse_mm": c.fit.cv_rmse_mm,
                    "evidence": c.evidence,
                }
                for c in self.causes
            ],
            "final": final,
            "gain": {
                "cv_rmse_ratio": ratio,
                "rmse_ratio": self.final.calibration.rmse_mm / self.baseline.calibration.rmse_mm,
                "max_abs_ratio": self.final.calibration.max_abs_mm
                / self.baseline.calibration.max_abs_mm,
            },
            "unexplained": self.unexplained,
            "structure": {
                "baseline": [s.__dict__ for s in self.structure_before],
                "final": [s.__dict__ for s in self.structure_after],
            },
            "candidates": {
                k: {"bic": b, "cv_rmse_mm": None if math.isnan(c) else c}
                for k, (b, c) in self.candidates.items()
            },
            "time_s": self.time_s,
        }


def report_key(name: str) -> tuple[str, float]:
    """A free parameter's report key ``name`` or ``name_<unit>`` (mm, deg, g...) and the
    factor from SI to that unit."""
    label, factor = FREE_PARAMETERS[name].label
    return (f"{name}_{label.lower()}" if label else name), factor


def parameter_values(fit: CalibrationResult, standard_error: bool = False) -> dict[str, float]:
    """Fitted parameters in report units, by :func:`report_key`."""
    values = fit.standard_error if standard_error else fit.estimate
    out = {}
    for name in fit.names:
        key, factor = report_key(name)
        out[key] = float(values[name] * factor)
    return out


# ------------------------------------------------------------------- residual structure


def _fourier(angle: np.ndarray, harmonics: int = 2) -> list[np.ndarray]:
    return [f(h * angle) for h in range(1, harmonics + 1) for f in (np.cos, np.sin)]


def _poly(x: np.ndarray, degree: int) -> list[np.ndarray]:
    span = np.ptp(x) if np.ptp(x) > 0 else 1.0
    z = (x - x.mean()) / span
    return [z**d for d in range(1, degree + 1)]


def features(design: Design, m: Measurements, model_position: np.ndarray) -> dict[str, np.ndarray]:
    """Candidate signatures, each a design matrix without intercept, shape (N, k).

    model_position : shape (N, 3), the fitted model's tip positions (for the deflection and
    the distance to the external magnet). [m]
    """
    t1, t2 = m.command[:, 0], m.command[:, 1]
    rest = rest_position(design.robot.free_length)
    centre = np.asarray(design.external_magnet.center)
    order = np.empty(len(m))
    order[m.order()] = np.arange(len(m))
    travel = np.zeros((len(m), 2))
    seq = m.order()
    step = np.diff(m.command[seq], axis=0)
    travel[seq[1:]] = np.sign(step)
    out = {
        "theta1": _fourier(t1),
        "theta2": _fourier(t2),
        "theta1 - theta2": _fourier(t1 - t2),
        "deflection": _poly(np.linalg.norm(model_position - rest, axis=1), 2),
        "distance to the external magnet": _poly(
            np.linalg.norm(model_position - centre, axis=1), 2
        ),
        "acquisition order": _poly(order, 3),
        "direction of travel": [travel[:, 0], travel[:, 1]],
    }
    return {k: np.column_stack(v) for k, v in out.items() if np.ptp(np.column_stack(v)) > 0}


def residual_structure(
    residuals: np.ndarray, feature_matrices: dict[str, np.ndarray]
) -> tuple[ResidualDependence, ...]:
    """F-test of the residuals (N, 3; NaN where not measured) against each feature: each
    measured component is regressed on the feature's columns plus an intercept, and the
    sums of squares are pooled over components. Strongest (smallest p) first."""
    out = []
    for name, x in feature_matrices.items():
        rss0 = rss1 = 0.0
        df1 = df2 = 0
        for c in range(3):
            ok = np.isfinite(residuals[:, c])
            if ok.sum() < x.shape[1] + 3:
                continue
            y = residuals[ok, c]
            a = np.column_stack([np.ones(ok.sum()), x[ok]])
            coef, *_ = np.linalg.lstsq(a, y, rcond=None)
            rank = np.linalg.matrix_rank(a)
            rss0 += float(np.sum((y - y.mean()) ** 2))
            rss1 += float(np.sum((y - a @ coef) ** 2))
            df1 += rank - 1
            df2 += ok.sum() - rank
        if df1 == 0 or df2 == 0 or rss0 == 0:
            continue
        f = ((rss0 - rss1) / df1) / max(rss1 / df2, 1e-300)
        out.append(ResidualDependence(name, 1 - rss1 / rss0, float(stats.f.sf(f, df1, df2))))
    return tuple(sorted(out, key=lambda s: s.p_value))


# ------------------------------------------------------------------------------ fitting


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
) -> Fit:
    """Calibrate ``effects`` from each start (None: the nominal design; a fit: its
    estimates; a mapping: these values, the others nominal), keep the best, and
    cross-validate it if ``cv``."""
    free = default_free(effects)
    model = model_for(effects)
    mode: bool | Literal["driven"] = "hysteresis" in effects

    def path_matters(params: np.ndarray) -> bool:
        """Twisting transmissions, or a strong magnet near the tip, can make the robot
        multistable; then its state depends on the path driven. The fast solve (each
        configuration on its own, or the played commands in one batch) is exact only
        where driving the bench's path ends in the same states."""
        if m.sequence is None:
            return False
        fast = predict(model, params, m, ordered=mode).equilibria.position
        driven = predict(model, params, m, ordered="driven").equilibria.position
        same_solved = np.array_equal(np.isnan(fast), np.isnan(driven))
        return not (same_solved and np.nanmax(np.abs(fast - driven), initial=0.0) < 1e-6)

    options: dict[str, object] = {"sigma": sigma, "max_nfev": max_nfev}

    def fit(start: Mapping[str, float] | None, path: bool | Literal["driven"]) -> Fitted:
        cal = calibrate(design, m, effects, free, initial=start, ordered=path, **options)  # type: ignore[arg-type]
        return cal, path

    # From each start: the fast fit, refitted along the path if the path matters at its
    # estimate; and a fit along the path from the start itself if the path matters there
    # (the fast fit can run into a region where it no longer does, e.g. a stiff rod).
    fits: list[Fitted] = []
    for s in starts:
        values = {} if s is None else s if isinstance(s, Mapping) else s.estimate
        initial = {n: v for n, v in values.items() if n in free} or None
        cal, path = fit(initial, mode)
        if path_matters(cal.params):
            cal, path = fit({n: cal.estimate[n] for n in free}, "driven")
        fits.append((cal, path))
        start_params = model.parameters(design)
        for n, v in (initial or {}).items():
            start_params[index(n)] = v
        if path_matters(start_params):
            fits.append(fit(initial, "driven"))
    cal, path = min(fits, key=lambda f: f[0].chi2 if f[0].unconverged == 0 else math.inf)
    if m.sequence is not None and max_nfev is None:  # full fits of data with a path
        start = _scan(model, m, cal, free)
        if start is not None:
            scanned, _ = fit(start, "driven")
            if scanned.unconverged == 0 and scanned.chi2 < cal.chi2:
                cal, path = scanned, "driven"
    options["ordered"] = path
    initial = {n: cal.estimate[n] for n in free}
    e = cal.errors[np.isfinite(cal.errors)]
    n = int(m.measured.sum())
    rss = float(np.nansum(cal.residuals**2))
    if e.size < len(m):  # unsolved rows count as a miss of the whole deflection
        rss = math.inf
    cv_rmse = math.nan
    if cv:
        cv_rmse = cross_validate(
            design, m, effects, free, k=k, seed=seed, initial=initial, **options
        ).rmse_mm
    return Fit(effects, cal, cv_rmse, rss, n, path)


def _scan(
    model: RingPairModel, m: Measurements, cal: CalibrationResult, free: Sequence[str]
) -> dict[str, float] | None:
    """A better start for a fit along the path, or None.

    Driven along a path, the robot snaps (or not) from one branch to another, so the misfit
    jumps where a parameter crosses a snap: a local fit stops at the edge of its basin
    (e.g. transmissions fitted too stiff to snap where the bench did). Evaluate the misfit
    along the path at the estimate with each positive parameter scaled by SCAN_FACTORS,
    alone and together with the others of its effect (both transmissions); return the best
    point if it beats the estimate."""
    groups = [[n] for n in free if FREE_PARAMETERS[n].kind == "log"]
    groups += [
        [n for n in names if n in free]
        for names in EFFECT_FREE.values()
        if sum(n in free and FREE_PARAMETERS[n].kind == "log" for n in names) > 1
    ]
    measured = np.isfinite(m.position)

    def misfit(params: np.ndarray) -> float:
        position = predict(model, params, m, ordered="driven").equilibria.position
        r = (position - m.position)[measured]
        return float(np.sum(r**2)) if np.isfinite(r).all() else math.inf

    best, best_value = None, misfit(cal.params)
    for group in groups:
        for factor in SCAN_FACTORS:
            params = cal.params.copy()
            for name in group:
                spec = FREE_PARAMETERS[name]
                params[index(name)] = np.clip(params[index(name)] * factor, spec.lower, spec.upper)
            value = misfit(params)
            if value < best_value:
                best, best_value = params, value
    if best is None:
        return None
    return {n: float(best[index(n)]) for n in free}


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
) -> Cause:
    """The accepted effect ``name`` (``before`` -> ``after``, structure ``s0`` -> ``s1``),
    its parameters as the ``final`` model estimates them, with their ``profiles``."""
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
    if params:
        text += ", with " + ", ".join(
            f"{k} = {v:.4g} (1 sigma {intervals[k][0]:.3g} to {intervals[k][1]:.3g})"
            for k, v in params.items()
        )
    return Cause(name, after, params, intervals, text + ".")


def diagnose(
    design: Design,
    m: Measurements,
    candidates: Iterable[str] = EFFECTS,
    *,
    k: int = 5,
    seed: int = 0,
    sigma: float | None = None,
    progress: Progress | None = None,
) -> Diagnosis:
    """Find which model effects the measurements ``m`` of ``design`` call for.

    candidates : effects to test (names of :data:`design.model.EFFECTS`).
    k : folds of the cross-validation over configurations. seed : its shuffling.
    sigma : one-sigma position noise for rows that do not state one. [m]
    progress : called with a short message before each fit.
    """
    t0 = time.perf_counter()
    say = progress or (lambda _: None)
    candidates = [c for c in EFFECTS if c in set(candidates)]
    if "hysteresis" in candidates and m.sequence is None:
        candidates.remove("hysteresis")  # needs the order of acquisition
    row_sigma(m, sigma)
    say("baseline")
    current = _fit(design, m, frozenset(), k=k, seed=seed, cv=True, starts=[None], sigma=sigma)
    baseline = current

    def structure(fit: Fit) -> tuple[ResidualDependence, ...]:
        model = model_for(fit.effects)
        path: Literal["driven"] | bool = "driven" if m.sequence is not None else False
        position = predict(model, fit.calibration.params, m, path).equilibria.position
        position = np.where(np.isfinite(position), position, m.position)
        return residual_structure(fit.calibration.residuals, features(design, m, position))

    def refit_current(start: CalibrationResult, cv: bool) -> Fit:
        return _fit(design, m, current.effects, k=k, seed=seed, cv=cv, starts=[start], sigma=sigma)

    s_base = structure(baseline)
    s_current = s_base
    accepted_steps: list[
        tuple[str, Fit, Fit, tuple[ResidualDependence, ...], tuple[ResidualDependence, ...]]
    ] = []
    tried: dict[str, tuple[float, float]] = {baseline.name: (baseline.bic(), baseline.cv_rmse_mm)}
    remaining = list(candidates)
    refit_from: set[str] = set()  # candidates whose estimates the current model was refitted from
    while remaining and not _noise_consistent(current, m):
        fits = []
        for name in remaining:
            say(f"testing {name} on top of {current.name}")
            # Screening: a short fit from the current estimates (and, in the first round,
            # from the nominal design: the baseline may have bent its parameters to mimic
            # the effect). The candidate that is taken on is refitted in full.
            starts: list[CalibrationResult | Mapping[str, float] | None] = [current.calibration]
            if not current.effects:
                starts.append(None)
            nested = {n: NESTED_START[n] for n in EFFECT_FREE[name] if n in NESTED_START}
            if nested:  # the candidate as it reduces to the current model
                starts.append({**current.calibration.estimate, **nested})
            f = _fit(
                design,
                m,
                current.effects | {name},
                k=k,
                seed=seed,
                cv=False,
                starts=starts,
                sigma=sigma,
                max_nfev=SCREEN_EVALUATIONS,
            )
            tried[f.name] = (f.bic(), math.nan)
            fits.append((f.bic() - current.bic(), name, f))
        accepted = None
        for drop, name, f in sorted(fits, key=lambda t: t[0]):
            if not drop < -BIC_DROP:
                break
            say(f"cross-validating {f.name}")
            f = _fit(
                design, m, f.effects, k=k, seed=seed, cv=True, starts=[f.calibration], sigma=sigma
            )
            tried[f.name] = (f.bic(), f.cv_rmse_mm)
            if f.cv_rmse_mm < (1 - CV_GAIN) * current.cv_rmse_mm:
                accepted = (name, f)
                break
        if accepted is None:
            break
        name, f = accepted
        # A candidate may only have found a better optimum of what the current model can
        # already do (e.g. rigid transmissions are the baseline). Refit the current model
        # from the candidate's estimates: if that closes the gap, the effect is not needed.
        if name not in refit_from:
            refit_from.add(name)
            say(f"refitting {current.name} from the estimates of {f.name}")
            refit = refit_current(f.calibration, cv=False)
            if refit.bic() < current.bic() - 1e-6 and not f.bic() - refit.bic() < -BIC_DROP:
                current = refit_current(refit.calibration, cv=True)
                s_current = structure(current)
                if not current.effects:
                    baseline, s_base = current, s_current
                continue
        s_new = structure(f)
        accepted_steps.append((name, current, f, s_current, s_new))
        current, s_current = f, s_new
        remaining.remove(name)

    # The causes' parameters as the final model estimates them, with profile-likelihood
    # intervals: the linearised errors are too small where parameters trade off along a
    # curved valley (optimize.fitting.likelihood).
    own = [p for step in accepted_steps for p in EFFECT_FREE[step[0]]]
    profiles = {}
    if own:
        say("profile-likelihood intervals of " + ", ".join(own))
        profiles = profile_intervals(
            design, m, current.calibration, own, ordered=current.ordered, sigma=sigma
        )
    causes = [_cause(design, *step, current, profiles) for step in accepted_steps]

    left = [s for s in s_current if s.p_value < STRUCTURE_P]
    unexplained = ""
    if left:
        unexplained = (
            "structure remains that no candidate explains: the residuals still depend on "
            + ", ".join(f"{s.feature} (R^2 {s.r2:.2f})" for s in left[:3])
        )
    elif np.isfinite(m.sigma).any() and not _noise_consistent(current, m):
        unexplained = (
            f"the residual ({current.calibration.rmse_mm:.3g} mm RMS) exceeds the stated "
            "noise without a pattern any candidate explains"
        )
    return Diagnosis(
        baseline=baseline,
        final=current,
        causes=tuple(causes),
        structure_before=s_base,
        structure_after=s_current,
        unexplained=unexplained,
        candidates=tried,
        time_s=time.perf_counter() - t0,
    )


__all__ = ["Cause", "Diagnosis", "Fit", "ResidualDependence", "diagnose", "residual_structure"]
