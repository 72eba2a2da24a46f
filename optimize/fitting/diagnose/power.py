"""The power of the data: could these data have told an effect apart from the final
model (:func:`power_of_data`). SI units; the ``*_mm`` figures are millimetres.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal

import numpy as np

from design.model import model_for
from design.records import Design
from design.registry import index
from design.units import DEG, MM
from optimize.fitting.calibrate import (
    EFFECT_FREE,
    predict,
    row_sigma,
)
from optimize.fitting.diagnose.evidence import _reason
from optimize.fitting.diagnose.fits import SCREEN_EVALUATIONS, _fit
from optimize.fitting.diagnose.result import Fit
from optimize.fitting.diagnose.scans import _bench_path
from optimize.fitting.measurements import Measurements

POWER_STRENGTH = {"wire_friction_angle": 2 * DEG, "catheter_friction_angle": 2 * DEG}
"""Strengths at which an effect whose nominal strength is nil is judged for the power of
the data (friction play of 2 deg in each transmission). [SI]"""
FIRST_ORDER_BAND = 5.0
"""The power of the data is refitted where its first-order margin lies within this factor
of DETECTABLE (:func:`power_of_data`): on null bench sets drawn from the whole design
space the first-order margins of torsion, hysteresis, gravity and large deflection lay
within 0.5-2.6x of the refitted ones (18 draws, tests/optimize/fitting/test_diagnose.py;
gravity on the final model of a large deflection + torsion benchmark draw: 0.27x).
[-]"""
REFITTED_POWER = frozenset({"near_field"})
"""Effects whose power of the data is always refitted: the final model absorbs much of the
finite magnet's field by moving its centre, far from linearly (first-order margins up to
50x the refitted ones on the same draws)."""
DETECTABLE = 1.0
"""The data can tell an effect apart where, at nominal strength, it leaves at least this
many noise sigmas RMS per coordinate that the model without it cannot absorb. [-]"""


def power_of_data(
    design: Design, m: Measurements, final: Fit, effect: str, sigma: float | None
) -> dict[str, object]:
    """Could these data tell ``effect`` apart from the ``final`` model?

    The final model with ``effect`` added, at the final estimates and the effect's
    nominal strength (POWER_STRENGTH where that is nil), predicts the measured
    coordinates; what the final model cannot absorb of them, RMS per coordinate over the
    noise (stated, else the final fit's residual), is the ``margin``: below DETECTABLE
    the data could not have named the effect. What it cannot absorb is first found to
    first order, the change of the predictions less its least-squares projection on the
    final fit's Jacobian (:func:`_unabsorbed`); where that margin lies within a factor
    FIRST_ORDER_BAND of DETECTABLE, where the answer turns on it, and for the effects of
    REFITTED_POWER, the final model is fitted to the predictions instead (a short fit from
    its estimates).
    """
    stated = np.isfinite(m.sigma)
    noise = float(np.median(m.sigma[stated])) if stated.any() else math.sqrt(final.rss / final.n)
    try:
        model = model_for(final.effects | {effect})
        params = final.calibration.params.copy()
        for name, value in POWER_STRENGTH.items():
            if name in EFFECT_FREE[effect]:
                params[index(name)] = value
        path = _bench_path(m)
        position = predict(model, params, m, path).equilibria.position
        if not np.isfinite(position[m.measured]).all():
            return {
                "margin": math.inf,
                "could_tell_apart": True,
                "note": ("at nominal strength it leaves configurations without an equilibrium"),
            }
        first = effect not in REFITTED_POWER
        rss = _unabsorbed(m, final, position, path, sigma) if first else math.nan
        how = "to first order"
        first_margin = math.sqrt(rss / final.n) / noise if noise > 0 else math.inf
        if not np.isfinite(rss) or (
            DETECTABLE / FIRST_ORDER_BAND <= first_margin <= DETECTABLE * FIRST_ORDER_BAND
        ):
            ideal = replace(m, position=np.where(m.measured, position, np.nan))
            fit = _fit(
                design,
                ideal,
                final.effects,
                k=2,
                seed=0,
                cv=False,
                starts=[final.calibration],
                sigma=sigma,
                max_nfev=SCREEN_EVALUATIONS,
                free=final.calibration.names,
                priors=dict(final.calibration.prior_width) or False,
                within=final.calibration.within,
            )
            if fit.unsolved:
                return {
                    "margin": math.inf,
                    "could_tell_apart": True,
                    "note": (
                        f"{final.name} cannot solve {fit.unsolved} of the configurations it "
                        "predicts"
                    ),
                }
            rss, how = fit.rss, "refitted"
    except Exception as exc:  # reported; the diagnosis goes on
        return {"margin": math.nan, "could_tell_apart": None, "note": f"failed: {_reason(exc)}"}
    rms = math.sqrt(rss / final.n)
    margin = rms / noise if noise > 0 else math.inf
    return {
        "margin": margin,
        "rms_mm": rms / MM,
        "noise_mm": noise / MM,
        "could_tell_apart": bool(margin >= DETECTABLE),
        "method": how,
        "note": f"at nominal strength it would leave {rms / MM:.3g} mm RMS per coordinate that "
        f"{final.name} cannot absorb ({how}), {margin:.2g} x the noise ({noise / MM:.3g} mm)",
    }


def _unabsorbed(
    m: Measurements,
    final: Fit,
    position: np.ndarray,
    path: bool | Literal["driven"],
    sigma: float | None,
) -> float:
    """What ``final`` cannot absorb of the change from its own predictions to
    ``position`` (N, 3) [m], to first order: the weighted change of the measured
    coordinates less its least-squares projection on the final fit's Jacobian, as a sum
    of squares [m^2]; NaN where the final model leaves a row without a state or the fit
    stored no Jacobian."""
    cal = final.calibration
    if cal.jacobian is None or cal.jacobian_rows is None:
        return math.nan
    own = predict(model_for(final.effects), cal.params, m, path).equilibria.position
    change = (position - own)[m.measured]
    s = row_sigma(m, sigma)[np.nonzero(m.measured)[0]]
    jac = cal.jacobian[: change.size]
    if not (np.isfinite(change).all() and np.isfinite(jac).all() and len(jac) == change.size):
        return math.nan
    weighted = change / s
    step = np.linalg.lstsq(jac, weighted, rcond=None)[0]
    return float(np.sum(((weighted - jac @ step) * s) ** 2))
