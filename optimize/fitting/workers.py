"""Independent fits in parallel: forked worker processes, one per core.

A diagnosis screens several candidate models, cross-validates over several folds and
judges the power of the data for several effects; each of these fits is independent of
the others, and each is mostly Python driving CasADi one configuration at a time, which
threads cannot overlap (the interpreter's lock). Forked workers inherit the parent's
built models and compiled libraries (:func:`design.model.model_for`, :mod:`design.compiled`)
instead of building them again, and the function to run need not be picklable (it is
inherited, not sent); only its results travel back.

``RINGPAIR_WORKERS`` sets the number of workers (default: the cores this process may
use; 1 runs everything in this process). Inside a worker everything runs serially.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, TypeVar

from design.compiled import use_threads

T = TypeVar("T")
R = TypeVar("R")

_JOB: tuple[Callable[[Any], Any], Sequence[Any]] | None = None
"""The function and items of the running :func:`parallel_map`, inherited by its workers."""
_IN_WORKER = False
WORKERS_VARIABLE = "RINGPAIR_WORKERS"


def worker_count() -> int:
    """How many worker processes :func:`parallel_map` uses (``RINGPAIR_WORKERS``, else the
    cores available to this process); 1 inside a worker."""
    if _IN_WORKER:
        return 1
    text = os.environ.get(WORKERS_VARIABLE, "").strip()
    if text:
        try:
            count = int(text)
        except ValueError:
            count = 0
        if count < 1:
            raise ValueError(
                f"{WORKERS_VARIABLE} must be a whole number of processes, at least 1; got {text!r}"
            )
        return count
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _start() -> None:
    global _IN_WORKER
    _IN_WORKER = True
    use_threads(1)  # the other workers keep the other cores busy


def _call(i: int) -> Any:
    assert _JOB is not None
    fn, items = _JOB
    return fn(items[i])


def parallel_map(fn: Callable[[T], R], items: Sequence[T]) -> list[R]:
    """``[fn(x) for x in items]``, the items spread over forked workers where there are
    several of each; in this process where fork is unavailable, where there is one
    worker or item, or where a worker dies (the pool breaks)."""
    global _JOB
    n = min(worker_count(), len(items))
    if n <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        return [fn(x) for x in items]
    _JOB = (fn, items)
    try:
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(n, mp_context=context, initializer=_start) as pool:
            return list(pool.map(_call, range(len(items))))
    except BrokenProcessPool:
        return [fn(x) for x in items]
    finally:
        _JOB = None
