"""Physical constants, SI."""

MU0 = 1.25663706127e-6
"""Vacuum permeability, CODATA 2022: the value scipy, and so magpylib, use, so the oracle
tests compare like with like. [T m / A]"""
