"""ringpair.optimize: choosing numbers, in two domains that do not import each other.

- :mod:`optimize.sizing`: the robot's dimensions by design NLPs (study files, Pareto
  fronts);
- :mod:`optimize.fitting`: the model against bench data (measurements, calibration,
  profile likelihood, diagnosis, synthetic data).

SI units are used for all inputs and outputs.
"""

from optimize.fitting.calibrate import CalibrationResult, calibrate, cross_validate
from optimize.fitting.diagnose import Diagnosis, diagnose
from optimize.fitting.measurements import (
    MeasurementError,
    Measurements,
    load_dataset,
    load_measurements,
)
from optimize.fitting.synth import synthesize
from optimize.sizing.nlp import OptimizationResult, evaluate_design, optimize_design, pareto_values
from optimize.sizing.studyfile import Study, StudyError, default_study, load_study

__all__ = [
    "CalibrationResult",
    "Diagnosis",
    "MeasurementError",
    "Measurements",
    "Study",
    "StudyError",
    "OptimizationResult",
    "calibrate",
    "cross_validate",
    "default_study",
    "diagnose",
    "evaluate_design",
    "load_dataset",
    "load_measurements",
    "load_study",
    "pareto_values",
    "optimize_design",
    "synthesize",
]
