"""Diagnosis: what the simulation gets wrong on measured data, the physical cause, and the gain.

Method (the result format is docs/formats.md's diagnosis JSON):

1. Calibrate the baseline (:func:`optimize.fitting.calibrate.calibrate`, its default free
   parameters) and cross-validate it over held-out configurations.
2. Look for structure in its residuals: regress them on smooth functions of each candidate
   cause's signature (each ring angle and their difference as two-harmonic Fourier series,
   the deflection and the distance to the external magnet as quadratics, the acquisition
   order as a cubic, the direction of travel as a sign) and F-test each against the
   residual noise (:func:`residual_structure`).
3. Greedy forward selection: screen every candidate effect added to the current model
   (its own parameters freed, :data:`optimize.fitting.calibrate.EFFECT_FREE`) by short fits
   from several starts; fit in full those whose Bayesian information criterion,
   n ln(RSS'/RSS) + k' ln n, falls by more than BIC_DROP (very strong evidence, Kass &
   Raftery 1995); cross-validate those whose full BIC still does, lowest first, and
   accept the first whose cross-validated RMSE falls by more than CV_GAIN; repeat while
   one is accepted and the residual is not yet consistent with the stated noise
   (chi-square test, when the data give sigma); where no single addition pays and
   structure remains, pairs.
   After each acceptance, refit the model with the parameters its effects make
   separable also free (:data:`optimize.fitting.calibrate.EFFECT_SEPARATES`: the field's
   strength under gravity), kept if that pays by the same two tests (:func:`.refine._refine`);
   the candidates of later rounds free them too.
4. Name each accepted cause with its evidence (the residual structure it removes, the
   cross-validated gain, its parameters as the final model estimates them with 1-sigma
   profile-likelihood intervals, :mod:`optimize.fitting.likelihood`), and say whether structure
   remains.

Data with an acquisition order are fitted along the bench's path wherever that changes
the states (a multistable robot), and each full fit of such data also scans the misfit
along the path around its estimate (:func:`_scan`): snap-throughs make it jump, which a
local least-squares fit cannot see. Such a fit also starts from a fit of the path's first
rows, where the whole path's fit misses them (:func:`_prefix_start`: before the robot
has snapped much its states change smoothly), and a fit of friction play or torsion from a
start without their parameters also from those at a few levels, where one fits better
(LEVELS: stick or slip, and the rings' snaps, jump with them). For the same reason a
screen starts from several points (:func:`screen_starts`; torsion also from stiff and
from soft transmissions, and from the other parameters fitted first with stiff
transmissions, STIFF_FIRST), and
the near field also from the external magnet's centre moved a few millimetres, about the
current estimates and about the nominal design, where that fits better
(:func:`_centre_scan`: near a strong magnet the rows' branches change with where it is).
A start where most rows are pulled onto the magnet is tried again with a stiffer rod
(STIFFER), and a fit that leaves measured rows without a state looks for one that solves
them with the magnet's centre moved a little (UNSOLVED_OFFSETS): a row without a state
costs the same wherever it has none, so the fit cannot see the way back.

The candidates are only ever judged through the data: the same fits, the same thresholds
for each. SI units inside; the ``*_mm`` figures are millimetres.

One concept per module: the search (:mod:`.search`, a class whose state is its fields),
a candidate's fit (:mod:`.fits`), its starts (:mod:`.starts`), the scans for better ones
(:mod:`.scans`), the refit after an acceptance (:mod:`.refine`), the power of the data
(:mod:`.power`), the verdicts and evidence (:mod:`.evidence`), the causes named with
their intervals (:mod:`.causes`) and the result with its JSON (:mod:`.result`); this
package re-exports their names.
"""

from __future__ import annotations

from optimize.fitting.calibrate import EFFECT_FREE
from optimize.fitting.diagnose.evidence import (
    BIC_DROP,
    CV_GAIN,
    HELD_OUT_RATIO,
    NOISE_P,
    _cause,
    _noise_consistent,
    _unexplained,
)
from optimize.fitting.diagnose.fits import (
    FOLD_ANCHOR,
    FOLD_EVALUATIONS,
    MIN_SOLVED,
    SCREEN_EVALUATIONS,
    _cross_validated,
    _fit,
)
from optimize.fitting.diagnose.power import (
    DETECTABLE,
    FIRST_ORDER_BAND,
    POWER_STRENGTH,
    REFITTED_POWER,
    power_of_data,
)
from optimize.fitting.diagnose.refine import _refine
from optimize.fitting.diagnose.result import (
    NULL_REASONS,
    Candidate,
    Cause,
    Diagnosis,
    Fit,
    finite_json,
    parameter_values,
    report_key,
)
from optimize.fitting.diagnose.scans import (
    CENTRE,
    CENTRE_OFFSETS,
    LEVELS,
    SCAN_FACTORS,
    SCAN_HEAD,
    UNSOLVED_OFFSETS,
    _centre_scan,
    _first_rows,
    _misfits,
    _parameters,
    _scan,
)
from optimize.fitting.diagnose.search import Search, diagnose
from optimize.fitting.diagnose.starts import STIFF_FIRST, STIFFER, screen_starts
from optimize.fitting.structure import ResidualDependence, residual_structure

# the package's own names, and what callers imported from the one module it was
# (the private ones for the tests of their concepts)
__all__ = [
    "BIC_DROP",
    "CENTRE",
    "CENTRE_OFFSETS",
    "CV_GAIN",
    "DETECTABLE",
    "EFFECT_FREE",
    "FIRST_ORDER_BAND",
    "FOLD_ANCHOR",
    "FOLD_EVALUATIONS",
    "HELD_OUT_RATIO",
    "LEVELS",
    "MIN_SOLVED",
    "NOISE_P",
    "NULL_REASONS",
    "POWER_STRENGTH",
    "REFITTED_POWER",
    "SCAN_FACTORS",
    "SCAN_HEAD",
    "SCREEN_EVALUATIONS",
    "STIFFER",
    "STIFF_FIRST",
    "UNSOLVED_OFFSETS",
    "Candidate",
    "Cause",
    "Diagnosis",
    "Fit",
    "ResidualDependence",
    "Search",
    "_cause",
    "_centre_scan",
    "_cross_validated",
    "_first_rows",
    "_fit",
    "_misfits",
    "_noise_consistent",
    "_parameters",
    "_refine",
    "_scan",
    "_unexplained",
    "diagnose",
    "finite_json",
    "parameter_values",
    "power_of_data",
    "report_key",
    "residual_structure",
    "screen_starts",
]
