"""Diagnosis finds the effect hidden in synthetic data, and nothing in baseline data.

Each test draws its design perturbation, noise and effect strength at random at test time
(the seed is in every failure message) inside plausible ranges, synthesises a bench data
set with :mod:`optimize.fitting.synth`, and hands only the data and the nominal design to
:func:`optimize.fitting.diagnose.diagnose`: no test passes by knowing what was planted except
through the data.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from design.designfile import default_design
from design.records import Design
from optimize.fitting.calibrate import EFFECT_FREE
from optimize.fitting.diagnose import diagnose, report_key, residual_structure
from optimize.fitting.likelihood import profile_sigma
from optimize.fitting.planted import draw_planted
from optimize.fitting.synth import SETUPS, setup_variant, synthesize_data
from ringpair.plots import compared_fits

DEMO = default_design()


def draw(
    effects: tuple[str, ...], seed: int, setup: str = "bench"
) -> tuple[Design, dict[str, float], float]:
    """A random set-up and truth: the nominal design (magnet distance and tube stiffness
    drawn in the ranges of ``setup``), the as-built robot's differences from it (stiffness,
    magnet placement), and each planted effect at a random plausible strength."""
    rng = np.random.default_rng(seed)
    gap, stiffness = SETUPS[setup]
    design = setup_variant(DEMO, rng.uniform(*gap), rng.uniform(*stiffness))
    truth = {
        "bending_rigidity_scale": rng.uniform(0.7, 1.3),
        "external_center_x": design.external_magnet.center[0] + rng.uniform(-3e-3, 3e-3),
        "external_center_y": rng.uniform(-3e-3, 3e-3),
        "external_center_z": rng.uniform(-3e-3, 3e-3),
    }
    if "torsion" in effects:  # transmissions 1.5-5x stiffer than the nominal
        truth["wire_torsion_scale"] = rng.uniform(1.5, 5.0)
        truth["catheter_torsion_scale"] = rng.uniform(1.5, 5.0)
    if "hysteresis" in effects:  # backlash of 2-6 deg in each transmission
        truth["wire_friction_angle"] = np.deg2rad(rng.uniform(2.0, 6.0))
        truth["catheter_friction_angle"] = np.deg2rad(rng.uniform(2.0, 6.0))
    if "gravity" in effects:  # mounting pieces of 0-0.3 g at the tip
        truth["tip_mass"] = rng.uniform(0.0, 0.3e-3)
    noise_mm = rng.uniform(0.1, 0.4)
    return design, truth, noise_mm


COVERAGE = 5.0
"""The truth lies within this many sigma of each estimate's profile likelihood. Wilks'
asymptotic r is standard normal (|r| > 4: 6e-5), but where the rod's compliance trades
against the magnet's distance along a long curved valley its tail is heavier: the
hysteresis draw seed 517601824 (top view, 63 rows) put the catheter's friction 4.23 sigma
out (estimate 1.7 deg, truth 4.8): the truth's misfit over the best fit's was 29 noise
variances, and 15, 3.8, 4.4, 3.8 and 6.5 on five fresh noise draws of the same set-up
(6 parameters: chi-square mean 6; 29 or more at 6e-5, 15 at 0.02). A biased estimate is
still caught: the fitted stiffnesses relative to the field's strength were 3-28 sigma out
before optimize.fitting.calibrate.FIELD_RELATIVE."""


def fresh_seed() -> int:
    return int.from_bytes(os.urandom(4), "little")


def run(effects: tuple[str, ...], seed: int, view: str = "3d", setup: str = "bench"):
    design, truth, noise = draw(effects, seed, setup)
    synthetic = synthesize_data(
        design, effects, view=view, noise_mm=noise, seed=seed, params_override=truth
    )
    data = synthetic.measurements
    return diagnose(design, data, seed=seed), truth, noise, design, synthetic


def realized_noise_ms(synthetic) -> float:
    """The mean square distance the drawn noise put between the data and the noise-free
    simulation, over the measured coordinates of each row. [mm^2]"""
    m = synthetic.measurements
    miss = np.where(m.measured, m.position - synthetic.noise_free.position, 0.0)
    return float(np.mean(np.sum(miss**2, axis=1))) * 1e6


@pytest.mark.parametrize(
    ("planted", "view", "setup"),
    [
        (("torsion",), "3d", "bench"),
        (("hysteresis",), "top", "bench"),
        (("gravity",), "3d", "bench"),
        (("near_field",), "3d", "near"),
        (("large_deflection",), "top", "soft"),
        (("torsion", "gravity"), "3d", "bench"),
    ],
)
def test_diagnosis_names_the_planted_effect_and_recovers_its_parameters(planted, view, setup):
    seed = fresh_seed()
    result, truth, noise, design, synthetic = run(planted, seed, view, setup)
    data = synthetic.measurements
    why = f"seed {seed}, truth {truth}, noise {noise:.2f} mm: {result.to_json()['causes']}"
    assert {c.name for c in result.causes} == set(planted), why
    # Coverage: each effect's own parameters within COVERAGE sigma of the reported
    # uncertainty, the profile likelihood (optimize.fitting.likelihood): the truth's
    # profile r, and the reported 1-sigma interval around the estimate.
    final = result.final
    own = [n for c in result.causes for n in EFFECT_FREE[c.name]]
    for name in own:
        estimate = final.calibration.estimate[name]
        key, factor = report_key(name)
        lower, upper = result.to_json()["final"]["interval"][key]
        assert lower <= estimate * factor <= upper, f"{name}: {why}"
        r = profile_sigma(
            design,
            data,
            final.calibration,
            name,
            truth[name],
            ordered=final.ordered,
            starts=[truth],
        )
        assert abs(r) < COVERAGE, f"{name} (truth at {r:.2f} sigma): {why}"
    # What is left is the noise. The gain: the final model removes at least half of the
    # baseline's cross-validated mean square error beyond the noise actually drawn (a weak
    # effect, e.g. the exact field 22 mm from the magnet, leaves little beyond the noise to
    # remove, so a fixed ratio would not do; and on 60 rows the drawn noise's mean square
    # is itself 10-20 % off its nominal value, as much as such an effect's whole excess).
    axes = 3 if view == "3d" else 2
    noise_ms = realized_noise_ms(synthetic)

    def excess(fit):
        return fit.cv_rmse_mm**2 - noise_ms

    assert result.final.cv_rmse_mm < result.baseline.cv_rmse_mm, why
    assert excess(result.final) < 0.5 * excess(result.baseline), why
    assert result.final.calibration.rmse_mm < 1.5 * noise * np.sqrt(axes), why
    assert all(c.evidence.startswith(c.name) for c in result.causes)
    labels = [label for _, _, label in compared_fits(result)]
    assert labels == ["baseline", f"{result.final.name} (final)"]
    doc = result.to_json()
    assert doc["gain"]["cv_rmse_ratio"] == pytest.approx(
        result.final.cv_rmse_mm / result.baseline.cv_rmse_mm
    )


@pytest.mark.parametrize("setup", list(SETUPS))
def test_baseline_data_name_no_cause(setup):
    seed = fresh_seed()
    result, truth, noise, _, _ = run((), seed, setup=setup)
    why = f"{setup} set-up, seed {seed}, truth {truth}, noise {noise:.2f} mm"
    assert result.causes == (), f"{why}: {result.to_json()['causes']}"
    assert result.to_json()["causes"] == []
    assert result.final is result.baseline
    assert [label for _, _, label in compared_fits(result)] == ["baseline (final)"]


def test_residual_structure_finds_a_pattern_and_not_noise():
    rng = np.random.default_rng(3)
    angle = rng.uniform(0, 2 * np.pi, 200)
    noise = rng.normal(0, 1.0, (200, 3))
    pattern = noise.copy()
    pattern[:, 0] += 2 * np.sin(angle)
    feats = {"angle": np.column_stack([np.cos(angle), np.sin(angle)])}
    assert residual_structure(pattern, feats)[0].p_value < 1e-10
    assert residual_structure(noise, feats)[0].p_value > 1e-3


def fit_from_truth(effects: tuple[str, ...], seed: int):
    """The data of ``draw(effects, seed)`` and a calibration started at the truth, each
    configuration solved on its own: (design, truth, noise, measurements, fit)."""
    from optimize.fitting.calibrate import calibrate, default_free

    design, truth, noise = draw(effects, seed)
    m = synthesize_data(design, effects, noise_mm=noise, seed=seed, params_override=truth)
    free = default_free(effects)
    fit = calibrate(
        design, m.measurements, effects, free, initial={k: truth[k] for k in free}, ordered=False
    )
    return design, truth, noise, m.measurements, fit


def test_a_fit_along_the_path_leaves_the_basin_where_the_robot_does_not_snap():
    """Regression (seed 2884561028 of the torsion + gravity test, once failed): the bench
    robot's transmissions are soft enough that its rings snap on the path. A least-squares
    fit started from the truth without following the path stops where the transmissions
    are too stiff to snap (RMS 1.26 mm against 0.21 mm noise), and there the path no
    longer matters, so nothing local leads back. The diagnosis' full fits scan the misfit
    along the path (:func:`optimize.fitting.diagnose._scan`) and must end at the noise."""
    from optimize.fitting.diagnose import _fit

    effects = ("torsion", "gravity")
    design, truth, noise, m, stuck = fit_from_truth(effects, 2884561028)
    assert stuck.rmse_mm > 3 * noise  # the trap is there
    fit = _fit(design, m, frozenset(effects), k=5, seed=0, cv=False, starts=[stuck], sigma=None)
    assert fit.calibration.rmse_mm < 1.5 * noise * np.sqrt(3)
    for name in ("wire_torsion_scale", "catheter_torsion_scale", "tip_mass"):
        err = abs(fit.calibration.estimate[name] - truth[name])
        assert err < 4 * fit.calibration.standard_error[name], name


def screen_from_nominal(design: Design, m, effects: frozenset[str]):
    """The diagnosis' screening fit of ``effects`` from the nominal design alone."""
    from optimize.fitting.diagnose import SCREEN_EVALUATIONS, _fit

    return _fit(
        design,
        m,
        effects,
        k=5,
        seed=0,
        cv=False,
        starts=[None],
        sigma=None,
        max_nfev=SCREEN_EVALUATIONS,
    )


def test_a_fit_of_torsion_from_nominal_also_starts_from_the_transmissions_levels():
    """Regression (seed 172425381 of the torsion + gravity test, once failed: 63 rows along
    a path, wire 1.5 and catheter 2.8 times nominal): every start of the diagnosis, from
    nominal, stiff and soft transmissions, ended where the catheter is 22 times nominal,
    4x the noise's RMS, and the final model stayed at 3x. A fit of torsion from a start
    without it also starts from its transmissions at LEVELS
    (:data:`optimize.fitting.diagnose.LEVELS`), and a screen from the nominal design must
    reach the noise and the truth's transmissions."""
    from optimize.fitting.calibrate import calibrate, default_free

    effects = frozenset({"torsion", "gravity"})
    seed = 172425381
    design, truth, noise = draw(tuple(effects), seed)
    m = synthesize_data(
        design, tuple(effects), noise_mm=noise, seed=seed, params_override=truth
    ).measurements
    limit = 1.5 * noise * np.sqrt(3)
    stuck = calibrate(design, m, effects, default_free(effects), ordered="driven")
    assert stuck.rmse_mm > 2 * limit  # the trap is there
    fit = screen_from_nominal(design, m, effects)
    assert fit.calibration.rmse_mm < limit, fit.calibration.rmse_mm
    for name in ("wire_torsion_scale", "catheter_torsion_scale"):
        estimate = fit.calibration.estimate[name]
        assert abs(estimate - truth[name]) < 0.2 * truth[name], (name, estimate, truth[name])


def test_a_fit_of_torsion_from_nominal_also_starts_from_a_quarter_of_its_stiffness():
    """Regression (benchmark seed [3, 3, 1], ``draw_planted``: torsion, a 107 mm rod seen
    from above, the wire at 0.32 and the catheter at 1.35 times nominal): with torsion's
    LEVELS from 0.5 up, the screen from the nominal design ended with the wire at 0.42
    and the catheter at 0.52, and the diagnosis' final model at 3x the noise's
    cross-validated RMSE. The levels span 0.25-4x nominal; a screen from the nominal design
    must reach the truth's transmissions."""
    from optimize.fitting.diagnose import EFFECT_FREE

    effects = frozenset({"torsion"})
    case = draw_planted(np.random.default_rng([3, 3, 1]), effects)
    assert case.truth["wire_torsion_scale"] < 0.4, case.truth  # the draw is the one above
    fit = screen_from_nominal(case.design, case.measurements, effects)
    for name in EFFECT_FREE["torsion"]:
        estimate, truth = fit.calibration.estimate[name], case.truth[name]
        assert abs(math.log(estimate / truth)) < math.log(1.25), (name, estimate, truth)


def test_the_profile_likelihood_covers_torsion_where_the_linearised_error_does_not():
    """Regression (seed 2313850729 of the torsion test, once failed coverage): the magnet
    at the far end of the bench range makes the rod's compliance and the magnet's distance
    nearly degenerate, and the transmissions' stiffness follows them along a curved valley.
    The fit (started at the truth, so not a stuck fit) lies over 4 linearised standard
    errors from the true catheter stiffness; the profile likelihood (the reported
    uncertainty, optimize.fitting.likelihood) puts both truths within 4 sigma."""
    effects = ("torsion",)
    design, truth, _, m, fit = fit_from_truth(effects, 2313850729)
    name = "catheter_torsion_scale"
    assert abs(fit.estimate[name] - truth[name]) > 4 * fit.standard_error[name]  # the trap
    for name in EFFECT_FREE["torsion"]:
        r = profile_sigma(design, m, fit, name, truth[name], ordered=False, starts=[truth])
        assert 1 < abs(r) < 4, name


def test_non_finite_numbers_become_null_with_their_reason():
    import math

    from optimize.fitting.diagnose import NULL_REASONS, finite_json

    nulls: dict[str, str] = {}
    doc = {"final": {"cv_rmse_mm": math.nan, "params": {"a": 1.0}}, "x": [np.inf, 2]}
    out = finite_json(doc, "", nulls)
    assert out == {"final": {"cv_rmse_mm": None, "params": {"a": 1.0}}, "x": [None, 2]}
    assert nulls == {"final.cv_rmse_mm": NULL_REASONS["cv_rmse_mm"], "x[0]": "not a finite number"}


def test_a_failing_candidate_is_reported_and_the_diagnosis_goes_on(monkeypatch):
    import json

    import optimize.fitting.diagnose as dg
    from optimize.fitting.diagnose import search

    real = dg._fit

    def fit(design, m, effects, **options):
        if "torsion" in effects:
            raise FloatingPointError("planted\nfailure")
        return real(design, m, effects, **options)

    monkeypatch.setattr(search, "_fit", fit)
    m = synthesize_data(DEMO, ("gravity",), n=24, noise_mm=0.2, seed=4).measurements
    result = dg.diagnose(DEMO, m, candidates=("torsion", "gravity"))
    assert [c.name for c in result.causes] == ["gravity"]
    doc = result.to_json()
    json.dumps(doc, allow_nan=False)
    failed = doc["candidates"]["torsion"]
    assert failed["verdict"] == "fit failed: FloatingPointError: planted failure"
    assert failed["bic"] is None and doc["null"]["candidates.torsion.bic"]
    assert doc["candidates"]["gravity"]["verdict"].startswith("accepted: BIC")
    assert doc["power"]["torsion"]["could_tell_apart"] in (True, False)


def test_a_profile_likelihood_that_fails_is_said_in_the_causes_evidence(monkeypatch):
    """Where the profile likelihood of a cause's parameters fails (a benchmark set did,
    near field with torsion, when a refit from given states reached an assertion), its
    intervals are null with their reason in the JSON and the evidence says why, instead
    of '1 sigma nan to nan'."""
    import json

    import optimize.fitting.diagnose as dg

    def profile(*args, **options):
        raise FloatingPointError("planted\nfailure")

    monkeypatch.setattr(dg.causes, "profile_intervals", profile)
    m = synthesize_data(DEMO, ("gravity",), n=24, noise_mm=0.2, seed=4).measurements
    result = dg.diagnose(DEMO, m, candidates=("gravity",))
    assert [c.name for c in result.causes] == ["gravity"]
    evidence = result.causes[0].evidence
    assert "1 sigma unknown: the profile likelihood failed (FloatingPointError: planted " in (
        evidence
    ), evidence
    assert "nan" not in evidence, evidence
    doc = result.to_json()
    json.dumps(doc, allow_nan=False)
    reason = doc["null"]["causes[0].interval.tip_mass_g[0]"]
    assert reason == "the profile likelihood could not be evaluated", doc["null"]


@pytest.mark.slow
def test_a_final_model_that_does_not_predict_held_out_rows_is_reported():
    """A right model predicts the configurations held out of its fit about as well as a
    linear model would with the same configurations (the ratio of the RMSEs within
    HELD_OUT_RATIO of held_out_inflation's: about 1.3 for 16 rows, several times that
    where a few configurations fix a parameter, e.g. a far magnet seen from above); far
    above it, the report says that the final model does not generalise instead of
    nothing (benchmark seed [2, 12, 0]: CV RMSE 16.7x the noise, unexplained ''). The
    smallest data sets (16 rows) of nothing planted, drawn from the whole design space;
    seeds 11, 16, 36 and 39 of this draw failed the rule against the plain ratio, or with
    held-out rows solved by the fold's own load ramp (which fell to another state). The
    rule is a linear model's, so the draw is one whose driven path does not snap: seed
    289219020 (a path snapping at 3 of 15 rows) fitted 8.7x the noise, the fit moving the
    magnet 26 mm to place the snaps (reported as a violated prior)."""
    from dataclasses import replace

    from optimize.fitting.calibrate import PULL_LIMIT
    from optimize.fitting.diagnose import HELD_OUT_RATIO, _fit, _unexplained
    from optimize.fitting.diagnose.evidence import _outside_priors
    from optimize.fitting.planted import draw_planted

    seed = fresh_seed()
    rng = np.random.default_rng(seed)
    case = draw_planted(rng, frozenset(), points=(16, 16))
    for _ in range(20):  # smooth data: a path without a snap
        if not case.synthetic.equilibria.snapped.any():
            break
        case = draw_planted(rng, frozenset(), points=(16, 16))
    m = case.measurements
    m.sigma[:] = np.nan  # the rule under test, not the chi-square one
    fit = _fit(case.design, m, frozenset(), k=5, seed=0, cv=True, starts=[None], sigma=None)
    ratio = fit.cv_rmse_mm / fit.calibration.rmse_mm
    why = (
        f"seed {seed}: {case.describe()}; RMSE {fit.calibration.rmse_mm:.3g} mm, CV {ratio:.2f}x"
        f" (a linear model's {fit.cv_expected_ratio:.2f}x)"
    )
    assert 1.0 <= fit.cv_expected_ratio < 10.0, why
    assert ratio < HELD_OUT_RATIO * fit.cv_expected_ratio, why
    # as the diagnosis does: a baseline outside its priors is also fitted within them
    # (seed 3427148848: the magnet's centre 10 prior sigmas out at 0.274 mm RMS, held within
    # them 0.277 mm; reported as a violated prior before)
    held = None
    if _outside_priors(fit):
        held = _fit(
            case.design, m, frozenset(), k=5, seed=0, cv=True, starts=[None], sigma=None,
            within=PULL_LIMIT,
        )  # fmt: skip
    assert _unexplained(m, fit, (), held) == "", why
    off = 1.1 * HELD_OUT_RATIO * fit.cv_expected_ratio
    text = _unexplained(m, replace(fit, cv_rmse_mm=off * fit.calibration.rmse_mm), (), held)
    assert "does not predict configurations it was not fitted to" in text, text
    assert f"{off:.1f}x the in-sample one" in text, text
    assert f"a right model would give about {fit.cv_expected_ratio:.1f}x" in text, text


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(8800, 8818))
def test_the_first_order_power_of_the_data_lies_within_its_band_of_the_refitted_one(
    seed, monkeypatch
):
    # The power of the data is taken to first order unless that lands within a factor
    # FIRST_ORDER_BAND of DETECTABLE: sound only while the first-order margin lies within
    # that factor of the refitted one, so that no verdict could differ. Checked against the
    # refit (a short fit of the baseline to each effect's predictions, the method before
    # it) on bench data drawn from the whole design space (optimize.fitting.planted); the
    # near field is always refitted (REFITTED_POWER): seed 8808 puts its first order 50x
    # off, seed 8815 8x. Where the refit meets a configuration the baseline cannot solve
    # (seed 8806, large deflection), both must still give the same verdict.
    from optimize.fitting import diagnose as module

    band = module.FIRST_ORDER_BAND
    case = draw_planted(np.random.default_rng(seed), frozenset())
    design, m = case.design, case.measurements
    base = module._fit(design, m, frozenset(), k=2, seed=0, cv=False, starts=[None], sigma=None)
    for effect in EFFECT_FREE:
        margins = []
        for forced in (1.0, math.inf):  # 1: always to first order; inf: always refitted
            monkeypatch.setattr(module.power, "FIRST_ORDER_BAND", forced)
            margins.append(module.power_of_data(design, m, base, effect, None))
        first, refit = (float(p["margin"]) for p in margins)  # type: ignore[arg-type]
        where = f"seed {seed}, {case.describe()}, {effect}: first {first:.3g}, refit {refit:.3g}"
        if "method" not in margins[0]:  # decided before either (no state at that strength)
            assert margins[0] == margins[1], where
            continue
        if effect in module.REFITTED_POWER:
            assert margins[0] == margins[1], where
            continue
        if "method" not in margins[1]:  # the refit met a configuration without a state
            assert margins[0]["could_tell_apart"] == margins[1]["could_tell_apart"], where
            continue
        assert [p["method"] for p in margins] == ["to first order", "refitted"], where
        if max(first, refit) < 1e-6:  # nothing to see either way (gravity across the view)
            continue
        assert 1 / band < first / refit < band, where


def test_a_causes_evidence_gives_the_final_models_error_where_a_later_refit_changed_it():
    """A cause's evidence cites the cross-validated RMSE of the fit it was accepted with;
    where the final model was refitted after (from another candidate's estimates: the
    example with the rings locked parallel, torsion accepted at 0.975 mm and refitted to
    0.244 mm on 0.28 mm of noise per row), it also gives the final model's, which the
    table above it shows; where they agree it does not repeat it."""
    from types import SimpleNamespace

    from optimize.fitting.diagnose import _cause
    from optimize.fitting.likelihood import Interval

    def fit(cv: float, bic: float) -> SimpleNamespace:
        estimate = {p: 1.0 for p in EFFECT_FREE["hysteresis"]}
        return SimpleNamespace(
            cv_rmse_mm=cv,
            bic=lambda: bic,
            calibration=SimpleNamespace(estimate=estimate),
            name="hysteresis",
        )

    before, after = fit(2.76, 0.0), fit(0.975, -93.0)
    profiles = {p: Interval(0.5, 1.5, 2) for p in EFFECT_FREE["hysteresis"]}
    for final, said in ((fit(0.244, -200.0), True), (fit(0.98, -94.0), False), (after, False)):
        text = _cause(DEMO, "hysteresis", before, after, (), (), final, profiles, False).evidence
        assert "falls from 2.76 to 0.975 mm" in text, text
        assert ("0.244 mm in the final model, hysteresis" in text) is said, text
        assert ("in the final model" in text) is said, text


def drawn_bench(rng, seed, effects, rows, noise_mm):
    """A random design (the whole design space), its robot as built with ``effects`` at
    random strengths, and its bench data along a path: (design, truth, measurements);
    ``rows``: the range of configurations drawn from."""
    from optimize.fitting.planted import as_built, effect_strengths
    from optimize.fitting.setups import random_design

    design = random_design(rng)
    truth = {**as_built(rng, design), **effect_strengths(rng, frozenset(effects))}
    m = synthesize_data(
        design,
        effects,
        n=int(rng.integers(*rows)),
        noise_mm=noise_mm,
        seed=seed,
        params_override=truth,
    ).measurements
    return design, truth, m


@pytest.mark.parametrize(
    "effects", [("torsion",), ("large_deflection",), ("hysteresis", "near_field")]
)
def test_a_scan_that_solves_each_points_first_rows_first_chooses_as_one_that_solves_all(
    effects, monkeypatch
):
    """:func:`optimize.fitting.diagnose._scan` solves each point on the path's first rows
    (SCAN_HEAD) and goes on only where they miss by less than the start does in whole. On
    set-ups drawn from the whole design space (random design, robot as built, effects at
    random strengths, along the bench's path), those rows' states must be the whole path's
    (the robot's state depends only on the rows before), and the scan must choose exactly
    what the same scan solving every point in whole chooses."""
    from design.model import model_for
    from optimize.fitting import diagnose as diagnosis
    from optimize.fitting.calibrate import default_free, predict

    seed = fresh_seed()
    rng = np.random.default_rng(seed)
    design, truth, m = drawn_bench(rng, seed, effects, (16, 31), 0.2)
    model = model_for(frozenset(effects))
    free = default_free(effects)
    params = diagnosis._parameters(model, design, truth)
    whole = predict(model, params, m, "driven").equilibria.position
    head = diagnosis._first_rows(m)
    first = predict(model, params, head, "driven").equilibria.position
    np.testing.assert_allclose(
        first, whole[m.order()[: len(head)]], rtol=0, atol=1e-12, err_msg=f"seed {seed}"
    )
    params = diagnosis._parameters(model, design, None)
    found = diagnosis._scan(model, m, params, free)
    monkeypatch.setattr(diagnosis.scans, "SCAN_HEAD", 1.0)
    assert found == diagnosis._scan(model, m, params, free), f"seed {seed}"


@pytest.mark.parametrize(
    "effects", [("torsion",), ("large_deflection", "gravity"), ("near_field",)]
)
def test_misfits_of_many_parameter_sets_solved_at_once_are_each_sets_own(effects, monkeypatch):
    """:func:`optimize.fitting.diagnose._misfits` solves the rows of several parameter
    vectors in one solve (per-column parameters). On set-ups drawn from the whole design
    space (random design, robot as built, effects at random strengths, rows on their own),
    each point's misfit must be that of its own :func:`predict` (a separately made solve),
    a row without a state the same in both (inf), and the scan on rows on their own must
    choose what the scan solving every row of every point chooses."""
    from design.model import model_for
    from design.registry import index
    from optimize.fitting import diagnose as diagnosis
    from optimize.fitting.calibrate import FREE_PARAMETERS, default_free, predict

    seed = fresh_seed()
    rng = np.random.default_rng(seed)
    model = model_for(frozenset(effects))
    free = default_free(effects)
    # a set-up where most rows have a state (not all pulled in), each measured row reached
    # on its own too (the bench's path may have led a row to a state no ramp reaches)
    for _ in range(10):
        design, truth, m = drawn_bench(rng, seed, effects, (16, 41), 0.3)
        exact = diagnosis._parameters(model, design, truth)
        reached = predict(model, exact, m, ordered=False).equilibria.position
        if m.seen.mean() >= 0.5 and np.isfinite(reached[m.seen]).all():
            break
    nominal = diagnosis._parameters(model, design, None)
    points = [nominal, exact]
    # about the truth at shrinking distances: near a strong magnet the farthest may pull
    # rows in (no state: inf, which must agree too), the nearest keep every row's state
    for scale in (0.3, 0.1, 0.03, 0.01, 0.003):
        p = exact.copy()
        for name in free:
            spec = FREE_PARAMETERS[name]
            step = scale * rng.normal() * spec.prior
            value = (
                p[index(name)] * np.exp(step)
                if spec.kind == "log"
                else p[index(name)] + step * spec.step
            )
            p[index(name)] = np.clip(value, spec.lower, spec.upper)
        points.append(p)
    together = diagnosis._misfits(model, m, points)
    for i, p in enumerate(points):
        position = predict(model, p, m, ordered=False).equilibria.position
        r = (position - m.position)[np.isfinite(m.position)]
        alone = float(np.sum(r**2)) if np.isfinite(r).all() else np.inf
        assert together[i] == pytest.approx(alone, rel=1e-9), f"seed {seed}, point {i}"
    assert np.isfinite(together[1:]).sum() >= 3, f"seed {seed}: too few points solve every row"
    found = diagnosis._scan(model, m, nominal, free, ordered=False)
    monkeypatch.setattr(diagnosis.scans, "SCAN_HEAD", 1.0)
    assert found == diagnosis._scan(model, m, nominal, free, ordered=False), f"seed {seed}"
