"""ringpair.optimize: choosing numbers, in two domains that do not import each other.

- :mod:`optimize.sizing`: the robot's dimensions by design NLPs (study files, Pareto
  fronts);
- :mod:`optimize.fitting`: the model against bench data (measurements, calibration,
  profile likelihood, diagnosis, synthetic data).

SI units are used for all inputs and outputs. The names below load when first used
(:mod:`design.lazy`): the fitting and NLP libraries take a second to import.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from design.lazy import lazy_exports

_WHERE = {
    "CalibrationResult": "optimize.fitting.calibrate",
    "calibrate": "optimize.fitting.calibrate",
    "cross_validate": "optimize.fitting.calibrate",
    "Diagnosis": "optimize.fitting.diagnose",
    "diagnose": "optimize.fitting.diagnose",
    "MeasurementError": "optimize.fitting.measurements",
    "Measurements": "optimize.fitting.measurements",
    "load_dataset": "optimize.fitting.measurements",
    "load_measurements": "optimize.fitting.measurements",
    "synthesize": "optimize.fitting.synth",
    "OptimizationResult": "optimize.sizing.nlp",
    "evaluate_design": "optimize.sizing.nlp",
    "optimize_design": "optimize.sizing.nlp",
    "pareto_values": "optimize.sizing.nlp",
    "Study": "optimize.sizing.studyfile",
    "StudyError": "optimize.sizing.studyfile",
    "default_study": "optimize.sizing.studyfile",
    "load_study": "optimize.sizing.studyfile",
}
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

__getattr__, __dir__ = lazy_exports(__name__, _WHERE)

if TYPE_CHECKING:
    from optimize.fitting.calibrate import CalibrationResult, calibrate, cross_validate
    from optimize.fitting.diagnose import Diagnosis, diagnose
    from optimize.fitting.measurements import (
        MeasurementError,
        Measurements,
        load_dataset,
        load_measurements,
    )
    from optimize.fitting.synth import synthesize
    from optimize.sizing.nlp import (
        OptimizationResult,
        evaluate_design,
        optimize_design,
        pareto_values,
    )
    from optimize.sizing.studyfile import Study, StudyError, default_study, load_study
