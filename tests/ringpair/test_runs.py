"""One run's folder is one run's (issue 55, ringpair.runs): a second run into a folder
in use is refused naming the holder; an earlier run's outputs that this run does not
write again (a stale best_design.toml after an infeasible rerun, Pareto files of a run
with Pareto, plates of another print process) are removed, and only those that are
unchanged since it wrote them; an interrupted run's marker is seen by the next run and
its manifest."""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import signal
import subprocess
import sys
import time

import pytest
from studies import SMALL

from ringpair.runs import LOCK, RUNNING

INFEASIBLE = (
    SMALL.replace(
        "magnet_clearance_mm = 5.0", "magnet_clearance_mm = 5.0\nmin_disc_radius_mm = 500.0"
    )
    .replace("starts = 2", "starts = 1")
    .replace("configurations = 24", "configurations = 8")
)
"""Ends after its optimisation (exit 3), within seconds."""


@pytest.fixture()
def study(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(INFEASIBLE)
    return path


def test_a_second_run_into_a_folder_in_use_is_refused(tmp_path, run, study):
    out = tmp_path / "out"
    out.mkdir()
    with open(out / LOCK, "w") as held:
        held.write("ringpair study (pid 4242)\n")
        held.flush()
        fcntl.flock(held, fcntl.LOCK_EX)
        result = run("study", str(study), "--out", str(out))
    assert result.exit_code == 2, result.output
    assert "in use by ringpair study (pid 4242)" in " ".join(result.output.split())
    assert sorted(p.name for p in out.iterdir()) == [LOCK]


@pytest.mark.slow
def test_stale_outputs_of_an_earlier_run_are_removed_and_only_those(tmp_path, run, study):
    out = tmp_path / "out"
    earlier = {
        "best_design.toml": b"name = 'old'\n",
        "pareto/pareto_external_distance.csv": b"epsilon,objective\n",
        "cad/plate_fdm_1.3mf": b"plate",
        "notes.txt": b"edited by someone since",
    }
    listed = []
    for rel, content in earlier.items():
        path = out / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content)
        digest = hashlib.sha256(content if rel != "notes.txt" else b"as written").hexdigest()
        listed.append({"path": rel, "bytes": len(content), "sha256": digest})
        os.utime(path, (time.time() - 3600,) * 2)
    mine = out / "mine.csv"
    mine.write_text("not ringpair's\n")
    os.utime(mine, (time.time() - 3600,) * 2)
    (out / "manifest.json").write_text(json.dumps({"files": listed}))
    result = run("study", str(study), "--out", str(out))
    assert result.exit_code == 3, result.output
    left = {str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()}
    assert not left & {rel for rel in earlier if rel != "notes.txt"}, left
    assert {"notes.txt", "mine.csv"} <= left  # changed since, or never listed: kept
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["failed_stage"] == "optimise"
    assert sorted(manifest["run"]["removed_stale"]) == sorted(
        rel for rel in earlier if rel != "notes.txt"
    )


@pytest.mark.slow
def test_an_interrupted_run_is_seen_by_the_next_run_and_its_manifest(tmp_path, study):
    # The interrupted run is a feasible study (its workspace, parts and report take far
    # longer than the infeasible one's seconds, which could end before the signal lands).
    feasible = tmp_path / "feasible.toml"
    feasible.write_text(SMALL)
    first = [sys.executable, "-m", "ringpair.cli", "study", str(feasible), "--out", "out"]
    args = [sys.executable, "-m", "ringpair.cli", "study", str(study), "--out", "out"]
    proc = subprocess.Popen(first, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    t0 = time.monotonic()
    while not (tmp_path / "out" / RUNNING).exists():
        assert time.monotonic() - t0 < 120 and proc.poll() is None
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=120)
    assert proc.returncode == 130
    assert (tmp_path / "out" / RUNNING).exists()
    rerun = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert rerun.returncode == 3, rerun.stderr
    assert "previous run into out was interrupted" in " ".join(rerun.stderr.split())
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert manifest["run"]["previous_run_interrupted"] is True
    assert not (tmp_path / "out" / RUNNING).exists()
