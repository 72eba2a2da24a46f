"""Equilibrium throughput: ringpair's compiled batch Newton against a per-configuration
``scipy.optimize.fsolve`` loop on the same equations, in one run.

Both solve r(q) = q - C Q(q) = 0 of the baseline model for the demonstrator, starting from
the straight robot. The baseline loop calls the model's own residual and Jacobian (the
same CasADi expressions, compiled the same way) once per configuration, as a user
would with a general-purpose root finder; it runs on a subsample and is scaled.

    python benchmarks/equilibrium.py [--n 100000] [--loop 2000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import fsolve

from design.compiled import compile_function
from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import RingPairModel


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000, help="configurations for ringpair")
    ap.add_argument("--loop", type=int, default=2_000, help="configurations for the fsolve loop")
    args = ap.parse_args()

    design = default_design()
    model = RingPairModel()
    params = model.parameters(design)
    rng = np.random.default_rng(0)
    theta = rng.uniform(0, 2 * np.pi, (args.n, 2))

    solve_equilibria(model, params, theta[:10, 0], theta[:10, 1])  # compile / load once
    t0 = time.perf_counter()
    solve_equilibria(model, params, theta[:, 0], theta[:, 1])
    t_first = time.perf_counter() - t0
    # The first call at a new batch size also builds CasADi maps of that size (~0.3 s
    # each, once per process); the throughput is that of the calls after it.
    t0 = time.perf_counter()
    eq = solve_equilibria(model, params, theta[:, 0], theta[:, 1])
    t_batch = time.perf_counter() - t0
    print(f"first call at this batch size (builds the maps): {t_first:.3f} s")

    residual = compile_function(model.residual)
    sub = theta[: args.loop]
    q_loop = np.empty((len(sub), 4))
    t0 = time.perf_counter()
    for k, th in enumerate(sub):

        def fun(q, th=th):
            return np.asarray(residual(q, th, params)[0]).ravel()

        def jac(q, th=th):
            return np.asarray(residual(q, th, params)[1])

        q_loop[k] = fsolve(fun, np.zeros(4), fprime=jac, xtol=1e-12)
    t_loop = time.perf_counter() - t0

    agree = np.abs(q_loop - eq.unknowns[: args.loop]).max()
    rate_batch = args.n / t_batch
    rate_loop = len(sub) / t_loop
    print(f"configurations: {args.n} (demonstrator, random ring angles)")
    print(
        f"ringpair batch Newton : {rate_batch:12,.0f} configurations/s "
        f"({t_batch:.3f} s; converged {eq.converged.mean():.1%}, stable {eq.stable.mean():.1%})"
    )
    print(
        f"fsolve loop (baseline): {rate_loop:12,.0f} configurations/s "
        f"({t_loop:.3f} s for {len(sub)}, scaled: {args.n / rate_loop:.1f} s)"
    )
    print(f"ratio                 : {rate_batch / rate_loop:12,.0f} x")
    print(f"largest difference in q between the two: {agree:.2e} (m or rad)")


if __name__ == "__main__":
    main()
