"""ringpair.optimize: choosing numbers.

Design studies and their NLPs (:mod:`optimize.study`, :mod:`optimize.nlp`), measured
data (:mod:`optimize.measurements`, :mod:`optimize.synth`), calibration
(:mod:`optimize.calibrate`) and model diagnosis (:mod:`optimize.diagnose`).
SI units are used for all inputs and outputs.
"""

from optimize.calibrate import CalibrationResult, calibrate, cross_validate
from optimize.diagnose import Diagnosis, diagnose
from optimize.measurements import MeasurementError, Measurements, load_dataset, load_measurements
from optimize.nlp import StudyResult, evaluate_design, pareto_values, solve_study
from optimize.study import Study, StudyError, default_study, load_study
from optimize.synth import synthesize

__all__ = [
    "CalibrationResult",
    "Diagnosis",
    "MeasurementError",
    "Measurements",
    "Study",
    "StudyError",
    "StudyResult",
    "calibrate",
    "cross_validate",
    "default_study",
    "diagnose",
    "evaluate_design",
    "load_dataset",
    "load_measurements",
    "load_study",
    "pareto_values",
    "solve_study",
    "synthesize",
]
