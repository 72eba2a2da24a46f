"""Strict JSON text: no bare ``NaN`` or ``Infinity``, which strict parsers reject.

Python's :func:`json.dumps` writes ``NaN`` for an uncomputable number; a JSON file read by
other tools must hold ``null`` instead, and say why. :func:`dumps_strict` writes every
non-finite number as ``null`` and, for a top-level object, lists each one under
``"null_reasons"`` by its path (``"forward.best_disc_radius_mm"``) with the reason: not
computable (NaN) or unbounded (infinite). numpy scalars and arrays become numbers and
lists; anything else unknown becomes its string.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

NULL_REASONS = "null_reasons"
"""Key of the top-level object that says why each ``null`` number is null."""


def _clean(value: Any, path: str, nulls: dict[str, str], reasons: dict[str, str]) -> Any:
    if isinstance(value, dict):
        return {
            k: _clean(v, f"{path}.{k}" if path else str(k), nulls, reasons)
            for k, v in value.items()
        }
    if isinstance(value, list | tuple):
        return [_clean(v, f"{path}[{i}]", nulls, reasons) for i, v in enumerate(value)]
    if isinstance(value, np.ndarray):
        return _clean(value.tolist(), path, nulls, reasons)
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        x = float(value)
        if math.isfinite(x):
            return x
        keys = [k.split("[")[0] for k in path.split(".")]
        known = next((reasons[k] for k in reversed(keys) if k in reasons), None)
        nulls[path] = known or ("not computable (NaN)" if math.isnan(x) else "unbounded (infinite)")
        return None
    if value is None or isinstance(value, str):
        return value
    return str(value)


def strict(value: Any, reasons: dict[str, str] | None = None) -> tuple[Any, dict[str, str]]:
    """``value`` with every non-finite number as None, and the reasons by path: the
    reason of the nearest enclosing key in ``reasons``, else what the number was."""
    nulls: dict[str, str] = {}
    return _clean(value, "", nulls, reasons or {}), nulls


def dumps_strict(value: Any, indent: int | None = 2, reasons: dict[str, str] | None = None) -> str:
    """JSON text of ``value`` that strict parsers read (module docstring)."""
    clean, nulls = strict(value, reasons)
    if isinstance(clean, dict) and nulls:
        clean[NULL_REASONS] = {**clean.get(NULL_REASONS, {}), **nulls}
    return json.dumps(clean, indent=indent, allow_nan=False) + "\n"
