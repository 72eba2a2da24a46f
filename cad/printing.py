"""How each printed part goes on the bed: its print orientation and whether it needs supports.

Every printed part's solid is built in its print frame (:mod:`cad.assembly`: +Z up, the
face named here on the bed at z = 0); the STL and the 3MF plates keep that orientation.
The orientation is chosen per part so that functional faces (bores that must fit, gear
flanks, the tracking groove) carry no support marks; where a part has a ledge, supports
are from the bed only and the reason is stated. The 3MF plates carry these as object
metadata (:func:`cad.export.threemf_bytes`), the bill of materials as columns.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PrintSetup:
    """One part's print set-up.

    on_bed : The face on the bed (the print frame's z = 0).
    supports : ``"none"`` or where supports go.
    why : Why this orientation: what it keeps clean.
    """

    on_bed: str
    supports: str
    why: str


PRINT_SETUP: dict[str, PrintSetup] = {
    "housing": PrintSetup(
        "base plate", "none", "U-slot seats and tapped holes open upwards, no overhang"
    ),
    "lid": PrintSetup(
        "top face (printed upside down)", "none", "tongues and bushing seats grow upwards"
    ),
    "gear_shaft_front": PrintSetup(
        "wheel face",
        "none",
        "axis vertical: round journals, catheter socket and teeth flanks without support "
        "marks; the glue port bridges",
    ),
    "gear_shaft_rear": PrintSetup(
        "wheel face", "none", "axis vertical: round journals and hex, teeth without supports"
    ),
    "worm": PrintSetup(
        "lower journal end",
        "none (turn automatic supports off)",
        "axis vertical: the thread's lower flank overhangs only the tooth depth; supports "
        "would fill the thread and cannot be cleaned from the flanks",
    ),
    "knob": PrintSetup("top face (printed upside down)", "none", "the D-bore opens upwards"),
    "shaft_bushing": PrintSetup(
        "one flange",
        "from the bed, under the upper flange only",
        "bore vertical and round; the upper flange is a 2 mm ledge",
    ),
    "worm_bushing": PrintSetup("flange", "none", "bore vertical and round"),
    "shaft_clip": PrintSetup("flat face", "none", "a flat ring"),
    "wire_mount": PrintSetup(
        "front face (hex bore opening)",
        "none",
        "hex bore and wire seat vertical and coaxial; the set-screw hole bridges",
    ),
    "mounting_piece_proximal": PrintSetup(
        "proximal face (catheter socket opening)",
        "none",
        "axis vertical: socket, ring seat and sleeve round and coaxial; the groove's ledge "
        "is half a wall",
    ),
    "mounting_piece_distal": PrintSetup(
        "far face (journal up)",
        "none",
        "axis vertical: journal and ring pocket round and coaxial, key without overhang",
    ),
}
"""The print set-up of every printed part, by part name."""


def print_setup(part: str) -> PrintSetup:
    """The :class:`PrintSetup` of ``part``; KeyError names the parts that have one."""
    try:
        return PRINT_SETUP[part]
    except KeyError:
        raise KeyError(f"no print set-up for {part!r}; known: {sorted(PRINT_SETUP)}") from None
