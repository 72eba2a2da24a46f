"""Safe storage of results a rerun reads back: JSON and NPZ, never pickle.

A stored result is one ``.npz`` file (read with ``numpy.load(allow_pickle=False)``) holding
a JSON document (``__doc__``) and the arrays it refers to (``a0``, ``a1``, ...). The
document says its schema (:data:`SCHEMA`), the key of the inputs it was computed from and a
SHA-256 digest of its contents; reading checks all three, so a file that is foreign (another
schema or key), truncated or altered is refused (:class:`StoredError`) and the caller
recomputes.

What the document can hold is data only: ``None``, booleans, integers, floats (NaN and
infinities included), strings, lists, tuples, dictionaries, sets, paths, NumPy arrays (no
object dtype but arrays of strings) and scalars, enumerations, and dataclasses. A dataclass
or an enumeration is named by module and qualified name and rebuilt only if its module lies
in one of the packages the caller allows (:func:`load`'s ``packages``) and the name is a
dataclass (or an ``Enum``) there; its fields are set as stored, no constructor or
``__post_init__`` runs. Nothing in a file selects code to run.

:func:`digest` hashes any such value canonically (the same encoding, keys sorted), so it
keys results by their inputs independent of pickle's protocol or Python's hash seed.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import hashlib
import importlib
import importlib.util
import io
import json
import math
import os
import warnings
import zipfile
from collections.abc import Callable
from importlib import metadata
from pathlib import Path, PurePath
from typing import Any

import numpy as np

from design.atomic import atomic_path

SCHEMA = "ringpair.stored/1"
"""Schema of the stored document; a file of another schema is refused."""
MAX_BYTES = 1 << 30
"""Largest stored file read back [bytes]; a larger one is refused, not read."""
DOC = "__doc__"


class StoredError(ValueError):
    """A stored file cannot be used (foreign, truncated, altered, not data); says why."""


class StoredWarning(UserWarning):
    """A stored result was refused and is being recomputed."""


class _Encoder:
    """Value -> JSON-able tree, arrays set aside (their index in the tree)."""

    def __init__(self) -> None:
        self.arrays: list[np.ndarray] = []

    def array(self, a: np.ndarray) -> dict[str, Any]:
        if a.dtype.hasobject:
            if a.dtype == object and all(isinstance(x, str) for x in a.flat):
                return {"__strings__": [str(x) for x in a.flat], "shape": list(a.shape)}
            raise TypeError(f"cannot store an array of dtype {a.dtype} (object, not strings)")
        self.arrays.append(np.ascontiguousarray(a))
        return {"__nd__": len(self.arrays) - 1}

    def __call__(self, v: Any) -> Any:  # noqa: C901 - one branch per kind of value
        if v is None or isinstance(v, bool | str):
            return v
        if isinstance(v, enum.Enum):
            return {"__enum__": _name(type(v)), "v": self(v.value)}
        if isinstance(v, np.ndarray):
            return self.array(v)
        if isinstance(v, np.generic):
            if isinstance(v, np.object_):
                raise TypeError("cannot store a NumPy object scalar")
            return {"__ns__": v.dtype.str, "v": self(v.item())}
        if isinstance(v, int):
            return v
        if isinstance(v, float):
            return v if math.isfinite(v) else {"__float__": repr(v)}
        if dataclasses.is_dataclass(v) and not isinstance(v, type):
            fields = {f.name: self(getattr(v, f.name)) for f in dataclasses.fields(v)}
            return {"__dc__": _name(type(v)), "fields": fields}
        if isinstance(v, tuple):
            return {"__tuple__": [self(x) for x in v]}
        if isinstance(v, list):
            return [self(x) for x in v]
        if isinstance(v, frozenset | set):
            items = sorted((self(x) for x in v), key=_canonical)
            return {"__frozenset__" if isinstance(v, frozenset) else "__set__": items}
        if isinstance(v, dict):
            if all(isinstance(k, str) and not k.startswith("__") for k in v):
                return {k: self(x) for k, x in v.items()}
            return {"__dict__": [[self(k), self(x)] for k, x in v.items()]}
        if isinstance(v, PurePath):
            return {"__path__": str(v)}
        raise TypeError(f"cannot store a value of type {type(v).__name__}")


def _name(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def _canonical(tree: Any) -> str:
    return json.dumps(tree, sort_keys=True, separators=(",", ":"))


def _hash(doc_tree: Any, arrays: list[np.ndarray]) -> str:
    h = hashlib.sha256(_canonical(doc_tree).encode())
    for a in arrays:
        h.update(f"|{a.dtype.str}{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def digest(*values: Any) -> str:
    """SHA-256 (hex) of ``values`` in the stored encoding, dictionary keys sorted. [-]"""
    enc = _Encoder()
    tree = enc(values)
    return _hash(tree, enc.arrays)


def source_digest(packages: tuple[str, ...], distribution: str) -> str:
    """SHA-256 (hex) of the version of ``distribution`` and of every source and data file of
    the top-level ``packages`` (found, not imported): what a stored result's key needs
    besides its inputs, so that results of other code (another version, an edited
    checkout, with or without git) are not reused."""
    return _source_digest(tuple(packages), distribution)


@functools.lru_cache(maxsize=4)
def _source_digest(packages: tuple[str, ...], distribution: str) -> str:
    h = hashlib.sha256()
    try:
        h.update(f"{distribution}=={metadata.version(distribution)}".encode())
    except metadata.PackageNotFoundError:
        h.update(f"{distribution}==unversioned".encode())
    for name in packages:
        spec = importlib.util.find_spec(name)
        roots = list(spec.submodule_search_locations or []) if spec else []
        for root in roots:
            for f in sorted(Path(root).rglob("*")):
                if f.is_file() and "__pycache__" not in f.parts and f.suffix != ".pyc":
                    h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def save(path: str | os.PathLike[str], value: Any, key: str) -> None:
    """Store ``value`` under input key ``key`` at ``path`` (atomically)."""
    enc = _Encoder()
    tree = enc(value)
    doc = {"schema": SCHEMA, "key": key, "digest": _hash(tree, enc.arrays), "value": tree}
    arrays: dict[str, Any] = {f"a{i}": a for i, a in enumerate(enc.arrays)}
    arrays[DOC] = np.array(json.dumps(doc))
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    with atomic_path(path) as tmp:
        tmp.write_bytes(buffer.getvalue())


def reuse(
    path: Path,
    key: str,
    packages: tuple[str, ...],
    valid: Callable[[Any], bool],
    kind: str,
    again: str,
) -> Any:
    """The value stored at ``path`` for ``key`` if it is ``kind`` (``valid``); None when no
    file is there, or with a warning ending in ``again`` when the file is foreign,
    truncated, altered or not ``kind``."""
    if not path.exists():
        return None
    try:
        value = load(path, key, packages)
        if not valid(value):
            raise StoredError(f"not {kind}")
    except StoredError as exc:
        warnings.warn(f"{path}: not reused ({exc}); {again}", StoredWarning, stacklevel=3)
        return None
    return value


def load(path: str | os.PathLike[str], key: str, packages: tuple[str, ...]) -> Any:
    """The value stored at ``path`` under ``key``; StoredError says why it cannot be used.

    packages : top-level packages whose dataclasses and enumerations may be rebuilt.
    """
    p = Path(path)
    try:
        if not p.is_file():
            raise StoredError("not a regular file")
        if p.stat().st_size > MAX_BYTES:
            raise StoredError(f"larger than {MAX_BYTES} bytes")
        with p.open("rb") as f, np.load(f, allow_pickle=False) as z:
            if DOC not in z.files:
                raise StoredError("no stored document in it")
            doc = json.loads(str(z[DOC][()]))
            if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
                raise StoredError(f"not of schema {SCHEMA}")
            if doc.get("key") != key:
                raise StoredError("computed from other inputs (its key differs)")
            arrays = [z[f"a{i}"] for i in range(len(z.files) - 1)]
    except StoredError:
        raise
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise StoredError(f"unreadable ({type(exc).__name__}: {exc})") from None
    if _hash(doc.get("value"), arrays) != doc.get("digest"):
        raise StoredError("its contents do not match its digest (truncated or altered)")
    return _Decoder(arrays, packages)(doc["value"])


class _Decoder:
    def __init__(self, arrays: list[np.ndarray], packages: tuple[str, ...]) -> None:
        self.arrays = arrays
        self.packages = packages

    def cls(self, name: Any, kind: str) -> type:
        module, _, qual = str(name).partition(":")
        if module.split(".")[0] not in self.packages or not qual:
            raise StoredError(f"{kind} {name!r} is outside the allowed packages")
        try:
            obj: Any = importlib.import_module(module)
            for part in qual.split("."):
                obj = getattr(obj, part)
        except (ImportError, AttributeError):
            raise StoredError(f"{kind} {name!r} does not exist") from None
        if not isinstance(obj, type):
            raise StoredError(f"{kind} {name!r} is not a class")
        return obj

    def __call__(self, t: Any) -> Any:  # noqa: C901 - one branch per tag
        if isinstance(t, list):
            return [self(x) for x in t]
        if not isinstance(t, dict):
            return t
        if "__nd__" in t:
            i = t["__nd__"]
            if not isinstance(i, int) or not 0 <= i < len(self.arrays):
                raise StoredError(f"array index {i!r} out of range")
            return self.arrays[i]
        if "__strings__" in t:
            strings, shape = t["__strings__"], t.get("shape")
            if not all(isinstance(x, str) for x in strings) or not isinstance(shape, list):
                raise StoredError("an array of strings holds other things")
            out = np.empty(len(strings), dtype=object)
            out[:] = strings
            return out.reshape([int(n) for n in shape])
        if "__ns__" in t:
            try:
                dtype = np.dtype(str(t["__ns__"]))
            except TypeError:
                raise StoredError(f"not a NumPy type: {t['__ns__']!r}") from None
            if dtype.hasobject:
                raise StoredError("a NumPy object scalar")
            return dtype.type(self(t["v"]))
        if "__float__" in t:
            text = t["__float__"]
            if text not in ("nan", "inf", "-inf"):
                raise StoredError(f"not a float: {text!r}")
            return float(text)
        if "__tuple__" in t:
            return tuple(self(x) for x in t["__tuple__"])
        if "__frozenset__" in t:
            return frozenset(self(x) for x in t["__frozenset__"])
        if "__set__" in t:
            return {self(x) for x in t["__set__"]}
        if "__dict__" in t:
            return {self(k): self(v) for k, v in t["__dict__"]}
        if "__path__" in t:
            return Path(str(t["__path__"]))
        if "__enum__" in t:
            cls = self.cls(t["__enum__"], "enumeration")
            if not issubclass(cls, enum.Enum):
                raise StoredError(f"{t['__enum__']!r} is not an enumeration")
            return cls(self(t["v"]))
        if "__dc__" in t:
            return self.dataclass(t)
        return {k: self(v) for k, v in t.items()}

    def dataclass(self, t: dict[str, Any]) -> Any:
        cls = self.cls(t["__dc__"], "dataclass")
        if not dataclasses.is_dataclass(cls):
            raise StoredError(f"{t['__dc__']!r} is not a dataclass")
        given = t.get("fields")
        names = {f.name for f in dataclasses.fields(cls)}
        if not isinstance(given, dict) or set(given) != names:
            raise StoredError(f"{t['__dc__']!r}: stored fields differ from the class's")
        obj = object.__new__(cls)
        for name, value in given.items():
            object.__setattr__(obj, name, self(value))
        return obj


__all__ = [
    "MAX_BYTES",
    "SCHEMA",
    "StoredError",
    "StoredWarning",
    "digest",
    "load",
    "save",
    "source_digest",
]
