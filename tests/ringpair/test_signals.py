"""Interrupts (issue 55): Ctrl-C (SIGINT) and SIGTERM end a run with one line,
``interrupted``, and exit 130, with no traceback (from Dask either, during a Pareto
sweep); worker processes die with a run killed outright (SIGKILL). Each through the
command line in a subprocess."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.slow


def start(*args: str, cwd) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "ringpair.cli", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def wait_for(condition, timeout: float = 300.0) -> None:
    t0 = time.monotonic()
    while not condition():
        assert time.monotonic() - t0 < timeout, "timed out"
        time.sleep(0.2)


def children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (Linux /proc)."""
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry))
    return out


def alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_an_interrupt_exits_130_saying_interrupted(tmp_path, sig):
    proc = start("workspace", "--step", "2", "--out", "ws", cwd=tmp_path)
    time.sleep(3.0)  # importing, compiling or solving
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "interrupted"
    assert "Traceback" not in err and "Aborted" not in err
    assert not list((tmp_path / "ws").rglob("*.tmp")) if (tmp_path / "ws").exists() else True


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and prctl")
def test_ctrl_c_during_a_pareto_sweep_stops_dask_quietly(tmp_path, pareto_study):
    (tmp_path / "s.toml").write_text(pareto_study)
    proc = start("optimize", "s.toml", "--out", "o", cwd=tmp_path)
    wait_for(lambda: (tmp_path / "o" / "workspace.png").exists())  # written before the sweep
    wait_for(lambda: len(children(proc.pid)) >= 2)  # the cluster's workers
    workers = children(proc.pid)
    time.sleep(2.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert lines[-1] == "interrupted", err  # after the run's size announcement, nothing else
    assert not any(w in err.lower() for w in ("traceback", "distributed", "warning")), err
    wait_for(lambda: not any(alive(w) for w in workers), timeout=20)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and prctl")
def test_fit_workers_die_with_a_killed_run(tmp_path):
    subprocess.run(
        [sys.executable, "-m", "ringpair.cli", "synth", "--n", "8", "--out", "bench"],
        cwd=tmp_path,
        check=True,
        capture_output=True,
    )
    env = dict(os.environ, RINGPAIR_WORKERS="2")
    proc = subprocess.Popen(
        [sys.executable, "-m", "ringpair.cli", "diagnose", "bench", "--folds", "2"],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wait_for(lambda: len(children(proc.pid)) >= 1 or proc.poll() is not None)
    workers = children(proc.pid)
    assert workers, "diagnose finished before forking its workers"
    proc.kill()
    proc.wait()
    wait_for(lambda: not any(alive(w) for w in workers), timeout=20)
