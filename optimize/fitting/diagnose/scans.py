"""Scans for a better start than a fit's own: the misfit at a fit's parameters moved by
factors, offsets of the external magnet's centre and levels of an effect's own
parameters, each point solved on the path's first rows first (:func:`_scan`), and many
parameter sets solved at once where rows are solved on their own (:func:`_misfits`).
SI units.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Literal

import numpy as np

from design.equilibrium import solve_equilibria
from design.model import RingPairModel, model_for
from design.records import Design
from design.registry import index
from design.units import MM
from optimize.fitting.calibrate import (
    EFFECT_FREE,
    FREE_PARAMETERS,
    predict,
)
from optimize.fitting.diagnose.result import Fit
from optimize.fitting.measurements import Measurements
from optimize.fitting.workers import parallel_map, worker_count

SCAN_FACTORS = (0.6, 0.7, 0.8, 0.9, 1.1, 1.25, 1.5)
"""Factors on each positive (log-fitted) parameter, alone and with the others of its
effect, at which a fit along the path looks for a better basin (see :func:`_scan`)."""
SCAN_HEAD = 1 / 3
"""The share of the rows, first in acquisition order, on which :func:`_scan` solves each
point first: their misfit is part of the whole's (a row's state depends only on the rows
before it along the path, and on nothing else solved on its own), so a point whose first
rows already miss by more than the start does in whole cannot beat it, and is not solved
further. A scan's points mostly miss by far more than its start. [-]"""
CENTRE = ("external_center_x", "external_center_y", "external_center_z")
CENTRE_OFFSETS = (-4 * MM, -2 * MM, 2 * MM, 4 * MM)
"""Moves of the external magnet's centre along each axis at which a screen of the near
field looks for a better start (see :func:`_scan`): near a strong magnet the rows' states
change branch with where it is, and the baseline's dipole-field estimate of the centre
can lie a branch away (seed [5, 1, 0]: from the baseline's estimates the near-field
screen ended at 300 times the noise's misfit, from the centre moved 4 mm along y at the
noise's). [m]"""
UNSOLVED_OFFSETS = (-1 * MM, -0.5 * MM, 0.5 * MM, 1 * MM)
"""Moves of the external magnet's centre along each free axis at which a fit that leaves
measured rows without a state looks for a start that solves them all (see :func:`_fit`).
Benchmark seed [3, 9, 1] (friction and the near field, 28 rows seen along a path): the
near-field candidate fitted the other rows at 1.07 times the noise's RMS but left one
pulled onto the magnet, charged so much that the candidate was rejected (BIC +90); its
estimate with the centre moved 0.5 mm along z solves every row. [m]"""
LEVELS = {
    **{
        n: tuple(f * FREE_PARAMETERS[n].prior * FREE_PARAMETERS[n].step for f in (0.5, 1.0, 2.0))
        for n in EFFECT_FREE["hysteresis"]
    },
    **{n: tuple(2 ** (k / 2) for k in range(-4, 5)) for n in EFFECT_FREE["torsion"]},
}
"""Values of an effect's own parameters (of each transmission, and every pair of them) at
which a fit of the effect looks for a better start than its own (see :func:`_scan`)
where its start has none of them (a start with them is a fit, or was leveled).

Friction angles [rad]: half, one and two widths of their prior (2.5, 5 and 10 deg).
Whether a ring sticks or slips on its way to a row jumps with the friction angle, so the
misfit is a staircase in it that a local fit does not climb. Benchmark seed [3, 9, 0]
(friction and the near field, 63 rows along a path near the magnet): from the near-field
model's estimates with no friction, friction with the near field fitted at 11x the
noise's RMS; with the catheter's friction at 5 deg the start is at 2x and the fit
reaches the noise.

Torsion scales [-]: 0.25 to 4 times nominal in steps of sqrt(2). Where a ring's twist
tips it over to another state depends on both transmissions' stiffness, and fits from
nominal, stiff and soft transmissions can all end in a basin where one transmission is
rigid. Gravity and torsion planted (tests/optimize/fitting/test_diagnose.py seed
172425381: 63 rows along a path, wire 1.5 and catheter 2.8 times nominal): every start
of the diagnosis ended at the catheter 22 times nominal, 4x the noise's RMS (the
transmissions at (2, 4) as well); from the nominal design with them at (1.41, 4), the
best of these levels, the fit reaches the noise. Benchmark seed [3, 3, 1] (torsion, a
107 mm rod seen from above, the wire at 0.32 times nominal): with levels from 0.5 up, the
screen from the nominal design ended with the wire at 0.42 and the catheter at 0.52
(truth 1.35), and the diagnosis' final model at 3x the noise's cross-validated RMSE; from
(0.25, 1) it reaches the truth's basin, 1.17x."""


def _parameters(
    model: RingPairModel, design: Design, values: Mapping[str, float] | None
) -> np.ndarray:
    """``model``'s parameter vector of ``design`` with ``values`` (by name) set. [SI]"""
    params = model.parameters(design)
    for name, value in (values or {}).items():
        params[index(name)] = value
    return params


def _scan(
    model: RingPairModel,
    m: Measurements,
    params: np.ndarray,
    free: Sequence[str],
    *,
    ordered: Literal["driven"] | bool = "driven",
    factors: Sequence[float] = SCAN_FACTORS,
    offsets: Sequence[float] = (),
    levels: Mapping[str, Sequence[float]] | None = None,
) -> dict[str, float] | None:
    """A better start for a fit than ``params``, or None.

    Where the robot is multistable the misfit jumps where a parameter moves a row's state
    to another branch, so a local fit stops at the edge of its basin. Driven along a path,
    the robot snaps (or not) from one branch to another (e.g. transmissions fitted too
    stiff to snap where the bench did); near a strong magnet, the rows' branches change
    with where the magnet is. Evaluate the misfit (solved as ``ordered``) at ``params``
    with each free positive parameter scaled by ``factors``, alone and together with the
    others of its effect (both transmissions), and with the external magnet's centre moved
    by each of ``offsets`` [m] along each free axis, and with the free parameters named in
    ``levels`` set to each of their values there [SI] (those of one effect together, every
    combination); return the best point if it beats ``params``. Each point is solved on the
    path's first rows first (SCAN_HEAD) and in whole only where they miss by less than
    ``params`` does in whole (along a path, less than the best point before it in the
    worker's share). Rows solved on their own are solved for all points at once
    (:func:`_misfits`; a path, point by point)."""
    moves: list[list[tuple[str, float, float]]] = []  # (name, factor, offset) each
    groups = [[n] for n in free if FREE_PARAMETERS[n].kind == "log"]
    groups += [
        [n for n in names if n in free]
        for names in EFFECT_FREE.values()
        if sum(n in free and FREE_PARAMETERS[n].kind == "log" for n in names) > 1
    ]
    for group in groups:
        for factor in factors:
            moves.append([(n, factor, 0.0) for n in group])
    for axis in (n for n in CENTRE if n in free):
        for offset in offsets:
            moves.append([(axis, 1.0, offset)])
    for names in EFFECT_FREE.values():  # a level v is the move (factor 0, offset v)
        leveled = [n for n in names if n in free and n in (levels or {})]
        for chosen in itertools.product(*[(None, *(levels or {})[n]) for n in leveled]):
            if any(v is not None for v in chosen):
                moves.append(
                    [(n, 0.0, v) for n, v in zip(leveled, chosen, strict=True) if v is not None]
                )

    points = [params]
    for move in moves:
        moved = params.copy()
        for name, factor, offset in move:
            spec = FREE_PARAMETERS[name]
            value = moved[index(name)] * factor + offset
            moved[index(name)] = np.clip(value, spec.lower, spec.upper)
        points.append(moved)
    head = _first_rows(m)
    # interleaved shares of the points, each in their order (the workers' loads even)
    shares = [
        s
        for s in (np.arange(1, len(points))[w :: worker_count()] for w in range(worker_count()))
        if s.size
    ]
    if ordered:  # each point's path on its own, its first rows first

        def misfit(data: Measurements, params: np.ndarray) -> float:
            position = predict(model, params, data, ordered=ordered).equilibria.position
            return float(_squared_misses(position[None], data.position)[0])

        bound = misfit(m, params)

        def share(idx: np.ndarray) -> np.ndarray:
            """Each point's misfit, in whole only where its first rows miss by less than
            the best whole misfit before it (a point that misses those rows by more
            cannot be the best)."""
            best, values = bound, np.empty(idx.size)
            for j, i in enumerate(idx):
                values[j] = misfit(head, points[i])
                if values[j] < best and len(head) < len(m):
                    values[j] = misfit(m, points[i])
                best = min(best, values[j])
            return values

    else:  # every row of every point in one solve: the first rows, then the others' rest
        rest = m.subset(m.order()[len(head) :])
        bound = float(_misfits(model, m, [params])[0])

        def share(idx: np.ndarray) -> np.ndarray:
            part = _misfits(model, head, [points[i] for i in idx])
            go = np.flatnonzero(part < bound)
            if go.size and len(rest):
                part[go] += _misfits(model, rest, [points[idx[j]] for j in go])
            return part

    values = np.full(len(points), bound)
    for idx, found in zip(shares, parallel_map(share, shares), strict=True):
        values[idx] = found
    best = int(np.argmin(values))  # the first of equals; 0: params themselves
    if best == 0 or not values[best] < values[0]:
        return None
    return {n: float(points[best][index(n)]) for n in free}


def _squared_misses(position: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """Sum of squared misses [m^2] of each of P predictions ``position`` (P, N, 3) of the
    measured positions (N, 3, NaN where not measured); inf where a measured row has no
    state."""
    r = (position - measured)[:, np.isfinite(measured)]
    return np.where(np.isfinite(r).all(axis=1), np.sum(r**2, axis=1), np.inf)


def _misfits(model: RingPairModel, m: Measurements, points: Sequence[np.ndarray]) -> np.ndarray:
    """:func:`_squared_misses` of ``m`` at each parameter vector of ``points`` [SI], every
    row solved on its own, all in one solve (per-column parameters: the load ramp's loop
    then runs once, not once per point; benchmark seed [2, 7, 0]'s 81 torsion levels of
    33 rows 5.5x faster, a large-deflection rod's 2x). [m^2]"""
    n = len(m)
    params = np.repeat(np.stack(points, axis=1), n, axis=1)
    command = np.tile(m.command, (len(points), 1))
    eq = solve_equilibria(model, params, command[:, 0], command[:, 1])
    return _squared_misses(eq.position.reshape(len(points), n, 3), m.position)


def _bench_path(m: Measurements) -> Literal["driven", False]:
    """How a check outside the fits solves the rows of ``m``: along the bench's path
    ("driven", :func:`predict`) where the data have an acquisition order (the states may
    depend on it), else each on its own."""
    return "driven" if m.sequence is not None else False


def _first_rows(m: Measurements) -> Measurements:
    """The first SCAN_HEAD of the rows of ``m`` in acquisition order, in that order."""
    return m.subset(m.order()[: math.ceil(SCAN_HEAD * len(m))])


def _centre_scan(
    design: Design,
    m: Measurements,
    around: Fit | None,
    effects: frozenset[str],
    free: Sequence[str],
) -> dict[str, float] | None:
    """A screening start for ``effects`` (with the near field): the estimates of
    ``around`` (None: the nominal design) with the external magnet's centre moved by
    CENTRE_OFFSETS where that fits better (:func:`_scan`; along the bench's path where the
    data have one: near the magnet the states depend on it), or None."""
    model = model_for(effects)
    params = _parameters(model, design, around.calibration.estimate if around is not None else None)
    return _scan(model, m, params, free, ordered=_bench_path(m), factors=(), offsets=CENTRE_OFFSETS)
