"""Profile-likelihood intervals (optimize.fitting.likelihood) against the linear theory they reduce
to, and at a parameter's bound."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import pytest

from design.designfile import default_design, load_design
from optimize.fitting import likelihood
from optimize.fitting.calibrate import calibrate, default_free
from optimize.fitting.likelihood import profile_intervals, profile_sigma
from optimize.fitting.synth import synthesize_data

DEMO = default_design()
EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def test_profile_interval_is_the_gauss_newton_interval_where_the_model_is_locally_linear():
    """For a model linear in its parameters over the error's range, the profile
    likelihood's 1-sigma interval is estimate +- the Gauss-Newton standard error (Bates &
    Watts 1988, Nonlinear Regression Analysis, ch. 6). Low-noise torsion data of the
    demonstrator make the model locally linear: each half-width must be the standard
    error to 3 %."""
    effects = ("torsion",)
    truth = {"wire_torsion_scale": 2.0, "catheter_torsion_scale": 3.0}
    m = synthesize_data(DEMO, effects, noise_mm=0.05, seed=3, params_override=truth).measurements
    fit = calibrate(DEMO, m, effects, default_free(effects), ordered=False)
    intervals = profile_intervals(DEMO, m, fit, list(truth), ordered=False)
    for name, iv in intervals.items():
        est, se = fit.estimate[name], fit.standard_error[name]
        assert iv.upper - est == pytest.approx(se, rel=0.03), name
        assert est - iv.lower == pytest.approx(se, rel=0.03), name
        # and the profile at an end is 1 sigma away, by construction of the search
        assert profile_sigma(DEMO, m, fit, name, iv.upper, ordered=False) == pytest.approx(
            1.0, abs=0.06
        )


def test_an_interval_end_the_bound_cuts_off_is_the_bound():
    """No tip mass in the data: the estimate is a small positive mass less than one
    standard error from zero, so the lower end of its interval is the bound, 0 g."""
    effects = ("gravity",)
    m = synthesize_data(
        DEMO, effects, noise_mm=0.3, seed=1, params_override={"tip_mass": 0.0}
    ).measurements
    fit = calibrate(DEMO, m, effects, default_free(effects), ordered=False)
    assert 0 < fit.estimate["tip_mass"] < fit.standard_error["tip_mass"]
    iv = profile_intervals(DEMO, m, fit, ["tip_mass"], ordered=False)["tip_mass"]
    assert iv.lower == 0.0
    assert iv.upper > fit.estimate["tip_mass"]


def test_profile_intervals_reject_a_parameter_that_is_not_free():
    effects = ("gravity",)
    m = synthesize_data(DEMO, effects, noise_mm=0.3, seed=1).measurements
    fit = calibrate(DEMO, m, effects, default_free(effects), ordered=False)
    with pytest.raises(ValueError, match="wire_torsion_scale.*not a free parameter"):
        profile_intervals(DEMO, m, fit, ["wire_torsion_scale"])


def test_an_interval_end_where_the_profile_jumps_is_the_jump(monkeypatch):
    """Where the refits snap to another branch beyond some value, r jumps across 1 there.
    A fit often stops at such an edge of its basin (the drawn near field and torsion set of
    the diagnosis benchmark, seed [2, 7, 0]: r 0 -> 48 within 1e-8 of the wire's torsion
    scale's estimate, and the search spent its MAX_FITS refits there). A jump that close
    is now placed to RESOLUTION of the standard error, beyond it, in fewer refits; a jump
    further out still gives an end beyond it and within the first step, and a profile
    without a jump ends where |r| = 1. A jump that only the refit from the estimates makes
    (from the nominal design the profile is smooth: a cliff of the refit's basin, not of
    the profile) ends where the smooth profile does. The refit is replaced by profiles of
    known r(u) (u = log of the value)."""
    estimate, se = 0.3, 0.07
    u_hat = math.log(estimate)  # the fit unit about the factor's nominal value, 1
    # one other parameter, "x", whose value names the basin a refit starts in
    fit = SimpleNamespace(
        estimate={"x": "estimate"},
        states=None,
        nominal={"x": "nominal", "wire_torsion_scale": 1.0},
    )

    def end(r_of_distance, step=se, from_nominal=None):
        def refit(design, m, fit, name, value, rest, starts, ordered, sigma):
            d = u_hat - math.log(value)
            basins = {
                "nominal" if s["x"] == "nominal" and from_nominal else "estimate" for s, _ in starts
            }
            r, basin = min(
                ((from_nominal if b == "nominal" else r_of_distance)(d), b) for b in basins
            )
            return -r, SimpleNamespace(estimate={"x": basin}, states=None)

        monkeypatch.setattr(likelihood, "_refit", refit)
        value, fits = likelihood._end(
            None, None, fit, "wire_torsion_scale", ("x",), u_hat, -1.0, step, 0.01, False, None
        )
        return u_hat - math.log(value), fits

    for jump in (1e-8 * se, 1e-4 * se, 0.5 * se):  # distance of the jump from the estimate
        distance, fits = end(lambda d, jump=jump: 0.5 * d / se if d < jump else 48.0)
        assert jump <= distance <= se * (1 + 1e-9), (jump, distance)
        if jump < 0.01 * se:
            assert distance <= jump + likelihood.RESOLUTION * se, (jump, distance)
            assert fits < likelihood.MAX_FITS, (jump, fits)
    distance, _ = end(lambda d: d / se, step=0.5 * se)
    assert distance == pytest.approx(se, rel=likelihood.TOLERANCE)
    for jump in (1e-8 * se, 0.5 * se):
        distance, _ = end(
            lambda d, jump=jump: 0.5 * d / se if d < jump else 48.0,
            step=0.5 * se,
            from_nominal=lambda d: d / (2 * se),
        )
        assert distance == pytest.approx(2 * se, rel=likelihood.TOLERANCE), jump


def test_a_further_uncertainty_widens_each_end_in_quadrature():
    # Independent errors add in quadrature (a 3-4-5 triangle): a log parameter's ends
    # 0.03 and 0.04 from the estimate in log units, widened by a relative 4 % (log1p 0.04),
    # lie 0.05 and 0.04 sqrt(2) from it; a linear one (the tip's mass) likewise in its
    # own unit; a parameter's bound still bounds it; an interval that could not be
    # computed stays NaN.
    rel = math.expm1(0.04)
    out = likelihood.widened(
        "wire_torsion_scale",
        2.0,
        likelihood.Interval(2 * math.exp(-0.03), 2 * math.exp(0.04), 3),
        rel,
    )
    assert out.lower == pytest.approx(2 * math.exp(-0.05), rel=1e-12)
    assert out.upper == pytest.approx(2 * math.exp(0.04 * math.sqrt(2)), rel=1e-12)
    assert out.fits == 3
    mass = likelihood.widened("tip_mass", 2e-4, likelihood.Interval(1.97e-4, 2.04e-4, 2), 0.02)
    assert (mass.lower, mass.upper) == pytest.approx((1.95e-4, 2e-4 + math.hypot(4e-6, 4e-6)))
    bounded = likelihood.widened("tip_mass", 1e-5, likelihood.Interval(0.0, 2e-4, 2), 2.0)
    assert bounded.lower == 0.0
    nan = likelihood.widened(
        "wire_torsion_scale", 2.0, likelihood.Interval(math.nan, math.nan, 0), rel
    )
    assert math.isnan(nan.lower) and math.isnan(nan.upper)


def test_a_profile_from_a_fit_at_the_edge_of_its_basin_along_a_path_reaches_the_truth():
    """The example with the rings locked parallel (examples/locked_parallel.toml), torsion
    planted (transmissions 0.6 and 1.8, both magnets 1.5 T against the design's 1.45),
    40 rows along the bench's path seen from above, 0.2 mm noise: ``ringpair synth`` and
    ``ringpair diagnose`` of that set ended at a catheter torsion scale of 2.152, at the edge
    of a basin where the path snaps at another row 4e-4 of it further down (misfit x80).
    Refitted only from there, the profile's 1-sigma interval was 2.152-2.208, 7 sigma off
    the truth. The truth, relative to the field's strength (the transmissions over
    (1.5 / 1.45)^2, :data:`optimize.fitting.calibrate.FIELD_RELATIVE`), must lie within the
    intervals of both transmissions."""
    design = load_design(EXAMPLES / "locked_parallel.toml")
    effects = ("torsion",)
    truth = {"wire_torsion_scale": 0.6, "catheter_torsion_scale": 1.8}
    field = (1.5 / 1.45) ** 2
    m = synthesize_data(
        design,
        effects,
        n=40,
        view="top",
        noise_mm=0.2,
        seed=1,
        params_override={**truth, "external_remanence": 1.5, "magnet_remanence": 1.5},
    ).measurements
    where_the_diagnosis_ended = {
        "bending_rigidity_scale": 0.96777,
        "external_center_x": 0.249497,
        "external_center_y": -0.000139,
        "external_center_z": 0.0,
        "wire_torsion_scale": 0.598767,
        "catheter_torsion_scale": 2.152463,
    }
    fit = calibrate(design, m, effects, ordered="driven", initial=where_the_diagnosis_ended)
    intervals = profile_intervals(design, m, fit, list(truth), ordered="driven")
    for name, value in truth.items():
        iv = intervals[name]
        assert iv.lower <= value / field <= iv.upper, (name, fit.estimate[name], iv)
