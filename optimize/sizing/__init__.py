"""Sizing: choosing the robot's dimensions, materials and magnet placement.

Study files (:mod:`optimize.sizing.studyfile`: what is free, within which bounds, under
which constraints and objective), the design NLP on the model's own expressions
(:mod:`optimize.sizing.nlp_problem`, solved by :mod:`optimize.sizing.nlp`), and Pareto
fronts (:mod:`optimize.sizing.pareto`). SI units are used for all inputs and outputs.
"""
