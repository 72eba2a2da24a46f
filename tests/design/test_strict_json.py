"""Strict JSON: what Python's json module writes as bare NaN is null with a reason.

Issue 52: results.json held 7 bare NaN that strict parsers reject. The parser here is
Python's own with ``parse_constant`` refusing NaN and Infinity, as strict parsers do.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from design.strict_json import NULL_REASONS, dumps_strict


def strict_load(text: str):
    def refuse(name: str):
        raise ValueError(f"bare {name} in JSON")

    return json.loads(text, parse_constant=refuse)


def test_nan_and_infinity_become_null_with_their_reason() -> None:
    doc = {
        "a": float("nan"),
        "b": [1.0, np.float64(np.inf), {"c": np.nan}],
        "d": np.array([1.5, np.nan]),
        "e": np.int64(3),
        "f": True,
    }
    with pytest.raises(ValueError):
        strict_load(json.dumps({"a": float("nan")}))  # what the json module alone writes
    out = strict_load(dumps_strict(doc, reasons={"c": "no state at this command"}))
    assert out["a"] is None and out["b"][1] is None and out["d"] == [1.5, None]
    assert out["e"] == 3 and out["f"] is True
    assert out[NULL_REASONS] == {
        "a": "not computable (NaN)",
        "b[1]": "unbounded (infinite)",
        "b[2].c": "no state at this command",
        "d[1]": "not computable (NaN)",
    }


def test_finite_documents_are_unchanged() -> None:
    doc = {"x": [1, 2.5, "s", None], "y": {"z": -0.0}}
    assert strict_load(dumps_strict(doc)) == doc
