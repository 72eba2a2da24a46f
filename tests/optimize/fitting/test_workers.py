"""Worker processes (optimize.fitting.workers): a diagnosis' independent fits give, on
forked workers (and with its first screen started in the background), exactly the numbers
they give in one process, from set-ups drawn over the whole design space; a dead worker
costs time, not the result; a bad worker count is named."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from optimize.fitting import workers
from optimize.fitting.calibrate import cross_validate, default_free
from optimize.fitting.diagnose import diagnose
from optimize.fitting.planted import draw_planted
from optimize.fitting.workers import Background, parallel_map, worker_count


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


def test_a_diagnosis_on_workers_equals_one_process(monkeypatch):
    """Every candidate's BIC change and verdict, the causes and the final cross-validated
    error of a diagnosis on two workers (the first screen's fits from the nominal design
    started in the background while the baseline is fitted) and in one process, on a
    torsion data set drawn from the whole design space (torsion: its screen has every kind
    of start that runs in the background)."""
    seed = int(np.random.SeedSequence().entropy % 2**32)
    case = draw_planted(np.random.default_rng(seed), frozenset({"torsion"}), points=(16, 24))
    runs = []
    for count in ("1", "2"):
        monkeypatch.setenv("RINGPAIR_WORKERS", count)
        d = diagnose(case.design, case.measurements, candidates=("torsion", "gravity"))
        table = {n: (c.bic_change, c.verdict) for n, c in d.candidates.items()}
        runs.append(([c.name for c in d.causes], table, d.final.cv_rmse_mm))
    alone, spread = runs
    assert spread == alone, f"seed {seed}: {case.describe()}"


def _pid_and_square(x: int) -> tuple[int, int]:
    return os.getpid(), x * x


def test_background_work_runs_in_another_process_in_order(monkeypatch):
    monkeypatch.setenv("RINGPAIR_WORKERS", "2")
    background = Background(_pid_and_square, [1, 2, 3])
    results = background.results()
    assert [r[1] for r in results] == [1, 4, 9]
    assert {r[0] for r in results} != {os.getpid()}


def _slow_square(x: int) -> int:
    time.sleep(0.5)
    return x * x


def test_stopped_background_work_leaves_the_items_it_did_not_take(monkeypatch):
    """After stop, the worker starts no more items: it hands back what it took (started or
    done), the rest are the caller's; results are those of the items taken."""
    monkeypatch.setenv("RINGPAIR_WORKERS", "2")
    items = list(range(40))
    background = Background(_slow_square, items)
    waited = time.monotonic()
    while background._claimed.value < 1 and time.monotonic() - waited < 60:
        time.sleep(0.05)  # until the worker has taken its first item
    taken = background.stop()
    assert 1 <= len(taken) < len(items) and taken == items[: len(taken)]
    assert background.stop() == taken  # stopping again changes nothing
    assert background.results() == [x * x for x in taken]


def test_background_work_of_one_worker_is_left_to_this_process(monkeypatch):
    monkeypatch.setenv("RINGPAIR_WORKERS", "1")
    assert Background(_pid_and_square, [2, 3]).results() == [(os.getpid(), 4), (os.getpid(), 9)]
    assert Background(_pid_and_square, [2, 3]).stop() == []


def test_background_work_whose_worker_dies_is_done_in_this_process(monkeypatch):
    monkeypatch.setenv("RINGPAIR_WORKERS", "2")
    assert Background(_square_unless_in_a_worker, [1, 2, 3]).results() == [1, 4, 9]


def test_a_cancelled_background_worker_is_gone(monkeypatch):
    monkeypatch.setenv("RINGPAIR_WORKERS", "2")
    background = Background(_slow_square, list(range(20)))
    process = background._process
    background.cancel()
    assert not process.is_alive()


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
