"""Self-locking of a worm drive: lead angle against the friction angle of the flanks.

A worm drive cannot be driven backwards from the wheel when the worm's lead angle is
smaller than the effective friction angle of the thread flanks. With normal pressure angle
``alpha_n`` the flank's normal force is ``1 / cos(alpha_n)`` times the axial load, so the
effective friction angle is ``rho' = arctan(mu / cos(alpha_n))`` (Niemann & Winter,
*Maschinenelemente* Bd. III, sec. 24.3; DIN 3996). Efficiencies of the screw:

    forward (worm drives wheel)   eta  = tan(gamma) / tan(gamma + rho')
    backward (wheel drives worm)  eta' = tan(gamma - rho') / tan(gamma)   (<= 0: self-locking)

Static self-locking is what holds the tip angle when the knob is let go; vibration can
still creep a drive whose margin is small, so the margin is reported as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cad.errors import CadError

# Coefficients of sliding friction used as design values: the LOW end of published dry
# ranges, because a lower coefficient is the unsafe side for self-locking.
# Printed PLA on PLA and cured resin on resin: 0.2-0.4 measured dry (e.g. Zhiani Hervan
# et al., Polymers 2021); hardened steel on tin bronze, oil lubricated at low sliding
# speed: 0.03-0.06 (Niemann & Winter Bd. III, Fig. 24.9).
FRICTION_COEFFICIENTS: dict[str, float] = {
    "pla-pla-dry": 0.20,
    "petg-petg-dry": 0.20,
    "resin-resin-dry": 0.20,
    "steel-pla-dry": 0.18,
    "steel-bronze-lubricated": 0.05,
}

DEFAULT_MATERIAL_PAIR = {"fdm": "pla-pla-dry", "resin": "resin-resin-dry"}


@dataclass(frozen=True)
class SelfLocking:
    """The numbers of the self-locking check.

    lead_angle_deg : Lead angle gamma of the worm at its reference diameter. [deg]
    friction_coefficient : Sliding friction coefficient mu of the material pair. [-]
    normal_pressure_angle_deg : alpha_n of the thread. [deg]
    friction_angle_deg : Effective friction angle rho' = arctan(mu / cos alpha_n). [deg]
    margin_deg : rho' - gamma; positive means self-locking. [deg]
    forward_efficiency : Efficiency with the worm driving. [-]
    backward_efficiency : Efficiency with the wheel driving; <= 0 when self-locking. [-]
    material_pair : Name of the material pair, or ``"custom"``.
    """

    lead_angle_deg: float
    friction_coefficient: float
    normal_pressure_angle_deg: float
    friction_angle_deg: float
    margin_deg: float
    forward_efficiency: float
    backward_efficiency: float
    material_pair: str

    @property
    def self_locking(self) -> bool:
        """True when the lead angle is below the effective friction angle."""
        return self.margin_deg > 0

    def summary(self) -> str:
        """One line for reports."""
        verdict = "self-locking" if self.self_locking else "NOT self-locking (back-drivable)"
        return (
            f"lead angle {self.lead_angle_deg:.2f} deg vs friction angle "
            f"{self.friction_angle_deg:.2f} deg (mu = {self.friction_coefficient:g}, "
            f"{self.material_pair}, alpha_n = {self.normal_pressure_angle_deg:g} deg): "
            f"{verdict}, margin {self.margin_deg:+.2f} deg, forward efficiency "
            f"{self.forward_efficiency:.0%}"
        )


def friction_coefficient(material_pair: str) -> float:
    """Design friction coefficient of a named material pair. [-]"""
    try:
        return FRICTION_COEFFICIENTS[material_pair]
    except KeyError:
        names = ", ".join(sorted(FRICTION_COEFFICIENTS))
        raise CadError(f"material pair must be one of {names}; got {material_pair!r}") from None


def self_locking(
    lead_angle_deg: float,
    friction_coefficient: float,
    normal_pressure_angle_deg: float = 20.0,
    material_pair: str = "custom",
) -> SelfLocking:
    """Check a worm drive for self-locking.

    Parameters
    ----------
    lead_angle_deg : Lead angle of the worm, 0 < gamma < 90. [deg]
    friction_coefficient : Sliding friction coefficient of the flank pair, >= 0. [-]
    normal_pressure_angle_deg : Normal pressure angle of the thread, 0 <= alpha_n < 90. [deg]
    material_pair : Label for the report.
    """
    if not 0.0 < lead_angle_deg < 90.0:
        raise CadError(f"worm lead angle must be in (0, 90) deg; got {lead_angle_deg:g} deg")
    if not friction_coefficient >= 0.0:
        raise CadError(f"friction coefficient must be >= 0; got {friction_coefficient:g}")
    if not 0.0 <= normal_pressure_angle_deg < 90.0:
        raise CadError(
            f"normal pressure angle must be in [0, 90) deg; got {normal_pressure_angle_deg:g} deg"
        )
    gamma = math.radians(lead_angle_deg)
    alpha_n = math.radians(normal_pressure_angle_deg)
    rho = math.atan(friction_coefficient / math.cos(alpha_n))
    forward = math.tan(gamma) / math.tan(gamma + rho) if gamma + rho < math.pi / 2 else 0.0
    backward = math.tan(gamma - rho) / math.tan(gamma)
    return SelfLocking(
        lead_angle_deg=lead_angle_deg,
        friction_coefficient=friction_coefficient,
        normal_pressure_angle_deg=normal_pressure_angle_deg,
        friction_angle_deg=math.degrees(rho),
        margin_deg=math.degrees(rho - gamma),
        forward_efficiency=forward,
        backward_efficiency=backward,
        material_pair=material_pair,
    )
