"""The report's short notes: what rounding to made sizes changed, tolerances in words, and
whether ``report.pdf`` was written. Lengths in mm."""

from __future__ import annotations

from typing import Any

from design.registry import file_unit
from design.units import MM


def rounding_note(forward: dict[str, Any]) -> str:
    """What rounding the optimum to what can be made (:func:`design.made.made_design`)
    changed: the disc radius of the rounded design (the hand-off) against the optimiser's
    unrounded numbers, under the model for design work. [mm]"""
    if "optimum" not in forward:
        return ""
    made, raw = forward["best"].disc_radius / MM, forward["optimum"].disc_radius / MM
    return (
        f"Sizes rounded to what can be made and bought: disc radius {made:.3f} mm, against "
        f"{raw:.3f} mm at the optimiser's unrounded numbers ({made - raw:+.3f} mm, "
        f"{100 * (made / raw - 1):+.1f} %)."
    )


def tolerance_words(name: str, kind: str, sigma: float) -> str:
    """One tolerance in the reader's units: a percentage, or the value in its file unit
    (``± 0.02 mm``)."""
    if kind == "rel":
        return f"± {100 * sigma:.3g} %"
    unit, scale = file_unit(name)
    return f"± {sigma / scale:.3g} {unit}"


PDF_MARK = "<!--pdf-->"
"""Where the first screen says whether ``report.pdf`` was written."""


def pdf_note(chromium: bool, failed: bool = False) -> str:
    """The first screen's line on ``report.pdf``: nothing where Chromium prints it, else
    why there is none and what to do."""
    if chromium and not failed:
        return ""
    why = (
        "headless Chromium failed to print it"
        if failed
        else "headless Chromium (Debian package <code>chromium</code>) is not installed"
    )
    return (
        f"<p class=next id=pdf>No <code>report.pdf</code> was written: {why}. Print this "
        "page from a browser, or install Chromium and run the study again (its stages are "
        "reused).</p>"
    )
