"""What a diagnosis found: the fits, the causes, every candidate's verdict, as the
diagnosis JSON of docs/formats.md (extended, nothing renamed; non-finite numbers are
null with their reason). The search itself is :mod:`optimize.fitting.diagnose.search`. SI units
inside; the ``*_mm`` figures are millimetres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from optimize.fitting.calibrate import FREE_PARAMETERS, CalibrationResult
from optimize.fitting.calibrate.priors import prior_sigma_shown
from optimize.fitting.structure import ResidualDependence


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
    unsolved: int = 0
    """Rows the model could not solve at the estimate (each adds to ``rss`` the straight
    robot's miss, :func:`optimize.fitting.calibrate.straight_miss`)."""
    cv_expected_ratio: float = math.nan
    """The ratio of ``cv_rmse_mm`` to the in-sample RMSE a right model would give with
    these configurations (:func:`optimize.fitting.calibrate.held_out_inflation`). [-]"""

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
            **prior_block(self.calibration),
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
class Candidate:
    """One model the search tried, and what became of it.

    effects : its effects. on_top_of : the name of the model it was added to.
    fit : its fit (the full one where it was fitted in full), None where the fit failed.
    bic_change : its BIC minus that of ``on_top_of``; NaN where the fit failed. [-]
    verdict : 'accepted: ...', 'rejected: ...', 'fit failed: ...' or 'not tried: ...',
        with the numbers it was decided on.
    """

    effects: frozenset[str]
    on_top_of: str
    fit: Fit | None
    bic_change: float
    verdict: str

    @property
    def name(self) -> str:
        return "+".join(sorted(self.effects)) or "baseline"

    def to_json(self) -> dict[str, object]:
        f = self.fit
        return {
            "effects": sorted(self.effects),
            "on_top_of": self.on_top_of,
            "bic": f.bic() if f else math.nan,
            "bic_change": self.bic_change,
            "rmse_mm": f.calibration.rmse_mm if f else math.nan,
            "cv_rmse_mm": f.cv_rmse_mm if f else math.nan,
            "cv_expected_ratio": f.cv_expected_ratio if f else math.nan,
            "params": parameter_values(f.calibration) if f else {},
            "uncertainty": parameter_values(f.calibration, standard_error=True) if f else {},
            "unsolved_rows": f.unsolved if f else None,
            **(prior_block(f.calibration) if f else {"prior": {}, "pull": {}, "beyond_prior": {}}),
            "verdict": self.verdict,
        }


NULL_REASONS = {
    "cv_rmse_mm": "not cross-validated (rejected on its BIC first, or another candidate of "
    "its round fitted better), or no held-out row solved",
    "cv_expected_ratio": "not cross-validated, or the fit has no Jacobian",
    "rmse_mm": "no row solved",
    "max_abs_mm": "no row solved",
    "bic": "the fit failed (see the verdict), or it fits the data exactly (a zero misfit)",
    "bic_change": "a BIC is undefined (see the candidate's verdict)",
    "uncertainty": "the data do not determine this parameter (it trades off with others)",
    "sigma": "no prior on this parameter (a flat one: --prior NAME=inf)",
    "interval": "the profile likelihood could not be evaluated",
    "cv_rmse_ratio": "a cross-validated RMSE is undefined",
    "rmse_ratio": "an RMSE is undefined or zero",
    "max_abs_ratio": "a largest error is undefined or zero",
}
"""Why a number of the diagnosis JSON is null, by its key (see :func:`finite_json`)."""


def finite_json(doc: object, path: str = "", nulls: dict[str, str] | None = None) -> object:
    """``doc`` with every non-finite number replaced by None and its JSON path added to
    ``nulls`` with the reason (:data:`NULL_REASONS`, by the nearest key that has one)."""
    nulls = {} if nulls is None else nulls
    if isinstance(doc, dict):
        return {k: finite_json(v, f"{path}.{k}" if path else str(k), nulls) for k, v in doc.items()}
    if isinstance(doc, (list, tuple)):
        return [finite_json(v, f"{path}[{i}]", nulls) for i, v in enumerate(doc)]
    if isinstance(doc, (float, np.floating)) and not math.isfinite(doc):
        keys = [k.split("[")[0] for k in path.split(".")]
        reason = next((NULL_REASONS[k] for k in reversed(keys) if k in NULL_REASONS), "")
        nulls[path] = reason or "not a finite number"
        return None
    return doc


@dataclass(frozen=True)
class Diagnosis:
    """What the data say about the model (docs/formats.md, diagnosis result).

    baseline, final : the calibrated baseline and the selected model.
    causes : accepted effects, in the order they were added (strongest first).
    structure_before, structure_after : residual structure of the baseline and the final
        model, strongest first.
    unexplained : the final residual still shows structure (or exceeds the stated noise)
        that no candidate explains, with how large it is.
    candidates : every model tried, by name, with its fit and verdict.
    power : what the data could tell apart: per candidate not named, the RMS per
        coordinate it would add, at nominal strength, beyond what the final model absorbs
        (the prior-bounded baseline where the baseline is not physical), over the noise
        (:func:`power_of_data`).
    time_s : wall time. [s]
    """

    baseline: Fit
    final: Fit
    causes: tuple[Cause, ...]
    structure_before: tuple[ResidualDependence, ...]
    structure_after: tuple[ResidualDependence, ...]
    unexplained: str
    candidates: dict[str, Candidate] = field(default_factory=dict)
    power: dict[str, dict[str, object]] = field(default_factory=dict)
    time_s: float = 0.0
    bounded: Fit | None = None
    """Where the calibrated baseline needs a parameter beyond PULL_LIMIT prior sigmas:
    the baseline fitted within them, the model the candidates had to beat and the power
    was judged against; else None."""

    def to_json(self) -> dict[str, Any]:
        """The diagnosis JSON of docs/formats.md, with optional extra keys; non-finite
        numbers are null, each with its reason under ``null``."""
        base, final = self.baseline.summary(), self.final.summary()
        final["interval"] = {k: list(v) for c in self.causes for k, v in c.intervals.items()}

        def ratio(a: float, b: float) -> float:
            return a / b if b else math.nan

        doc = {
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
                "cv_rmse_ratio": ratio(self.final.cv_rmse_mm, self.baseline.cv_rmse_mm),
                "rmse_ratio": ratio(
                    self.final.calibration.rmse_mm, self.baseline.calibration.rmse_mm
                ),
                "max_abs_ratio": ratio(
                    self.final.calibration.max_abs_mm, self.baseline.calibration.max_abs_mm
                ),
            },
            "unexplained": self.unexplained,
            "structure": {
                "baseline": [s.__dict__ for s in self.structure_before],
                "final": [s.__dict__ for s in self.structure_after],
            },
            "candidates": {k: c.to_json() for k, c in self.candidates.items()},
            "power": self.power,
            "time_s": self.time_s,
            "baseline_within_priors": self.bounded.summary() if self.bounded else None,
        }
        nulls: dict[str, str] = {}
        out = finite_json(doc, "", nulls)
        assert isinstance(out, dict)
        out["null"] = nulls
        return out


def report_key(name: str) -> tuple[str, float]:
    """A free parameter's report key ``name`` or ``name_<unit>`` (mm, deg, g...) and the
    factor from SI to that unit."""
    label, factor = FREE_PARAMETERS[name].label
    return (f"{name}_{label.lower()}" if label else name), factor


def prior_block(fit: CalibrationResult) -> dict[str, object]:
    """The priors of ``fit``'s parameters in report units, by :func:`report_key`:
    ``prior`` (the nominal value, the one-sigma width, and whether that width is of
    ln(value / nominal), ``"log"``, or in the key's unit, ``"linear"``), ``pull`` (prior
    sigmas moved, signed), ``conflict`` (the prior-data conflict in sigmas,
    :meth:`CalibrationResult.conflict`), ``beyond_prior`` (the pulls beyond PULL_LIMIT,
    where the conflict is too) and ``physical`` (none is). A fit
    without priors is judged by the default ones."""
    prior, pulls = {}, fit.pulls()
    for name in fit.names:
        key, factor = report_key(name)
        spec = FREE_PARAMETERS[name]
        prior[key] = {
            "nominal": float(fit.nominal[name] * factor),
            "sigma": prior_sigma_shown(name, fit.width(name)),
            "scale": spec.kind,
        }
    beyond = {report_key(n)[0]: p for n, p in fit.beyond_prior().items()}
    return {
        "prior": prior,
        "pull": {report_key(n)[0]: p for n, p in pulls.items()},
        "conflict": fit.conflict(),
        "beyond_prior": beyond,
        "physical": not beyond,
        "fitted_with_priors": fit.priors,
    }


def parameter_values(fit: CalibrationResult, standard_error: bool = False) -> dict[str, float]:
    """Fitted parameters in report units, by :func:`report_key`."""
    values = fit.standard_error if standard_error else fit.estimate
    out = {}
    for name in fit.names:
        key, factor = report_key(name)
        out[key] = float(values[name] * factor)
    return out


__all__ = [
    "NULL_REASONS",
    "Candidate",
    "Cause",
    "Diagnosis",
    "Fit",
    "finite_json",
    "parameter_values",
    "prior_block",
    "report_key",
]
