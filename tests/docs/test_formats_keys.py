"""docs/formats.md documents the design file the reader accepts: every key that
:mod:`design.designfile` reads (its sections' keys, and the keys it writes itself) has a
row in the design-file section's key table."""

from __future__ import annotations

import re
from pathlib import Path

from design.designfile import SECTIONS, TOP_KEYS, default_design, design_to_dict

FORMATS = Path(__file__).resolve().parents[2] / "docs" / "formats.md"


def _design_section() -> str:
    """The text of docs/formats.md from '## Design file' up to the next '## ' heading."""
    text = FORMATS.read_text(encoding="utf-8")
    start = text.index("## Design file")
    end = text.index("\n## ", start + 1)
    return text[start:end]


def _dotted(doc: dict, prefix: str = "") -> set[str]:
    """Every leaf key of a design-file document, dotted (``robot.catheter.outer_diameter_mm``)."""
    out: set[str] = set()
    for k, v in doc.items():
        out |= _dotted(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}"}
    return out


def accepted_keys() -> set[str]:
    """The dotted keys the reader accepts: each section's keys (SECTIONS), the keys that
    :func:`design_to_dict` writes (shape, process) and the top-level ones."""
    numeric = {f"{section}.{key.name}" for section, keys in SECTIONS.items() for key in keys}
    written = _dotted(design_to_dict(default_design()))
    top = {k for k in TOP_KEYS if k not in SECTIONS}
    return numeric | written | top


def test_the_design_section_has_a_row_for_every_key_the_reader_accepts():
    section = _design_section()
    rows = set(re.findall(r"^\|\s*`([\w.]+)`", section, re.M))
    keys = accepted_keys() - {"name", "description"}  # shown in the example, not the table
    assert len(keys) > 30  # the reader's keys were found, not an empty set
    missing = sorted(keys - rows)
    assert not missing, f"docs/formats.md lacks a key-table row for {missing}"


def test_the_example_shows_the_top_level_keys():
    section = _design_section()
    for key in ("name", "description"):
        assert re.search(rf"^{key} = ", section, re.M), key
