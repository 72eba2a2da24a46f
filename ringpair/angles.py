"""Angle lists on the command line: 'START:STOP:STEP' (inclusive stop), 'a,b,c' or 'a'."""

from __future__ import annotations

import math

import numpy as np


def parse_angles(text: str, option: str) -> np.ndarray:
    """Degrees from a range or list; raises ValueError naming ``option`` on bad input."""
    expected = (
        f"{option} expects degrees as START:STOP:STEP (e.g. 0:180:12), a comma list "
        f"(e.g. 0,45,90) or one number"
    )
    try:
        if ":" in text:
            parts = [float(p) for p in text.split(":")]
            if len(parts) != 3:
                raise ValueError
            start, stop, step = parts
            if step <= 0 or stop < start:
                raise ValueError(f"{expected}; STEP must be > 0 and STOP >= START; got {text!r}")
            n = int(math.floor((stop - start) / step + 1e-9)) + 1
            values = start + step * np.arange(n)
        else:
            values = np.array([float(p) for p in text.split(",")])
    except ValueError as exc:
        if str(exc).startswith(option):
            raise
        raise ValueError(f"{expected}; got {text!r}") from None
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError(f"{expected}; got {text!r}")
    if values.size > 1_000_000:
        raise ValueError(f"{option} gives {values.size} angles; at most 1000000 are allowed")
    return values
