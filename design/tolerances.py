"""Manufacturing tolerances: how far the disc of a design spreads over perturbed copies
of it (a Monte Carlo over :data:`TOLERANCES`). SI units."""

from __future__ import annotations

from typing import Any

import numpy as np

from design.equilibrium import solve_equilibria
from design.geometry import curve_disc_radius
from design.home import HOME_COMMAND
from design.model import RingPairModel
from design.records import Design
from design.registry import PARAMETERS, index
from design.workspace import angle_grid

TOLERANCES = {n: p.tolerance for n, p in PARAMETERS.items() if p.tolerance is not None}
"""Manufacturing and placement tolerances of the Monte Carlo (one sigma), parameter ->
('rel', fraction) or ('abs', SI value), from :mod:`design.registry`: grade spread of NdFeB
remanence (2 %), ground-magnet dimensions (+-0.02 mm), extruded-tube modulus (10 %), NiTi
wire (5 %), and +-1 mm placement of the external magnet."""

TOLERANCE_LOOP = 120
"""Parallel-ring loop samples per Monte Carlo sample: the polygon's inscribed disc is then
within r (1 - cos(pi / 120)) ~ 0.01 mm of the loop's for a 27 mm disc."""


def tolerance_spread(
    design: Design, samples: int, seed: int, model: RingPairModel
) -> dict[str, Any]:
    """The disc about home (the workspace's, :func:`design.geometry.curve_disc_radius` on
    TOLERANCE_LOOP samples) of ``samples`` perturbed copies of ``design`` [m] (TOLERANCES,
    seeded); NaN for a copy without a home state."""
    rng = np.random.default_rng(seed)
    base = model.parameters(design)
    params = np.repeat(base[:, None], samples, axis=1)
    for name, (kind, sigma) in TOLERANCES.items():
        noise = rng.normal(0.0, sigma, samples)
        i = index(name)
        params[i] = params[i] * (1 + noise) if kind == "rel" else params[i] + noise
    loop = angle_grid(2 * np.pi / TOLERANCE_LOOP)
    theta = np.tile(loop, samples)
    eq = solve_equilibria(model, np.repeat(params, len(loop), axis=1), theta, theta)
    home = solve_equilibria(
        model, params, np.full(samples, HOME_COMMAND[0]), np.full(samples, HOME_COMMAND[1])
    )
    radii = []
    for k in range(samples):
        rows = slice(k * len(loop), (k + 1) * len(loop))
        ok = eq.stable[rows]
        about = (eq.position[rows][ok] - home.position[k])[:, 1:]
        radii.append(curve_disc_radius(about) if home.stable[k] else float("nan"))
    return {"disc_radius": np.array(radii), "samples": samples, "seed": seed}
