"""Backlash and Coulomb friction in the transmissions: the play (backlash) operator.

A transmission with play of half-width w (friction angle) passes the commanded rotation
to the ring only once the slack is taken up: the ring's angle y follows the command u as

    y_k = min(max(y_{k-1}, u_k - w), u_k + w),

so it trails the command by w in the direction of travel and stays put for the first 2 w
of a reversal (Krasnosel'skii & Pokrovskii, *Systems with Hysteresis*, 1989, the play
operator). The path starts centred (y_0 = u_0). Written on CasADi symbols and accumulated
over the sequence with ``mapaccum``. Angles in radians.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np


def play_step(previous: ca.SX, command: ca.SX, half_width: ca.SX) -> ca.SX:
    """One step of the play operator. [rad]"""
    return ca.fmin(ca.fmax(previous, command - half_width), command + half_width)


@lru_cache(maxsize=32)
def _accumulated(n: int) -> ca.Function:
    y = ca.SX.sym("y", 2)
    u = ca.SX.sym("u", 2)
    w = ca.SX.sym("w", 2)
    step = ca.Function("play", [y, u, w], [play_step(y, u, w)])
    return step.mapaccum("play_path", n)


def play(commands: np.ndarray, half_width: np.ndarray) -> np.ndarray:
    """Ring angles after the play of each transmission along an ordered path.

    commands : shape (2, N), commanded (theta1, theta2) in order. [rad]
    half_width : shape (2,), play half-width of (wire, catheter). [rad]
    Returns shape (2, N). [rad]
    """
    commands = np.asarray(commands, float)
    n = commands.shape[1]
    if n == 0:
        return commands.copy()
    out = _accumulated(n)(commands[:, 0], commands, np.asarray(half_width, float))
    return np.asarray(out)
