"""Worker processes (optimize.fitting.workers): a diagnosis' independent fits give, on
forked workers, exactly the numbers they give in one process, from set-ups drawn over the
whole design space; a dead worker costs time, not the result; a bad worker count is
named."""

from __future__ import annotations

import os

import numpy as np
import pytest

from optimize.fitting import workers
from optimize.fitting.calibrate import cross_validate, default_free
from optimize.fitting.planted import draw_planted
from optimize.fitting.workers import parallel_map, worker_count


def test_cross_validation_folds_on_workers_equal_one_process(monkeypatch):
    """The folds of a cross-validation, fitted on two workers and in one process, on a
    torsion data set drawn from the whole design space (optimize.fitting.planted)."""
    seed = int(np.random.SeedSequence().entropy % 2**32)
    case = draw_planted(np.random.default_rng(seed), frozenset({"torsion"}), points=(16, 24))
    effects = frozenset({"torsion"})
    runs = []
    for count in ("1", "2"):
        monkeypatch.setenv("RINGPAIR_WORKERS", count)
        runs.append(
            cross_validate(
                case.design, case.measurements, effects, default_free(effects), k=4, seed=0
            )
        )
    alone, spread = runs
    np.testing.assert_array_equal(
        spread.errors, alone.errors, err_msg=f"seed {seed}: {case.describe()}"
    )
    np.testing.assert_array_equal(spread.folds, alone.folds)
    assert spread.rmse_mm == alone.rmse_mm or (
        np.isnan(spread.rmse_mm) and np.isnan(alone.rmse_mm)
    ), f"seed {seed}"


def _square_unless_in_a_worker(x: int) -> int:
    if workers._IN_WORKER:
        os._exit(3)  # a worker dies (as on a crash in native code)
    return x * x


def test_a_worker_that_dies_leaves_the_work_to_this_process(monkeypatch):
    monkeypatch.setenv("RINGPAIR_WORKERS", "2")
    assert parallel_map(_square_unless_in_a_worker, [1, 2, 3]) == [1, 4, 9]


def test_a_worker_runs_its_own_work_serially(monkeypatch):
    """No worker forks workers of its own: inside one the count is 1."""
    monkeypatch.setenv("RINGPAIR_WORKERS", "2")
    assert parallel_map(lambda _: worker_count(), [0, 1]) == [1, 1]
    assert parallel_map(lambda _: os.getpid(), [0, 1]) != [os.getpid()] * 2


@pytest.mark.parametrize("text", ["two", "0", "-1", "1.5"])
def test_a_bad_worker_count_is_named(monkeypatch, text):
    monkeypatch.setenv("RINGPAIR_WORKERS", text)
    with pytest.raises(ValueError, match=rf"RINGPAIR_WORKERS .* at least 1; got '{text}'"):
        worker_count()
