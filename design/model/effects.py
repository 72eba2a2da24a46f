"""The model's switchable effects by name (docs/formats.md) and how options name sets of
them."""

from __future__ import annotations

EFFECTS = ("near_field", "large_deflection", "torsion", "gravity", "hysteresis")
"""Model extensions by name (docs/formats.md): the causes a diagnosis can name."""
PRINTED_TIP = "printed_tip"
"""The tip as built (:mod:`design.model.ring_pair`'s docstring): a switch of the model
beside the effects, not among them, since it is known geometry of the design rather than
a cause to find in data (diagnosis and the effects table leave it out)."""
SWITCHES = (*EFFECTS, PRINTED_TIP)
"""Everything a :class:`RingPairModel` can switch on."""


DEFAULT_EFFECTS = frozenset({"near_field", "large_deflection", "gravity", PRINTED_TIP})
"""The model for design work: the robot as it will be built (the printed tip's rigid segment
and weight, :data:`PRINTED_TIP`; its pieces from the design file's ``[tip.mounting]`` or the
resin defaults), the most faithful model that is well posed from a design file alone and
stays fast (about 11,000 configurations per second on two cores). ``torsion`` is left out:
with touching rings (kappa > 1) it makes the robot multistable, so the state depends on the
path driven and on mechanical stops, not on the commanded angles alone; ``hysteresis`` needs
friction angles, which come from bench data."""


def available_effects() -> tuple[str, ...]:
    """The effects this version implements (all of EFFECTS once each is wired in)."""
    return EFFECTS


def parse_effects(text: str) -> frozenset[str]:
    """'none', 'default' (:data:`DEFAULT_EFFECTS`), 'all' (every effect and the printed
    tip, :data:`SWITCHES`) or a comma list of their names (which may include 'default');
    ValueError names the bad one."""
    text = text.strip()
    if text in ("none", "baseline"):
        return frozenset()
    if text == "default":
        return DEFAULT_EFFECTS
    if text == "all":
        return frozenset(SWITCHES)
    names = [t.strip() for t in text.split(",") if t.strip()]
    if not names:
        raise ValueError(
            f"no model effect named in {text!r}; expected 'none', 'default', 'all' or a comma "
            f"list of {', '.join(SWITCHES)}"
        )
    if "default" in names:  # 'default,torsion': the model for design work and more
        names = [n for n in names if n != "default"] + sorted(DEFAULT_EFFECTS)
    bad = [n for n in names if n not in SWITCHES]
    if bad:
        raise ValueError(
            f"unknown model effect {bad[0]!r}; expected 'none', 'default', 'all' or a comma "
            f"list of {', '.join(SWITCHES)}"
        )
    return frozenset(names)
