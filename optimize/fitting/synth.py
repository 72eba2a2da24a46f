"""Synthetic bench data: simulate a robot driven along a bench path, add tracker noise.

The "truth" is the design with optional parameter overrides (e.g. a softer rod, a wire
that twists, friction in the transmissions) under a model with the chosen effects. The
robot is driven along the commands in order (:func:`design.equilibrium.solve_sequence`),
as on a bench, so hysteresis and snap-through appear as they would; each row records its
place in that order (``sequence``). Configurations whose equilibrium does not converge
or is unstable (the robot pulled onto the magnet, lost) are counted; along a path they
stay as rows without a position (driven but not seen: the robot went through them, and
what comes after depends on it), without one they are dropped. SI units are used for
all inputs and outputs.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from design.equilibrium import Equilibria, solve_equilibria, solve_sequence
from design.model import RingPairModel, model_for
from design.records import Design
from design.registry import NAMES, index
from design.suggest import did_you_mean
from optimize.fitting.measurements import Measurements, make_measurements

VIEWS = ("3d", "top")
"""'3d': x, y and z measured; 'top': a camera above the robot sees x and y only."""

DEFAULT_N = 60
DEFAULT_PROXIMAL_DEG = (0.0, 120.0, 240.0)
"""theta2 values of the default bench path. [deg]"""


def default_commands(n: int = DEFAULT_N, both_ways: bool = True) -> np.ndarray:
    """A bench path like the paper's, about ``n`` points: for each theta2 in
    DEFAULT_PROXIMAL_DEG, theta1 sweeps from theta2 (parallel rings) to theta2 + 180 deg
    (antiparallel) and back, so both directions of travel are seen; ``both_ways=False``:
    the forward sweeps only, each configuration once.

    Returns shape (M, 2), M close to n, in driving order. [rad]
    """
    if n < 2 * len(DEFAULT_PROXIMAL_DEG):
        raise ValueError(f"n must be at least {2 * len(DEFAULT_PROXIMAL_DEG)}; got {n}")
    per_block = n / len(DEFAULT_PROXIMAL_DEG)
    if both_ways:
        steps = max(1, int(round((per_block - 1) / 2)))  # forward steps; block = 2 steps + 1
        relative = np.linspace(0.0, 180.0, steps + 1)
        sweep = np.concatenate([relative, relative[-2::-1]])
    else:
        sweep = np.linspace(0.0, 180.0, max(2, int(round(per_block))))
    rows = [np.column_stack([t2 + sweep, np.full(sweep.size, t2)]) for t2 in DEFAULT_PROXIMAL_DEG]
    return np.deg2rad(np.vstack(rows))


@dataclass(frozen=True)
class Synthetic:
    """A synthetic data set and how it was made.

    measurements : the noisy data (lost configurations: without a position along a
        path, removed without one).
    params : shape (n,), the true model parameter vector (design + overrides). [SI]
    model : the model that produced the data.
    equilibria : the noise-free simulation of every commanded configuration, in order.
    dropped : number of configurations lost (unconverged or unstable): not seen.
    snapped : number of kept configurations reached by a snap-through.
    noise_free : the measurements without their noise (the same rows and coordinates).
    """

    measurements: Measurements
    params: np.ndarray
    model: RingPairModel
    equilibria: Equilibria
    dropped: int
    snapped: int
    noise_free: Measurements


SETUPS: dict[str, tuple[tuple[float, float], tuple[float, float]]] = {
    "bench": ((0.060, 0.100), (0.8, 1.25)),  # around the paper's demonstrator
    "near": ((0.015, 0.022), (3.5, 4.5)),  # magnet face 15-22 mm away, a stiffer rod
    "soft": ((0.070, 0.090), (0.25, 0.35)),  # a soft rod: deflections of L / 5
}
"""Set-ups a designer meets, as ranges of the external magnet's face gap from the rest tip
[m] and of a factor on both tubes' Young's moduli [-] (see :func:`setup_variant`): the
exact field matters only near the magnet and the rod's nonlinearity only at large
deflections. The diagnosis tests and benchmark draw their nominal designs from these."""


def setup_variant(design: Design, face_gap: float, stiffness: float) -> Design:
    """``design`` with its external magnet's face ``face_gap`` beyond the rest tip on the
    rod's axis [m] and both tubes' Young's moduli scaled by ``stiffness`` [-]."""
    em = design.external_magnet
    centre = (design.robot.free_length + em.length / 2 + face_gap, 0.0, 0.0)
    robot = design.robot
    tubes = {
        t: dataclasses.replace(
            getattr(robot, t), youngs_modulus=getattr(robot, t).youngs_modulus * stiffness
        )
        for t in ("catheter", "wire")
    }
    return dataclasses.replace(
        design,
        external_magnet=dataclasses.replace(em, center=centre),
        robot=dataclasses.replace(robot, **tubes),
    )


def true_parameters(design: Design, params_override: Mapping[str, float] | None) -> np.ndarray:
    """Parameter vector of ``design`` with ``params_override`` (names of
    :data:`design.registry.NAMES`, SI values) applied; ValueError names a bad name."""
    params = RingPairModel.parameters(design)
    for name, value in (params_override or {}).items():
        if name not in NAMES:
            raise ValueError(f"unknown model parameter {name!r}{did_you_mean(name, NAMES)}")
        value = float(value)
        if not np.isfinite(value):
            raise ValueError(f"parameter {name} must be a finite number; got {value!r}")
        params[index(name)] = value
    return params


def synthesize_data(
    design: Design,
    effects: Iterable[str] = (),
    *,
    commands: np.ndarray | None = None,
    n: int = DEFAULT_N,
    view: str = "3d",
    noise_mm: float = 0.3,
    seed: int | None = 0,
    params_override: Mapping[str, float] | None = None,
    tip_angles: bool = False,
    angle_noise_deg: float = 1.0,
    record_sigma: bool = False,
    ordered: bool = True,
) -> Synthetic:
    """Simulate a bench run of ``design`` and return the data with how they were made.

    effects : model effects of the truth (names of :data:`design.model.EFFECTS`).
    commands : shape (M, 2), commanded (theta1, theta2) in driving order [rad]; default
        :func:`default_commands` (``n``; one way when not ``ordered``).
    view : '3d' (x, y, z measured) or 'top' (x, y; z left empty).
    noise_mm : one-sigma Gaussian noise on each measured coordinate. [mm]
    seed : seed of ``numpy.random.default_rng``; the same seed gives the same data.
    params_override : true values of model parameters (names of
        :data:`design.registry.NAMES`) that differ from the design. [SI]
    tip_angles : also record the ring angles at the tip, with ``angle_noise_deg`` noise. [deg]
    record_sigma : write ``noise_mm`` as each row's sigma (default: the data do not say).
    ordered : drive the robot along the commands and record the order (``sequence``);
        False: each configuration's state on its own (the load ramp from rest,
        :func:`design.equilibrium.solve_equilibria`), no ``sequence`` column, so each
        configuration once (a data set without the order cannot tell repeats apart,
        docs/formats.md); not with ``hysteresis``, which needs a path.
    """
    if view not in VIEWS:
        raise ValueError(f"view must be one of {', '.join(VIEWS)}; got {view!r}")
    if not (np.isfinite(noise_mm) and noise_mm >= 0):
        raise ValueError(f"noise_mm must be a finite number >= 0; got {noise_mm!r}")
    if not (np.isfinite(angle_noise_deg) and angle_noise_deg >= 0):
        raise ValueError(f"angle_noise_deg must be a finite number >= 0; got {angle_noise_deg!r}")
    model = model_for(frozenset(effects))
    params = true_parameters(design, params_override)
    if commands is None:
        cmd = default_commands(n, both_ways=ordered)
    else:
        cmd = np.asarray(commands, float).reshape(-1, 2)
    if len(cmd) == 0:
        raise ValueError("commands must hold at least one (theta1, theta2) pair")
    if not ordered and "hysteresis" in model.effects:
        raise ValueError("hysteresis needs a path: synthesize it with ordered=True")
    if not ordered:
        _, first, count = np.unique(cmd, axis=0, return_index=True, return_counts=True)
        if (count > 1).any():
            t1, t2 = np.rad2deg(cmd[first[np.argmax(count > 1)]])
            raise ValueError(
                f"commands repeat the configuration ({t1:g}, {t2:g}) deg; without the order "
                "(ordered=False) expected each configuration once"
            )
    solve = solve_sequence if ordered else solve_equilibria
    eq = solve(model, params, cmd[:, 0], cmd[:, 1])
    keep = eq.converged & eq.stable
    rng = np.random.default_rng(seed)
    noise = rng.normal(0.0, noise_mm * 1e-3, size=(len(cmd), 3))
    angle_noise = rng.normal(0.0, np.deg2rad(angle_noise_deg), size=(len(cmd), 2))
    exact = np.where(keep[:, None], eq.position, np.nan)
    if view == "top":
        exact[:, 2] = np.nan
    position = exact + noise
    angles = eq.tip_angles + angle_noise if tip_angles else None
    sigma = np.full(len(cmd), noise_mm * 1e-3) if record_sigma and noise_mm > 0 else None
    rows = np.arange(len(cmd)) if ordered else np.flatnonzero(keep)
    source = f"synthetic ({model.name} model, {view} view, noise {noise_mm:g} mm, seed {seed})"

    def measurements(position: np.ndarray, angles: np.ndarray | None) -> Measurements:
        return make_measurements(
            cmd[rows],
            position[rows],
            tip_angles=None if angles is None else angles[rows],
            sequence=rows if ordered else None,
            sigma=None if sigma is None else sigma[rows],
            source=source,
        )

    return Synthetic(
        measurements=measurements(position, angles),
        params=params,
        model=model,
        equilibria=eq,
        dropped=int(np.count_nonzero(~keep)),
        snapped=int(np.count_nonzero(eq.snapped & keep)),
        noise_free=measurements(exact, eq.tip_angles if tip_angles else None),
    )


def synthesize(design: Design, effects: Iterable[str] = (), **options: Any) -> Measurements:
    """The measurements of :func:`synthesize_data` (same arguments)."""
    return synthesize_data(design, effects, **options).measurements
