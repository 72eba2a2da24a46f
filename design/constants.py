"""Physical constants, SI."""

import math

MU0 = 4e-7 * math.pi
"""Vacuum permeability (the pre-2019 exact value; the CODATA 2018 value differs by 5e-10
relative, far below anything modelled here). [T m / A]"""
