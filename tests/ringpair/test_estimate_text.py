"""Estimates written to the digits their uncertainty gives them (ringpair.tables)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ringpair.tables import estimate_text


@pytest.mark.parametrize(
    ("value", "error", "text"),
    [
        (4.3e-10, 0.031, "0.000"),  # a tip mass at its bound of 0 g
        (-1e-12, 0.5, "0.00"),  # no minus sign on a zero
        (1.23456, 0.012, "1.235"),
        (12345.6, 300.0, "12346"),
        (1.234567, math.nan, "1.2346"),  # error unknown: 5 significant digits
        (1.234567, 0.0, "1.2346"),
        (1.234567, math.inf, "1.2346"),
    ],
)
def test_estimate_text_cases(value, error, text):
    assert estimate_text(value, error) == text


def test_estimate_text_rounds_within_a_twentieth_of_the_error():
    """Rounding half a unit in the last digit shown, one digit past the error's first,
    moves the value by at most a twentieth of its one-sigma error, plus the text's own
    rounding back to a float (an ulp: seed 506391565 drew -184793.50338 with a 1.1e-9
    error, 16 significant digits); and no digit fewer (the error's first digit is always
    shown)."""
    rng = np.random.default_rng()
    seed = int(rng.integers(2**31))
    rng = np.random.default_rng(seed)
    for _ in range(2000):
        error = 10 ** rng.uniform(-9, 4)
        value = rng.normal() * 10 ** rng.uniform(-12, 6)
        text = estimate_text(value, error)
        bound = error / 20 + np.spacing(abs(value))
        assert abs(float(text) - value) <= bound, (seed, value, error, text)
        decimals = len(text.split(".")[1]) if "." in text else 0
        assert 10.0**-decimals <= error, (seed, value, error, text)
