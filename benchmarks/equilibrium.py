"""Equilibrium: the state by the load ramp against Newton from the straight robot, in one run.

For the baseline model and the model for design work, on the paper's demonstrator and on a
near-magnet set-up (the demonstrator's tubes, rings 3.5 / 1.0 x 0.8 mm with a 0.3 mm gap,
free length 140 mm, an N52 cylinder 25 x 80 mm whose face is 18 mm beyond the rest tip),
the same random ring angles are solved two ways:

- ringpair's state (:func:`design.equilibrium.solve_equilibria`): the stable equilibrium
  connected to the unloaded robot by the load ramp, with snaps and contact;
- the named baseline, Newton from the straight robot at full load (what ringpair did
  before the ramp): the same compiled Newton iteration, batched, until the residual is
  below the same tolerance.

It prints each one's throughput (configurations per second, two threads), how many of
ringpair's states fail an independent re-check of stability (goal 0), and how often
Newton from straight is wrong: no convergence, an unstable equilibrium, or a stable state
more than 0.01 mm away from the ramp's (another branch).

    python benchmarks/equilibrium.py [--n 100000] [--n-design 8000] [--seed 0]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from design.designfile import default_design, load_design
from design.equilibrium import TOLERANCE, kernels, solve_equilibria, stable_states
from design.model import DEFAULT_EFFECTS, model_for
from design.records import Design

SAME = 1e-5
"""Two states are the same when their tips are this close. [m]"""


def near_magnet() -> Design:
    """The near-magnet set-up of the README (examples/near_magnet.toml)."""
    return load_design(Path(__file__).resolve().parents[1] / "examples" / "near_magnet.toml")


def newton_from_straight(model, params, command, iterations=40):
    """Plain batch Newton from the straight robot at full load: (unknowns, converged)."""
    kern = kernels(model)
    n = command.shape[1]
    x = np.zeros((model.n_unknowns, n))
    if model.n_unknowns > model.n_rod:
        x[model.n_rod :] = command
    running = np.ones(n, bool)
    converged = np.zeros(n, bool)
    ones = np.ones((1, n))
    for _ in range(iterations):
        a = np.flatnonzero(running)
        if a.size == 0:
            break
        r, step, *_ = kern.run("newton", [x[:, a], command[:, a], ones[:, a]], params)
        done = np.max(np.abs(r), axis=0) < TOLERANCE
        converged[a[done]] = True
        lost = ~np.isfinite(step).all(axis=0)
        x[:, a[~done & ~lost]] -= step[:, ~done & ~lost]
        x[:, a[lost]] = np.nan
        running[a[done | lost]] = False
    return x, converged


def run(name: str, design: Design, effects: frozenset[str], n: int, rng) -> None:
    model = model_for(effects)
    params = model.parameters(design)
    command = rng.uniform(0.0, 2 * np.pi, (2, n))
    # Warm-up at the same batch size: compiling (once per machine) and building CasADi's
    # maps for each batch size (about 0.3 s each, once per process) are not throughput.
    solve_equilibria(model, params, command[0], command[1])
    t0 = time.perf_counter()
    eq = solve_equilibria(model, params, command[0], command[1])
    t_ramp = time.perf_counter() - t0
    recheck = stable_states(model, params, np.nan_to_num(eq.unknowns.T), command)
    returned_unstable = int(np.count_nonzero(eq.stable & ~recheck))

    newton_from_straight(model, params, command)
    t0 = time.perf_counter()
    x, converged = newton_from_straight(model, params, command)
    t_newton = time.perf_counter() - t0
    stable = converged & stable_states(model, params, np.nan_to_num(x), command)
    position = np.full((n, 3), np.nan)
    if stable.any():
        position[stable] = np.asarray(
            model.pose.map(int(stable.sum()))(x[:, stable], command[:, stable], params)[0]
        ).T
    other = stable & eq.stable & ~(np.abs(position - eq.position).max(axis=1) <= SAME)
    wrong = ~converged | (converged & ~stable) | other
    contact = np.array(["contact" in f for f in eq.failure])
    print(f"\n{name}, {model.name} model, {n:,} random ring-angle pairs")
    print(
        f"  ringpair load ramp    : {n / t_ramp:10,.0f} configurations/s; states "
        f"{eq.stable.mean():6.1%}, snapped {eq.snapped.mean():5.1%}, no state "
        f"{(~eq.stable).mean():5.1%} (contact {contact.mean():.1%}); "
        f"unstable states returned: {returned_unstable}"
    )
    print(
        f"  Newton from straight  : {n / t_newton:10,.0f} configurations/s; wrong "
        f"{wrong.mean():6.1%} (not converged {(~converged).mean():.1%}, unstable "
        f"{(converged & ~stable).mean():.1%}, another branch {other.mean():.1%})"
    )
    print(f"  speed ratio ramp / Newton from straight: {t_newton / t_ramp:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000, help="configurations, baseline model")
    ap.add_argument("--n-design", type=int, default=8_000, help="configurations, design work")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    print("goals: baseline >= 300,000 configurations/s, design work >= 10,000/s, 0 unstable")
    for name, design in (("demonstrator", default_design()), ("near magnet", near_magnet())):
        run(name, design, frozenset(), args.n, rng)
        run(name, design, DEFAULT_EFFECTS, args.n_design, rng)


if __name__ == "__main__":
    main()
