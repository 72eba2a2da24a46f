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
