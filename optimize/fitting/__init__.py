"""Fitting: the model against bench measurements.

Measured data (:mod:`optimize.fitting.measurements`), synthetic data sets
(:mod:`optimize.fitting.synth`), calibration by least squares
(:mod:`optimize.fitting.calibrate`, derivatives from :mod:`optimize.fitting.sensitivity`;
the paper's grid in :mod:`optimize.fitting.paper_grid`), profile-likelihood intervals
(:mod:`optimize.fitting.likelihood`) and model diagnosis (:mod:`optimize.fitting.diagnose`).
SI units are used for all inputs and outputs.
"""
