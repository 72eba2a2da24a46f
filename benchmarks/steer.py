"""Steering: ringpair's batch inverse against per-target scipy least squares, in one run.

Targets are the tips of random ring-angle pairs of the paper's demonstrator (baseline
model), so every one is reachable. Solved two ways:

- ringpair (:func:`design.steering.steer`): all targets in one batch, Newton on the state
  and the angles together from the 5-deg grid's interpolated map (the grid solved inside
  the timing); every distinct solution of each target, each solved again on its own by
  the load ramp (the check that it lands), with its flags (multistable: a search for
  other stable states) and fold margin;
- the named baseline: ``scipy.optimize.least_squares`` per target on the same forward map
  (the state by :func:`design.equilibrium.solve_equilibria`, one configuration per call,
  finite-difference Jacobian), started from the closest tip on the same 5-deg grid of ring
  angles ringpair seeds from (the grid is solved once, outside the timing); it finds one
  solution per target.

It prints the time per target of each, wall clock and CPU (the process's, all threads:
on a shared machine the wall clock is noisy), their ratio (goal >= 50x), how many targets
ringpair reaches (to 1e-6 mm), and whether the answers agree: every solution least
squares converges to (to 1e-6 mm) is among ringpair's solutions for that target (angles
within SAME_SOLUTION); every target where they differ, or where either does not reach
it, is listed. Least squares solves every target (about 40 s for 10,000); ``--n-scipy``
takes a random subsample of them for a quicker run.

    python benchmarks/steer.py [--n 10000] [--n-scipy N] [--seed 0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import least_squares

from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import model_for
from design.steering import REACHED, SEED_STEP, steer
from design.steering.grid import _solved_grid
from design.workspace import angle_grid

SAME_SOLUTION = 1e-3
"""Two solutions of one target are the same when their angles agree to this [rad]: both
put the tip within REACHED (1e-9 m) of the target, which pins the angles to about 1e-7
rad where the map is regular but only to about sqrt(1e-9 m / 20 mm) = 2e-4 rad at the
workspace's rim, where it folds (the rings parallel)."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10_000, help="targets for ringpair")
    ap.add_argument(
        "--n-scipy", type=int, default=None, help="of them, for least squares (default: all)"
    )
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    model = model_for(frozenset())
    params = model.parameters(default_design())
    made = rng.uniform(0, 2 * np.pi, (2, args.n))
    eq = solve_equilibria(model, params, made[0], made[1])
    targets = eq.position[eq.stable, 1:]
    steer(model, params, targets[:10])  # compile once per machine: not throughput
    _solved_grid.cache_clear()  # the timed run solves its seed grid itself

    t0, c0 = time.perf_counter(), time.process_time()
    result = steer(model, params, targets)
    t_ringpair = (time.perf_counter() - t0) / len(targets)
    c_ringpair = (time.process_time() - c0) / len(targets)
    reached = np.zeros(len(targets), bool)
    reached[result.target_index[result.reached]] = True

    angles = angle_grid(SEED_STEP)
    g1, g2 = (g.ravel() for g in np.meshgrid(angles, angles, indexing="ij"))
    grid = solve_equilibria(model, params, g1, g2)
    grid_tip = np.where(grid.stable[:, None], grid.position[:, 1:], np.nan)

    def tip(theta: np.ndarray) -> np.ndarray:
        e = solve_equilibria(model, params, theta[:1], theta[1:])
        return e.position[0, 1:] if e.stable[0] else np.full(2, 1.0)

    n_scipy = len(targets) if args.n_scipy is None else min(args.n_scipy, len(targets))
    sample = rng.choice(len(targets), n_scipy, replace=False)
    t0, c0 = time.perf_counter(), time.process_time()
    answers = []
    for k in sample:
        start = int(np.nanargmin(np.linalg.norm(grid_tip - targets[k], axis=1)))
        fit = least_squares(
            lambda th, k=k: tip(th) - targets[k],
            [g1[start], g2[start]],
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        answers.append(fit.x)
    t_scipy = (time.perf_counter() - t0) / len(sample)
    c_scipy = (time.process_time() - c0) / len(sample)
    agree = converged = 0
    differ = []
    for k, x in zip(sample, answers, strict=True):
        mine = result.theta[(result.target_index == k) & result.reached]
        wrapped = np.abs(np.angle(np.exp(1j * (mine - x)))).max(axis=1)
        found = bool(len(mine) and wrapped.min() < SAME_SOLUTION)
        ok = np.linalg.norm(tip(x) - targets[k]) <= REACHED
        converged += ok
        agree += ok and found
        if not (ok and found):
            differ.append(
                f"    target {k} ({targets[k, 0] * 1e3:.6f}, {targets[k, 1] * 1e3:.6f}) mm: "
                f"least squares {np.rad2deg(x % (2 * np.pi)).round(4)} deg "
                f"({'converged' if ok else 'not converged'}), ringpair "
                f"{np.rad2deg(mine).round(4).tolist()} deg"
            )
    for k in np.flatnonzero(~reached):
        differ.append(f"    target {k}: ringpair does not reach it (made from a tip)")

    print(f"demonstrator, baseline model, {len(targets):,} reachable targets")
    print(
        f"  ringpair batch inverse : {t_ringpair * 1e3:8.3f} ms per target "
        f"(CPU {c_ringpair * 1e3:.3f} ms); reached {reached.mean():.2%}; "
        f"{len(result) / len(targets):.2f} solutions per target"
    )
    print(
        f"  scipy least_squares    : {t_scipy * 1e3:8.3f} ms per target "
        f"(CPU {c_scipy * 1e3:.3f} ms; {len(sample)} targets); converged {converged}/{len(sample)}"
    )
    print(f"  same answers: {agree}/{converged} least-squares solutions are among ringpair's")
    print(f"  answers that differ: {len(differ)}")
    print("\n".join(differ))
    print(
        f"  speed ratio (goal >= 50x): {t_scipy / t_ringpair:.0f}x wall clock, "
        f"{c_scipy / c_ringpair:.0f}x CPU"
    )


if __name__ == "__main__":
    main()
