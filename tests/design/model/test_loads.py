"""Effects as objects (design.model.loads) against the statics of a rigid body written out
here with numpy: each point mass's weight and its moment about the rod's end, the moment
of a force carried a rigid offset along the tangent; and the order in which the model
composes them. The seed of each random case is in its test id."""

from __future__ import annotations

from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from design.model.effects import PRINTED_TIP, SWITCHES
from design.model.loads import TIP_EFFECTS, Gravity, PrintedTip, TipFrame, tip_effects


def _frame(rng: np.random.Generator) -> tuple[TipFrame, np.ndarray, np.ndarray]:
    tangent = rng.normal(size=3)
    tangent /= np.linalg.norm(tangent)
    s = SimpleNamespace(gravity=ca.DM(rng.normal(0.0, 9.81, 3)))
    masses = tuple((float(rng.uniform(0, 0.01)), float(rng.uniform(0, 1e-3))) for _ in range(5))
    at = TipFrame(s, float(rng.uniform(0, 1)), float(rng.uniform(0, 0.01)), ca.DM(tangent), masses)
    return at, rng.normal(size=3), rng.normal(size=3) * 1e-3


def _np(x) -> np.ndarray:
    return np.asarray(ca.DM(x)).ravel()


@pytest.mark.parametrize("seed", range(5))
def test_gravity_adds_each_point_weight_and_its_moment_about_the_rod_end(seed):
    at, force, torque = _frame(np.random.default_rng(seed))
    f, t = Gravity().add(at, ca.DM(force), ca.DM(torque))
    g = at.load * _np(at.s.gravity)
    tangent = _np(at.tangent)
    want_f = force + sum(m * g for _, m in at.masses)
    want_t = torque + sum(np.cross(arm * tangent, m * g) for arm, m in at.masses)
    np.testing.assert_allclose(_np(f), want_f, rtol=1e-13, atol=1e-18, err_msg=f"seed {seed}")
    np.testing.assert_allclose(_np(t), want_t, rtol=1e-13, atol=1e-18, err_msg=f"seed {seed}")


@pytest.mark.parametrize("seed", range(5))
def test_the_printed_tip_moves_the_moment_to_the_rod_end_an_offset_behind(seed):
    at, force, torque = _frame(np.random.default_rng(seed))
    f, t = PrintedTip().add(at, ca.DM(force), ca.DM(torque))
    want_t = torque + np.cross(at.offset * _np(at.tangent), force)
    np.testing.assert_allclose(_np(f), force, rtol=0, atol=0)
    np.testing.assert_allclose(_np(t), want_t, rtol=1e-13, atol=1e-18, err_msg=f"seed {seed}")


def test_the_model_composes_the_printed_tip_before_gravity_and_only_those_switched_on():
    # The rigid segment's arm applies to the field's force at the tracked point, not to
    # the weights, whose arms are their own: printed tip first.
    assert [e.name for e in TIP_EFFECTS] == [PRINTED_TIP, "gravity"]
    assert [e.name for e in tip_effects(frozenset(SWITCHES))] == [PRINTED_TIP, "gravity"]
    assert [e.name for e in tip_effects(frozenset({"gravity", "torsion"}))] == ["gravity"]
    assert tip_effects(frozenset()) == ()
