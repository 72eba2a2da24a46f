"""Value lists on the command line (ring angles, a moved magnet's position): 'START:STOP:STEP'
(inclusive stop, either direction), 'a,b,c' or 'a'."""

from __future__ import annotations

import math

import numpy as np

MAX_ANGLES = 1_000_000
"""Angles one option may list at most (a 0.001 deg grid over 1000 deg)."""
MAX_ABS_DEG = 36_000.0
"""Largest commanded angle either way, a hundred turns: beyond it a typing error. [deg]"""
MAX_ABS_MM = 100_000.0
"""Largest coordinate of a moved magnet either way, 100 m: beyond it a typing error. [mm]"""


def parse_angles(text: str, option: str) -> np.ndarray:
    """Degrees from a range or list; raises ValueError naming ``option`` on bad input.

    A range runs from START towards STOP in steps of STEP, down as well as up
    (``60:-60:2`` is 60, 58, ..., -60); a negative STEP must point towards STOP.
    """
    return _parse(text, option, "degrees", "0:180:12 or 60:-60:2", "0,45,90", MAX_ABS_DEG)


def parse_lengths(text: str, option: str) -> np.ndarray:
    """Millimetres from a range or list, as :func:`parse_angles` reads degrees."""
    return _parse(text, option, "millimetres", "100:200:10", "120,150", MAX_ABS_MM)


def _parse(
    text: str, option: str, unit: str, ranges: str, listed: str, max_abs: float
) -> np.ndarray:
    """Values in ``unit`` from a range or list, each within +-``max_abs``."""
    expected = (
        f"{option} expects {unit} as START:STOP:STEP (e.g. {ranges}), a comma "
        f"list (e.g. {listed}) or one number"
    )
    try:
        if ":" in text:
            parts = [float(p) for p in text.split(":")]
            if len(parts) != 3:
                raise ValueError
            start, stop, step = parts
            values = _range(start, stop, step, expected=f"{expected}; got {text!r}", option=option)
        else:
            values = np.array([float(p) for p in text.split(",")])
    except ValueError as exc:
        if str(exc).startswith(option):
            raise
        raise ValueError(f"{expected}; got {text!r}") from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError(f"{expected}, all finite; got {text!r}")
    if np.abs(values).max() > max_abs:
        span = "a hundred turns" if unit == "degrees" else "100 m"
        symbol = "deg" if unit == "degrees" else "mm"
        raise ValueError(f"{option} must lie within +-{max_abs:g} {symbol} ({span}); got {text!r}")
    if values.size > MAX_ANGLES:
        raise ValueError(f"{option} gives {values.size} values; at most {MAX_ANGLES} are allowed")
    return values


def _range(start: float, stop: float, step: float, expected: str, option: str) -> np.ndarray:
    """START, START +- STEP, ... up to STOP inclusive (within 1e-9 of a step)."""
    if not all(math.isfinite(x) for x in (start, stop, step)):
        raise ValueError(f"{expected}: START, STOP and STEP must be finite")
    if step == 0 or (step < 0 and stop > start):
        raise ValueError(f"{expected}: STEP must be > 0 (or < 0 with STOP below START)")
    count = abs(stop - start) / abs(step)
    if not count < MAX_ANGLES:  # also catches a count that overflows to inf
        raise ValueError(
            f"{option} {start:g}:{stop:g}:{step:g} gives {count + 1:.4g} values; at most "
            f"{MAX_ANGLES} are allowed"
        )
    n = int(math.floor(count + 1e-9)) + 1
    return start + math.copysign(abs(step), stop - start) * np.arange(n)
