"""The robot's home: where it sits in the field when it is meant to be neutral, the centre
every workspace measure is taken about.

Definition. The home is the state of the robot with its rings commanded antiparallel,
theta1 = pi, theta2 = 0 (:data:`HOME_COMMAND`: the distal ring's moment against the
proximal one's, so the field's moment on the pair cancels as far as the rings can), in the
model the study designs with: gravity, the printed tip's weight and rigid segment, the
near field, and with ``torsion`` the transmissions' twist and the stops (which hold the
rings short of antiparallel where the stop angle is below 180 deg: "as far as the rings
can"). Its state is the one :func:`design.equilibrium.solve_equilibria` defines (stable,
reached from the unloaded robot by the load ramp).

- ``home`` position: the tip (proximal ring centre) of that state, base frame. [m]
- ``droop``: its distance from the straight, weightless tip
  (:func:`design.geometry.rest_position`), reported as its own number: the robot's own
  weight and the printed pieces' sag it, and where the rings sit in different fields the
  pair's moment does not cancel. A robot hanging along gravity, the rings at one place,
  has home = the straight tip.

The antiparallel commands at other phases (theta1 = phi + pi, theta2 = phi) trace the
neutral loop (:mod:`design.workspace`); the study's ``neutral`` constraint keeps it within
its tolerance of the robot's rest with the field off, so the home is that loop's phase-0
point, fixed so that the NLP and the forward check measure about the same state.

SI units are used for all inputs and outputs; angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from design.equilibrium import Equilibria, solve_equilibria
from design.geometry import rest_position
from design.model import RingPairModel

HOME_COMMAND = (np.pi, 0.0)
"""Ring angles commanded at home (theta1 distal, theta2 proximal): antiparallel. [rad]"""


@dataclass(frozen=True)
class Home:
    """The robot's home (module docstring).

    state : the home's equilibrium (one row).
    position : shape (3,), its tip, base frame (NaN without a state). [m]
    straight : shape (3,), the straight, weightless tip. [m]
    droop : distance of ``position`` from ``straight``. [m]
    """

    state: Equilibria
    position: np.ndarray
    straight: np.ndarray
    droop: float

    @property
    def stable(self) -> bool:
        """Whether the home is a stable state of the model."""
        return bool(self.state.stable[0])


def home_of(state: Equilibria, free_length: float) -> Home:
    """The :class:`Home` of a solved home ``state`` (one row at :data:`HOME_COMMAND`) of a
    robot of ``free_length`` [m]."""
    if len(state) != 1:
        raise ValueError(f"a home is one state, got {len(state)}")
    position = np.asarray(state.position[0], float)
    straight = rest_position(free_length)
    return Home(state, position, straight, float(np.linalg.norm(position - straight)))


def solve_home(model: RingPairModel, params: np.ndarray, free_length: float) -> Home:
    """The home of the robot with parameter vector ``params`` (``model.parameters(design)``)
    in ``model``; ``free_length`` [m] places the straight tip."""
    state = solve_equilibria(model, params, [HOME_COMMAND[0]], [HOME_COMMAND[1]])
    return home_of(state, free_length)
