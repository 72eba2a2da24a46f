"""Large-deflection rod: ringpair's compiled shooting solve (design.rod) against PyElastica's
dynamic relaxation of a Cosserat rod, on the same rod and loads, in one run.

The rod is the demonstrator's (L = 150 mm, EI = 3.92e-4 N m^2), modelled in PyElastica as a
solid round rod of the catheter's outer radius (0.9 mm) with E = EI / I. Two load cases:
Bisshopp-Drucker's perpendicular dead tip load F L^2 / EI = 5 (71 % deflection), and a
3-D case (tip force, tip moment with an axial part, a distributed load across both).
PyElastica integrates the damped dynamics (position Verlet, analytical linear damping at
twice the first bending frequency, loads ramped over one time constant) until the tip has
moved less than 0.1 um per half time constant three times running.

Setting up the peer fairly (both are documented PyElastica practice for statics):
- PyElastica's clamp (OneEndFixedBC) holds its whole first element, whose bending hinge is
  half an element further out; a rod started at s = 0 is therefore too flexible by half an
  element, a first-order error (1.5 % of the deflection with 50 elements, 1.6 mm here).
  The PyElastica rod starts half an element inside the wall, s = -h/2, so that its clamped
  face is at s = 0; the error is then second order (5 um at 50 elements).
- Dynamic relaxation only needs the static state, so the elements' rotational inertia is
  scaled up 10x (mass scaling): it removes the stiff shear-rotation mode of a slender rod
  that otherwise limits the time step below the axial-wave limit.
Its remaining differences from the Kirchhoff rod are physical and small: axial stretch and
shear (a few um here) and twist, which does not move the centreline of an isotropic rod.

ringpair's time is a whole numeric solve of its rod (design.rod's compiled boundary residual
and Jacobian, driven to zero by tests/support/rods.py: scipy's MINPACK root finder from the
straight rod, the load ramped in four steps) after a one-time compilation, which is
reported separately.

    python benchmarks/rod.py [--elements 50]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import elastica as ea
import numpy as np
from elastica.version import VERSION as ELASTICA_VERSION
from scipy.interpolate import CubicSpline

from design import rod

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "support"))
from rods import dead_load, rod_functions, solve_tip_load  # noqa: E402

LENGTH = 0.15  # [m]
BENDING_RIGIDITY = 3.92e-4  # [N m^2]
RADIUS = 0.9e-3  # [m]
DENSITY = 1000.0  # [kg/m^3], fictitious: only the static state is compared
INERTIA_SCALE = 10.0
CFL = 0.5
SETTLED = 1e-7  # [m] tip motion per half time constant, three times running


@dataclass(frozen=True)
class Case:
    name: str
    force: np.ndarray  # tip force, base frame [N]
    moment: np.ndarray  # tip moment, base frame [N m]
    distributed_load: np.ndarray  # [N/m]


def cases() -> list[Case]:
    ei, length = BENDING_RIGIDITY, LENGTH
    return [
        Case(
            "Bisshopp-Drucker F L^2/EI = 5",
            ei / length**2 * np.array([0.0, 5.0, 0.0]),
            np.zeros(3),
            np.zeros(3),
        ),
        Case(
            "3-D: tip force, tip moment, distributed load",
            ei / length**2 * np.array([-0.5, 1.5, 0.5]),
            ei / length * np.array([0.3, -1.0, 0.5]),
            ei / length**3 * np.array([0.0, 0.0, -2.0]),
        ),
    ]


class _TipWrench(ea.NoForces):
    """Dead force on the last node and dead moment (base frame) on the last element, both
    ramped linearly over ``ramp_time``. PyElastica's torques are in the element frame."""

    def __init__(self, force: np.ndarray, moment: np.ndarray, ramp_time: float) -> None:
        super().__init__()
        self.force, self.moment, self.ramp_time = force, moment, ramp_time

    def apply_forces(self, system, time: float = 0.0) -> None:  # type: ignore[no-untyped-def]
        system.external_forces[:, -1] += min(1.0, time / self.ramp_time) * self.force

    def apply_torques(self, system, time: float = 0.0) -> None:  # type: ignore[no-untyped-def]
        local = system.director_collection[:, :, -1] @ self.moment
        system.external_torques[:, -1] += min(1.0, time / self.ramp_time) * local


class _Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
    pass


def elastica_relax(case: Case, elements: int, max_steps: int = 5_000_000):
    """Relax the PyElastica rod under ``case``. Returns (positions (n + 1, 3), rest arc
    length of the nodes (n + 1,), steps, converged)."""
    area = np.pi * RADIUS**2
    second_moment = np.pi * RADIUS**4 / 4
    youngs = BENDING_RIGIDITY / second_moment
    h = LENGTH / (elements - 0.5)  # the first element's middle is the clamped face, s = 0
    body = ea.CosseratRod.straight_rod(
        elements,
        np.array([-h / 2, 0.0, 0.0]),
        np.array([1.0, 0.0, 0.0]),
        np.array([0.0, 1.0, 0.0]),
        LENGTH + h / 2,
        RADIUS,
        DENSITY,
        youngs_modulus=youngs,
    )
    body.mass_second_moment_of_inertia *= INERTIA_SCALE
    body.inv_mass_second_moment_of_inertia /= INERTIA_SCALE
    omega1 = 1.8751**2 * np.sqrt(BENDING_RIGIDITY / (DENSITY * area * LENGTH**4))
    dt = CFL * h / np.sqrt(youngs / DENSITY)
    sim = _Simulator()
    sim.append(body)
    sim.constrain(body).using(
        ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,)
    )
    sim.add_forcing_to(body).using(_TipWrench, case.force, case.moment, 1 / omega1)
    if np.any(case.distributed_load):
        gravity = case.distributed_load / (DENSITY * area)
        sim.add_forcing_to(body).using(ea.GravityForces, acc_gravity=gravity)
    sim.dampen(body).using(
        ea.AnalyticalLinearDamper, uniform_damping_constant=2 * omega1, time_step=dt
    )
    sim.finalize()
    stepper = ea.PositionVerlet()
    chunk = int(0.5 / omega1 / dt) + 1
    t, steps, quiet = np.float64(0.0), 0, 0
    last = body.position_collection[:, -1].copy()
    while steps < max_steps and quiet < 3:
        for _ in range(chunk):
            t = stepper.step(sim, t, dt)
        steps += chunk
        tip = body.position_collection[:, -1].copy()
        quiet = quiet + 1 if np.abs(tip - last).max() < SETTLED else 0
        last = tip
    arc = -h / 2 + h * np.arange(elements + 1)
    return body.position_collection.T.copy(), arc, steps, quiet >= 3


def _warm_up_numba() -> None:
    """Trigger PyElastica's just-in-time compilation outside the timed runs."""
    small = Case(
        "warm-up",
        np.array([0.0, 1e-3, 0.0]),
        np.array([0.0, 0.0, 1e-5]),
        np.array([0.0, 0.0, -1e-3]),
    )
    elastica_relax(small, 8, max_steps=10)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--elements", type=int, default=50, help="PyElastica elements")
    ap.add_argument("--repeats", type=int, default=200, help="ringpair solves to average")
    args = ap.parse_args()

    t0 = time.perf_counter()
    rod_functions(dead_load, 6, rod.STEPS, compile=True)
    t_build = time.perf_counter() - t0
    _warm_up_numba()
    print(
        f"rod: L = {LENGTH * 1e3:.0f} mm, EI = {BENDING_RIGIDITY:.3g} N m^2; ringpair "
        f"RK4 {rod.STEPS} steps (built and compiled in {t_build:.1f} s, cached on disk);\n"
        f"PyElastica {ELASTICA_VERSION}, {args.elements} elements, r = {RADIUS * 1e3:.1f} mm"
    )
    ratios = []
    for case in cases():
        loads = (case.force, case.moment, case.distributed_load)
        sol = solve_tip_load(LENGTH, BENDING_RIGIDITY, *loads, compile=True)
        t0 = time.perf_counter()
        for _ in range(args.repeats):
            solve_tip_load(LENGTH, BENDING_RIGIDITY, *loads, compile=True)
        t_ours = (time.perf_counter() - t0) / args.repeats

        t0 = time.perf_counter()
        nodes, arc, steps, settled = elastica_relax(case, args.elements)
        t_peer = time.perf_counter() - t0

        spline = CubicSpline(arc, nodes, axis=0)
        s = np.linspace(0.0, LENGTH, rod.STEPS + 1)
        tip_gap = np.linalg.norm(nodes[-1] - sol.position)
        shape_gap = np.linalg.norm(spline(s) - sol.centreline, axis=1).max()
        deflection = np.linalg.norm(sol.position[1:])  # across the base axis
        ratios.append(t_peer / t_ours)
        print(f"\n{case.name}")
        print(
            f"  ringpair tip (mm)  : {np.array2string(sol.position * 1e3, precision=4)}"
            f"  deflection {deflection / LENGTH:.0%} of L, converged {sol.converged}, "
            f"residual {sol.residual:.1e}"
        )
        print(
            f"  PyElastica tip (mm): {np.array2string(nodes[-1] * 1e3, precision=4)}"
            f"  settled {settled} after {steps:,} steps"
        )
        print(
            f"  agreement          : tip {tip_gap * 1e3:.4f} mm, centreline max "
            f"{shape_gap * 1e3:.4f} mm"
        )
        print(
            f"  time               : ringpair {t_ours * 1e3:.3f} ms, PyElastica "
            f"{t_peer:.2f} s, ratio {t_peer / t_ours:,.0f} x"
        )
    print(f"\nslowest ratio: {min(ratios):,.0f} x (goal: 100 x); agreement goal 0.1 mm")


if __name__ == "__main__":
    main()
