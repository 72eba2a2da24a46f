"""The report's words on what to make: the printed tip and the bill of materials.

From the CAD stage's summary (:func:`ringpair.pipeline._cad_summary`): the first screen's
card (the tip's size, mass and process; what to buy and print, in totals) and the bill of
materials section (``cad/bom.csv`` as a table). Sizes in mm, masses in g.
"""

from __future__ import annotations

import html
from typing import Any

from ringpair.html_page import table
from ringpair.tables import page_number

EFFECT_WORDS = {
    "near_field": "exact ring field",
    "large_deflection": "large deflection",
    "torsion": "transmission twist",
    "gravity": "gravity",
    "printed_tip": "printed tip",
    "hysteresis": "friction and backlash",
}
"""Each model effect (:data:`design.model.SWITCHES`) as a reader names it."""


def model_title(effects: frozenset[str] | set[str]) -> str:
    """A model as a reader names it: "baseline (as in the paper)" or "baseline with" its effects
    in words (:data:`EFFECT_WORDS`), in a fixed order."""
    if not effects:
        return "baseline (as in the paper)"
    rank = {e: k for k, e in enumerate(EFFECT_WORDS)}
    words = [EFFECT_WORDS.get(e, e) for e in sorted(effects, key=lambda e: (rank.get(e, 99), e))]
    return "baseline with " + ", ".join(words)


def _grams(x: Any) -> str:
    """A mass in g, three significant digits, never an exponent (a 1,300 g magnet)."""
    return "" if x is None or x == "" else page_number(float(x), 3)


def bom_totals_words(bom: list[dict[str, Any]]) -> str:
    """What to buy and print in one sentence: items, pieces and printed mass per process."""
    bought = [r for r in bom if r["kind"] == "bought"]
    printed = [r for r in bom if r["kind"] == "printed"]
    mass: dict[str, float] = {}
    for r in printed:
        mass[r["process"]] = mass.get(r["process"], 0.0) + r["quantity"] * float(r["mass_g"])
    per = ", ".join(f"{m:.1f} g {p}" for p, m in sorted(mass.items()))
    return (
        f"{len(bought)} items to buy ({sum(r['quantity'] for r in bought)} pieces), "
        f"{len(printed)} parts to print ({sum(r['quantity'] for r in printed)} pieces, {per})"
    )


def tip_card(cad: dict[str, Any] | None) -> str:
    """The first screen's card on what to make: the printed tip and the bill's totals, or a
    line saying the CAD stage did not run."""
    if not cad or not cad.get("tip"):
        return "<div class=card><b>Parts</b>: the CAD stage did not run.</div>"
    t = cad["tip"]
    words = bom_totals_words(cad.get("bom", []))
    return (
        f"<div class=card id=tip><b>Printed tip</b>: Ø{t['outer_diameter_mm']:.2f} mm × "
        f"{t['rigid_length_mm']:.2f} mm rigid, {t['mass_g']:.3g} g, {html.escape(t['process'])}"
        f" ({html.escape(t['material'])}, walls {t['wall_mm']:.2g} mm).<br>"
        f"<b>Bill of materials</b>: {html.escape(words)} (<code>cad/bom.csv</code>)</div>"
    )


def bom_section(cad: dict[str, Any]) -> str:
    """The bill of materials: bought items (with cut lengths), then printed parts (with
    process, material, mass, the face on the bed and supports)."""
    bom = cad.get("bom", [])
    if not bom:
        return ""
    bought = [
        [
            r["item"].replace("_", " "),
            r["quantity"],
            r["specification"],
            r["size_mm"],
            "" if r["cut_length_mm"] is None else f"{r['cut_length_mm']:.1f}",
            _grams(r["mass_g"]),
            r["note"],
        ]
        for r in bom
        if r["kind"] == "bought"
    ]
    printed = [
        [
            r["item"].replace("_", " "),
            r["quantity"],
            r["process"],
            r["material"],
            _grams(r["mass_g"]),
            r["size_mm"],
            r["on_bed"],
            r["supports"],
        ]
        for r in bom
        if r["kind"] == "printed"
    ]
    return f"""<h3 id="bom">Bill of materials</h3>
<p>{html.escape(bom_totals_words(bom))}; the same rows in <code>cad/bom.csv</code>.</p>
<h4>To buy</h4>
{table(["item", "qty", "specification", "size (mm)", "cut length (mm)", "mass (g)", "note"],
       bought)}
<h4>To print</h4>
{table(["part", "qty", "process", "material", "mass (g)", "size (mm)", "on the bed",
        "supports"], printed)}"""  # fmt: skip
