"""Force map: ringpair's batch contact solve against a per-configuration scipy solve, in one run.

The demonstrator (baseline model) over a grid of both ring angles, a wall across its reach
(a plane at y = WALL_MM, normal -y). Solved two ways:

- ringpair (:func:`design.contact.solve_in_contact`): every configuration in one batch,
  the free state by the load ramp, then Newton on the contact force, each iterate the
  model's equilibrium solved in compiled, mapped calls (inside the timing);
- the named baseline: ``scipy.optimize.root`` (MINPACK's hybrid method, finite-difference
  Jacobian) per pressed configuration on the same equations, unknowns (state x, normal
  force lambda): the model's residual r(x) with the contact force lambda nu applied at
  the contact point, and the gap g(x) = 0 (the model's residual and pose called one
  configuration at a time); started from the free state ringpair found (given to it,
  outside its timing: the baseline is charged only for the contact solve).

It prints the time per pressed configuration of each (wall clock and process CPU), the
ratio (goal >= 100x), the ratio for ringpair's contact step alone (its run less its free
solve, timed separately: the baseline's own share of the work), and the largest
differences of the tip (mm) and of the contact force (mN) between the two (tolerances
0.01 mm, 0.01 mN).

    python benchmarks/force.py [--step 15] [--wall 10]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import root

from design.contact import FORCE, MOMENT, solve_in_contact
from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import model_for
from design.obstacles import gaps, tip_body
from design.records import Obstacle
from design.units import MM


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def _baseline(model, params, command, x0, wall, body):
    """scipy root on (r(x, lambda), g(x)) for one configuration: (tip, force on the wall)."""
    n = model.n_unknowns
    scale = model.unknown_scale(params)

    def wrench(x):
        pose = model.pose(x, command, params)
        position, tangent = np.asarray(pose[0]).ravel(), np.asarray(pose[1])[:, 0]
        g, q, nu = gaps(wall, position[None], tangent[None], body)
        return position, g[0], q[0], nu[0]

    def equations(z):
        x, lam = z[:n] * scale, z[n] * 1e-3
        position, g, q, nu = wrench(x)
        p = params.copy()
        p[FORCE : FORCE + 3] += lam * nu
        p[MOMENT : MOMENT + 3] += np.cross(q - position, lam * nu)
        r = np.asarray(model.residual(x, command, p)[0]).ravel()
        return np.concatenate([r / scale, [g / MM]])

    sol = root(
        equations, np.concatenate([x0 / scale, [0.0]]), method="hybr", options={"xtol": 1e-12}
    )
    x, lam = sol.x[:n] * scale, sol.x[n] * 1e-3
    position, _, _, nu = wrench(x)
    return position, -lam * nu, bool(sol.success)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--step", type=float, default=15.0, help="grid step [deg]")
    parser.add_argument("--wall", type=float, default=10.0, help="wall at y = this [mm]")
    args = parser.parse_args()
    design = default_design()
    model = model_for(frozenset())
    params = model.parameters(design)
    body = tip_body(design, printed=False)
    wall = Obstacle("plane", (0.15, args.wall * MM, 0.0), (0.0, -1.0, 0.0))
    grid = np.deg2rad(np.arange(0.0, 360.0, args.step))
    t1, t2 = (a.ravel() for a in np.meshgrid(grid, grid, indexing="ij"))
    solve_in_contact(model, params, t1[:2], t2[:2], [wall], body)  # compiled, warm
    start = _clock()
    eq, contact = solve_in_contact(model, params, t1, t2, [wall], body)
    wall_rp, cpu_rp = (b - a for a, b in zip(start, _clock(), strict=True))
    start = _clock()
    solve_equilibria(model, params, t1, t2)  # ringpair's free states alone
    wall_free, cpu_free = (b - a for a, b in zip(start, _clock(), strict=True))
    pressed = np.flatnonzero(contact.in_contact)
    free = solve_equilibria(model, params, t1[pressed], t2[pressed])  # the baseline's starts
    start = _clock()
    tips, forces, ok = [], [], []
    for k, i in enumerate(pressed):
        tip, force, good = _baseline(
            model, params, np.array([t1[i], t2[i]]), free.unknowns[k], wall, body
        )
        tips.append(tip)
        forces.append(force)
        ok.append(good)
    wall_sp, cpu_sp = (b - a for a, b in zip(start, _clock(), strict=True))
    m = max(len(pressed), 1)
    d_tip = np.abs(np.array(tips) - eq.position[pressed]).max() / MM if len(pressed) else 0.0
    d_force = np.abs(np.array(forces) - contact.force[pressed]).max() * 1e3 if len(pressed) else 0.0
    print(f"{len(t1)} configurations, {len(pressed)} pressed on the wall at y = {args.wall:g} mm")
    print(
        f"ringpair (all, in batch): {wall_rp / m * 1e3:.3f} ms wall, {cpu_rp / m * 1e3:.3f} ms "
        "CPU per pressed configuration"
    )
    print(
        f"scipy root per configuration (contact solve only): {wall_sp / m * 1e3:.3f} ms wall, "
        f"{cpu_sp / m * 1e3:.3f} ms CPU; converged {sum(ok)}/{len(ok)}"
    )
    print(f"ratio: {wall_sp / wall_rp:.1f}x wall, {cpu_sp / cpu_rp:.1f}x CPU (goal >= 100x)")
    # like for like: the baseline starts from the free states, so charge ringpair only for
    # what follows them (its whole run less its free solve of every configuration)
    wall_c, cpu_c = max(wall_rp - wall_free, 1e-12), max(cpu_rp - cpu_free, 1e-12)
    print(
        f"ringpair's contact step alone (whole run less its free solve, "
        f"{wall_free / m * 1e3:.3f} ms per pressed configuration): {wall_c / m * 1e3:.3f} ms "
        f"wall; ratio {wall_sp / wall_c:.1f}x wall, {cpu_sp / cpu_c:.1f}x CPU"
    )
    print(
        f"largest differences: tip {d_tip:.2e} mm (tolerance 0.01), force {d_force:.2e} mN "
        "(tolerance 0.01)"
    )
    if len(pressed):
        f = np.linalg.norm(contact.force[pressed], axis=1) * 1e3
        print(f"force on the wall: {f.min():.3f} to {f.max():.3f} mN")


if __name__ == "__main__":
    main()
