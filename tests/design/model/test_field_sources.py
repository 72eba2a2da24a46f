"""The model with field sources (design.model.field): a uniform field against the linear
cantilever's closed form, drawn source sets against the independent solve written on
magpylib (tests/support/oracle.py), and the classic external magnet unchanged."""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np
import pytest
from oracle import chain_state, linear_state
from scipy.optimize import brentq
from setups import random_design

from design.designfile import default_design
from design.equilibrium import solve_equilibria
from design.model import CLASSIC, model_for
from design.records import Design, Source

SEED = int(os.environ.get("RINGPAIR_SEED", np.random.SeedSequence().entropy % 2**32))
MU0 = 4e-7 * np.pi * 1.00000000055
AGREEMENT = 1e-5
"""A state and the independent solve's agree to this (0.01 mm). [m]"""


def solve(design: Design, effects, commands: np.ndarray):
    model = model_for(frozenset(effects)).for_design(design)
    return solve_equilibria(model, model.parameters(design), commands[:, 0], commands[:, 1])


def in_field(design: Design, *sources: Source, external: bool = False) -> Design:
    return replace(
        design, sources=sources, external_magnet=design.external_magnet if external else None
    )


def ring_moment(design: Design) -> float:
    t = design.tip
    volume = np.pi / 4 * (t.magnet_outer_diameter**2 - t.magnet_inner_diameter**2)
    return t.remanence / MU0 * volume * t.magnet_length


def bending_rigidity(design: Design) -> float:
    def ei(tube):
        return tube.youngs_modulus * np.pi / 64 * (tube.outer_diameter**4 - tube.inner_diameter**4)

    return ei(design.robot.catheter) + ei(design.robot.wire)


# A uniform field B along the straight robot and no gradient: the rings' moment M (the sum
# of the two, across the tip) feels the torque M x B only, which bends the tip by phi in
# the plane of M and the robot until M B cos(phi) L / EI = phi (the linear cantilever:
# tip rotation T L / EI, deflection T L^2 / (2 EI); Gere & Timoshenko). The rings turn
# towards the field; antiparallel rings feel none.
@pytest.mark.parametrize("field_t", [1e-3, 0.02, 3.0])
def test_uniform_field_along_the_robot_bends_the_linear_cantilever_as_in_closed_form(field_t):
    print(f"seed {SEED}")
    rng = np.random.default_rng([SEED, int(field_t * 1e3)])
    design = in_field(default_design(), Source("uniform", b=(field_t, 0.0, 0.0)))
    commands = rng.uniform(-np.pi, np.pi, (6, 2))
    commands[0] = [0.3, 0.3 + np.pi]  # antiparallel: no torque
    eq = solve(design, (), commands)
    length, ei, m = design.robot.free_length, bending_rigidity(design), ring_moment(design)
    for k, (t1, t2) in enumerate(commands):
        total = m * np.array([0, np.cos(t1) + np.cos(t2), np.sin(t1) + np.sin(t2)])
        size = np.linalg.norm(total)
        k_ = size * field_t * length / ei
        phi = 0.0 if size < 1e-12 * m else brentq(lambda p, k_=k_: p - k_ * np.cos(p), 0, np.pi / 2)
        # the tip turns about u = e x x (e the unit moment) and moves along -e
        e = total / size if size > 0 else np.zeros(3)
        expected = np.array([length, 0, 0]) - length / 2 * phi * e
        assert eq.stable[k]
        # (the solver converges to ~1e-10 of the length)
        np.testing.assert_allclose(eq.position[k], expected, rtol=0, atol=1e-9 * length)


LAYOUT = ("uniform", "cuboid", "sphere", "coil")
"""The drawn source sets' kinds: one of each (each model compiles once per layout), each
source present or, in a third of the draws, of no strength."""


def draw_sources(design: Design, rng) -> tuple[Source, ...]:
    """One source of each kind of :data:`LAYOUT` around the tip of the straight robot,
    each giving about 2-30 mT there or nothing (the external magnet is the cylinder):
    block and spherical magnets 50-150 mm from the tip, a coil of 30-100 mm radius
    40-150 mm away, a uniform field."""
    tip = np.array([design.robot.free_length, 0.0, 0.0])

    def unit():
        v = rng.normal(size=3)
        return tuple(v / np.linalg.norm(v))

    def place(distance):
        d = np.array(unit())
        d[0] = abs(d[0])  # ahead of the base
        return tuple(tip + distance * d / np.linalg.norm(d))

    out = []
    for kind in LAYOUT:
        on = float(rng.random() > 1 / 3)
        if kind == "uniform":
            out.append(Source("uniform", b=tuple(on * rng.normal(size=3) * 0.01)))
        elif kind == "coil":
            r = rng.uniform(0.03, 0.1)
            b = on * rng.uniform(2e-3, 2e-2)  # at the centre, mu0 N I / (2 r)
            out.append(Source("coil", radius=r, turns=100.0, current=2 * r * b / (MU0 * 100),
                              center=place(rng.uniform(0.04, 0.15)), axis=unit()))  # fmt: skip
        else:
            size = rng.uniform(0.01, 0.03)
            common = {
                "remanence": on * rng.uniform(0.8, 1.4),
                "center": place(rng.uniform(0.05, 0.15)),
                "magnetization": unit(),
            }
            if kind == "cuboid":
                out.append(Source("cuboid", dimensions=tuple(size * rng.uniform(0.5, 1.5, 3)),
                                  **common))  # fmt: skip
            elif kind == "sphere":
                out.append(Source("sphere", diameter=size, **common))
            else:
                out.append(Source("cylinder", diameter=size, length=size, **common))
    return tuple(out)


# Drawn robots (the whole design space, optimize.fitting.setups) in drawn source sets,
# with the external magnet: the solver's state against the oracle's load ramp
# (linear rod) and energy minimisation (the chain, large deflection), written on magpylib.
@pytest.mark.parametrize(
    "effects",
    [(), ("near_field",), pytest.param(("near_field", "large_deflection"), marks=pytest.mark.slow)],
    ids=str,
)
def test_drawn_source_sets_agree_with_an_independent_solve_on_magpylib(effects):
    print(f"seed {SEED}")
    rng = np.random.default_rng([SEED, len(effects)])
    checked = 0
    designs = 3 if "large_deflection" not in effects else 1
    for drawn in range(designs + 4):
        if drawn >= designs and checked:
            break  # (more robots are drawn only while no stable state has been compared)
        base = random_design(rng)
        design = in_field(base, *draw_sources(base, rng), external=True)
        commands = rng.uniform(-np.pi, np.pi, (2, 2))
        eq = solve(design, effects, commands)
        for k, command in enumerate(commands):
            if not eq.stable[k]:
                continue
            try:
                if "large_deflection" in effects:
                    tip = chain_state(design, frozenset(effects), command)[2]
                else:
                    tip = linear_state(design, frozenset(effects), command)[1]
            except ValueError as error:  # the oracle's own flow: scipy's event location
                # fails where the event changes sign within one step (seed 1986036991)
                print(f"seed {SEED}: oracle failed at {command}: {error}; not compared")
                continue
            err = np.abs(eq.position[k] - tip).max()
            kinds = [s.kind for s in design.sources]
            assert err < AGREEMENT, f"seed {SEED}, {kinds}, command {command}: {err * 1e3:.4f} mm"
            checked += 1
    assert checked


def test_the_external_magnet_alone_is_the_classic_model():
    design = default_design()
    assert model_for(frozenset()).for_design(design).layout == CLASSIC
    assert model_for(frozenset()).for_design(design) is model_for(frozenset())
