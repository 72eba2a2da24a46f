"""One run's folder is one run's: a lock against concurrent runs, a marker of a run in
progress (so the next run and its manifest see one that was interrupted), and the removal
of an earlier run's outputs that this run did not write again.

The lock (``OUT/.ringpair.lock``, an advisory ``flock`` the kernel releases when the
process ends, however it ends) refuses a second run into the same folder with a message
naming the run that holds it. The marker (``OUT/.ringpair-running.json``) is written when a
run starts and removed when it ends, failed or not; one found at the start was left by a
run that was interrupted or killed. Stale outputs are found from the earlier run's
``manifest.json`` (its files with their SHA-256): a file listed there that is unchanged
since (so it is what ringpair wrote, not something edited or put there since), was not
written by this run and is not part of a stage this run reused, is removed. Nothing else
is ever removed.
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from design.atomic import write_text

LOCK = ".ringpair.lock"
RUNNING = ".ringpair-running.json"
MANIFEST = "manifest.json"


class FolderBusy(RuntimeError):
    """Another run holds the folder's lock; the message says which."""


@dataclass
class RunFolder:
    """A run's folder while it runs. started : the run's start (epoch seconds). [s]
    interrupted : the marker an earlier, interrupted run left (its pid, command, start),
    or None. removed : stale files removed (relative paths)."""

    out: Path
    command: str
    started: float
    interrupted: dict[str, Any] | None = None
    removed: list[str] = field(default_factory=list)

    def remove_stale(self, reused: Iterable[str] = ()) -> list[str]:
        """Remove the files of the earlier run's manifest that are unchanged, not written
        by this run and not under a folder of ``reused`` (a reused stage's files, e.g.
        ``cad``); the relative paths removed."""
        from ringpair.pipeline import sha256

        keep = tuple(f"{r}/" for r in reused)
        for entry in _listed(self.out / MANIFEST):
            rel = entry["path"]
            path = self.out / rel
            if rel.startswith(keep) or not _inside(path, self.out):
                continue
            try:
                info = path.lstat()
                if not path.is_file() or path.is_symlink() or info.st_mtime >= self.started:
                    continue
                if info.st_size != entry.get("bytes") or sha256(path) != entry.get("sha256"):
                    continue  # changed since: not ours any more
                path.unlink()
            except OSError:
                continue
            self.removed.append(rel)
        return self.removed


def _listed(manifest: Path) -> list[dict[str, Any]]:
    """The files an earlier run's manifest lists ([] when none can be read)."""
    try:
        doc = json.loads(manifest.read_text(encoding="utf-8"))
        files = doc["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return []
    if not isinstance(files, list):
        return []
    return [f for f in files if isinstance(f, dict) and isinstance(f.get("path"), str)]


def _inside(path: Path, folder: Path) -> bool:
    try:
        return path.resolve().is_relative_to(folder.resolve()) and ".." not in Path(path).parts
    except (OSError, RuntimeError):
        return False


@contextlib.contextmanager
def run_folder(out: Path, command: str) -> Iterator[RunFolder]:
    """Hold ``out`` for one run of ``command``: FolderBusy if another run holds it; the
    marker of an interrupted earlier run read; this run's marker written, and removed when
    the block ends (not when the process is killed or interrupted: the next run sees it)."""
    import fcntl

    out.mkdir(parents=True, exist_ok=True)
    fd = os.open(out / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 200, 0).decode(errors="replace").strip() or "another run"
            raise FolderBusy(
                f"{out} is in use by {holder}; wait for it to end or choose another --out"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"ringpair {command} (pid {os.getpid()})\n".encode(), 0)
        marker = out / RUNNING
        folder = RunFolder(out, command, time.time(), _marker(marker))
        write_text(
            marker,
            json.dumps({"pid": os.getpid(), "command": command, "started": folder.started}) + "\n",
        )
        try:
            yield folder
        except (Exception, SystemExit):  # the run ended (failed): its files are whole
            marker.unlink(missing_ok=True)
            raise
        # an interrupt (BaseException) leaves the marker for the next run to see
        marker.unlink(missing_ok=True)
    finally:
        os.close(fd)


def _marker(path: Path) -> dict[str, Any] | None:
    """What an interrupted run's marker says, {} if unreadable, None if there is none."""
    if not path.exists():
        return None
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


__all__ = ["LOCK", "RUNNING", "FolderBusy", "RunFolder", "run_folder"]
