"""The entries for configurations on their own: the state by the load ramp, the exact
check of given states, and a design's states."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from design.equilibrium import settings
from design.equilibrium.finish import Equilibria, _commands, _finish
from design.equilibrium.newton import _check, _Checks
from design.equilibrium.paths import solve_sequence
from design.equilibrium.ramp import _ramp
from design.model import RingPairModel
from design.records import Design


def solve_equilibria(
    model: RingPairModel,
    params: np.ndarray,
    theta1: ArrayLike,
    theta2: ArrayLike,
    *,
    multistable: bool = False,
    neighbours: np.ndarray | None = None,
    max_load_step: float = settings.MAX_LOAD_STEP,
) -> Equilibria:
    """The state of each configuration on its own (commanded ring angles (theta1[i],
    theta2[i]) [rad]): the stable equilibrium connected to the unloaded robot by the load
    ramp (module docstring).

    params : model parameter vector, shape (k,), from ``model.parameters(design)``, or one
        per configuration, shape (k, N). [SI]
    multistable : also look for other stable states at each command (costs a few more
        solves per configuration).
    neighbours : shape (N, k), the configurations next to each (-1 for none; a grid's):
        another stable state found at one is looked for from there at its neighbours,
        so that the search follows a branch instead of depending on where Newton from a
        far start lands.
    max_load_step : largest step of the load ramp (smaller: a finer ramp, for checks).
    ``hysteresis`` needs an order, so here it is ignored (the commands are taken as reached
    from the centre of the play); use :func:`solve_sequence` for ordered commands.
    """
    params = np.asarray(params, float)
    command = _commands(theta1, theta2)
    checks = _Checks(command.shape[1])
    x, reached, snapped, failure = _ramp(model, params, command, checks, max_load_step)
    return _finish(
        model, params, command, x, reached, snapped, failure, checks, multistable, neighbours
    )


def stable_states(
    model: RingPairModel, params: np.ndarray, unknowns: np.ndarray, command: np.ndarray
) -> np.ndarray:
    """Whether each given state is a converged, stable equilibrium (the exact check).

    unknowns : shape (n, N). command : shape (2, N). [SI]
    """
    converged, stable, _ = _check(model, np.asarray(params, float), command, unknowns)
    return converged & stable


def solve_design(
    design: Design,
    theta1: ArrayLike,
    theta2: ArrayLike,
    model: RingPairModel | None = None,
    ordered: bool = False,
    multistable: bool = False,
) -> Equilibria:
    """The states of ``design`` (baseline model unless given, for ``design``'s field:
    :meth:`RingPairModel.for_design`) for commanded angles. [rad]

    ordered : follow the commands as a path (:func:`solve_sequence`) instead of solving
        each on its own; required for ``hysteresis`` and to see snap-through along a path.
    multistable : look for other stable states (configurations on their own only).
    """
    model = (model or RingPairModel()).for_design(design)
    if ordered:
        return solve_sequence(model, model.parameters(design), theta1, theta2)
    return solve_equilibria(
        model, model.parameters(design), theta1, theta2, multistable=multistable
    )
