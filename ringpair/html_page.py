"""Pieces of the HTML reports: images embedded in the page (full size or as thumbnails),
tables and collapsed blocks."""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Sequence
from pathlib import Path


def img(path: Path, alt: str) -> str:
    """An ``<img>`` with the PNG at ``path`` embedded, so the page stands alone."""
    data = base64.b64encode(path.read_bytes()).decode()
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


def thumb(path: Path, caption: str, width: int = 300) -> str:
    """A ``<figure>`` with the PNG at ``path`` scaled down to ``width`` pixels (when
    wider) and embedded, and ``caption`` under it."""
    from PIL import Image

    with Image.open(path) as im:
        small = im.convert("RGB")
        if small.width > width:
            small = small.resize((width, round(small.height * width / small.width)))
        buf = io.BytesIO()
        small.save(buf, format="PNG", optimize=True)
    data = base64.b64encode(buf.getvalue()).decode()
    text = html.escape(caption)
    return (
        f'<figure><img alt="{text}" src="data:image/png;base64,{data}">'
        f"<figcaption>{text}</figcaption></figure>"
    )


def table(
    header: Sequence[object],
    rows: Sequence[Sequence[object]],
    marked: Sequence[bool] | None = None,
) -> str:
    """A ``<table>``: a header row, then one row per item; every cell escaped; rows whose
    ``marked`` entry is true get ``class="mark"``."""

    def row(cells: Sequence[object], tag: str, mark: bool = False) -> str:
        cls = ' class="mark"' if mark else ""
        body = "".join(f"<{tag}>{html.escape(str(c))}</{tag}>" for c in cells)
        return f"<tr{cls}>{body}</tr>"

    flags = list(marked) if marked is not None else [False] * len(rows)
    body = "".join(row(r, "td", m) for r, m in zip(rows, flags, strict=True))
    return f"<table>{row(header, 'th')}{body}</table>"


def details(summary: str, body: str) -> str:
    """A collapsed ``<details>`` block: ``summary`` (escaped) shown, ``body`` (HTML) on a
    click."""
    return f"<details><summary>{html.escape(summary)}</summary>{body}</details>"
