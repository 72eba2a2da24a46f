"""Residual structure: does what a fitted model leaves depend on a candidate's signature?

Each candidate cause of a misfit has a signature: each ring angle and their difference
(two-harmonic Fourier series), the deflection and the distance to the external magnet
(quadratics), the acquisition order (a cubic), the direction of travel (its sign). The
residuals are regressed on each and F-tested against pure noise
(:func:`residual_structure`). SI units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from design.geometry import rest_position
from design.records import Design
from optimize.fitting.measurements import Measurements

STRUCTURE_P = 1e-3
"""A residual dependence on a feature is reported as structure below this p-value."""


@dataclass(frozen=True)
class ResidualDependence:
    """Residual dependence on one feature.

    feature : what the residuals were regressed on. r2 : fraction of the residual variance
    the regression explains. p_value : F-test of the regression against pure noise.
    """

    feature: str
    r2: float
    p_value: float


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


__all__ = ["STRUCTURE_P", "ResidualDependence", "features", "residual_structure"]
