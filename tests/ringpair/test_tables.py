"""Tables of results: the effects comparison."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from ringpair import tables


def test_effect_shifts_skip_configurations_without_a_state(monkeypatch, demonstrator):
    """A configuration without a state (NaN tip) is left out of the largest and RMS shift
    and counted, not turned into a NaN row."""

    def solve(design, theta1, theta2, model, ordered=False):
        # Each effect moves the tip 1 mm along y; under any effect the first command has
        # no state.
        position = np.tile([design.robot.free_length, 0.0, 0.0], (len(theta1), 1))
        position[:, 1] = 1e-3 * len(model.effects)
        if model.effects:
            position[0] = np.nan
        return SimpleNamespace(
            position=position,
            stable=np.isfinite(position[:, 0]),
            snapped=np.zeros(len(theta1), bool),
        )

    monkeypatch.setattr(tables, "solve_design", solve)
    rows, baseline_max = tables.effect_shifts(demonstrator, np.deg2rad([0, 10, 20]), np.zeros(1))
    by_effect = {r["effect"]: r for r in rows}
    assert baseline_max == 0.0
    assert by_effect["gravity"]["max_shift_mm"] == pytest.approx(1.0)
    assert by_effect["gravity"]["rms_shift_mm"] == pytest.approx(1.0)
    assert by_effect["gravity"]["without_state"] == 1
    assert by_effect["all"]["max_deflection_mm"] == pytest.approx(len(rows) - 1)


def test_check_rows_show_failures_and_tight_margins_and_collapse_the_rest():
    # The shapes of cad.checks' rows: limits as text, ">= x (process)" or "<= x".
    checks = [
        {"item": "a", "check": "min_wall", "value": 2.7, "limit": ">= 0.8 (fdm)", "passed": True},
        {"item": "b", "check": "min_wall", "value": 0.85, "limit": ">= 0.8 (fdm)", "passed": True},
        {"item": "c", "check": "volume", "value": 0.0995, "limit": "<= 0.1", "passed": True},
        {"item": "d", "check": "volume", "value": 0.001, "limit": "<= 0.1", "passed": True},
        {"item": "e", "check": "watertight", "value": 0.0, "limit": "1", "passed": False},
        {"item": "f", "check": "shaft_angle", "value": 90.0, "limit": "90 +- 0.01", "passed": True},
    ]
    shown, rest = tables.check_rows(checks)
    assert [c["item"] for c in shown] == ["b", "c", "e"]  # within 10 % of the limit, or failed
    assert [c["item"] for c in rest] == ["a", "d", "f"]


def test_check_values_read_without_raw_exponents():
    # Issue 52: the page showed values such as 8.4e-12 and 2e-05; every unit the CAD checks
    # use is written in fixed digits (or percent), and no value reads as an exponent.
    cases = {
        (1.23456e-05, "mm"): "0.000",
        (0.49857, "mm"): "0.499",
        (-0.0312, "mm"): "-0.031",
        (89.99999, "deg"): "90.00",
        (8.4e-12, "relative"): "0.00 %",
        (0.0123, "fraction"): "1.23 %",
        (30.0, ""): "30",
        (float("nan"), "mm"): "not measured",
        (None, "mm"): "not measured",
    }
    for (value, unit), text in cases.items():
        assert tables.check_value_text(value, unit) == text, (value, unit)
    rng = np.random.default_rng(52)
    for value in 10.0 ** rng.uniform(-15, 3, 200) * rng.choice([-1, 1], 200):
        for unit in ("mm", "deg", "relative", "fraction", "", "mm^3"):
            assert "e" not in tables.check_value_text(float(value), unit), (value, unit)


def test_limits_the_stage_could_not_move_are_named_in_words_with_why():
    """An active bound at the end of what its quantity admits (the rings' gap at 0 mm, the
    default study's optimum) and an active constraint the study sets no limit for are
    listed after the moved rows in words, with the reason, not as their keys."""
    moved = [{"meaning": "the limit on x", "groups": ["neutral"], "gain": 0.2}]
    best = SimpleNamespace(active=["neutral", "bound.magnet_gap.low", "ring_seat"])
    rows = tables.limit_rows(best, moved)
    assert rows[0] is moved[0] and len(rows) == 3
    gap, seat = rows[1], rows[2]
    assert gap["meaning"] == "the lower bound of the face-to-face gap of the rings"
    assert gap["reason"] == "not moved: at the end of what the quantity admits"
    assert seat["meaning"] == (
        "the limit on the ring bore minus the printed pieces' wire bore and passage"
    )
    assert seat["reason"] == "not moved: the study sets no limit for it"
    assert np.isnan(gap["gain"]) and np.isnan(seat["old"])


def test_design_numbers_read_without_raw_exponents():
    """Issue 52: the report's design table showed the optimum's ring gap as 5.108e-11 mm and
    the NiTi modulus as 6e+04 MPa. Design quantities in file units print with four
    significant digits, 0 below a millionth of the unit, thousands grouped, never an
    exponent (drawn over 18 decades, both signs)."""
    cases = {
        5.108e-11: "0",
        6e4: "60,000",
        249.05: "249.1",
        0.3922: "0.3922",
        1.45: "1.45",
        150.0: "150",
        -9.81: "-9.81",
        0.000123456: "0.0001235",
        float("nan"): "",
        None: "",
    }
    for value, text in cases.items():
        assert tables.page_number(value) == text, value
    rng = np.random.default_rng(5252)
    for value in 10.0 ** rng.uniform(-12, 6, 400) * rng.choice([-1, 1], 400):
        text = tables.page_number(float(value))
        assert "e" not in text, value
        if abs(value) >= tables.NEGLIGIBLE:  # the digits shown are the number's
            assert float(text.replace(",", "")) == pytest.approx(value, rel=1e-3), value
