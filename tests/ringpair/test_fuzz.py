"""Property tests of the command line (issue 17): generated design files, study files,
measurement CSVs and option strings, valid, invalid and extreme, through ``ringpair``
in-process. Each run keeps the promises :func:`fuzzing.run_case` checks: exit 0 or 2 and
never a traceback; on exit 2 nothing written; on exit 0 self-consistent rows, strict
JSON and no temporary left; nothing outside its folder.

CI runs a fixed, modest set of examples (derandomised, so a failure reproduces);
``python benchmarks/fuzz.py`` runs many more, at random.
"""

from __future__ import annotations

from fuzzing import data_cases, design_cases, input_cases, option_cases, run_case, study_cases
from hypothesis import HealthCheck, given, settings

CI = settings(
    deadline=None,
    database=None,  # tests write only to temporary folders
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.large_base_example],
)


def _kept_promises(case) -> None:
    outcome = run_case(case)
    assert not outcome.problems, (case.args, outcome.problems, outcome.output[-2000:])


@settings(CI, max_examples=60)
@given(design_cases())
def test_design_files_keep_the_promises(case):
    _kept_promises(case)


@settings(CI, max_examples=40)
@given(option_cases())
def test_option_strings_keep_the_promises(case):
    _kept_promises(case)


@settings(CI, max_examples=60)
@given(data_cases())
def test_measurement_files_keep_the_promises(case):
    _kept_promises(case)


@settings(CI, max_examples=40)
@given(study_cases())
def test_study_files_keep_the_promises(case):
    _kept_promises(case)


@settings(CI, max_examples=15)
@given(input_cases())
def test_hostile_inputs_keep_the_promises(case):
    # file kinds, deep nesting, integers beyond int64, corners of the design space (issue 55)
    _kept_promises(case)
