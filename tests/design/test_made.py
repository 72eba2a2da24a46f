"""A design rounded to what can be made, and the explicit hand-off file (issue 52).

The optimiser's raw digits (``magnet_outer_diameter_mm = 1.34999999998``) and a
``[tip.mounting]`` left to defaults a later version may change made the hand-off file
unfit to order parts from. Random designs from the whole design space, with raw digits
added, are rounded; every value must land on its step, within half a step of the input,
and the file must read back as the same design. Seeds in the ids.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np
import pytest
from setups import random_design

from design.designfile import default_design, dumps_design, loads_design
from design.made import RESOLUTION, SIGNIFICANT, made_design
from design.registry import PARAMETERS, design_with, file_unit


def raw(design, rng):
    """``design`` with optimiser-like digits: each length moved by a few parts in 1e7."""
    values = {
        n: p.value(design) * (1 + rng.uniform(-3e-7, 3e-7))
        for n, p in PARAMETERS.items()
        if p.field is not None and PARAMETERS[n].unit == "m"
    }
    return design_with(design, values)


@pytest.mark.parametrize("seed", range(5200, 5206))
def test_rounded_values_land_on_their_steps_and_read_back(seed) -> None:
    rng = np.random.default_rng(seed)
    design = raw(random_design(rng) if seed > 5200 else default_design(), rng)
    made = made_design(design)
    text = dumps_design(made, explicit=True)
    # (a magnetisation direction is a unit vector: the reader normalises it, digits and all)
    sizes = text[: text.index("magnetization")] + text[text.index("[environment]") :]
    assert not re.search(r"\d\.\d{7,}", sizes), f"seed {seed}: raw digits in\n{text}"
    assert loads_design(text, source="made") == made
    for name, p in PARAMETERS.items():
        if p.field is None:
            continue
        _, scale = file_unit(name)
        x, y = p.value(design) / scale, p.value(made) / scale
        step = RESOLUTION.get(name)
        if step is None:
            assert y == pytest.approx(x, rel=10.0 ** (1 - SIGNIFICANT)), f"seed {seed}: {name}"
            continue
        # on the step (or, where that made the design impossible, on a tenth of it)
        on = [abs(y / s - round(y / s)) < 1e-6 for s in (step, step / 10)]
        assert any(on), f"seed {seed}: {name} = {y}"
        assert abs(y - x) <= (0.5 if on[0] else 0.05) * step + 1e-12, f"seed {seed}: {name}"


def test_the_issue_52_digits_are_rounded() -> None:
    d = default_design()
    tip = replace(
        d.tip, magnet_outer_diameter=1.34999999998e-3, magnet_inner_diameter=0.6e-3,
        magnet_gap=0.0349200385363e-3,
    )  # fmt: skip
    text = dumps_design(made_design(replace(d, tip=tip)), explicit=True)
    assert "magnet_outer_diameter_mm = 1.35\n" in text
    assert "gap_mm = 0.03\n" in text


def test_explicit_hand_off_states_every_mounting_choice() -> None:
    d = default_design()
    text = dumps_design(d, explicit=True)
    section = text[text.index("[tip.mounting]") :].split("\n\n")[0]
    for key in (
        'process = "resin"', "wall_mm = 0.5", "fit_allowance_mm = 0.05",
        "running_clearance_mm = 0.1", "density_kg_m3 = 1180", "stop_angle_deg = 180",
        "pretwist_deg = 0",
    ):  # fmt: skip
        assert key in section, section
    # the defaults-only file says none of it, and both read back as the same design
    assert "[tip.mounting]" not in dumps_design(d)
    assert loads_design(text, source="explicit") == loads_design(dumps_design(d), source="short")
    assert math.isclose(loads_design(text, source="x").tip.mounting.wall, 0.5e-3)
