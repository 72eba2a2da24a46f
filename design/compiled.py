"""Compile CasADi functions to native code once, and reuse them from a disk cache.

The generated C source is hashed; the shared library lives in ``$RINGPAIR_CACHE`` (default
``~/.cache/ringpair``) under that hash, so a model is compiled the first time it is used
on a machine and loaded in milliseconds afterwards. Without a C compiler the CasADi
virtual machine evaluates the same function (about 15x slower), with a warning.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import shutil
import subprocess
import tempfile
import threading
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

CFLAGS = ("-O1", "-shared", "-fPIC")
"""-O1: on the largest model (all effects, 1 MB of C) it compiles in 9 s against -O2's
15 s and solves as fast (400 configurations 0.39 s against 0.43 s, a 60-step path 0.10 s
both); -O0 compiles in 3 s but solves 3x slower."""
_loaded: dict[str, list[ca.Function]] = {}


def cache_dir() -> Path:
    """Where compiled models are kept."""
    return Path(os.environ.get("RINGPAIR_CACHE", Path.home() / ".cache" / "ringpair"))


def _compiler() -> str | None:
    if os.environ.get("RINGPAIR_NO_COMPILE"):
        return None
    return os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")


def compile_function(function: ca.Function) -> ca.Function:
    """Native-code twin of ``function`` (same inputs and outputs), or ``function`` itself
    when no C compiler is available."""
    return compile_functions([function])[0]


def compile_functions(functions: list[ca.Function]) -> list[ca.Function]:
    """Native-code twins of ``functions``, generated into one C file and one shared
    library, so that what they share (a model's rod and field code) is compiled once; or
    the functions themselves when no C compiler is available."""
    cc = _compiler()
    if cc is None:
        warnings.warn(
            "no C compiler found: ringpair evaluates its model in CasADi's "
            "virtual machine, about 15x slower",
            RuntimeWarning,
            stacklevel=3,
        )
        return list(functions)
    name = "_".join(f.name() for f in functions)[:60]
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    for function in functions:
        gen.add(function)
    source = gen.dump()
    digest = hashlib.sha256(
        (source + " ".join(CFLAGS) + ca.CasadiMeta.version()).encode()
    ).hexdigest()
    key = f"{name}_{digest[:20]}"
    if key not in _loaded:
        target = cache_dir() / f"{key}.so"
        if not target.exists():
            with _building(target):
                # Another process may have built it while this one waited.
                if not target.exists() and not _build(cc, name, key, source, target):
                    return list(functions)
        _loaded[key] = [ca.external(f.name(), str(target)) for f in functions]
    return _loaded[key]


@contextlib.contextmanager
def _building(target: Path) -> Iterator[None]:
    """Hold the lock on building ``target``: processes that need the same model at once
    (the test workers, a study's Dask workers) compile it once, the others wait for it
    instead of compiling it too. Where the file system has no locks, build anyway."""
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target.with_suffix(".lock"), "a") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX)
        except OSError:
            pass
        yield


def _build(cc: str, name: str, key: str, source: str, target: Path) -> bool:
    """Compile ``source`` into the shared library ``target``; False (with a warning) if
    the compiler fails."""
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        src = Path(tmp) / f"{name}.c"
        src.write_text(source)
        lib = Path(tmp) / f"{key}.so"
        result = subprocess.run(
            [cc, *CFLAGS, str(src), "-o", str(lib), "-lm"],
            capture_output=True,
            text=True,
            check=False,
        )
        if result.returncode != 0:
            warnings.warn(
                f"compiling {name} failed ({result.stderr.strip()[:200]}); "
                "using CasADi's virtual machine",
                RuntimeWarning,
                stacklevel=4,
            )
            return False
        os.replace(lib, target)  # atomic: concurrent processes never see half a library
    return True


THREADS = 2
"""Threads of a mapped function of at least THREADED_FROM columns."""
THREADED_FROM = 32
"""Columns from which a map runs on THREADS threads: below, starting the threads costs
more than they save (the large-deflection rod's Newton step, 2 columns: 283 us threaded,
113 us serial; 32: about even; 2048: 30 ms against 49 ms serial), and a fit's load ramps
run mostly on a few columns."""


_threads = THREADS


def use_threads(count: int) -> None:
    """Threads of the maps made from now on (1: none). A process whose siblings keep the
    other cores busy, a worker of :mod:`optimize.fitting.workers`, gains nothing from them
    and pays for starting them at every call: with both cores busy, a 64-column Newton
    step of the torsion model took 618 us threaded against 280 us serial."""
    global _threads
    _threads = count


def map_threads(size: int) -> int:
    """The threads a map of ``size`` columns made now runs on."""
    return _threads if size >= THREADED_FROM else 1


def mapped(function: ca.Function, size: int) -> ColumnEvaluator:
    """``function`` mapped over ``size`` columns (on :func:`map_threads` threads)."""
    threads = map_threads(size)
    if threads > 1:
        return ColumnEvaluator(function.map(size, "thread", threads))
    return ColumnEvaluator(function.map(size))


class ColumnEvaluator:
    """Evaluates a mapped function on column-major buffers without DM conversions (which
    would cost more than the solve itself); the outputs' layout is read from CasADi once
    (querying it on every call cost a tenth of a fit's solves), and each thread keeps its
    CasADi buffer and arrays bound to it (binding them anew cost a third of a call: a load
    ramp makes ~100 calls on a few columns)."""

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self.nnz_in = [function.nnz_in(i) for i in range(function.n_in())]
        self.nnz_out = [function.nnz_out(i) for i in range(function.n_out())]
        self.shapes = [
            (function.size2_out(i), function.size1_out(i)) for i in range(function.n_out())
        ]
        self._local = threading.local()

    def _bound(self) -> tuple[Callable[[], None], list[np.ndarray], list[np.ndarray]]:
        """This thread's (trigger, input arrays, output arrays), bound to its buffer."""
        bound = getattr(self._local, "bound", None)
        if bound is None:
            buf, trigger = self.function.buffer()
            ins = [np.empty(n) for n in self.nnz_in]
            outs = [np.empty(n) for n in self.nnz_out]
            for i, a in enumerate(ins):
                buf.set_arg(i, memoryview(a))  # type: ignore[call-arg, arg-type]
            for i, o in enumerate(outs):
                buf.set_res(i, memoryview(o))  # type: ignore[call-arg, arg-type]
            bound = self._local.bound = (buf, trigger, ins, outs)  # (buf keeps them bound)
        return bound[1], bound[2], bound[3]

    def __call__(self, args: list[np.ndarray]) -> list[np.ndarray]:
        """Each output as (rows, size) for inputs ``args`` (each (rows, size)); new
        arrays (the buffers are reused)."""
        trigger, ins, outs = self._bound()
        for buf, a in zip(ins, args, strict=True):
            buf[:] = np.ravel(a, order="F")  # (the assignment converts to float64)
        trigger()
        return [o.reshape(shape).T.copy() for o, shape in zip(outs, self.shapes, strict=True)]


class BufferEvaluator:
    """Calls a CasADi function on float64 buffers (no DM conversions, which cost more than
    a compiled evaluation of the rod). Inputs that stay the same over many calls can be
    set once (:meth:`fix`) and the others given to :meth:`views`, which returns the
    outputs as views of the buffers (no copies: a path's Newton corrector makes ~10^3
    calls of ~15 us each, and the copies and conversions around them cost twice that)."""

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self.buffer, self.trigger = function.buffer()
        self.args = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self.outs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        for i, a in enumerate(self.args):
            self.buffer.set_arg(i, memoryview(a))  # type: ignore[call-arg, arg-type]
        for i, o in enumerate(self.outs):
            self.buffer.set_res(i, memoryview(o))  # type: ignore[call-arg, arg-type]
        shapes = [(function.size2_out(i), function.size1_out(i)) for i in range(function.n_out())]
        self._views = [o.reshape(shape).T for o, shape in zip(self.outs, shapes, strict=True)]

    def fix(self, i: int, value: ArrayLike) -> None:
        """Set input ``i`` for the calls of :meth:`views` that follow."""
        self.args[i][:] = np.ravel(value, order="F")  # (the assignment converts to float64)

    def views(self, *args: np.ndarray) -> list[np.ndarray]:
        """The outputs for the first inputs ``args`` and the fixed others, as views of the
        buffers: valid until the next call (copy what must outlive it)."""
        for buf, a in zip(self.args, args, strict=False):
            buf[:] = a.ravel(order="F")
        self.trigger()
        return self._views
