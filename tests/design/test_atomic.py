"""Atomic writes: all or nothing, with the usual file mode."""

from __future__ import annotations

import os
import stat

import pytest

from design.atomic import atomic_path, write_text


def test_failed_write_leaves_neither_target_nor_temporary(tmp_path):
    target = tmp_path / "out.csv"
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("stage failed")
    assert list(tmp_path.iterdir()) == []


def test_written_file_has_the_umask_mode(tmp_path):
    old = os.umask(0o022)
    try:
        write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o644
    assert (tmp_path / "a.txt").read_text() == "x"


def test_a_device_or_fifo_is_never_replaced(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(FileExistsError, match="not a regular file"):
        write_text(fifo, "x")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["pipe"]


def test_only_proven_temporaries_of_dead_writers_are_removed(tmp_path):
    """A name with a forged proof, or a proven one whose writer lives, is kept."""
    from design.atomic import _proof, remove_stale_temporaries

    dead = tmp_path / f".a.csv.999999999.abcd1234.{_proof('.a.csv.999999999.abcd1234')}.tmp"
    forged = tmp_path / ".b.csv.999999999.abcd1234.0123456789abcdef.tmp"
    stem = f".c.csv.{os.getpid()}.abcd1234"
    live = tmp_path / f"{stem}.{_proof(stem)}.tmp"
    for p in (dead, forged, live):
        p.write_text("")
    assert remove_stale_temporaries(tmp_path) == [dead]
    assert forged.exists() and live.exists()
