"""The old name of :mod:`optimize.fitting.diagnose.result` (what a diagnosis found and its
JSON), kept so that imports of it keep working; import from
:mod:`optimize.fitting.diagnose` instead."""

from optimize.fitting.diagnose.result import (
    NULL_REASONS,
    Candidate,
    Cause,
    Diagnosis,
    Fit,
    finite_json,
    parameter_values,
    report_key,
)

__all__ = [
    "NULL_REASONS",
    "Candidate",
    "Cause",
    "Diagnosis",
    "Fit",
    "finite_json",
    "parameter_values",
    "report_key",
]
