"""Fitting: the model against bench measurements.

Measured data (:mod:`optimize.fitting.measurements`), synthetic data sets
(:mod:`optimize.fitting.synth`; planted effects on random set-ups across the design space
for the diagnosis benchmark, :mod:`optimize.fitting.planted` and
:mod:`optimize.fitting.setups`), calibration by least squares
(:mod:`optimize.fitting.calibrate`, derivatives from :mod:`optimize.fitting.sensitivity`;
the paper's grid in :mod:`optimize.fitting.paper_grid`), profile-likelihood intervals
(:mod:`optimize.fitting.likelihood`) and model diagnosis (:mod:`optimize.fitting.diagnose`,
residual structure in :mod:`optimize.fitting.structure`, the result and its JSON in
:mod:`optimize.fitting.diagnose.result`; :mod:`optimize.fitting.diagnosis` is its old
name). SI units are used for all inputs and outputs.
"""
