"""Atomic file writes: a temporary file beside the target, then a rename; and the clean-up
of temporaries that a killed run left behind.

A temporary is named ``.<target name>.<pid>.<8 random characters>.<proof>.tmp``: the process
id tells a later run whether its writer is still alive, and the proof (an HMAC-SHA256 of
the rest of the name under a key kept in the user's ringpair cache,
:data:`KEY_FILE`) shows that ringpair wrote it. The clean-up
(:func:`remove_stale_temporaries`) removes only temporaries with a valid proof whose
writer is gone: a file that merely looks like a temporary (someone's own file, a
temporary of another program or of another user's ringpair) is never touched.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import hmac
import os
import re
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path

_TEMPORARY = re.compile(
    r"^\.(?P<target>.+)\.(?P<pid>\d+)\.(?P<nonce>[a-z0-9_]{8})\.(?P<proof>[0-9a-f]{16})\.tmp$"
)
"""A temporary of :func:`atomic_path`."""
DEPTH = 3
"""How deep below an output folder temporaries are looked for (ringpair writes at most
``OUT/pareto/points/``)."""
KEY_FILE = "temporaries.key"
"""The file in the ringpair cache (``$RINGPAIR_CACHE``, default ``~/.cache/ringpair``)
holding the key that proves a temporary is ringpair's (created on first use, mode 0600)."""


@functools.lru_cache(maxsize=4)
def _key(cache: str) -> bytes:
    """The user's temporaries key in ``cache``; a key of this process alone where none can
    be kept (its temporaries then are never removed by a later run)."""
    path = Path(cache) / KEY_FILE
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except FileExistsError:
            pass
        else:
            with os.fdopen(fd, "w") as f:
                f.write(secrets.token_hex(32))
        info = os.stat(path, follow_symlinks=False)
        if not stat.S_ISREG(info.st_mode) or info.st_size > 4096:
            raise OSError("not a key file")
        key = path.read_text(encoding="ascii").strip()
        if len(key) < 32:
            raise OSError("key too short")
        return key.encode()
    except (OSError, UnicodeDecodeError):
        return secrets.token_bytes(32)


def _cache() -> str:
    return os.environ.get("RINGPAIR_CACHE", str(Path.home() / ".cache" / "ringpair"))


def _proof(stem: str) -> str:
    """The proof of ownership of a temporary named ``stem`` + ``.<proof>.tmp``."""
    return hmac.new(_key(_cache()), stem.encode(), hashlib.sha256).hexdigest()[:16]


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it onto ``target`` on success.

    On any exception the temporary file is removed and ``target`` is left untouched, so a
    failed run never leaves a half-written file. A run killed outright (SIGKILL) can leave
    the temporary; the next run's :func:`remove_stale_temporaries` removes it.
    """
    target = Path(target)
    with contextlib.suppress(FileNotFoundError):
        mode = os.stat(target).st_mode
        if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):  # a folder fails in os.replace
            raise FileExistsError(f"{target} is not a regular file; it is not replaced")
    target.parent.mkdir(parents=True, exist_ok=True)
    while True:
        stem = f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}"
        tmp_path = target.parent / f"{stem}.{_proof(stem)}.tmp"
        try:
            os.close(os.open(tmp_path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
            break
        except FileExistsError:  # pragma: no cover - 2^32 names
            continue
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o666 & ~_umask())  # created 0600; give the usual mode
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

    Only temporaries that ringpair proves it wrote (their name's HMAC, see the module) are
    removed; one whose writer is still running (its process id is alive) is kept, so two
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
    removed = [path for path in candidates if _stale(path, target)]
    for path in removed:
        path.unlink(missing_ok=True)
    return removed


def _stale(path: Path, target: str | None) -> bool:
    """Whether ``path`` is a regular file, a temporary ringpair proves it wrote (of
    ``target``, if given), whose writer is gone."""
    match = _TEMPORARY.match(path.name)
    if match is None or (target is not None and match["target"] != target):
        return False
    stem = path.name[: -len(f".{match['proof']}.tmp")]
    if not hmac.compare_digest(_proof(stem), match["proof"]):
        return False
    try:
        if not stat.S_ISREG(os.stat(path, follow_symlinks=False).st_mode):
            return False
    except OSError:
        return False
    return not _alive(match["pid"])


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
