"""The diagnosis on set-ups it has never seen: a fixed-seed sample of the benchmark's
planted data sets (:mod:`optimize.fitting.planted`, ``benchmarks/diagnose.py``).

Each case draws a nominal design from the whole design space, a robot as built that
differs from it, the planted effects and a bench run with noise; the diagnosis gets only
the design file and the data, written as a data-set folder and read back (as a user's).
Two data sets per effect, two pairs and two null sets, and a null set, torsion and
torsion with gravity with the magnet on the robot's axis; the sample keeps to 16-30
configurations to fit CI's time (the benchmark draws 16-80). The generator's criterion
makes every planted effect detectable (the best model without it leaves at least
DETECTABLE noise sigmas per coordinate on the noise-free data); a case that is not says
so and fails.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from optimize.fitting.calibrate import UnsolvedStart, calibrate, default_free
from optimize.fitting.diagnose import (
    BIC_DROP,
    MIN_SOLVED,
    SCREEN_EVALUATIONS,
    _centre_scan,
    _fit,
    _refine,
    diagnose,
    screen_starts,
)
from optimize.fitting.measurements import load_dataset, save_dataset
from optimize.fitting.planted import PLANTABLE, PLANTED_SETS, Planted, draw_planted
from optimize.fitting.workers import parallel_map

SEED = 15
"""The sample's seed (a case's generator is seeded with (SEED, its planted set's index in
PLANTED_SETS, its number))."""
POINTS = (16, 30)
PAIRS = (frozenset({"torsion", "gravity"}), frozenset({"near_field", "large_deflection"}))
CASES = [(frozenset(), j) for j in range(2)]
CASES += [(frozenset({e}), j) for e in PLANTABLE for j in range(2)]
CASES += [(pair, 0) for pair in PAIRS]
ON_AXIS = [frozenset(), frozenset({"torsion"}), frozenset({"torsion", "gravity"})]
"""... and three with the magnet on the robot's axis (the paper's arrangement, symmetric:
:func:`optimize.fitting.setups.on_axis`), numbered from ON_AXIS_NUMBER."""
ON_AXIS_NUMBER = 10
CASES += [(p, ON_AXIS_NUMBER) for p in ON_AXIS]


def drawn(planted: frozenset[str], first: int, number: int, **options) -> tuple[Planted, str]:
    """The benchmark's set of ``planted`` drawn from the seed [first, its index in
    PLANTED_SETS, number] (``options``: :func:`draw_planted`'s), and a line naming it for
    failure messages."""
    seed = [first, PLANTED_SETS.index(planted), number]
    case = draw_planted(np.random.default_rng(seed), planted, **options)
    return case, f"seed {seed}: {case.describe()}"


FIT = {"k": 5, "seed": 0, "cv": False, "sigma": None}
"""The fits' options in these tests (:func:`_fit`): folds as the diagnosis', no CV."""
SCREEN = {**FIT, "max_nfev": SCREEN_EVALUATIONS}
"""... and a screen's budget."""


@pytest.mark.slow
@pytest.mark.parametrize(
    ("planted", "number"),
    CASES,
    ids=[
        f"{'+'.join(sorted(p)) or 'null'}-{'on-axis' if j >= ON_AXIS_NUMBER else j}"
        for p, j in CASES
    ],
)
def test_the_planted_effects_are_named_and_nothing_else(planted, number, tmp_path):
    case, why = drawn(planted, SEED, number, points=POINTS, on_axis=number >= ON_AXIS_NUMBER)
    assert case.detectable, f"not detectable after {case.tries} draws: {why}"
    design, m = load_dataset(save_dataset(tmp_path / "set", case.design, case.measurements))
    result = diagnose(design, m, seed=number)
    doc = result.to_json()
    verdicts = "; ".join(f"{k}: {c['verdict']}" for k, c in doc["candidates"].items())
    why += f"; named {[c.name for c in result.causes]}; {verdicts}"
    assert {c.name for c in result.causes} == set(planted), why
    # every candidate carries its verdict; the JSON is strict (null, never NaN)
    assert all(c["verdict"] for c in doc["candidates"].values()), why
    json.dumps(doc, allow_nan=False)
    # what is left is the noise: RMS distance ~ noise x sqrt(measured axes)
    axes = 3 if case.view == "3d" else 2
    assert result.final.cv_rmse_mm <= 1.3 * case.noise_mm * math.sqrt(axes), why


@pytest.mark.slow
def test_gravity_frees_the_field_strength_it_separates():
    """The benchmark's gravity set (seed [2, 4, 0]): the robot as built has its external
    remanence 10 % off; gravity's known rod weight separates it from the bending rigidity,
    and the diagnosis' refit with it free (``_refine``) brings the held-out error to the
    noise (CV RMSE 2.24x the noise with it fixed, benchmarks/diagnose.py)."""
    case, why = drawn(frozenset({"gravity"}), 2, 0)
    effects = frozenset({"gravity"})
    fixed = _fit(case.design, case.measurements, effects, starts=[None], **{**FIT, "cv": True})
    tried: dict = {}
    refined = _refine(
        case.design, case.measurements, fixed, tried, k=5, seed=0, sigma=None, say=print
    )
    noise = case.noise_mm * math.sqrt(3 if case.view == "3d" else 2)
    assert fixed.cv_rmse_mm > 1.3 * noise, why  # the set shows what the refit is for
    assert "external_remanence" in refined.calibration.names, f"{why}; {tried}"
    assert refined.cv_rmse_mm <= 1.3 * noise, why
    (verdict,) = [c.verdict for c in tried.values()]
    assert verdict.startswith("accepted"), why


@pytest.mark.slow
def test_every_passing_candidate_is_fitted_in_full_before_one_is_added():
    """The benchmark's near-field-with-torsion set (seed [2, 7, 0]: a 97 mm rod, 33 rows
    without order): on top of torsion, large deflection's screening fit ranks above near
    field's, and a search that fitted in full only the first passing candidate added
    large deflection, then gravity (CV 1.78x the noise). Fitting every passing candidate
    in full, near field wins on its full BIC and the final model reaches the planted
    model's CV (1.09x the noise; the goal 1.3x)."""
    planted = frozenset({"near_field", "torsion"})
    case, why = drawn(planted, 2, 0)
    result = diagnose(case.design, case.measurements, seed=0)
    verdicts = {k: c.verdict for k, c in result.candidates.items()}
    why += f"; {verdicts}"
    assert {c.name for c in result.causes} == set(planted), why
    assert verdicts["large_deflection+torsion"].startswith("rejected"), why
    assert "near_field+torsion fits better" in verdicts["large_deflection+torsion"], why
    noise = case.noise_mm * math.sqrt(3 if case.view == "3d" else 2)
    assert result.final.cv_rmse_mm <= 1.3 * noise, why


@pytest.mark.slow
def test_a_screen_of_torsion_along_a_path_reaches_the_soft_transmissions_basin():
    """A drawn gravity-with-torsion set (seed [5, 13, 0]: a 208 mm rod, 57 rows with their
    order, top view; transmissions 0.41 and 0.62 x their nominal torsional rigidity).
    Screened on top of gravity from the current estimates, the nominal design and stiffer
    transmissions only, torsion stayed in basins of ~10 times the noise's misfit, and the
    diagnosis named friction play to absorb the rest. One of the screen's starts must
    reach the noise (the fit from the truth does: RSS 3.0e-6 m^2 on 114 coordinates of
    0.18 mm noise)."""
    planted = frozenset({"gravity", "torsion"})
    case, why = drawn(planted, 5, 0)
    design, m = case.design, case.measurements
    current = _fit(design, m, frozenset({"gravity"}), starts=[None], **SCREEN)

    def misfit(start):
        try:
            fit = _fit(design, m, planted, starts=[start], free=default_free(planted), **SCREEN)
        except UnsolvedStart:
            return math.inf
        return fit.rss if fit.unsolved == 0 else math.inf

    rss = parallel_map(misfit, screen_starts(current, planted, {}))
    noise_rss = int(m.measured.sum()) * (case.noise_mm * 1e-3) ** 2
    assert min(rss) < 1.5 * noise_rss, f"{why}; RSS / noise's {np.array(rss) / noise_rss}"


@pytest.mark.slow
def test_a_screen_of_the_near_field_starts_from_the_centre_that_fits_best():
    """A drawn near-field set (seed [5, 1, 0]: a 217 mm rod, 54 rows in 3-D without
    order, the magnet's centre 3.5 mm off the file's along z). From the calibrated
    baseline's estimates and from the nominal design, the near-field screen ended at 300
    and 110 times the noise's misfit (BIC +540 on the baseline's) and the diagnosis named
    nothing: near the magnet the rows' states change branch with where it is, and the
    dipole-field baseline put it 4 mm off. Moved by the scan, the centre gives a start
    from which the screen passes (BIC -388 from the noise-level fit of the truth)."""
    planted = frozenset({"near_field"})
    case, why = drawn(planted, 5, 0)
    design, m = case.design, case.measurements
    baseline = _fit(design, m, frozenset(), starts=[None], **FIT)
    start = _centre_scan(design, m, baseline, planted, default_free(planted))
    assert start is not None, why
    screen = _fit(design, m, planted, starts=[start], **SCREEN)
    assert screen.bic() - baseline.bic() < -BIC_DROP, f"{why}; BIC {screen.bic() - baseline.bic()}"


@pytest.mark.slow
def test_a_screen_of_the_near_field_also_scans_the_centre_about_the_nominal_design():
    """A drawn near-field set (seed [7, 1, 0]: a 214 mm rod, 75 rows in 3-D with their
    order, noise 0.14 mm, margin 130). The dipole-field baseline ran to a rod 10 times
    stiffer (which snaps nowhere), and the near-field screens from its estimates, with the
    centre moved or not, and from the nominal design (to a rod 230 times stiffer) ended at
    15,000-20,000 times the noise's misfit: the diagnosis named nothing (CV 62x the
    noise). About the nominal design the centre moved 2 mm along z fits at 50 times the
    noise's misfit (0.166 -> 0.0002 m^2), and the screen from there reaches the noise."""
    planted = frozenset({"near_field"})
    case, why = drawn(planted, 7, 0)
    design, m = case.design, case.measurements
    start = _centre_scan(design, m, None, planted, default_free(planted))
    assert start is not None, why
    screen = _fit(design, m, planted, starts=[start], **SCREEN)
    noise_rss = int(m.measured.sum()) * (case.noise_mm * 1e-3) ** 2
    assert screen.rss < 1.5 * noise_rss, f"{why}; RSS / noise's {screen.rss / noise_rss:.3g}"


@pytest.mark.slow
def test_a_screen_from_where_the_rod_is_pulled_onto_the_magnet_also_starts_stiffer():
    """A drawn large-deflection-with-torsion set (seed [3, 10, 0]: a 211 mm rod, 39 rows
    with their order, margin of the large deflection 5). At the nominal design the
    large-deflection rod is pulled onto the magnet at 24 of 39 configurations, so a screen
    from there was skipped (as from the torsion model's estimates) and the diagnosis named
    torsion alone, CV 5.2 times the noise. From the rod twice as stiff (STIFFER) every row
    has a state, and the screen passes on top of torsion."""
    planted = frozenset({"large_deflection", "torsion"})
    case, why = drawn(planted, 3, 0)
    design, m = case.design, case.measurements
    with pytest.raises(UnsolvedStart):
        calibrate(design, m, planted, max_nfev=SCREEN_EVALUATIONS, min_solved=MIN_SOLVED)
    torsion = _fit(design, m, frozenset({"torsion"}), starts=[None], **FIT)
    screen = _fit(design, m, planted, starts=[None], **SCREEN)
    assert screen.unsolved == 0, why
    assert screen.bic() - torsion.bic() < -BIC_DROP, f"{why}; BIC {screen.bic() - torsion.bic()}"


@pytest.mark.slow
def test_a_fit_that_leaves_a_row_pulled_onto_the_magnet_looks_nearby_for_its_state():
    """A drawn friction-with-near-field set (seed [3, 9, 1]: a 126 mm rod, 51
    configurations along a path, 23 of them lost onto the magnet and not seen). Fitted
    from the truth, the planted model reached 1.07 times the noise's RMS on the other rows
    but left one pulled onto the magnet, charged the straight robot's miss: BIC +90 on
    the friction model's, and the diagnosis did not name the near field. The centre moved
    0.5 mm (UNSOLVED_OFFSETS) gives that row its state; the fit from there must solve
    every row at the noise and pass."""
    planted = frozenset({"hysteresis", "near_field"})
    case, why = drawn(planted, 3, 1)
    design, m = case.design, case.measurements
    friction = _fit(design, m, frozenset({"hysteresis"}), starts=[None], **SCREEN)
    free = default_free(planted)
    truth = {n: v for n, v in case.truth.items() if n in free}
    screen = _fit(design, m, planted, starts=[truth], free=free, **SCREEN)
    assert screen.unsolved == 0, why
    noise_rms = case.noise_mm * math.sqrt(3)
    assert screen.calibration.rmse_mm < 1.2 * noise_rms, why
    assert screen.bic() - friction.bic() < -BIC_DROP, f"{why}; BIC {screen.bic() - friction.bic()}"


@pytest.mark.slow
def test_a_path_is_fitted_from_its_first_rows_and_friction_from_its_levels():
    """The benchmark's friction-with-near-field set (seed [3, 9, 0]: a 139 mm rod, 63 rows
    along a path near the magnet). The near-field model fitted the whole path at 12x the
    noise's RMS with a rod 20x stiffer than built, which snaps nowhere, and friction on
    top of it failed (BIC +70): the diagnosis named gravity and large deflection instead
    (CV 6.5x the noise). Fitted first on the path's first rows (PREFIX_SHARE), the near
    field reaches 2.3x; from there, with the catheter's friction at one of
    LEVELS (a local fit cannot climb the staircase of stick and slip), friction
    reaches the noise and pays."""
    planted = frozenset({"hysteresis", "near_field"})
    case, why = drawn(planted, 3, 0)
    design, m = case.design, case.measurements
    noise_rms = case.noise_mm * math.sqrt(3)
    near = _fit(design, m, frozenset({"near_field"}), starts=[None], **FIT)
    assert near.calibration.rmse_mm < 3 * noise_rms, f"{why}; {near.calibration.rmse_mm:.3g}"
    screen = _fit(design, m, planted, starts=[near.calibration], **SCREEN)
    assert screen.unsolved == 0, why
    assert screen.calibration.rmse_mm < 1.3 * noise_rms, f"{why}; {screen.calibration.rmse_mm}"
    assert screen.bic() - near.bic() < -BIC_DROP, f"{why}; BIC {screen.bic() - near.bic()}"
