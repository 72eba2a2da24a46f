"""Pareto sweeps on a real local Dask cluster: monotone fronts, resuming, failed points."""

from __future__ import annotations

from studies import SMALL

from optimize.sizing.nlp import evaluate_design, kept_optimum, optimize_design
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


def test_a_bound_the_looser_answer_meets_keeps_it_as_the_epsilon_constraint_method_says():
    """Along a sweep the feasible set only shrinks, so an optimum that meets the tighter
    bound is the optimum there (the epsilon-constraint method; Haimes, Lasdon & Wismer
    1971): :func:`kept_optimum` returns it without a solve, and IPOPT solving that point
    from the study's own start reaches the same disc radius; a bound it breaks is
    solved. The bound's state is checked against the forward evaluation's."""
    study = loads_study(SWEEP)
    best = optimize_design(study)
    distance = best.values["external_distance"]
    for below in (5e-3, 0.0):
        kept = kept_optimum(study, "external_distance", distance - below, best)
        assert kept is not None and kept.design == best.design
        assert kept.objective == best.objective and kept.epsilon == {
            "external_distance": distance - below
        }
        state = next(s for s in kept.constraints if s.name == "epsilon.external_distance")
        forward = evaluate_design(
            study, best.design, best.materials, {"external_distance": distance - below}
        )
        twin = next(s for s in forward.constraints if s.name == state.name)
        assert abs(state.value - twin.value) < 1e-12 and abs(state.margin - twin.margin) < 1e-12
        assert abs(state.margin - below) < 1e-9
        assert state.active == (below == 0.0) == (state.name in kept.active)
    direct = optimize_design(study, epsilon={"external_distance": distance - 5e-3})
    assert direct.feasible and abs(direct.objective - best.objective) <= 1e-6
    assert kept_optimum(study, "external_distance", distance + 5e-3, best) is None
    result, error = _solve_point(
        study, "external_distance", distance + 5e-3, best.values, (best, "")
    )
    assert not error and result is not None and result.seconds > 0
    assert result.objective < best.objective  # a farther magnet, a smaller disc


def test_each_sweep_is_two_interleaved_chains_from_the_optimum():
    """Point i of a sweep continues from point i - 2 of the same sweep (its chain's next
    looser bound); a sweep's first two points start from the optimum, so a 6-point sweep
    is two chains of 3 the two workers can run side by side."""
    from optimize.sizing.pareto import CHAINS, predecessor

    plan = [("magnet_volume", e, None) for e in (6, 5, 4, 3, 2, 1)]
    plan += [("external_distance", e, None) for e in (1, 2, 3)]
    chains = [predecessor(plan, i) for i in range(len(plan))]
    assert CHAINS == 2
    assert chains == [None, None, 0, 1, 2, 3, None, None, 6]
