"""Runs killed outright (SIGKILL, no clean-up handlers) at a random moment, then rerun
(issue 17): the rerun leaves no stray temporary and gives the files of an uninterrupted
run. ``optimize`` resumes its Pareto points (``OUT/points``); ``cad`` and ``diagnose``
start again (their files are replaced atomically, so a killed run leaves old or new files,
never half of one). The kill times are drawn from a seeded generator, so a failure
reproduces.
"""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
import time
import zipfile

import pytest

from ringpair.runs import LOCK, MANIFEST

pytestmark = pytest.mark.slow


def ringpair(*args: str, cwd, timeout: float = 300.0) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "ringpair.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


def killed(*args: str, cwd, after: float) -> None:
    """Start ``ringpair args`` and SIGKILL it (and its Dask workers) ``after`` seconds in."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "ringpair.cli", *args],
        cwd=cwd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # its own process group: the workers die with it
    )
    time.sleep(after)
    try:
        os.killpg(proc.pid, 9)
    except ProcessLookupError:  # it had finished
        pass
    proc.wait()


def files(folder, skip=()) -> dict[str, object]:
    """Each file below ``folder`` (but those named in ``skip``) -> its bytes, or for a zip
    (3MF) its members' bytes: a zip stamps the time of writing on each member."""

    def content(path):
        if zipfile.is_zipfile(path):
            with zipfile.ZipFile(path) as z:
                return {name: z.read(name) for name in z.namelist()}
        return path.read_bytes()

    # The run folder's lock and manifest (ringpair.runs) name the process and its start.
    skip = {*skip, LOCK, MANIFEST}
    return {
        str(p.relative_to(folder)): content(p)
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name not in skip
    }


def temporaries(folder) -> list[str]:
    return [str(p.relative_to(folder)) for p in folder.rglob("*.tmp")]


def test_optimize_killed_and_rerun_equals_an_uninterrupted_run(tmp_path, pareto_study):
    study = tmp_path / "study.toml"
    study.write_text(pareto_study)
    whole = ringpair("optimize", str(study), "--out", "whole", cwd=tmp_path)
    assert whole.returncode == 0, whole.stderr
    after = random.Random(17).uniform(2.0, 6.0)
    killed("optimize", str(study), "--out", "again", cwd=tmp_path, after=after)
    rerun = ringpair("optimize", str(study), "--out", "again", cwd=tmp_path)
    assert rerun.returncode == 0, rerun.stderr
    assert temporaries(tmp_path / "again") == []
    # a stored Pareto point and the summary hold timings; the rest is byte for byte
    timed = ("summary.json", *(p.name for p in (tmp_path / "whole" / "points").iterdir()))
    assert files(tmp_path / "again", skip=timed) == files(tmp_path / "whole", skip=timed)
    summary = [json.loads((tmp_path / d / "summary.json").read_text()) for d in ("again", "whole")]
    for key in ("feasible", "objective", "values", "metrics", "active", "constraints", "forward"):
        assert summary[0][key] == summary[1][key], key


def test_cad_killed_and_rerun_equals_an_uninterrupted_run(tmp_path):
    whole = ringpair("cad", "--no-render", "--out", "whole", cwd=tmp_path)
    assert whole.returncode == 0, whole.stderr
    after = random.Random(7).uniform(3.0, 8.0)
    killed("cad", "--no-render", "--out", "again", cwd=tmp_path, after=after)
    rerun = ringpair("cad", "--no-render", "--out", "again", cwd=tmp_path)
    assert rerun.returncode == 0, rerun.stderr
    assert temporaries(tmp_path / "again") == []
    # the summary holds timings, STEP files their time of writing
    volatile = ("cad_summary.json", "ringpair_robot.step")
    assert files(tmp_path / "again", skip=volatile) == files(tmp_path / "whole", skip=volatile)


def test_diagnose_killed_and_rerun_equals_an_uninterrupted_run(tmp_path):
    assert ringpair("synth", "--n", "8", "--out", "bench", cwd=tmp_path).returncode == 0
    args = ("diagnose", "bench", "--folds", "2")
    whole = ringpair(*args, "--json", "whole.json", "--report", "whole", cwd=tmp_path)
    assert whole.returncode == 0, whole.stderr
    after = random.Random(3).uniform(2.0, 6.0)
    killed(*args, "--json", "again.json", "--report", "again", cwd=tmp_path, after=after)
    rerun = ringpair(*args, "--json", "again.json", "--report", "again", cwd=tmp_path)
    assert rerun.returncode == 0, rerun.stderr
    assert temporaries(tmp_path) == []
    assert files(tmp_path / "again") == files(tmp_path / "whole")
    doc = [json.loads((tmp_path / f"{d}.json").read_text()) for d in ("again", "whole")]
    for d in doc:
        d.pop("time_s")
    assert doc[0] == doc[1]
