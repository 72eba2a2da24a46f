"""Units at the boundaries: files, options and reports use millimetres, degrees and
megapascals; the code is SI inside. Multiply a boundary value by its constant to get SI,
divide an SI value by it to get the boundary unit."""

import math

MM = 1e-3
"""One millimetre. [m]"""
MPA = 1e6
"""One megapascal. [Pa]"""
DEG = math.pi / 180
"""One degree. [rad]"""
MM3 = 1e-9
"""One cubic millimetre. [m^3]"""
GRAM = 1e-3
"""One gram. [kg]"""
