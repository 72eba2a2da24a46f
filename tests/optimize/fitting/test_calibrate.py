"""Calibration: the implicit-function Jacobian against finite differences, recovery of
planted parameters within the reported uncertainty (coverage), the paper's grid search
and cross-validation."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from design.designfile import load_design
from design.equilibrium import solve_equilibria, solve_sequence
from design.model import RingPairModel
from design.registry import index
from design.units import MM
from optimize.fitting.calibrate import (
    PAPER_FIELD_GRID,
    PAPER_STIFFNESS_GRID,
    SENSITIVE,
    calibrate,
    calibrate_from_starts,
    configuration_folds,
    cross_validate,
    grid_search_two_factors,
    predict,
    prediction_sensitivities,
    two_factor_parameters,
)
from optimize.fitting.measurements import make_measurements
from optimize.fitting.planted import draw_planted
from optimize.fitting.synth import default_commands, synthesize, synthesize_data


def _fd_columns(solve, params, names, rel=1e-6):
    """Central finite differences of the tip position and angles (N, 5, k). [SI]"""
    cols = []
    for name in names:
        i = index(name)
        h = rel * max(abs(params[i]), 1e-3)
        up, down = params.copy(), params.copy()
        up[i] += h
        down[i] -= h
        a, b = solve(up), solve(down)
        cols.append(
            (np.hstack([a.position, a.tip_angles]) - np.hstack([b.position, b.tip_angles]))
            / (2 * h)
        )
    return np.stack(cols, axis=2)


def _check_jacobian(model, params, solve, names, ordered=None, m=None):
    pred = predict(model, params, m, ordered)
    _, d = prediction_sensitivities(model, params, pred)
    exact = d[:, :, [SENSITIVE.index(n) for n in names]]
    fd = _fd_columns(solve, params, names)
    scale = np.abs(fd).max(axis=(0, 1), keepdims=True) + 1e-12
    np.testing.assert_allclose(exact / scale, fd / scale, atol=2e-5)


NAMES_BASELINE = (
    "bending_rigidity_scale",
    "external_remanence",
    "magnet_remanence",
    "external_center_x",
    "external_center_y",
    "external_center_z",
    "external_magnetization_y",
    "free_length",
    "wire_youngs_modulus",
)


def test_implicit_function_jacobian_matches_finite_differences_baseline(demonstrator):
    model = RingPairModel()
    params = model.parameters(demonstrator)
    params[index("external_center_y")] = 0.003  # off-axis: no symmetric zero derivatives
    m = synthesize(demonstrator, n=6, noise_mm=0.0)

    def solve(p):
        return solve_equilibria(model, p, m.command[:, 0], m.command[:, 1])

    _check_jacobian(model, params, solve, NAMES_BASELINE, m=m)


def test_implicit_function_jacobian_matches_finite_differences_torsion(demonstrator):
    model = RingPairModel(frozenset({"torsion"}))
    params = model.parameters(demonstrator)
    params[index("wire_torsion_scale")] = 3.0  # stiff enough to hold every configuration
    # rings neither parallel nor antiparallel, where the lags vanish by symmetry
    cmd = np.deg2rad([[30.0, 0.0], [75.0, 10.0], [110.0, -20.0], [150.0, 45.0], [250.0, 100.0]])
    m = make_measurements(cmd, np.zeros((len(cmd), 3)))

    def solve(p):
        return solve_equilibria(model, p, m.command[:, 0], m.command[:, 1])

    names = (
        "wire_torsion_scale",
        "catheter_torsion_scale",
        "bending_rigidity_scale",
        "magnet_remanence",
    )
    _check_jacobian(model, params, solve, names, m=m)


def test_friction_acts_through_the_play_in_the_jacobian(demonstrator):
    model = RingPairModel(frozenset({"hysteresis"}))
    params = model.parameters(demonstrator)
    params[index("wire_friction_angle")] = np.deg2rad(3.3)
    params[index("catheter_friction_angle")] = np.deg2rad(1.7)
    m = synthesize(demonstrator, n=12, noise_mm=0.0)
    cmd = m.command

    def solve(p):
        return solve_sequence(model, p, cmd[:, 0], cmd[:, 1])

    names = ("wire_friction_angle", "catheter_friction_angle", "bending_rigidity_scale")
    _check_jacobian(model, params, solve, names, ordered=True, m=m)


@pytest.mark.parametrize("seed", [11, 12])
def test_calibration_recovers_planted_baseline_parameters_within_uncertainty(demonstrator, seed):
    rng = np.random.default_rng(seed)
    nominal = RingPairModel.parameters(demonstrator)
    truth = {
        "bending_rigidity_scale": rng.uniform(0.6, 1.4),
        **{
            f"external_center_{a}": nominal[index(f"external_center_{a}")]
            + rng.uniform(-3e-3, 3e-3)
            for a in "xyz"
        },
    }
    noise = rng.uniform(0.1, 0.5)
    view = str(rng.choice(["3d", "top"]))
    m = synthesize(demonstrator, noise_mm=noise, seed=seed, view=view, params_override=truth)
    res = calibrate(demonstrator, m)
    assert res.converged and not res.at_bounds and res.unconverged == 0
    for name, value in truth.items():
        assert abs(res.estimate[name] - value) < 3 * res.standard_error[name], name
    assert res.noise_mm == pytest.approx(noise, rel=0.3)
    assert np.allclose(np.diag(res.correlation), 1.0)
    coords = 3 if view == "3d" else 2
    assert res.rmse_mm == pytest.approx(noise * np.sqrt(coords), rel=0.35)


def test_calibration_recovers_torsional_rigidity(demonstrator):
    rng = np.random.default_rng(21)
    truth = {
        "wire_torsion_scale": rng.uniform(2.0, 4.0),
        "catheter_torsion_scale": rng.uniform(1.0, 3.0),
    }
    m = synthesize(demonstrator, ["torsion"], noise_mm=0.3, seed=21, params_override=truth)
    res = calibrate(demonstrator, m, ["torsion"])
    assert res.converged
    for name, value in truth.items():
        assert abs(res.estimate[name] - value) < 3 * res.standard_error[name], name
        assert res.standard_error[name] < 0.3 * value


def test_calibration_recovers_friction_from_an_ordered_path(demonstrator):
    truth = {"wire_friction_angle": np.deg2rad(4.0), "catheter_friction_angle": np.deg2rad(2.0)}
    m = synthesize(
        demonstrator, ["hysteresis"], noise_mm=0.3, seed=4, view="top", params_override=truth
    )
    res = calibrate(demonstrator, m, ["hysteresis"])
    assert res.converged
    for name, value in truth.items():
        assert abs(res.estimate[name] - value) < 3 * res.standard_error[name], name


def test_ratio_of_remanence_and_rigidity_is_all_the_baseline_sees(demonstrator):
    m = synthesize(
        demonstrator, noise_mm=0.2, seed=2, params_override={"bending_rigidity_scale": 0.9}
    )
    free = ("bending_rigidity_scale", "external_remanence", "external_center_x")
    res = calibrate(demonstrator, m, free=free)
    assert "determine only 2 of 3" in res.message
    assert np.isinf(res.standard_error["external_remanence"])
    assert np.isinf(res.standard_error["bending_rigidity_scale"])
    with_priors = calibrate(demonstrator, m, free=free, priors=True)
    assert with_priors.converged
    # the prior (10 % on the remanence) is what pins the pair down
    rel = (
        with_priors.standard_error["external_remanence"]
        / with_priors.estimate["external_remanence"]
    )
    assert 0.05 < rel < 0.11
    assert all(np.isfinite(list(with_priors.standard_error.values())))


def _planted_two_factors(demonstrator, ke, kb):
    base = RingPairModel.parameters(demonstrator)
    p = two_factor_parameters(base, ke, kb)
    names = ("bending_rigidity_scale", "external_remanence")
    names += tuple(f"external_center_{a}" for a in "xyz")
    return synthesize(demonstrator, noise_mm=0.0, params_override={n: p[index(n)] for n in names})


def test_grid_search_returns_planted_factors_on_its_grid(demonstrator):
    ke, kb = PAPER_STIFFNESS_GRID[3], PAPER_FIELD_GRID[60]
    grid = grid_search_two_factors(demonstrator, _planted_two_factors(demonstrator, ke, kb))
    assert grid.objective.shape == (10, 101) and grid.evaluations == 1010
    assert grid.stiffness_scale == ke and grid.field_scale == kb
    assert grid.max_abs_mm < 1e-9


def test_grid_search_between_nodes_is_as_good_as_its_resolution(demonstrator):
    step_e = PAPER_STIFFNESS_GRID[1] - PAPER_STIFFNESS_GRID[0]
    step_b = PAPER_FIELD_GRID[1] - PAPER_FIELD_GRID[0]
    ke, kb = PAPER_STIFFNESS_GRID[3] + 0.3 * step_e, PAPER_FIELD_GRID[60] + 0.4 * step_b
    m = _planted_two_factors(demonstrator, ke, kb)
    grid = grid_search_two_factors(
        demonstrator, m, field_grid=PAPER_FIELD_GRID[40:81], objective="rms"
    )
    assert abs(grid.stiffness_scale - ke) <= step_e
    nearest = grid_search_two_factors(
        demonstrator,
        m,
        stiffness_grid=PAPER_STIFFNESS_GRID[3:4],
        field_grid=PAPER_FIELD_GRID[60:61],
        objective="rms",
    )
    assert grid.rmse_mm <= nearest.rmse_mm  # never worse than the grid node nearest the truth
    np.testing.assert_allclose(grid.errors.max() * 1e3, grid.max_abs_mm)


def test_cross_validation_holds_out_whole_configurations(demonstrator):
    m = synthesize(demonstrator, noise_mm=0.3, seed=8)  # the path visits each pair twice
    folds = configuration_folds(m, 5, seed=1)
    for a in range(len(m)):
        same = np.all(m.command == m.command[a], axis=1)
        assert (folds[same] == folds[a]).all()
    np.testing.assert_array_equal(folds, configuration_folds(m, 5, seed=1))
    cv = cross_validate(demonstrator, m, k=5, seed=1)
    fit = calibrate(demonstrator, m)
    assert cv.unconverged == 0 and np.isfinite(cv.fold_rmse_mm).all()
    assert fit.rmse_mm < cv.rmse_mm < 1.5 * fit.rmse_mm


def test_folds_deal_only_configurations_seen(demonstrator):
    """A configuration driven but never seen (x, y, z empty, docs/formats.md) has no error
    to hold out: it is in every training set (fold -1) and never makes a fold of its own;
    the seen ones are dealt as if it were absent."""
    m = synthesize(demonstrator, noise_mm=0.3, seed=8)
    configurations, group = np.unique(m.command, axis=0, return_inverse=True)
    lost = np.isin(np.asarray(group).ravel(), np.arange(0, len(configurations), 3))
    position = m.position.copy()
    position[lost] = np.nan
    partly = dataclasses.replace(m, position=position)
    folds = configuration_folds(partly, 5, seed=1)
    assert (folds[lost] == -1).all()
    assert sorted(set(folds[~lost])) == list(range(5))
    seen_only = configuration_folds(partly.subset(~lost), 5, seed=1)
    np.testing.assert_array_equal(folds[~lost], seen_only)
    n_seen = len(np.unique(m.command[~lost], axis=0))
    with pytest.raises(ValueError, match=f"distinct seen configurations \\({n_seen}\\)"):
        configuration_folds(partly, n_seen + 1)


def test_bad_free_parameters_are_named(demonstrator):
    m = synthesize(demonstrator, n=6, noise_mm=0.1)
    with pytest.raises(ValueError, match="cannot be calibrated"):
        calibrate(demonstrator, m, free=["poisson"])
    with pytest.raises(ValueError, match="distinct"):
        calibrate(demonstrator, m, free=["tip_mass", "tip_mass"])
    with pytest.raises(ValueError, match="between 2 and"):
        configuration_folds(m, 1)


def test_unused_import_guard():
    assert len(default_commands(6)) >= 6 and synthesize_data is not None


def test_path_through_the_play_equals_driving_the_robot(demonstrator):
    """Without torsion the order acts only through the play: the batch shortcut of
    ``predict`` gives the states of :func:`solve_sequence`, rows in any order."""
    model = RingPairModel(frozenset({"hysteresis"}))
    params = model.parameters(demonstrator)
    params[index("wire_friction_angle")] = np.deg2rad(4.0)
    params[index("catheter_friction_angle")] = np.deg2rad(2.0)
    m = synthesize(demonstrator, n=24, noise_mm=0.0)
    shuffled = m.subset(np.random.default_rng(0).permutation(len(m)))
    pred = predict(model, params, shuffled)
    driven = solve_sequence(model, params, m.command[:, 0], m.command[:, 1])
    np.testing.assert_allclose(
        pred.equilibria.position, driven.position[shuffled.sequence], atol=1e-12
    )
    np.testing.assert_allclose(pred.equilibria.command, shuffled.command)


@pytest.mark.parametrize("effects", [(), ("torsion",), ("large_deflection",)])
def test_warm_started_fit_ends_on_the_ramps_states_and_optimum(demonstrator, effects):
    """Warm starts (each evaluation from the last states) change the speed, not the
    answer: the same estimates as a fit whose every state comes from the ramp, and the
    returned residuals are the ramp's at the estimate."""
    truth = {"wire_torsion_scale": 2.5, "catheter_torsion_scale": 1.5}
    seed = 22
    m = synthesize(demonstrator, ["torsion"], n=24, noise_mm=0.3, seed=seed, params_override=truth)
    warm = calibrate(demonstrator, m, effects, max_nfev=20)
    cold = calibrate(demonstrator, m, effects, max_nfev=20, warm_start=False)
    why = f"seed {seed}, {effects}: warm {warm.estimate}, cold {cold.estimate}"
    for name in cold.names:
        assert warm.estimate[name] == pytest.approx(cold.estimate[name], rel=1e-6, abs=1e-9), why
    ramp = solve_equilibria(
        RingPairModel(frozenset(effects)), warm.params, m.command[:, 0], m.command[:, 1]
    )
    np.testing.assert_allclose(warm.residuals, m.position - ramp.position, atol=1e-9)


SNAP_DRAWS = 30
"""Large-deflection bench sets drawn at most until one has a snapped configuration."""


@pytest.mark.parametrize("seed", [2962359177, None], ids=["ci-2962359177", "random"])
def test_warm_starts_from_snapped_states_end_on_the_ramps_optimum(seed):
    """States the ramp reached by a fall (snap-through) are warm-started too, and the fit
    still ends where a fit whose every state comes from the ramp does: large-deflection
    data with snapped configurations, drawn from the whole design space
    (optimize.fitting.planted; the seed is in the message). Seed 2962359177 failed on CI
    when rejected trial steps set the warm starts (one crossed a fold; the fit then
    followed the other state and stopped at twice the ramp's chi2). On random draws the
    answer is the ramp's state at the warm fit's estimate, and its misfit never far above
    the ramp-only fit's."""
    fixed = seed is not None
    seed = int(np.random.SeedSequence().entropy % 2**32) if seed is None else seed
    rng = np.random.default_rng(seed)
    effects = ("large_deflection",)
    for _ in range(SNAP_DRAWS):
        case = draw_planted(rng, frozenset(effects), points=(15, 20))
        if case.synthetic.snapped:
            break
    if not case.synthetic.snapped:  # (seed 708063447 drew its first at the 20th)
        assert not fixed, f"seed {seed}: no snapped configuration in {SNAP_DRAWS} draws"
        pytest.skip(f"seed {seed}: no snapped configuration in {SNAP_DRAWS} draws")
    why = f"seed {seed}: {case.describe()}"
    m = case.measurements
    warm = calibrate(case.design, m, effects, max_nfev=20)
    ramp = predict(RingPairModel(frozenset(effects)), warm.params, m).equilibria.position
    np.testing.assert_allclose(
        warm.residuals, np.where(m.measured, m.position - ramp, np.nan), atol=1e-9, err_msg=why
    )
    cold = calibrate(case.design, m, effects, max_nfev=20, warm_start=False)
    if fixed:
        assert warm.estimate == pytest.approx(cold.estimate, rel=1e-6, abs=1e-9), why
        assert warm.chi2 == pytest.approx(cold.chi2, rel=1e-6), why
    else:
        # Two local searches of an objective that jumps where the ramp's fall changes:
        # they agreed on 58 of 60 measured seeds; of the others the warm fit was once far
        # better (chi2 13 against 6028) and once 1.8 % worse.
        assert warm.chi2 <= 1.1 * cold.chi2, why


def test_warm_starts_on_other_states_refit_with_the_ramp(demonstrator, monkeypatch):
    """Where the warm-started states are not the ramp's at the fit's answer, the fit is
    made again from its start with those rows by the ramp: the answer of a fit without
    warm starts."""
    import optimize.fitting.calibrate.problem as calibration  # where the fit solves

    def elsewhere(model, params, x, start, end):
        """A Newton solve that lands elsewhere for commands with theta1 > 0."""
        out, ok = drive(model, params, x, start, end)
        return np.where(start[0] > 0, out * 1.01, out), ok

    drive = calibration.drive
    monkeypatch.setattr(calibration, "drive", elsewhere)
    m = synthesize(demonstrator, [], n=24, noise_mm=0.3, seed=23)
    warm = calibrate(demonstrator, m, (), max_nfev=20)
    cold = calibrate(demonstrator, m, (), max_nfev=20, warm_start=False)
    moved = int(np.count_nonzero(m.command[:, 0] > 0))
    assert 0 < moved < len(m)
    assert f"fitted again from the start with {moved} row(s) by the load ramp" in warm.message
    assert warm.estimate == pytest.approx(cold.estimate, rel=1e-6)
    assert warm.chi2 == pytest.approx(cold.chi2, rel=1e-6)


def test_held_out_inflation_is_finite_where_one_configuration_alone_fixes_a_parameter():
    """Where one configuration alone fixes a parameter and the Jacobian's columns differ in
    scale by up to 10^6 (a drawn null set of 16 rows failed a test run: from (J^T J)^+ the hat
    matrix was no projection, and the held-out trace came out negative, a math domain
    error), the ratio is a number >= 1: held out, a right model cannot predict better than
    in sample. Random Jacobians; the seed is printed."""
    from optimize.fitting.calibrate import held_out_inflation

    seed = int(np.random.SeedSequence().entropy % 2**32)
    rng = np.random.default_rng(seed)
    for trial in range(300):
        rows, axes, p = int(rng.integers(8, 30)), int(rng.integers(2, 4)), int(rng.integers(2, 7))
        n = rows * axes
        j = rng.normal(size=(n, p)) * 10.0 ** rng.uniform(-1, 5, size=p)
        alone = int(rng.integers(rows))  # the configuration that alone fixes the last one
        j[:, -1] = 0.0
        j[alone * axes : (alone + 1) * axes, -1] = rng.normal(size=axes) * 10.0 ** rng.uniform(
            -1, 5
        )
        j[int(rng.integers(n))] = 0.0  # a coordinate the parameters do not move
        fold = np.repeat(rng.permutation(rows) % 5, axes)
        ratio = held_out_inflation(j, fold, np.ones(n, bool))
        assert np.isfinite(ratio) and ratio >= 1 - 1e-9, f"seed {seed}, trial {trial}: {ratio}"


def test_held_out_inflation_reproduces_refits_of_a_linear_model():
    """For a model linear in its parameters, the expected cross-validated over in-sample
    squared error of held_out_inflation equals that of refitting each fold by least
    squares (an independent Monte Carlo of the refits; Hastie, Tibshirani & Friedman,
    The Elements of Statistical Learning, sec. 7.10): for parameters spread over the
    configurations, and for one that mostly two configurations fix (as a far magnet seen
    from above), where it is larger. Random Jacobians; the seed is printed."""
    from optimize.fitting.calibrate import held_out_inflation

    seed = int(np.random.SeedSequence().entropy % 2**32)
    rng = np.random.default_rng(seed)
    rows, axes = int(rng.integers(14, 30)), int(rng.integers(2, 4))
    p, k = int(rng.integers(3, 8)), 5
    n = rows * axes
    row = np.repeat(np.arange(rows), axes)
    fold = np.arange(rows)[rng.permutation(rows)] % k
    spread = np.nan
    for local in (False, True):
        j = rng.normal(size=(n, p))
        if local:  # the last parameter acts mostly on two configurations of one fold
            two = np.flatnonzero(fold == 0)[:2]
            j[:, -1] = rng.normal(size=n) * np.where(np.isin(row, two), 1.0, 0.01)
        position = np.ones(n, bool)
        expected = held_out_inflation(j, fold[row], position)
        held = fitted = 0.0
        for _ in range(2000):
            y = rng.normal(size=n)
            beta = np.linalg.lstsq(j, y, rcond=None)[0]
            fitted += float(np.sum((y - j @ beta) ** 2))
            for f in range(k):
                out = fold[row] == f
                b_f = np.linalg.lstsq(j[~out], y[~out], rcond=None)[0]
                held += float(np.sum((y[out] - j[out] @ b_f) ** 2))
        why = f"seed {seed}, local {local}: {rows} rows x {axes}, {p} parameters"
        assert expected == pytest.approx(np.sqrt(held / fitted), rel=0.05), why
        if local:
            assert expected > 1.15 * spread, why
        spread = expected


def test_held_out_rows_continue_from_the_full_fits_state(demonstrator):
    """At the full fit's own parameters a held-out row continued from its state is that
    state: the distances equal the full fit's errors (and so the fold's error moves only
    with the fold's parameters, not with a fall of its ramp)."""
    from optimize.fitting.calibrate import _continued

    m = synthesize(demonstrator, ["torsion"], n=20, noise_mm=0.3, seed=5)
    full = calibrate(demonstrator, m, ("torsion",), max_nfev=10)
    held = np.arange(len(m)) % 3 == 0
    e = _continued(RingPairModel(frozenset({"torsion"})), full, full, m, held, None)
    np.testing.assert_allclose(e[held], full.errors[held], rtol=1e-9, atol=1e-12)
    assert np.isnan(e[~held]).all()


@pytest.mark.parametrize("seed", [7, None], ids=["seed-7", "random"])
def test_a_fold_started_from_the_full_fits_states_is_that_fold(monkeypatch, seed):
    """A cross-validation fold starts at the fit of all the data; warm-starting its first
    evaluation from that fit's states (``states``) saves a load ramp of every row and
    changes nothing else: the same estimates (to 1e-3 of their standard errors) and
    residuals (to 1 % of the noise) as the fold fitted without them. A torsion data set
    drawn from the whole design space (seed in the message); states of the wrong shape are
    refused with the expected shape."""
    import optimize.fitting.calibrate.problem as calibration  # where the fit solves

    fixed = seed is not None
    seed = int(np.random.SeedSequence().entropy % 2**32) if seed is None else seed
    case = draw_planted(np.random.default_rng(seed), frozenset({"torsion"}), points=(16, 24))
    why = f"seed {seed}: {case.describe()}"
    m, effects = case.measurements, ("torsion",)
    full = calibrate(case.design, m, effects, max_nfev=15)
    held = np.arange(len(m)) % 4 == 0
    ramped: list[int] = []  # rows solved by the load ramp: in whole predictions, or alone
    solve, whole = calibration.solve_equilibria, calibration.predict

    def counted(model, params, theta1, theta2, *args, **kwargs):
        ramped.append(np.size(theta1))
        return solve(model, params, theta1, theta2, *args, **kwargs)

    def counted_whole(model, params, data, *args, **kwargs):
        ramped.append(len(data))
        return whole(model, params, data, *args, **kwargs)

    monkeypatch.setattr(calibration, "solve_equilibria", counted)
    monkeypatch.setattr(calibration, "predict", counted_whole)
    options = {"rows": ~held, "initial": full.estimate, "max_nfev": 10}
    plain = calibrate(case.design, m, effects, **options)
    rows_plain, ramped[:] = sum(ramped), []
    warm = calibrate(case.design, m, effects, states=full.states, **options)
    # Both searches stop at 10 evaluations: along a flat valley the states' last digits
    # move an unconverged estimate by a little (seed 1446157788: 4e-4 of a torsion scale
    # whose standard error is 1.6e3, 1e-6 of it). A different branch or start moves it by
    # whole standard errors and the residuals by millimetres.
    for name, value in plain.estimate.items():
        shift = abs(warm.estimate[name] - value) / plain.standard_error[name]
        assert shift < 1e-3 or warm.estimate[name] == pytest.approx(value, rel=1e-9), (
            f"{why}: {name} {warm.estimate[name]:.9g} warm, {value:.9g} plain, "
            f"{shift:.2g} standard errors apart"
        )
    noise_m = case.noise_mm * 1e-3
    np.testing.assert_allclose(warm.residuals, plain.residuals, atol=1e-2 * noise_m, err_msg=why)
    if fixed or full.unconverged == 0:
        assert sum(ramped) <= rows_plain - len(m), why  # the first evaluation's ramp
    with pytest.raises(ValueError, match=r"states: expected shape \(\d+, \d+\)"):
        calibrate(case.design, m, effects, states=full.states[:, :2], **options)


def test_a_fit_from_given_states_far_from_its_start_is_the_fit_without_them(demonstrator):
    """Rows' states given to a fit (a fold or a profile refit starts from the full fit's)
    whose one Newton solve at the start fails go through the ramp (a trial version that
    continued warm rows in the parameters failed on given states, whose parameters are
    unknown, and benchmark set [2, 7, 0] then reported no intervals): torsion data, the
    states of a fit of them, a start with the transmissions 4x stiffer; the answer is the
    fit's without the states."""
    truth = {"wire_torsion_scale": 0.5, "catheter_torsion_scale": 0.6}
    m = synthesize(demonstrator, ["torsion"], n=24, noise_mm=0.3, seed=24, params_override=truth)
    fit = calibrate(demonstrator, m, ("torsion",))
    stiff = {n: 4 * fit.estimate[n] for n in truth}
    given = calibrate(demonstrator, m, ("torsion",), initial=stiff, states=fit.states)
    plain = calibrate(demonstrator, m, ("torsion",), initial=stiff)
    assert given.estimate == pytest.approx(plain.estimate, rel=1e-6)
    assert given.chi2 == pytest.approx(plain.chi2, rel=1e-6)


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_a_fit_from_a_symmetric_start_is_as_good_as_the_truth(seed):
    """The magnet on the robot's axis (examples/near_magnet.toml, as in the paper's set-up)
    makes the nominal design its own mirror image: at parallel rings the ramp from rest
    meets a symmetric bifurcation, and which side it takes follows the sign of the fitted
    magnet offsets. These torsion data (ramp states of the truth, top view) once left the
    fit at its start, 3.5 mm RMS on 0.2 mm noise, reported converged: its warm answer fitted
    them, the ramp there tipped four rows to the other side, and every step of the restart
    from the symmetric start tipped them too. Reference: the truth's own misfit (the
    noise); a least-squares fit of the right model is never much worse."""
    design = load_design(Path(__file__).resolve().parents[3] / "examples" / "near_magnet.toml")
    truth = {"wire_torsion_scale": 0.5, "catheter_torsion_scale": 2.0}
    effects = ("torsion",)
    syn = synthesize_data(
        design, effects, n=30, view="top", noise_mm=0.2, seed=seed,
        params_override=truth, record_sigma=True, ordered=False,
    )  # fmt: skip
    m = syn.measurements
    model = RingPairModel(frozenset(effects))
    params = model.parameters(design)
    for name, value in truth.items():
        params[index(name)] = value
    at_truth = predict(model, params, m).equilibria.position
    chi2_truth = float(np.nansum(((at_truth - m.position) / (0.2 * MM)) ** 2))
    fit = calibrate(design, m, effects)
    assert fit.chi2 <= 1.05 * chi2_truth, f"seed {seed}: {fit.message}; {fit.estimate}"


def test_a_fit_of_data_with_a_path_follows_it_where_the_path_matters():
    """On-axis torsion set [99, 9] of optimize.fitting.planted (a 244 mm rod, 15 rows with
    their order, 3-D, 0.38 mm noise): the bench drove the path, and where the robot is
    multistable the states depend on it. Solved each on its own, every start ended at 1.7x
    the noise's RMS distance; fitted along the path (from the start, where the path
    matters already, or from the best), at the noise's (reference: noise x sqrt(3))."""
    seed = [99, 9]
    case = draw_planted(
        np.random.default_rng(seed), frozenset({"torsion"}), points=(16, 30), on_axis=True
    )
    best, fits = calibrate_from_starts(case.design, case.measurements, ("torsion",))
    rms = {k: round(f.rmse_mm, 3) for k, f in fits.items()}
    why = f"seed {seed}: {case.describe()}; RMS {rms}"
    driven = [f for label, f in fits.items() if label.startswith("along the path")]
    assert case.ordered and driven, why
    assert any(best is f for f in driven), why
    assert best.rmse_mm <= 1.3 * case.noise_mm * np.sqrt(3), why
    assert fits["nominal"].rmse_mm > 1.5 * best.rmse_mm, why
