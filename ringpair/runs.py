"""One run's folder is one run's, and what a rerun reads back from it: a lock against
concurrent runs, a marker of a run in progress (so the next run and its manifest see one
that was interrupted), the removal of an earlier run's outputs that this run did not write
again, and the stored results of a study's stages.

The lock (``OUT/.ringpair.lock``, an advisory ``flock`` the kernel releases when the
process ends, however it ends) refuses a second run into the same folder with a message
naming the run that holds it. The marker (``OUT/.ringpair-running.json``) is written when a
run starts and removed when it ends, failed or not; one found at the start was left by a
run that was interrupted or killed. Stale outputs are found from the earlier run's
``manifest.json`` (its files with their SHA-256): a file listed there that is unchanged
since (so it is what ringpair wrote, not something edited or put there since), was not
written by this run and is not part of a stage this run reused, is removed. Nothing else
is ever removed.

A study's stages are stored in ``OUT/.stages`` (:mod:`design.stored`) under the key of
all their inputs (:func:`inputs_key`); :func:`stored_stage` reads one back or says, in a
warning, why not.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from design import stored
from design.atomic import write_text
from optimize.sizing.studyfile import Study

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


def finish_run(folder: RunFolder, keep: Iterable[str] = ()) -> None:
    """Remove the earlier run's stale outputs, then write ``manifest.json``: the command,
    the run's folder (an interrupted earlier run, the stale files removed) and every file
    this run wrote (modified since it started), with its size and SHA-256."""
    folder.remove_stale(keep)
    files = sorted(
        p
        for p in folder.out.rglob("*")
        if p.is_file()
        and not p.is_symlink()
        and p.name != MANIFEST
        and not p.name.startswith(".ringpair")
        and p.stat().st_mtime >= folder.started
    )
    doc = {
        "command": folder.command,
        "started": folder.started,
        "run": {
            "previous_run_interrupted": folder.interrupted is not None,
            "removed_stale": folder.removed,
        },
        "files": [
            {"path": str(p.relative_to(folder.out)), "bytes": p.stat().st_size, "sha256": sha256(p)}
            for p in files
        ],
    }
    write_text(folder.out / MANIFEST, json.dumps(doc, indent=2) + "\n")


def _marker(path: Path) -> dict[str, Any] | None:
    """What an interrupted run's marker says, {} if unreadable, None if there is none."""
    if not path.exists():
        return None
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


# Stored stage results (design.stored) and the hashes of inputs.


def sha256(path: Path) -> str:
    """SHA-256 (hex) of the file at ``path``."""
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def tree_hash(path: Path) -> str:
    """Identity of a file or a folder's files: names (relative) and SHA-256s."""
    files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
    return stored.digest(*[(str(p.relative_to(path.parent)), sha256(p)) for p in files])


def inputs_key(study: Study, study_text: str, data: Path | None) -> str:
    """Identity of everything a study's stages depend on: the study file's text, the study
    as resolved (its base design's values included), the bytes of the base design file it
    names, the measured data set's files (when given) and the code
    (:func:`optimize.sizing.pareto.code_digest`: version and source). [-]"""
    from optimize.sizing.pareto import code_digest

    named = Path(study.base_source) if study.base_source != "embedded" else None
    base_file = sha256(named) if named is not None and named.is_file() else None
    data_files = tree_hash(data) if data is not None else None
    return stored.digest(study_text, study, base_file, data_files, code_digest())


def stored_stage(out: Path, name: str, key: str) -> tuple[Any, float] | None:
    """A stage's stored (result, seconds) for ``key``, or None: not stored, or stored but
    foreign, truncated or altered (then with a warning, and the stage runs again)."""
    from optimize.sizing.pareto import PACKAGES

    value = stored.reuse(
        stage_path(out, name, key),
        key,
        PACKAGES,
        lambda v: isinstance(v, dict) and set(v) == {"result", "seconds"},
        "a stage result",
        f"stage '{name}' runs again",
    )
    if value is None:
        return None
    return value["result"], float(value["seconds"])


def stage_path(out: Path, name: str, key: str) -> Path:
    """Where stage ``name``'s result for ``key`` is stored in the folder ``out``."""
    return out / ".stages" / f"{name}-{key[:20]}.npz"


__all__ = [
    "LOCK",
    "RUNNING",
    "FolderBusy",
    "RunFolder",
    "finish_run",
    "inputs_key",
    "run_folder",
    "sha256",
    "stage_path",
    "stored_stage",
    "tree_hash",
]
