"""Cross-validation over held-out configurations: the folds, each fold's fit, the
held-out errors continued from the full fit's states, and the ratio a right model
gives (:func:`held_out_inflation`). SI units; the ``*_mm`` figures are millimetres.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from design.equilibrium import drive
from design.model import RingPairModel, model_for
from design.records import Design
from design.units import MM
from optimize.fitting.calibrate.fit import calibrate
from optimize.fitting.calibrate.result import CalibrationResult
from optimize.fitting.measurements import Measurements
from optimize.fitting.sensitivity import (
    applied_commands,
    position_errors,
    sensitivities,
)
from optimize.fitting.workers import parallel_map


@dataclass(frozen=True)
class CrossValidation:
    """K-fold cross-validation over held-out configurations.

    rmse_mm : RMS over all held-out rows of the model-measurement distance. [mm]
    fold_rmse_mm : shape (k,), the same per fold. [mm]
    errors : shape (N,), each row's distance when it was held out; NaN if unsolved. [m]
    folds : shape (N,) int, the fold of each row.
    unconverged : held-out rows the fitted model could not solve.
    expected_ratio : ``rmse_mm`` over the in-sample RMSE that a right model, linear in its
        parameters near the fit of all the data, gives on average with these
        configurations and folds (:func:`held_out_inflation`); NaN without that fit. [-]
    """

    rmse_mm: float
    fold_rmse_mm: np.ndarray
    errors: np.ndarray
    folds: np.ndarray
    unconverged: int
    expected_ratio: float = math.nan


def configuration_folds(m: Measurements, k: int, seed: int | None = 0) -> np.ndarray:
    """Fold number of each row (shape (N,)): rows with the same commanded angles share a
    fold, so a held-out configuration is never seen in training; folds are seeded. Only
    seen configurations are dealt into folds: a configuration driven but never seen
    carries no error to hold out and gets -1 (always in training, where it only keeps
    the path)."""
    seen = np.round(m.command[m.seen], 12)
    configurations = np.unique(seen, axis=0)
    n_groups = len(configurations)
    if not 2 <= k <= n_groups:
        raise ValueError(
            f"k must be between 2 and the number of distinct seen configurations ({n_groups}); "
            f"got {k}"
        )
    perm = np.random.default_rng(seed).permutation(n_groups)
    fold_of_group = np.empty(n_groups, int)
    fold_of_group[perm] = np.arange(n_groups) % k
    commands = np.round(m.command, 12)
    match = (commands[:, None, :] == configurations[None, :, :]).all(axis=2)
    return np.where(match.any(axis=1), fold_of_group[match.argmax(axis=1)], -1)


def held_out_inflation(jacobian: np.ndarray, fold: np.ndarray, position: np.ndarray) -> float:
    """The ratio of the cross-validated to the in-sample RMS position error that a right
    model, linear in its parameters near a fit of all the data, gives on average, for
    equal noise on every coordinate. [-]

    jacobian : shape (n, k), the fit's whitened Jacobian (:attr:`CalibrationResult.jacobian`).
    fold : shape (n,), the fold each residual is held out in.
    position : shape (n,) bool, the residuals that count (the position coordinates).

    With the hat matrix H = J (J^T J)^+ J^T, a held-out block f's prediction error is
    (I - H_ff)^-1 e_f (e the in-sample residuals), whose covariance is s^2 (I - H_ff)^-1;
    the in-sample residuals' is s^2 (I - H). So the expected squared errors are
    s^2 sum_f tr (I - H_ff)^-1 held out and s^2 tr (I - H) in sample. About
    sqrt((1 + p/(0.8 n)) / (1 - p/n)) for p parameters spread over n coordinates held out
    a fifth at a time; far above it where a few configurations alone fix a parameter
    (Hastie, Tibshirani & Friedman, *The Elements of Statistical Learning*, 2nd ed.,
    sec. 7.10: the leave-one-out form e_i / (1 - H_ii)).
    """
    # H from J's own singular vectors, an exact projection to rounding (from (J^T J)^+ it is
    # not where J is ill-conditioned, and I - H_ff of a fold whose configurations alone fix
    # a parameter, singular in theory, then had eigenvalues of either sign around 1e-9: a
    # negative held-out trace, a drawn null set of 16 rows). The same rank as (J^T J)^+ at
    # rcond 1e-10: singular values above 1e-5 of the largest.
    u, sv, _ = np.linalg.svd(np.asarray(jacobian, float), full_matrices=False)
    u = u[:, sv > 1e-5 * sv.max(initial=0.0)] if sv.size else u
    hat = u @ u.T
    held = 0.0
    for f in np.unique(fold[fold >= 0]):
        i = np.flatnonzero(fold == f)
        block = np.linalg.pinv(np.eye(i.size) - hat[np.ix_(i, i)], rcond=1e-12)
        held += float(np.trace(block[np.ix_(position[i], position[i])]))
    fitted = float(np.sum(1.0 - np.diag(hat)[position]))
    return math.sqrt(held / fitted) if fitted > 0 and held >= 0 else math.nan


def _continued(
    model: RingPairModel,
    full: CalibrationResult,
    fold: CalibrationResult,
    m: Measurements,
    held: np.ndarray,
    ordered: bool | Literal["driven"] | None,
) -> np.ndarray:
    """The held-out rows' distances (shape (N,), NaN elsewhere or unsolved) [m] at the
    ``fold``'s parameters, each from the state of the fit ``full`` of all the data, by
    :func:`design.equilibrium.drive` (Newton, contracting, on the stable side of the
    folds): the fold's miss on the state the robot is in."""
    errors = np.full(len(m), np.nan)
    assert full.states is not None
    cols = np.flatnonzero(held & np.isfinite(full.states).all(axis=1))
    if cols.size == 0:
        return errors
    start = applied_commands(model, full.params, m, ordered)[0][cols]
    end = applied_commands(model, fold.params, m, ordered)[0][cols]
    x, ok = drive(model, fold.params, full.states[cols].T, start.T, end.T)
    if ok.any():
        out, _ = sensitivities(model, fold.params, x.T[ok], end[ok])
        position = np.full((len(m), 3), np.nan)
        position[cols[ok]] = out[:, :3]
        errors[cols[ok]] = position_errors(position, m)[cols[ok]]
    return errors


def cross_validate(
    design: Design,
    m: Measurements,
    effects: Iterable[str] = (),
    free: Sequence[str] | None = None,
    *,
    k: int = 5,
    seed: int | None = 0,
    full: CalibrationResult | None = None,
    **options: object,
) -> CrossValidation:
    """K-fold cross-validated position error of :func:`calibrate` (same ``options``):
    fit on k-1 folds of configurations, predict the held-out fold.

    full : the fit of all the data. A held-out row with a state there is predicted from
        that state at the fold's parameters (:func:`_continued`); the fold's own solve
        (load ramp or path) only where that fails. Near a fold of the equilibria, a
        fold's parameters a little off the full fit's can make the ramp fall to another
        state; its error would then measure that jump, not how well the fold's
        parameters predict the robot in the state it is in. Its states also warm-start
        each fold's first evaluation (a fold starts at its estimate, options' ``initial``),
        which otherwise costs a load ramp of every row.
    """
    folds = configuration_folds(m, k, seed)
    model = model_for(frozenset(effects))
    ordered = options.get("ordered")

    def fold(f: int) -> np.ndarray:
        held = folds == f
        warm = None if full is None else full.states
        res = calibrate(design, m, effects, free, rows=~held, states=warm, **options)  # type: ignore[arg-type]
        errors = np.where(held, res.errors, np.nan)
        if full is not None and full.states is not None:
            continued = _continued(model, full, res, m, held, ordered)  # type: ignore[arg-type]
            errors = np.where(np.isfinite(continued), continued, errors)
        return errors

    per_fold = parallel_map(fold, range(k))
    errors = np.full(len(m), np.nan)
    fold_rmse = np.full(k, np.nan)
    for f, e_f in enumerate(per_fold):
        held = folds == f
        errors[held] = e_f[held]
        e = e_f[held]
        e = e[np.isfinite(e)]
        fold_rmse[f] = np.sqrt(np.mean(e**2)) / MM if e.size else np.nan
    ok = np.isfinite(errors)  # (rows not seen have no error)
    expected = math.nan
    if full is not None and full.jacobian is not None and full.jacobian_rows is not None:
        rows = full.jacobian_rows
        position = np.arange(rows.size) < int(m.measured[full.rows].sum())
        expected = held_out_inflation(full.jacobian, folds[rows], position)
    return CrossValidation(
        rmse_mm=float(np.sqrt(np.mean(errors[ok] ** 2)) / MM) if ok.any() else float("nan"),
        fold_rmse_mm=fold_rmse,
        errors=errors,
        folds=folds,
        unconverged=int(np.count_nonzero(m.seen & ~ok)),
        expected_ratio=expected,
    )
