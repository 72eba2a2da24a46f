"""What a fit's numbers do not say by themselves, said for ``calibrate`` and ``diagnose``:
measured positions out of the robot's reach (units? the wrong design file?), a fit that
misses the data by orders of magnitude, and parameters the data cannot separate.

Each check returns sentences for the user; they name the data file, and never blame an
option the user did not pass. Millimetres in the messages, SI inside.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from design.records import Design
from design.units import MM

if TYPE_CHECKING:
    from optimize.fitting.calibrate import CalibrationResult
    from optimize.fitting.measurements import Measurements

REACH_FACTOR = 2.0
"""Measured tips farther from the base than this many times the robot's reach are not
this robot's (a unit error, another set-up). [-]"""
MISS_NOISE = 100.0
"""A fit whose RMS error exceeds the stated noise this many times explains nothing. [-]"""
MISS_REACH = 0.2
"""Without stated noise: an RMS error above this fraction of the reach explains nothing. [-]"""
TRADE_OFF = 0.9
"""Estimates correlated beyond this (in magnitude) trade off against each other. [-]"""

UNITS_HINT = "check the units (mm, deg) and that the design file describes this set-up"


def reach(design: Design) -> float:
    """How far the tip can be from the base: free length plus the rigid tip. [m]"""
    tip = design.tip
    return design.robot.free_length + tip.spacing + tip.magnet_length / 2


def coordinates(m: Measurements) -> int:
    """Measured numbers a fit can use: position coordinates and tip angles. [-]"""
    return int(np.isfinite(m.position).sum() + np.isfinite(m.tip_angles).sum())


def out_of_reach(design: Design, m: Measurements) -> list[str]:
    """A sentence if measured tips lie farther from the base than the robot can reach
    (the distance over the coordinates measured, a lower bound of the true one)."""
    distance = np.sqrt(np.nansum(m.position**2, axis=1))
    far = float(distance.max(initial=0.0))
    if far <= REACH_FACTOR * reach(design):
        return []
    return [
        f"{m.source}: measured tip positions lie up to {far / MM:.4g} mm from the base, but "
        f"the robot of '{design.name}' reaches {reach(design) / MM:.4g} mm at most; " + UNITS_HINT
    ]


def misses(design: Design, m: Measurements, fit: CalibrationResult) -> list[str]:
    """A sentence if the fit misses the data by far more than their noise (stated) or by
    a good part of the robot's reach (noise not stated)."""
    rmse = fit.rmse_mm * MM
    sigma = m.sigma[np.isfinite(m.sigma)]
    if sigma.size:
        noise = float(np.median(sigma))
        if not rmse > MISS_NOISE * noise:
            return []
        how = f"{rmse / noise:,.0f} times the stated noise ({noise / MM:.3g} mm)"
    else:
        far = reach(design)
        if not rmse > MISS_REACH * far:
            return []
        how = f"while the robot reaches {far / MM:.4g} mm"
    return [
        f"the model does not explain {m.source}: it misses by {fit.rmse_mm:.4g} mm RMS, "
        f"{how}; " + UNITS_HINT
    ]


def inseparable(fit: CalibrationResult) -> list[str]:
    """A sentence naming the parameters the data cannot separate: those whose standard
    error is wider than the nominal design's own uncertainty (the prior width of
    :mod:`optimize.fitting.calibrate`), with the pairs that trade off. The errors are the
    data's alone (a fit with priors: without the priors' residuals, which bound every
    error by its prior)."""
    from optimize.fitting.calibrate import FREE_PARAMETERS

    errors = fit.data_standard_error or fit.standard_error
    correlation = fit.correlation if fit.data_correlation is None else fit.data_correlation
    loose = []
    for name in fit.names:
        spec, error = FREE_PARAMETERS[name], errors[name]
        if spec.kind == "log":  # error relative to the estimate against a relative width
            spread, width = error / max(abs(fit.estimate[name]), 1e-300), spec.prior
            shown = f"{spread:.2g} relative"
        else:
            spread, width = error, spec.prior * spec.step
            label, factor = spec.label
            shown = f"{error * factor:.2g} {label}".rstrip()
        if not spread <= width:  # also infinite and NaN errors
            loose.append((name, shown))
    if not loose:
        return []
    names = [n for n, _ in loose]
    index = {n: i for i, n in enumerate(fit.names)}
    pairs = [
        f"{a} and {b} trade off (correlation {correlation[index[a], index[b]]:+.2f})"
        for k, a in enumerate(names)
        for b in names[k + 1 :]
        if abs(correlation[index[a], index[b]]) > TRADE_OFF
    ]
    return [
        "the data cannot separate "
        + ", ".join(f"{n} (standard error {s})" for n, s in loose)
        + ": wider than the nominal design's own uncertainty"
        + (f"; {'; '.join(pairs)}" if pairs else "")
        + ". More configurations, spread over both ring angles, would pin them down"
    ]


def fit_warnings(design: Design, m: Measurements, fit: CalibrationResult) -> list[str]:
    """The warnings about a finished fit: that it :func:`misses` the data, or else which
    parameters are :func:`inseparable` (data that are not this robot's separate nothing)."""
    return misses(design, m, fit) or inseparable(fit)
