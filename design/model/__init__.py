"""The ring-pair model: one set of CasADi expressions, with switchable physical effects
and the design's field sources, from which every numeric function (equilibrium residual,
Jacobian, stability indicator, tip pose) is built.

One module per concept, their public names re-exported here:

- :mod:`design.model.effects`: the effects by name and how options name sets of them;
- :mod:`design.model.loads`: effects as objects, the loads each adds (printed tip, gravity);
- :mod:`design.model.symbols`: the parameter symbols and the quantities derived from them;
- :mod:`design.model.field`: the field of the external magnet and the field sources;
- :mod:`design.model.ring_pair`: :class:`RingPairModel` (the module's docstring describes
  the model) and :func:`model_for`.

SI units are used for all inputs and outputs.
"""

from design.model.effects import (
    DEFAULT_EFFECTS,
    EFFECTS,
    PRINTED_TIP,
    SWITCHES,
    available_effects,
    parse_effects,
)
from design.model.field import CLASSIC, FieldLayout, field_model, layout_of, magnet_clearance
from design.model.ring_pair import COARSE_STEPS, RingPairModel, model_for, sylvester_minors
from design.model.symbols import Symbols, ring_positions

__all__ = [
    "CLASSIC",
    "COARSE_STEPS",
    "DEFAULT_EFFECTS",
    "EFFECTS",
    "PRINTED_TIP",
    "SWITCHES",
    "FieldLayout",
    "RingPairModel",
    "Symbols",
    "available_effects",
    "field_model",
    "layout_of",
    "magnet_clearance",
    "model_for",
    "parse_effects",
    "ring_positions",
    "sylvester_minors",
]
