"""Profile-likelihood intervals of calibrated parameters.

The Gauss-Newton standard error of :func:`optimize.fitting.calibrate.calibrate` is exact only
where the model is linear in its parameters over the error's range. Where parameters
trade off along a curved valley (a far, weak external field: the rod's compliance and the
magnet's distance are nearly degenerate, and the transmissions' torsional rigidities
follow them), it can be several times too small. The profile likelihood does not assume
linearity: fix one parameter at a value, refit all the others, and compare the misfit
(Venzon & Moolgavkar 1988; Raue et al. 2009, Bioinformatics 25:1923). With
s^2 = chi^2 / dof of the best fit, the 1-sigma interval is where

    r(p) = sign(p - p_hat) sqrt((chi^2_profile(p) - chi^2_min) / s^2)

crosses -1 and +1. r is linear in the fit unit (log for positive quantities) for a
quadratic misfit, so a secant on r finds each end in a few fits; a bracket keeps it safe
where r is not linear (snap-throughs along a path), and where r jumps across 1 the end is
the jump, once bracketed to RESOLUTION of the standard error. An end that the parameter's
bound cuts off is the bound.

A jump may be the refit's, not the profile's: along a driven path a fit often ends at the
edge of its basin, where a little change of any parameter makes the path snap at another
row and misses the rest of it by millimetres; a refit from there cannot climb back over
that cliff, while other values of the other parameters keep the snap where the data have
it. So where r first exceeds JUMP times what the linear standard error predicts, the point
is refitted from the nominal design too; the better refit counts, and if that is the
nominal design's, each later refit starts from both.

SI units.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from design.records import Design
from optimize.fitting.calibrate import FREE_PARAMETERS, CalibrationResult, calibrate
from optimize.fitting.calibrate.priors import pull
from optimize.fitting.measurements import Measurements
from optimize.fitting.workers import parallel_map

TOLERANCE = 0.05
"""An interval end is found when |r| is within this of 1. [-]"""
MAX_FITS = 6
"""Refits per interval end at most."""
RESOLUTION = 0.01
"""An interval end is also found when r = 1 is bracketed to within this fraction of the
linear standard error: where the refits snap to another branch of the robot beyond some
value, r jumps there across 1 and no value has |r| near 1 (benchmark seed [2, 7, 0], the
near field and torsion: the lower end of the wire's torsion scale, r 0 -> 48 across
1e-8 of it, took its six refits of up to 100 evaluations each, 41 of 87 s). [-]"""
JUMP = 3.0
"""A refit whose |r| exceeds this many times the linear prediction (the distance from the
estimate over the linear standard error, at least 1) is tried again from the nominal
design. Found on the example with the rings locked parallel (torsion planted, 40 rows
along a path, top view): refitted from the estimate, r was 51-59 within 4e-4 of the
catheter's torsion scale on either side and the interval 2.152-2.208 (the truth 1.68
relative to the field's strength); from the nominal design r <= 1.3 from 1.2 to 2.6. [-]"""


@dataclass(frozen=True)
class Interval:
    """A 1-sigma profile-likelihood interval of one parameter.

    lower, upper : the interval's ends; a bound of the parameter where the profile does
        not reach 1 sigma before it. [SI]
    fits : refits it took.
    """

    lower: float
    upper: float
    fits: int


def _range(name: str, nominal: float) -> tuple[float, float]:
    """The values the fit admits for ``name`` (its absolute bounds and span). [SI]"""
    spec = FREE_PARAMETERS[name]
    return max(spec.lower, nominal - spec.span), min(spec.upper, nominal + spec.span)


def profile_intervals(
    design: Design,
    m: Measurements,
    fit: CalibrationResult,
    names: Iterable[str],
    *,
    ordered: bool | Literal["driven"] | None = None,
    sigma: float | None = None,
) -> dict[str, Interval]:
    """1-sigma profile-likelihood intervals of ``names`` (free parameters of ``fit``).

    ordered, sigma : as the fit was made (see :func:`optimize.fitting.calibrate.calibrate`).
    """
    _check(fit)
    free = fit.names
    names = list(names)
    for name in names:
        if name not in free:
            raise ValueError(f"{name!r} is not a free parameter of the fit ({list(free)})")

    def end(job: tuple[str, float]) -> tuple[float, int]:
        """One end of ``name``'s interval (``sign`` -1: the lower) and the fits it took."""
        name, sign = job
        rest = tuple(n for n in free if n != name)
        lo, hi = _range(name, fit.nominal[name])
        u_hat = FREE_PARAMETERS[name].fit_unit(fit.estimate[name], fit.nominal[name])
        # The linear standard error in fit units: the first step of each end's search.
        spec = FREE_PARAMETERS[name]
        se = fit.standard_error[name] / spec.unit_size(fit.estimate[name])
        se = se if np.isfinite(se) and se > 0 else spec.prior
        bound = lo if sign < 0 else hi
        return _end(design, m, fit, name, rest, u_hat, sign, se, bound, ordered, sigma)

    ends = parallel_map(end, [(name, sign) for name in names for sign in (-1.0, 1.0)])
    return {
        name: Interval(lower[0], upper[0], lower[1] + upper[1])
        for name, lower, upper in zip(names, ends[::2], ends[1::2], strict=True)
    }


def profile_sigma(
    design: Design,
    m: Measurements,
    fit: CalibrationResult,
    name: str,
    value: float,
    *,
    ordered: bool | Literal["driven"] | None = None,
    sigma: float | None = None,
    starts: Sequence[Mapping[str, float]] = (),
) -> float:
    """r at ``value`` of ``name``: how many sigma of the profile likelihood it lies from
    ``fit``'s estimate (signed; |r| > 4 rejects it at the 4-sigma level). The others are
    refitted from ``fit``'s estimates and from each of ``starts`` (SI values by name), the
    best counts. [-]"""
    _check(fit)
    rest = tuple(n for n in fit.names if n != name)
    begin = [(fit.estimate, fit.states), *((s, None) for s in starts)]
    r, _ = _refit(design, m, fit, name, value, rest, begin, ordered, sigma)
    return r


def widened(name: str, estimate: float, interval: Interval, relative: float) -> Interval:
    """``interval`` of ``name`` around ``estimate`` with a further, independent one-sigma
    uncertainty of ``relative`` of its value added to each side in quadrature, on the
    fit's scale (log: relative), within the values the parameter admits; NaN stays NaN.
    [SI]"""
    spec = FREE_PARAMETERS[name]

    def end(value: float, side: float) -> float:
        if spec.kind == "log":
            spread = math.hypot(math.log(value / estimate), math.log1p(relative))
            return estimate * math.exp(side * spread)
        return estimate + side * math.hypot(value - estimate, relative * estimate)

    lower = max(end(interval.lower, -1.0), spec.lower)
    upper = min(end(interval.upper, 1.0), spec.upper)
    return Interval(lower, upper, interval.fits)


def _check(fit: CalibrationResult) -> None:
    """Nothing to check: a fit with priors is profiled on its posterior (:func:`_refit`)."""


def _refit(
    design: Design,
    m: Measurements,
    fit: CalibrationResult,
    name: str,
    value: float,
    rest: Sequence[str],
    starts: Sequence[tuple[Mapping[str, float], np.ndarray | None]],
    ordered: bool | Literal["driven"] | None,
    sigma: float | None,
) -> tuple[float, CalibrationResult]:
    """Refit ``rest`` with ``name`` fixed at ``value``: (signed r, the best refit). Each
    start is the others' values and the rows' states near them or None (the first
    evaluation warm-starts from them, :func:`optimize.fitting.calibrate.calibrate`: a
    profile's point lies near the fit or the point before it). A fit with priors is
    refitted with them and profiled on its posterior."""
    priors: bool | dict[str, float] = {n: fit.width(n) for n in rest} if fit.priors else False
    cal = min(
        (
            calibrate(
                design,
                m,
                fit.effects,
                rest,
                fixed={name: value},
                initial={n: s[n] for n in rest if n in s},
                ordered=ordered,
                sigma=sigma,
                states=states,
                priors=priors,
            )
            for s, states in starts
        ),
        key=lambda c: c.chi2 + c.prior_chi2,
    )
    s2 = fit.chi2 / fit.dof
    # With priors, the posterior's: the data's misfit over its noise, plus the priors' own
    # (the fixed parameter's too, which the refit does not see).
    own = pull(name, value, fit.nominal[name], fit.width(name)) ** 2 if fit.priors else 0.0
    prior = cal.prior_chi2 + own - fit.prior_chi2
    r = math.sqrt(max((cal.chi2 - fit.chi2) / s2 + prior, 0.0))
    return math.copysign(r, value - fit.estimate[name]), cal


def _end(
    design: Design,
    m: Measurements,
    fit: CalibrationResult,
    name: str,
    rest: Sequence[str],
    u_hat: float,
    sign: float,
    step: float,
    bound: float,
    ordered: bool | Literal["driven"] | None,
    sigma: float | None,
) -> tuple[float, int]:
    """One end of the 1-sigma interval: (value [SI], refits)."""
    spec, nominal = FREE_PARAMETERS[name], fit.nominal[name]
    span = abs(spec.fit_unit(bound, nominal) - u_hat)
    if span < 1e-12:
        return bound, 0
    # Where each refit starts: the last point within 1 sigma (first the estimate), and,
    # once a refit from the nominal design has done better than that, there too (a
    # refit from that refit's basin can be as stuck at its edge: the example above).
    starts = [({n: fit.estimate[n] for n in rest}, fit.states)]
    below, above = (0.0, 0.0), None  # (distance from u_hat, |r|) with |r| < 1 and > 1
    h = min(step, span)
    fits, retried = 0, False
    for _ in range(MAX_FITS):
        value = spec.physical(u_hat + sign * h, nominal)
        r, cal = _refit(design, m, fit, name, value, rest, starts, ordered, sigma)
        r, fits = abs(r), fits + len(starts)
        if r > JUMP * max(1.0, h / step) and not retried:  # the refit's cliff?
            retried = True
            again, other = _refit(
                design, m, fit, name, value, rest, [(fit.nominal, None)], ordered, sigma
            )
            fits += 1
            if abs(again) < r:
                r, cal = abs(again), other
                starts.append((fit.nominal, None))
        if abs(r - 1) < TOLERANCE:
            return value, fits
        if r < 1:
            below, starts[0] = (h, r), ({n: cal.estimate[n] for n in rest}, cal.states)
            if h >= span:
                return bound, fits  # the bound comes before 1 sigma
        else:
            above = (h, r)
        if above is None:  # extrapolate r linearly from the estimate
            h = min(h / r if r > 0.1 else 4 * h, span)
        else:  # secant across r = 1, bisection if it leaves the bracket
            (h0, r0), (h1, r1) = below, above
            if h1 - h0 < RESOLUTION * step:  # placed well enough: the nearest point beyond
                return spec.physical(u_hat + sign * h1, nominal), fits
            h = h0 + (1 - r0) * (h1 - h0) / (r1 - r0)
            if not h0 < h < h1:
                h = 0.5 * (h0 + h1)
    # Out of refits: the nearest point beyond 1 sigma (conservative), else the last below.
    h = above[0] if above is not None else below[0]
    return spec.physical(u_hat + sign * h, nominal), fits


__all__ = ["Interval", "profile_intervals", "profile_sigma", "widened"]
