"""Where fits start: a stiffer rod where most rows are pulled onto the magnet, an
effect's own parameters at their levels, a fit of the path's first rows, and the
starts of a screen (:func:`screen_starts`) with its jobs. SI units.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Mapping, Sequence
from typing import Literal

import numpy as np

from design.model import RingPairModel
from design.records import Design
from design.registry import index
from optimize.fitting.calibrate import (
    EFFECT_FREE,
    NESTED_START,
    SOFT_START,
    CalibrationResult,
    Priors,
    UnsolvedStart,
    calibrate,
    default_free,
)
from optimize.fitting.diagnose.result import Fit
from optimize.fitting.diagnose.scans import LEVELS, _bench_path, _parameters, _scan
from optimize.fitting.measurements import Measurements

PREFIX_SHARE = 0.2
PREFIX_PER_PARAMETER = 3
"""A full fit of data with a path also fits the path's first rows in the order of
acquisition, a fifth of its measured numbers (at least three per free parameter), from
the nominal design (see :func:`_prefix_start`). [-]"""
PREFIX_GAP = 2.0
"""... and starts from that fit where the fit of the whole path misses those rows by
more than this factor times their own fit's RMS error: it then sits in a basin that
trades the early rows for later ones. Before the robot has snapped much, its states
change smoothly with the parameters, and a local fit of them finds the basin a fit of
the whole path (a staircase of snaps) does not. Benchmark seed [3, 9, 0]: the near-field
model fitted the whole path at 12x the noise's RMS with a rod 20x stiffer than built
(which snaps nowhere); its first 13 rows fit at the noise with the rod's stiffness
within 10 %, and from there the whole path fits at 2.3x. [-]"""
STIFFER = (2.0, 4.0)
"""Factors on the rod's bending stiffness at which a fit also starts where a start leaves
most rows without a state (the robot pulled onto the magnet): a stiffer rod deflects
less and stays clear of it. Benchmark seed [3, 10, 0] (large deflection and torsion, a
211 mm rod): from the torsion model's estimates and from the nominal design the
large-deflection rod was pulled in at 26 of 39 configurations, and the candidate failed;
twice as stiff, every configuration has a state. [-]"""


def _stiffer(
    model: RingPairModel, design: Design, initial: Mapping[str, float] | None, free: Sequence[str]
) -> list[dict[str, float]]:
    """``initial`` with the rod's bending stiffness scaled by each of STIFFER (none where
    it is not free). [SI]"""
    name = "bending_rigidity_scale"
    if name not in free:
        return []
    value = float(_parameters(model, design, initial)[index(name)])
    return [{**(initial or {}), name: value * f} for f in STIFFER]


def _leveled_start(
    model: RingPairModel,
    design: Design,
    m: Measurements,
    initial: Mapping[str, float] | None,
    free: Sequence[str],
    mode: bool | Literal["driven"],
    *,
    unset: Iterable[str],
) -> dict[str, float] | None:
    """A start better than ``initial`` (None: the nominal design) with the free
    parameters of LEVELS not in ``unset`` (a start's values) at their levels, or None;
    solved along the bench's path where the data or ``mode`` have one. [SI]"""
    known = set(unset)
    levels = {n: v for n, v in LEVELS.items() if n in free and n not in known}
    if not levels:
        return None
    params = _parameters(model, design, initial)
    path = "driven" if mode else _bench_path(m)
    return _scan(model, m, params, free, ordered=path, factors=(), levels=levels)


def _prefix_start(
    design: Design,
    m: Measurements,
    effects: frozenset[str],
    free: Sequence[str],
    fitted: CalibrationResult,
    sigma: float | None,
    priors: bool | Priors = True,
) -> dict[str, float] | None:
    """The fit of the path's first rows (PREFIX_SHARE, PREFIX_PER_PARAMETER) from the
    nominal design, where ``fitted`` (the fit of the whole path) misses those rows by more
    than PREFIX_GAP times its RMS error on them; else None. [SI]"""
    order = m.order()
    counts = np.cumsum(m.measured[order].sum(axis=1))
    need = max(PREFIX_SHARE * counts[-1], PREFIX_PER_PARAMETER * len(free))
    rows = int(np.searchsorted(counts, need)) + 1
    if rows >= len(m):  # the whole path
        return None
    early = np.zeros(len(m), bool)
    early[order[:rows]] = True
    try:
        own = calibrate(
            design,
            m.subset(early),
            effects,
            free,
            ordered="driven",
            sigma=sigma,
            priors=priors,
            posterior=False,
        )
    except UnsolvedStart:
        return None
    mine = own.errors[np.isfinite(own.errors)]
    if mine.size == 0:
        return None
    whole = fitted.errors[early & m.seen]  # a row without a state there: a miss too
    whole_rms = math.sqrt(np.mean(whole**2)) if np.isfinite(whole).all() else math.inf
    return dict(own.estimate) if whole_rms > PREFIX_GAP * math.sqrt(np.mean(mine**2)) else None


Start = CalibrationResult | Mapping[str, float] | None
"""Where a fit starts (see :func:`_fit`)."""
STIFF_FIRST = "stiff first"
"""A screening job's start: :func:`optimize.fitting.calibrate.stiff_start` from the
nominal design, found in the job itself (a full fit). On-axis torsion set [99, 4] of
``draw_planted(on_axis=True)`` (a 222 mm rod, 21 rows): from every other start torsion
ended at 1.65 times the noise's misfit and the near field was named on top of it; with
this start torsion alone is named, CV/noise 1.25 (from the current estimates and with a
screen's budget the pre-fit did not get there)."""
Starts = list[Start]


def screen_starts(
    current: Fit, effects: frozenset[str], screened: Mapping[str, Mapping[str, float]]
) -> Starts:
    """Where a screen of ``effects`` on top of ``current`` starts: the current estimates,
    the nominal design (in every round: the current model may have bent its parameters to
    mimic the missing effect, into a basin the candidate cannot leave from there;
    benchmark seed [2, 7, 0], near_field on top of torsion: BIC -3 from the other starts,
    -114 from the nominal design), the added effects' own estimates from their single
    screens (``screened``: effect -> its parameters' estimates), the candidate as it
    reduces to the current model (NESTED_START), and the nominal design with softer
    transmissions (SOFT_START)."""
    added = effects - current.effects
    starts: Starts = [current.calibration, None]
    guesses = {n: v for e in added for n, v in screened.get(e, {}).items()}
    own = [n for e in added for n in EFFECT_FREE[e]]
    nested = {n: NESTED_START[n] for n in own if n in NESTED_START}
    for extra in (guesses, nested):
        if extra:
            starts.append({**current.calibration.estimate, **extra})
    return [*starts, *_soft_start(added)]


def _soft_start(added: frozenset[str]) -> Starts:
    """SOFT_START of the ``added`` effects' own parameters, from the nominal design (the
    current estimates may mimic the effect), where they have any."""
    soft = {n: SOFT_START[n] for e in added for n in EFFECT_FREE[e] if n in SOFT_START}
    return [soft] if soft else []


def _on_top(effects: frozenset[str], names: Sequence[str]) -> tuple[str, ...]:
    """The free parameters of ``effects`` as a candidate on top of a fit with free
    ``names``: their own, and those of ``names`` (what :func:`_refine` freed there)."""
    own = default_free(effects)
    return (*own, *(n for n in names if n not in own))


Job = tuple[frozenset[str], Start | str, tuple[str, ...]]
"""A screening fit: the candidate's effects, where it starts, its free parameters."""


def _job_key(job: Job) -> Hashable:
    """``job`` as a key: equal for jobs with equal effects, free parameters and starts (the
    nominal design, equal values, STIFF_FIRST); a start from a fit is that fit's own."""
    effects, start, free = job
    if isinstance(start, CalibrationResult):
        return effects, id(start), free
    return effects, tuple(sorted(start.items())) if isinstance(start, Mapping) else start, free
