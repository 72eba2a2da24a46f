"""The epsilon bounds of the Pareto sweeps. SI units."""

from __future__ import annotations

import numpy as np

from design.magnets import ring_volume
from optimize.sizing.studyfile import ParetoSweep, Study


def pareto_values(study: Study, sweep: ParetoSweep) -> np.ndarray:
    """The epsilon bounds of one Pareto sweep, shape (points,), in increasing order. [SI]

    Without an explicit range, the sweep spans the free bounds of its quantity (for the
    magnet volume: the smallest and largest rings the ring bounds and the minimum wall
    allow, base values for the fixed ones). ValueError if the quantity cannot change in this study.
    """
    low, high = sweep.low, sweep.high
    if low is None or high is None:
        if sweep.against == "magnet_volume":
            tip = study.base.tip
            fixed = {
                "magnet_outer_diameter": tip.magnet_outer_diameter,
                "magnet_inner_diameter": tip.magnet_inner_diameter,
                "magnet_length": tip.magnet_length,
            }
            rng = {}
            for name, value in fixed.items():
                b = study.bound(name)
                rng[name] = (b.low, b.high) if b else (value, value)
            od, idia = rng["magnet_outer_diameter"], rng["magnet_inner_diameter"]
            h = rng["magnet_length"]
            bore = min(idia[1], od[0] - 2 * study.limits.min_wall)
            lo_ = 2 * ring_volume(od[0], max(bore, 0.0), h[0])
            hi_ = 2 * ring_volume(od[1], idia[0], h[1])
        else:
            b = study.bound(sweep.against)
            if b is None:
                raise ValueError(
                    f"pareto sweep against {sweep.against} needs free.{sweep.against}_mm "
                    "or an explicit range_mm"
                )
            lo_, hi_ = b.low, b.high
        low = lo_ if low is None else low
        high = hi_ if high is None else high
    if not high > low:
        raise ValueError(f"pareto sweep against {sweep.against} has an empty range")
    return np.linspace(low, high, sweep.points)
