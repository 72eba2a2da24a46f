"""The design NLP's ``ring_stiffness`` rows (optimize/sizing/nlp_problem.py) against the
closed form of the rings' rotational stiffness.

With the field off and the rod unloaded (straight), the only torques on the rings are the
transmissions' (GJ_i / L each) and their mutual one, T_1 = -T_2 = K12 sin(theta_1 -
theta_2) (design/ring_coupling.py; the coefficient K12 itself is tested against magpylib
there). At parallel rings the Hessian of the rings' potential is

    H = diag(1 / C_1, 1 / C_2) - K12 [[1, -1], [-1, 1]],   C_i = L / GJ_i,

so det H = (1 - kappa) / (C_1 C_2), kappa = K12 (C_1 + C_2): the parallel rings are stable
iff kappa < 1 (the paper's "K12 L (1/GJ_wire + 1/GJ_catheter)"). Held against a stop by
the pre-twist p < 0, the contact torque is lambda = -p / (C_1 + C_2) (design/stops.py's
closed form, less the contact's 1 / STOP_STIFFNESS) and the row counts it as the secant
stiffness lambda / HOLD_ANGLE on the relative angle: K12 is replaced by K12 - lambda /
HOLD_ANGLE, and the held rings pass iff |p| > (kappa - 1) HOLD_ANGLE.

Set-ups are drawn across the design space the tool accepts (ring sizes, gap, tubes, free
length), each seed printed on failure.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from design.designfile import default_design
from design.geometry import magnet_spacing
from design.model import RingPairModel, Symbols
from design.registry import NAMES, index, parameter_vector
from design.ring_coupling import coupling_coefficient
from design.stops import STOP_SMOOTHING, STOP_STIFFNESS, resting_angles
from optimize.sizing.nlp_problem import HOLD_ANGLE, ring_stiffness

SEEDS = range(12)


def _row(effects: frozenset[str]) -> ca.Function:
    model = RingPairModel(effects)
    x = ca.SX.sym("x", model.n_unknowns)
    c = ca.SX.sym("c", 2)
    prm = ca.SX.sym("p", len(NAMES))
    s = Symbols(prm)
    r, _ = model.residual(x, c, prm)
    return ca.Function("row", [x, c, prm], [ring_stiffness(model, r, x, s), s.torsional_rigidity])


def _drawn(seed: int) -> np.ndarray:
    """A parameter vector with the field off and drawn rings, gap, tubes and length."""
    rng = np.random.default_rng(seed)
    p = parameter_vector(default_design())
    outer = rng.uniform(1.0e-3, 6.0e-3)
    p[index("magnet_outer_diameter")] = outer
    p[index("magnet_inner_diameter")] = max(rng.uniform(0.2, 0.6) * outer, 0.6e-3)
    p[index("magnet_length")] = rng.uniform(0.5e-3, 5.0e-3)
    p[index("magnet_gap")] = rng.choice([0.0, rng.uniform(0.0, 3e-3)])
    p[index("magnet_remanence")] = rng.uniform(0.8, 1.45)
    p[index("free_length")] = rng.uniform(0.03, 0.25)
    for tube in ("catheter", "wire"):
        p[index(f"{tube}_youngs_modulus")] *= rng.uniform(0.3, 3.0)
    p[index("external_remanence")] = 0.0  # field off
    return p


def _closed_form(k12: float, compliance: np.ndarray) -> float:
    h = np.diag(1 / compliance) - k12 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    w = np.sqrt(compliance)
    return float(np.linalg.eigvalsh(h * np.outer(w, w))[0])


def _k12(p: np.ndarray) -> float:
    spacing = magnet_spacing(p[index("magnet_length")], p[index("magnet_gap")])
    return float(
        coupling_coefficient(
            p[index("magnet_outer_diameter")], p[index("magnet_inner_diameter")],
            p[index("magnet_length")], spacing, p[index("magnet_remanence")],
        )
    )  # fmt: skip


@pytest.mark.parametrize("effects", [{"torsion"}, {"torsion", "large_deflection"}])
def test_free_rings_stiffness_is_the_two_by_two_closed_form(effects):
    """Parallel rings, field off, no stops: the row is the least eigenvalue of
    K_t^-1/2 H K_t^-1/2 and is negative exactly when kappa > 1."""
    row = _row(frozenset(effects))
    model = RingPairModel(frozenset(effects))
    for seed in SEEDS:
        p = _drawn(seed)
        phi = np.random.default_rng(seed + 100).uniform(0, 2 * np.pi)
        x = np.concatenate([np.zeros(model.n_rod), [phi, phi]])
        value, rigidity = (np.asarray(v).ravel() for v in row(x, [phi, phi], p))
        compliance = p[index("free_length")] / rigidity
        k12 = _k12(p)
        expected = _closed_form(k12, compliance)
        assert value[0] == pytest.approx(expected, rel=1e-6, abs=1e-9), f"seed {seed}"
        kappa = k12 * compliance.sum()
        assert (value[0] < 0) == (kappa > 1), f"seed {seed}: kappa {kappa:.3f}"


def test_rings_held_at_the_stop_count_the_contact_torque_over_the_hold_angle():
    """Touching rings (kappa drawn in [2.5, 6] through the free length) pressed against the
    lower stop by the pre-twist p: the row is the closed form with K12 - |lambda| /
    HOLD_ANGLE, lambda = -p / (C_1 + C_2), so it changes sign where |p| = (kappa - 1)
    HOLD_ANGLE; a stop touched without pressing (p = 0) adds nothing. (The pre-twists are
    beyond the contact's rounded corner, 2 STOP_SMOOTHING (1 + k C), where lambda is the
    closed form's.)"""
    effects = frozenset({"torsion", "printed_tip"})
    row = _row(effects)
    model = RingPairModel(effects)
    for seed in SEEDS:
        p = _drawn(seed)
        p[index("magnet_gap")] = 0.0
        p[index("stop_angle")] = np.deg2rad(170.0)
        rigidity = np.asarray(row(np.zeros(model.n_unknowns), [0, 0], p)[1]).ravel()
        k12 = _k12(p)
        kappa = np.random.default_rng(seed + 200).uniform(2.5, 6.0)
        p[index("free_length")] = kappa / (k12 * np.sum(1 / rigidity))  # C_i = L / GJ_i
        compliance = p[index("free_length")] / rigidity
        corner = 2 * STOP_SMOOTHING * (1 + STOP_STIFFNESS)
        for factor in (0.0, 0.9, 1.1):
            pretwist = -factor * (kappa - 1) * HOLD_ANGLE
            assert factor == 0 or -pretwist > corner
            p[index("pretwist")] = pretwist
            angles = np.asarray(
                resting_angles(np.zeros(2), p[index("stop_angle")], pretwist, compliance)
            ).ravel()
            x = np.concatenate([np.zeros(model.n_rod), angles])
            value = float(row(x, [0.0, 0.0], p)[0])
            held = -pretwist / compliance.sum() / HOLD_ANGLE
            expected = _closed_form(k12 - held, compliance)
            # lambda is the closed form's to 1 / STOP_STIFFNESS (1e-4) of terms of order kappa
            assert value == pytest.approx(expected, abs=1e-4 * (1 + 2 * kappa)), (
                f"seed {seed}, pre-twist {np.rad2deg(pretwist):.3f} deg"
            )
            if factor > 0:
                assert (value > 0) == (factor > 1), f"seed {seed}: kappa {kappa:.3f}"
