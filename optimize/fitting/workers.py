"""Independent fits in parallel: forked worker processes, one per core.

A diagnosis screens several candidate models, cross-validates over several folds and
judges the power of the data for several effects; each of these fits is independent of
the others, and each is mostly Python driving CasADi one configuration at a time, which
threads cannot overlap (the interpreter's lock). Forked workers inherit the parent's
built models and compiled libraries (:func:`design.model.model_for`, :mod:`design.compiled`)
instead of building them again, and the function to run need not be picklable (it is
inherited, not sent); only its results travel back.

:class:`Background` runs jobs in one more forked worker while this process goes on with
work they do not depend on (a diagnosis screens candidates from the nominal design while
it fits the baseline, one core otherwise idle).

``RINGPAIR_WORKERS`` sets the number of workers (default: the cores this process may
use; 1 runs everything in this process). Inside a worker everything runs serially.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from multiprocessing.connection import Connection
from typing import Any, Generic, TypeVar

from design.compiled import use_threads
from design.processes import die_with_parent

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


def _start(parent: int) -> None:
    global _IN_WORKER
    _IN_WORKER = True
    die_with_parent(parent)  # a killed run leaves no worker behind
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
        with ProcessPoolExecutor(
            n, mp_context=context, initializer=_start, initargs=(os.getpid(),)
        ) as pool:
            return list(pool.map(_call, range(len(items))))
    except BrokenProcessPool:
        return [fn(x) for x in items]
    finally:
        _JOB = None


def _background(
    fn: Callable[[Any], Any], items: Sequence[Any], claimed: Any, send: Connection, parent: int
) -> None:
    """A background worker's work: each item not yet claimed (``claimed``: the items
    taken so far, shared), one after the other, until none are left; then their results,
    or None where anything failed (:meth:`Background.results` then runs them in its own
    process, where errors show)."""
    _start(parent)
    try:
        out = []
        while True:
            with claimed.get_lock():
                i = claimed.value
                if i >= len(items):
                    break
                claimed.value = i + 1
            out.append(fn(items[i]))
        send.send(out)
    except BaseException:  # noqa: BLE001 (reported by running again in the parent)
        send.send(None)
    finally:
        send.close()


class Background(Generic[T, R]):
    """``fn`` of each of ``items`` in one forked worker, one after the other, started now
    while this process goes on. :meth:`stop` lets it start no more (their items are the
    caller's again), :meth:`results` waits for those it took, :meth:`cancel` stops it.
    Where :func:`parallel_map` would run in this process (one worker, no fork) it takes
    none; where it fails, :meth:`results` runs its items here."""

    def __init__(self, fn: Callable[[T], R], items: Sequence[T]) -> None:
        self.items = list(items)
        self._fn = fn
        self._process: Any = None
        self._taken: list[T] = []
        self._stopped = False
        if worker_count() > 1 and self.items and "fork" in multiprocessing.get_all_start_methods():
            context = multiprocessing.get_context("fork")
            self._claimed = context.Value("i", 0)
            self._receive, send = context.Pipe(duplex=False)
            self._process = context.Process(
                target=_background,
                args=(fn, self.items, self._claimed, send, os.getpid()),
                daemon=True,
            )
            self._process.start()
            send.close()

    def stop(self) -> list[T]:
        """Let the worker start no more items: the items it has taken (started or done)."""
        if not self._stopped and self._process is not None:
            with self._claimed.get_lock():
                taken = self._claimed.value
                self._claimed.value = len(self.items)
            self._taken = self.items[:taken]
        self._stopped = True
        return self._taken

    def results(self) -> list[R]:
        """The results of the items taken (all, unless :meth:`stop` came first), in their
        order; waits for the worker."""
        taken = self._taken if self._stopped else self.items
        out = None
        if self._process is not None:
            try:
                out = self._receive.recv()
            except (EOFError, OSError):  # the worker died
                out = None
            self.cancel()
        return out if out is not None else [self._fn(x) for x in taken]

    def cancel(self) -> None:
        """Stop the worker (its results are not needed)."""
        if self._process is not None:
            self._process.kill()
            self._process.join()
            self._receive.close()
            self._process = None
