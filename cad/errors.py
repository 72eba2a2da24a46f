"""The one error class of the CAD layer.

Every geometry that cannot be built (a magnet seat wider than the piece, a wire bore wider
than the ring's bore, a gear with pointed teeth) raises :class:`CadError`. The message
names the quantity, what was expected and what was found, in millimetres or degrees.
"""

from __future__ import annotations


class CadError(ValueError):
    """A part that cannot be built from the given dimensions. The message is for the user."""


def require(condition: bool, quantity: str, expected: str, found: float, unit: str = "mm") -> None:
    """Raise :class:`CadError` unless ``condition`` holds.

    Parameters
    ----------
    condition : What must be true for the geometry to exist.
    quantity : Name of the offending quantity, e.g. ``"distal piece: wire bore diameter"``.
    expected : What it must be, e.g. ``"smaller than the magnet bore (2 mm)"``.
    found : The value found. [unit]
    unit : Unit of ``found`` as printed (``"mm"``, ``"deg"``, ``""``).
    """
    if not condition:
        suffix = f" {unit}" if unit else ""
        raise CadError(f"{quantity} must be {expected}; got {found:.4g}{suffix}")
