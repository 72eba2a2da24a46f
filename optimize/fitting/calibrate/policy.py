"""Which parameters calibration frees, and how: the fit units, bounds and prior widths of
each (:data:`FREE_PARAMETERS`, from :mod:`design.registry`), the baseline's and each
effect's free parameters, the parameters the field's strength leaves relative, and
the starts of a fit of torsion. SI units.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass

from design.registry import PARAMETERS, FitSpec, file_unit
from optimize.fitting.sensitivity import SENSITIVE


@dataclass(frozen=True)
class FreeParameter(FitSpec):
    """How one model parameter is fitted: its :class:`design.registry.FitSpec`, its name and
    the unit shown in reports (label, factor from SI)."""

    name: str = ""
    label: tuple[str, float] = ("", 1.0)


def _free_parameter(name: str) -> FreeParameter:
    """How ``name`` is fitted, from the registry."""
    fit = PARAMETERS[name].fit
    assert fit is not None
    label, size = file_unit(name)
    shown = ("", 1.0) if PARAMETERS[name].unit == "-" else (label, 1 / size)
    return FreeParameter(**asdict(fit), name=name, label=shown)


FREE_PARAMETERS: dict[str, FreeParameter] = {n: _free_parameter(n) for n in SENSITIVE}
"""The parameters calibration can free, with their fit units, bounds and prior widths."""

BASELINE_FREE = (
    "bending_rigidity_scale",
    "external_center_x",
    "external_center_y",
    "external_center_z",
)
"""Default free parameters of the baseline: the rod's compliance (which the paper's
"compound" modulus could not pin down) and where the external magnet really is.
``external_remanence`` is left out: it is not separable from the bending rigidity
without gravity or torsion (see the module docstring)."""
EFFECT_FREE: dict[str, tuple[str, ...]] = {
    "torsion": ("wire_torsion_scale", "catheter_torsion_scale"),
    "hysteresis": ("wire_friction_angle", "catheter_friction_angle"),
    "gravity": ("tip_mass",),
    "near_field": (),
    "large_deflection": (),
}
"""Each effect's own parameters, freed with it by default."""
EFFECT_SEPARATES: dict[str, tuple[str, ...]] = {"gravity": ("external_remanence",)}
"""Parameters that are not an effect's own but that the effect makes separable: under
gravity the rod's own weight (a known load) fixes the scale of its compliance, so the
strength of the field (external remanence, which also absorbs the tip magnets'
remanence as built) is no longer bound to the bending rigidity. Not freed by default
(with torsion too the extra freedom slows the search and can lead it astray); the
diagnosis frees them in a refit once the effect is accepted (its ``_refine``)."""
FIELD_RELATIVE = (
    "bending_rigidity_scale",
    "wire_torsion_scale",
    "catheter_torsion_scale",
    "tip_mass",
)
"""Parameters the data fix only relative to the field's strength while the remanences are
not free: every magnetic torque goes with the rings' remanence times the external
magnet's (the rings' mutual torque with the rings' remanence squared), so scaling both
remanences by sqrt(s) and these by s leaves every tip where it was (exactly without
gravity: the rod's own weight does not scale; tests/design/test_state_properties.py).
A robot whose magnets are 5 % stronger than the design file says is fitted 5 % stiffer."""
NESTED_START = {"wire_torsion_scale": 10.0, "catheter_torsion_scale": 10.0}
"""A fit of torsion is also started where it all but reduces to the model without it
(transmissions 10 times stiffer than nominal, nearly rigid, the baseline's assumption; the
nominal value can lie beyond a snap-through of the rings from the data's branch, where
a local fit cannot come back from; :func:`calibrate_from_starts`, the diagnosis' screens)."""
SOFT_START = {"wire_torsion_scale": 0.5, "catheter_torsion_scale": 0.5}
"""... and on the other side of nominal (transmissions twice as compliant): driven along a
path, soft transmissions let the rings lag and snap where stiffer ones do not, a basin of
its own that fits from nominal or stiffer starts do not reach (seed [5, 13, 0], gravity
and torsion planted, wire 0.41 x nominal GJ: from nominal and stiffer starts the misfit
stayed 11 times the noise's, and friction play was named to absorb the rest; from the
nominal design with these it is the noise's)."""
FIELD_TOLERANCE = math.hypot(
    *(PARAMETERS[n].tolerance[1] for n in ("magnet_remanence", "external_remanence"))  # type: ignore[index]
)
"""Relative one-sigma uncertainty of the field's strength: the two remanences' tolerances
(design.registry) in quadrature. [-]"""


def default_free(effects: Iterable[str] = ()) -> tuple[str, ...]:
    """The baseline's free parameters plus each effect's own (in EFFECT_FREE order)."""
    effects = set(effects)
    extra = [n for e, names in EFFECT_FREE.items() if e in effects for n in names]
    return (*BASELINE_FREE, *extra)


def _check_free(free: Sequence[str]) -> tuple[str, ...]:
    free = tuple(free)
    for name in free:
        if name not in FREE_PARAMETERS:
            raise ValueError(
                f"parameter {name!r} cannot be calibrated; expected names from "
                f"{', '.join(FREE_PARAMETERS)}"
            )
    if len(set(free)) != len(free):
        raise ValueError(f"free parameters must be distinct; got {list(free)}")
    if not free:
        raise ValueError("at least one free parameter is needed")
    return free
