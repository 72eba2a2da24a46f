"""Worker processes that die with their parent, and interrupts as one exception.

A worker forked or spawned for a run (the fitting pool of :mod:`optimize.fitting.workers`,
the Dask workers of a local cluster) asks the kernel to kill it when its parent dies
(:func:`die_with_parent`, Linux ``prctl(PR_SET_PDEATHSIG)`` through ctypes), so a run
killed outright (``kill -9``) leaves no worker behind. Elsewhere it is a no-op.

:class:`Interrupted` is what Ctrl-C (SIGINT) and SIGTERM raise once
:func:`raise_on_signals` is installed: a ``BaseException`` (like ``KeyboardInterrupt``),
so no ``except Exception`` takes it for a failure, with the signal's number. A library
that catches it where its own C++ code calls back into Python (CasADi's IPOPT interface
turns it into a warning and a stopped solve) would swallow it: the signal is also recorded,
and :func:`raise_if_interrupted` raises it again after such a call.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from types import FrameType

PR_SET_PDEATHSIG = 1
"""prctl option: the signal a process gets when its parent thread dies (linux/prctl.h)."""


def die_with_parent(parent: int | None = None) -> bool:
    """Have the kernel SIGKILL this process when its parent dies (Linux); whether it is
    arranged. ``parent``: the parent's pid when known, checked afterwards (a parent that
    died before the call leaves this process orphaned: it exits at once)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        arranged = libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False
    if arranged and parent is not None and os.getppid() != parent:
        os._exit(1)
    return arranged


class Interrupted(BaseException):  # noqa: N818 - named as what happened, like KeyboardInterrupt
    """The run was interrupted by ``signum`` (SIGINT: Ctrl-C; SIGTERM)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


_seen: list[int] = []
"""The signal :func:`raise_on_signals`' handler took, once one arrived."""


def raise_if_interrupted() -> None:
    """Raise :class:`Interrupted` again if a signal arrived (after a call into a library
    that may have caught the first one); nothing otherwise."""
    if _seen:
        raise Interrupted(_seen[0])


def raise_on_signals(on_second: int = 130) -> None:
    """From now on SIGINT and SIGTERM raise :class:`Interrupted` in the main thread (a
    signal ignored when the process started, as ``nohup`` or a shell's ``&`` do, stays
    ignored); a second signal while the first is handled ends the process at once (exit
    ``on_second``)."""
    _seen.clear()

    def handler(signum: int, frame: FrameType | None) -> None:
        if _seen:
            os._exit(on_second)
        _seen.append(signum)
        raise Interrupted(signum)

    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, handler)


__all__ = ["Interrupted", "die_with_parent", "raise_if_interrupted", "raise_on_signals"]
