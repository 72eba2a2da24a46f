"""Pareto sweeps on a real local Dask cluster: monotone fronts, resuming, failed points."""

from __future__ import annotations

from studies import SMALL

from optimize.sizing.nlp import optimize_design
from optimize.sizing.pareto import _solve_point, is_monotone, point_key, run_sweeps
from optimize.sizing.studyfile import loads_study

SWEEP = (
    SMALL
    + """
[[pareto]]
against = "external_distance"
points = 3
"""
)


def test_sweep_on_two_dask_workers_is_monotone_and_resumes(tmp_path):
    study = loads_study(SWEEP)
    seen = []
    first = run_sweeps(study, tmp_path, workers=2, progress=lambda d, n: seen.append((d, n)))
    points = first.sweeps["external_distance"]
    assert first.solved == 3 and first.resumed == 0 and first.workers == 2
    assert seen[-1] == (3, 3)
    assert all(p.feasible for p in points)
    assert [p.epsilon for p in points] == sorted(p.epsilon for p in points)
    assert is_monotone(points)  # a farther magnet never helps the disc radius here
    assert points[-1].objective < points[0].objective
    # Each point is the NLP with that bound: solved here in-process from the study's own
    # start, it reaches the optimum the sweep reached from its neighbour's design
    # (continuation in the bound), to within 1 um of disc radius (IPOPT's tolerance).
    direct = optimize_design(study, epsilon={"external_distance": points[1].epsilon})
    assert abs(points[1].objective - direct.objective) <= 1e-6
    again = run_sweeps(study, tmp_path, workers=2)
    assert again.solved == 0 and again.resumed == 3
    assert [p.objective for p in again.sweeps["external_distance"]] == [p.objective for p in points]


def test_changed_inputs_are_not_taken_for_solved_ones():
    study = loads_study(SWEEP)
    other = loads_study(SWEEP.replace("twist_limit_deg = 20.0", "twist_limit_deg = 19.0"))
    key = point_key(study, "external_distance", 0.1)
    assert key == point_key(loads_study(SWEEP), "external_distance", 0.1)
    assert key != point_key(other, "external_distance", 0.1)
    assert key != point_key(study, "external_distance", 0.1000001)
    # a point continued from a neighbour is not taken for one solved from the study's starts
    assert key != point_key(study, "external_distance", 0.1, ("continuation", []))


def test_a_point_that_raises_is_recorded_not_fatal():
    result, error = _solve_point(None, "external_distance", 0.1)  # type: ignore[arg-type]
    assert result is None and error.startswith("AttributeError")
