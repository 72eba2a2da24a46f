"""Pieces of the HTML reports: images embedded in the page, and tables."""

from __future__ import annotations

import base64
import html
from collections.abc import Sequence
from pathlib import Path


def img(path: Path, alt: str) -> str:
    """An ``<img>`` with the PNG at ``path`` embedded, so the page stands alone."""
    data = base64.b64encode(path.read_bytes()).decode()
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


def table(header: Sequence[object], rows: Sequence[Sequence[object]]) -> str:
    """A ``<table>``: a header row, then one row per item; every cell escaped."""

    def row(cells: Sequence[object], tag: str) -> str:
        return "<tr>" + "".join(f"<{tag}>{html.escape(str(c))}</{tag}>" for c in cells) + "</tr>"

    return f"<table>{row(header, 'th')}{''.join(row(r, 'td') for r in rows)}</table>"
