"""Reading an input file (design, study, measurements, targets): a regular file of
bounded size, one message if it cannot be read."""

from __future__ import annotations

import os
import stat
from pathlib import Path

MAX_INPUT_BYTES = 64 * 1024 * 1024
"""Largest input file (design, study, measurements, targets) read. [bytes]"""


def read_regular(path: str | os.PathLike[str], encoding: str = "utf-8") -> str:
    """The text of ``path`` if it is a regular file of at most :data:`MAX_INPUT_BYTES`;
    OSError saying what it is otherwise (a FIFO, a device or a socket is never opened: it
    could block or never end)."""
    p = Path(path)
    info = os.stat(p)  # FileNotFoundError, IsADirectoryError below: as open() would say
    if stat.S_ISDIR(info.st_mode):
        raise IsADirectoryError(21, "is a folder", str(p))
    if not stat.S_ISREG(info.st_mode):
        raise OSError(f"{p} is not a regular file (a device, FIFO or socket); not read")
    if info.st_size > MAX_INPUT_BYTES:
        raise OSError(f"{p} has {info.st_size:,} bytes, more than {MAX_INPUT_BYTES:,}; not read")
    with p.open("r", encoding=encoding) as f:
        text = f.read(MAX_INPUT_BYTES + 1)
    if len(text) > MAX_INPUT_BYTES:
        raise OSError(f"{p} grew past {MAX_INPUT_BYTES:,} bytes while read; not read")
    return text


def read_input(path: Path, kind: str, error: type[Exception]) -> str:
    """The UTF-8 text of the ``kind`` file (e.g. "design") at ``path``; ``error`` with
    one message if it does not exist or cannot be read."""
    try:
        return read_regular(path)
    except FileNotFoundError:
        raise error(f"{kind} file {path} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{kind} file {path} cannot be read: {exc}") from None
