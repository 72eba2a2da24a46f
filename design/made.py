"""Sizes that can be made or bought: a design rounded to each quantity's resolution.

An optimiser's numbers (``magnet_outer_diameter_mm = 1.34999999998``) are not what a
maker orders or a printer makes. :func:`made_design` rounds every quantity a design file
holds to the step it is bought or made in (:data:`RESOLUTION`, in file units: ring magnets
are ground to 0.05 mm, tubes and wire come in 0.01 mm steps, a tube is cut to half a
millimetre, a printed gap is set to 0.01 mm, a magnet is placed to half a millimetre,
angles to a degree), everything else to :data:`SIGNIFICANT` digits. The caller re-runs the
model on the result and states the change (``ringpair study`` does).
"""

from __future__ import annotations

import math

from design.designfile import DesignError, dumps_design, loads_design
from design.records import Design
from design.registry import PARAMETERS, design_with, file_unit

RESOLUTION: dict[str, float] = {
    "free_length": 0.5,
    "catheter_outer_diameter": 0.01,
    "catheter_inner_diameter": 0.01,
    "wire_outer_diameter": 0.01,
    "wire_inner_diameter": 0.01,
    "magnet_outer_diameter": 0.05,
    "magnet_inner_diameter": 0.05,
    "magnet_length": 0.05,
    "magnet_gap": 0.01,
    "magnet_remanence": 0.01,
    "external_remanence": 0.01,
    "external_diameter": 0.1,
    "external_length": 0.1,
    "external_center_x": 0.5,
    "external_center_y": 0.5,
    "external_center_z": 0.5,
    "mount_wall": 0.01,
    "mount_fit_allowance": 0.01,
    "mount_running_clearance": 0.01,
    "stop_angle": 1.0,
    "pretwist": 1.0,
    "tip_mass": 0.001,
}
"""Step each quantity is bought or made in, by registry name, in its file unit (mm, T,
deg, g). [file unit]"""

SIGNIFICANT = 4
"""Significant digits of the quantities without a step of their own (moduli, densities,
ratios, directions). [-]"""


def made_value(name: str, value: float) -> float:
    """``value`` (SI) of parameter ``name`` rounded to what can be made (module
    docstring). [SI]"""
    _, scale = file_unit(name)
    x = value / scale
    step = RESOLUTION.get(name)
    if step is not None:
        digits = max(0, -math.floor(math.log10(step)) + 1)
        rounded = round(round(x / step) * step, digits)
    elif x == 0 or not math.isfinite(x):
        rounded = x
    else:
        rounded = float(f"{x:.{SIGNIFICANT}g}")
    return rounded * scale


def made_design(design: Design) -> Design:
    """``design`` with every quantity it holds rounded to what can be made
    (:func:`made_value`). A quantity whose rounding would make the design impossible (a
    ring bore the wire no longer turns in) keeps a tenth of the step instead. [SI]"""
    values = {name: p.value(design) for name, p in PARAMETERS.items() if p.field is not None}
    rounded = {name: made_value(name, v) for name, v in values.items()}
    candidate = design_with(design, rounded)
    try:
        return loads_design(dumps_design(candidate), source="rounded design")
    except DesignError:
        pass
    finer = {}
    for name, v in values.items():
        step = RESOLUTION.get(name)
        if step is None:
            finer[name] = rounded[name]
            continue
        _, scale = file_unit(name)
        tenth = step / 10
        digits = max(0, -math.floor(math.log10(tenth)) + 1)
        finer[name] = round(round(v / scale / tenth) * tenth, digits) * scale
    return loads_design(dumps_design(design_with(design, finer)), source="rounded design")
