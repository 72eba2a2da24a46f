"""Safe storage of what reruns read back (design.stored, issue 55): values of every kind
the stages store come back equal; a file that is foreign, truncated, altered, of another
key or naming code outside the project is refused (StoredError), and loading never runs
code from the file (a planted pickle payload, an object array, a class outside the
project's packages)."""

from __future__ import annotations

import io
import json
import os
import pickle
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from studies import SMALL

from design import stored
from design.designfile import default_design
from optimize.sizing.studyfile import loads_study

PACKAGES = ("design", "optimize", "tests")


class _Payload:
    """Unpickling it would create ``marker``: the proof that code from a file ran."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.makedirs, (str(self.marker),))


def payload(marker: Path) -> bytes:
    return pickle.dumps({"result": _Payload(marker), "seconds": 1.0})


def test_values_of_every_kind_come_back_equal(tmp_path):
    design = default_design()
    study = loads_study(SMALL)
    value = {
        "design": design,
        "study": study,
        "array": np.arange(6.0).reshape(2, 3),
        "bools": np.array([True, False]),
        "nan": float("nan"),
        "inf": (float("-inf"), np.float64(2.5), np.int64(-3)),
        "keys": {1: "a", ("x", 2): None, "__dunder": 3},
        "sets": (frozenset({"torsion", "gravity"}), {1, 2}),
        "path": Path("cad/parts.csv"),
        "big": 10**30,
    }
    stored.save(tmp_path / "v.npz", value, "k")
    back = stored.load(tmp_path / "v.npz", "k", PACKAGES)
    assert back["design"] == design and back["study"] == study
    assert np.array_equal(back["array"], value["array"]) and back["bools"].dtype == bool
    assert np.isnan(back["nan"]) and back["inf"][0] == float("-inf")
    assert type(back["inf"][1]) is np.float64 and back["inf"][2] == -3
    assert back["keys"] == value["keys"] and back["sets"] == value["sets"]
    assert back["path"] == value["path"] and back["big"] == 10**30


def test_digest_is_canonical_and_sees_every_field():
    study = loads_study(SMALL)
    assert stored.digest(study) == stored.digest(loads_study(SMALL))
    assert stored.digest({"a": 1, "b": 2}) == stored.digest({"b": 2, "a": 1})
    edited = loads_study(SMALL.replace("starts = 2", "starts = 3"))
    assert stored.digest(study) != stored.digest(edited)
    assert stored.digest(np.zeros(3)) != stored.digest(np.zeros(3, dtype=np.float32))


def _tamper(path: Path, change) -> None:
    """Rewrite the stored document of ``path`` through ``change(doc)``."""
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    doc = change(json.loads(str(arrays.pop("__doc__")[()])))
    buffer = io.BytesIO()
    np.savez(buffer, __doc__=np.array(json.dumps(doc)), **arrays)
    path.write_bytes(buffer.getvalue())


@dataclass(frozen=True)
class Plain:
    x: float


@pytest.mark.parametrize(
    "spoil, reason",
    [
        (lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2]), "unreadable"),
        (lambda p: p.write_bytes(b""), "unreadable"),
        (lambda p: _tamper(p, lambda d: d | {"schema": "other/9"}), "schema"),
        (lambda p: _tamper(p, lambda d: d | {"key": "other"}), "key differs"),
        (lambda p: _tamper(p, lambda d: d | {"value": {"__dc__": "x", "fields": {}}}), "digest"),
        (lambda p: p.unlink() or p.mkdir(), "regular file"),
    ],
    ids=["truncated", "empty", "foreign schema", "other inputs", "altered", "a folder"],
)
def test_a_spoiled_file_is_refused_with_its_reason(tmp_path, spoil, reason):
    path = tmp_path / "v.npz"
    stored.save(path, {"x": Plain(1.0)}, "k")
    spoil(path)
    with pytest.raises(stored.StoredError, match=reason):
        stored.load(path, "k", PACKAGES)


def _forged(path: Path, value, key="k") -> None:
    """A file with a valid digest whose document holds ``value`` (a forger's file)."""
    doc = {"schema": stored.SCHEMA, "key": key, "digest": stored._hash(value, []), "value": value}
    buffer = io.BytesIO()
    np.savez(buffer, __doc__=np.array(json.dumps(doc)))
    path.write_bytes(buffer.getvalue())


@pytest.mark.parametrize(
    "value, reason",
    [
        ({"__dc__": "os:system", "fields": {}}, "outside the allowed packages"),
        ({"__dc__": "subprocess:Popen", "fields": {"args": "true"}}, "outside"),
        ({"__enum__": "builtins:eval", "v": "1"}, "outside"),
        ({"__dc__": "design.stored:load", "fields": {}}, "not a class"),
        ({"__dc__": "design.stored:StoredError", "fields": {}}, "not a dataclass"),
        ({"__dc__": "design.records:Design", "fields": {"robot": 1}}, "fields differ"),
        ({"__ns__": "O", "v": 1}, "object"),
    ],
)
def test_a_forged_document_names_no_code_that_runs(tmp_path, value, reason):
    path = tmp_path / "v.npz"
    _forged(path, value)
    with pytest.raises(stored.StoredError, match=reason):
        stored.load(path, "k", PACKAGES)


def test_a_pickle_payload_in_any_form_never_runs(tmp_path):
    marker = tmp_path / "ran"
    plain = tmp_path / "plain.npz"
    plain.write_bytes(payload(marker))  # a bare pickle where an NPZ is expected
    in_array = tmp_path / "array.npz"  # an object array inside an NPZ (pickled by numpy)
    with zipfile.ZipFile(in_array, "w") as z:
        buffer = io.BytesIO()
        np.save(buffer, np.array([_Payload(marker)], dtype=object), allow_pickle=True)
        z.writestr("__doc__.npy", buffer.getvalue())
    for path in (plain, in_array):
        with pytest.raises(stored.StoredError):
            stored.load(path, "k", PACKAGES)
    assert not marker.exists()


def test_an_object_array_is_not_stored(tmp_path):
    with pytest.raises(TypeError, match="object"):
        stored.save(tmp_path / "v.npz", np.array([None]), "k")
    assert not (tmp_path / "v.npz").exists()


def test_source_digest_changes_with_the_source(tmp_path, monkeypatch):
    package = tmp_path / "pkg_h55"
    package.mkdir()
    (package / "__init__.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    before = stored._source_digest.__wrapped__(("pkg_h55",), "pkg_h55")
    (package / "__init__.py").write_text("X = 2\n")
    assert stored._source_digest.__wrapped__(("pkg_h55",), "pkg_h55") != before
