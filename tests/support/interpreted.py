"""A model's solver functions evaluated in CasADi's virtual machine instead of compiled,
for tests that solve a few configurations of a model no other test uses.

A drawn field layout (a cuboid, a sphere, a coil and a uniform field beside the external
magnet) makes 7.5 MB of C, which takes one to two minutes to compile on one core per set
of effects; evaluated in the virtual machine the same expressions (the same graph that
would be compiled, :mod:`design.compiled`) build in ~2 s and solve two configurations in
~0.2 s. That compiled code computes what the virtual machine does is checked on the field
kernels themselves (tests/design/model/test_field_sources.py)."""

from __future__ import annotations

import warnings
from unittest.mock import patch

import design.compiled
from design.equilibrium.kernels import kernels
from design.model import RingPairModel


def interpreted(model: RingPairModel) -> RingPairModel:
    """``model``, its solver's functions (:func:`design.equilibrium.kernels.kernels`, kept
    for the process) built for CasADi's virtual machine unless built already."""
    with patch.object(design.compiled, "_compiler", lambda: None), warnings.catch_warnings():
        warnings.filterwarnings("ignore", "no C compiler found", RuntimeWarning)
        kernels(model)
    return model
