"""Whether an NLP optimum is the robot's: its equilibria the states forward simulation
reaches, its loops driven from sample to sample without a snap. SI units."""

from __future__ import annotations

import numpy as np

from design.equilibrium import drive, solve_equilibria
from optimize.sizing.nlp_problem import (
    Core,
)

BRANCH_TOLERANCE = 1e-6
"""An NLP equilibrium is the robot's state when its unknowns are within this of the state
forward simulation reaches (dimensionless: unknowns over their scale, i.e. 1e-6 of the
free length or 1e-6 rad; IPOPT's equilibria are exact to about 1e-8 of that scale)."""
ARRIVAL_TOLERANCE = 1e-4
"""A loop driven from one sample arrives at the next sample's state when the unknowns agree
within this (as BRANCH_TOLERANCE; looser, since a snap moves them by far more and the
driven states carry the path solver's tolerance besides IPOPT's)."""


def _off_branch(c: Core, prm: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Configurations where the NLP's equilibria x (n, K) are not the states the robot
    reaches (:func:`design.solve_equilibria`: stable, connected to the unloaded robot), and
    those states (n, K), NaN where there is none."""
    eq = solve_equilibria(c.model, c.configuration_params(prm), c.commands[0], c.commands[1])
    reached = eq.unknowns.T
    scale = c.model.unknown_scale(prm)[:, None]
    with np.errstate(invalid="ignore"):
        differs = ~(np.max(np.abs(reached - x) / scale, axis=0) <= BRANCH_TOLERANCE)
    return np.flatnonzero(differs), reached


def _loop_faults(c: Core, prm: np.ndarray, x: np.ndarray) -> str:
    """Why the robot could not be driven around the study's loops through its sampled
    states x (n, K'; the states forward simulation reaches, which the NLP's equal), or ''
    when it can: each loop (parallel rings, the workspace's rim;
    antiparallel, the neutral loop; rings at right angles) is driven from every sample to
    the next (:func:`design.equilibrium.drive`, sub-steps of 1 degree, failing where the
    robot would snap) and must arrive at the next sample's state; and no sampled state
    may share its command with another stable state (``multistable``)."""
    k, kn = c.shape.configurations, c.shape.neutral_configurations
    scale = c.model.unknown_scale(prm)[:, None]
    loops = (("parallel", 0, k), ("antiparallel", k, kn), ("right-angle", k + kn, kn))
    for name, first, count in loops:
        idx = first + np.arange(count)
        ahead = np.roll(idx, -1)
        end = c.commands[:, idx] + 2 * np.pi / count  # the next sample, unwrapped
        reached, ok = drive(c.model, prm, x[:, idx], c.commands[:, idx], end)
        expected = x[:, ahead].copy()
        if c.model.n_unknowns > c.model.n_rod:  # tip angles: a turn further at the wrap
            expected[c.model.n_rod :] += end - c.commands[:, ahead]
        with np.errstate(invalid="ignore"):
            same = np.max(np.abs(reached - expected) / scale, axis=0) <= ARRIVAL_TOLERANCE
        bad = np.flatnonzero(~(ok & same))
        if bad.size:
            where = ", ".join(f"{i}-{(i + 1) % count}" for i in bad[:4])
            return f"the {name} loop snaps between samples {where} (of {count})"
    sampled = c.commands[:, :-1]
    eq = solve_equilibria(
        c.model, c.configuration_params(prm)[:, :-1], sampled[0], sampled[1], multistable=True
    )
    if eq.multistable.any():
        return f"multistable at configurations {np.flatnonzero(eq.multistable).tolist()[:6]}"
    return ""
