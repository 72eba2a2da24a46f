"""Random set-ups from the whole design space the tool accepts, for property tests: the
generator lives in the package (:mod:`optimize.fitting.setups`, the diagnosis benchmark
draws from it at run time); the effect sets here are the tests' own."""

from __future__ import annotations

import itertools

from optimize.fitting.setups import face_distance, random_design

EFFECT_SETS = tuple(
    frozenset(c)
    for k in range(5)
    for c in itertools.combinations(("near_field", "large_deflection", "torsion", "gravity"), k)
)
"""Every set of the effects that act on a configuration on its own (hysteresis needs a
path)."""

__all__ = ["EFFECT_SETS", "face_distance", "random_design"]
