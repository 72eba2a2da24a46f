"""Atomic file writes: a temporary file beside the target, then a rename; and the clean-up
of temporaries that a killed run left behind.

A temporary is named ``.<target name>.<pid>.<8 random characters>.tmp``: the process id
tells a later run whether its writer is still alive (:func:`remove_stale_temporaries`).
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path

_TEMPORARY = re.compile(r"^\.(?P<target>.+?)(?:\.(?P<pid>\d+))?\.[a-z0-9_]{8}\.tmp$")
"""A temporary of :func:`atomic_path` (older ones have no process id)."""
_PLAIN_TEMPORARY = re.compile(r"^tmp[a-z0-9_]{8}\.tmp$")
"""A temporary of ``tempfile.mkstemp(suffix='.tmp')``, as the Pareto points' store
(a folder ``points``) writes them."""
DEPTH = 3
"""How deep below an output folder temporaries are looked for (ringpair writes at most
``OUT/pareto/points/``)."""


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it onto ``target`` on success.

    On any exception the temporary file is removed and ``target`` is left untouched, so a
    failed run never leaves a half-written file. A run killed outright (SIGKILL) can leave
    the temporary; the next run's :func:`remove_stale_temporaries` removes it.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=target.parent
    )
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(target: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``target`` atomically."""
    with atomic_path(target) as tmp:
        tmp.write_text(text, encoding="utf-8")


def remove_stale_temporaries(
    folder: str | os.PathLike[str], target: str | None = None
) -> list[Path]:
    """Remove the temporaries that killed runs left in ``folder`` and below it; the paths.

    target : only the temporaries of this file name, in ``folder`` itself (for a command
        that writes one file). Default: every temporary in the tree (for a command that
        owns the folder).

    A temporary whose writer is still running (its process id is alive) is kept, so two
    runs into the same folder do not break each other's writes.
    """
    root = Path(folder)
    if not root.is_dir():
        return []
    if target is not None:
        candidates = list(root.glob(f".{_glob_escape(target)}.*.tmp"))
    else:
        candidates = []
        for here, subfolders, names in os.walk(root):
            if len(Path(here).relative_to(root).parts) >= DEPTH:
                subfolders.clear()
            candidates += [Path(here, n) for n in names if n.endswith(".tmp")]
    removed = [path for path in candidates if path.is_file() and _stale(path, target)]
    for path in removed:
        path.unlink(missing_ok=True)
    return removed


def _stale(path: Path, target: str | None) -> bool:
    """Whether ``path`` is a temporary (of ``target``, if given) whose writer is gone."""
    match = _TEMPORARY.match(path.name)
    if match is None:
        plain = _PLAIN_TEMPORARY.match(path.name) is not None
        return target is None and plain and path.parent.name == "points"
    return (target is None or match["target"] == target) and not _alive(match["pid"])


def _glob_escape(name: str) -> str:
    """``name`` with glob's special characters taken literally."""
    return re.sub(r"([*?\[])", r"[\1]", name)


def _alive(pid: str | None) -> bool:
    """Whether process ``pid`` runs (False for no pid; True where it cannot be told)."""
    if pid is None:
        return False
    if os.name != "posix":
        return True
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True
