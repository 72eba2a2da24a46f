"""One run's folder is one run's for the commands that write a folder without a study's
stages (issue 55, ringpair.runs.held_run): ``cad`` and ``workspace`` record what they
wrote in manifest.json; a rerun removes the earlier run's outputs it did not write again
(another print process's plates) and nothing else; an interrupted run leaves a marker the
next run warns about and records; a second run into a folder in use is refused. The CAD
itself is replaced by a stand-in that writes what build_parts writes (names by process), so
each run takes a second, not a minute."""

from __future__ import annotations

import fcntl
import hashlib
import json
import time
from dataclasses import dataclass

import pytest
import tomli_w
from bad_designs import edited

import cad
from ringpair.runs import LOCK, RUNNING


@dataclass
class _Report:
    passed: bool = True

    def summary(self) -> str:
        return "stand-in CAD report"


@pytest.fixture()
def fake_cad(monkeypatch):
    """build_parts replaced: writes checks.csv and one plate named by the tip's process;
    ``fake_cad.interrupt`` set makes it stop with Ctrl-C after the plate."""

    class Fake:
        interrupt = False

        def __call__(self, design, out, process, render=True):
            (out / "checks.csv").write_text("item,check\n")
            (out / f"plate_{design.tip.mounting.process}_1.3mf").write_text("plate")
            if self.interrupt:
                raise KeyboardInterrupt
            return _Report()

    fake = Fake()
    monkeypatch.setattr(cad, "build_parts", fake)
    return fake


def _design(tmp_path, doc, process):
    path = tmp_path / f"{process}.toml"
    path.write_text(tomli_w.dumps(edited(doc, "tip.mounting", {"process": process})))
    return str(path)


def _manifest(out):
    return json.loads((out / "manifest.json").read_text())


def test_a_resin_rerun_of_cad_removes_the_fdm_plates_and_nothing_else(
    tmp_path, run, demonstrator_doc, fake_cad
):
    out = tmp_path / "cad"
    first = run("cad", _design(tmp_path, demonstrator_doc, "fdm"), "--out", str(out))
    assert first.exit_code == 0, first.output
    assert {f["path"] for f in _manifest(out)["files"]} == {"checks.csv", "plate_fdm_1.3mf"}
    (out / "notes.txt").write_text("mine\n")  # the user's, never listed: never removed
    second = run("cad", _design(tmp_path, demonstrator_doc, "resin"), "--out", str(out))
    assert second.exit_code == 0, second.output
    names = sorted(p.name for p in out.iterdir())
    assert names == [LOCK, "checks.csv", "manifest.json", "notes.txt", "plate_resin_1.3mf"]
    manifest = _manifest(out)
    assert manifest["run"]["removed_stale"] == ["plate_fdm_1.3mf"]
    assert {f["path"] for f in manifest["files"]} == {"checks.csv", "plate_resin_1.3mf"}


def test_an_interrupted_cad_leaves_a_marker_the_next_run_reports(
    tmp_path, run, demonstrator_doc, fake_cad
):
    out = tmp_path / "cad"
    design = _design(tmp_path, demonstrator_doc, "resin")
    fake_cad.interrupt = True
    assert run("cad", design, "--out", str(out)).exit_code != 0
    assert (out / RUNNING).is_file() and not (out / "manifest.json").exists()
    fake_cad.interrupt = False
    again = run("cad", design, "--out", str(out))
    assert again.exit_code == 0, again.output
    assert "previous run into" in again.output and "was interrupted" in again.output
    assert _manifest(out)["run"]["previous_run_interrupted"] is True
    assert not (out / RUNNING).exists()


def test_a_second_cad_into_a_folder_in_use_is_refused(tmp_path, run, fake_cad):
    out = tmp_path / "cad"
    out.mkdir()
    with open(out / LOCK, "w") as held:
        held.write("ringpair cad (pid 4242)\n")
        held.flush()
        fcntl.flock(held, fcntl.LOCK_EX)
        result = run("cad", "--out", str(out))
    assert result.exit_code == 2, result.output
    assert "in use by ringpair cad (pid 4242)" in " ".join(result.output.split())
    assert sorted(p.name for p in out.iterdir()) == [LOCK]


def test_a_workspace_rerun_lists_what_it_wrote_and_keeps_the_users_files(tmp_path, run):
    out = tmp_path / "ws"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    result = run("workspace", "--step=90", "--effects=none", "--out", str(out))
    assert result.exit_code == 0, result.output
    listed = {f["path"] for f in _manifest(out)["files"]}
    assert {"workspace.csv", "summary.json", "controllable.png"} <= listed
    assert "notes.txt" not in listed and (out / "notes.txt").read_text() == "mine\n"


def test_an_infeasible_optimize_rerun_removes_the_earlier_best_design_and_pareto_files(
    tmp_path, run
):
    # the earlier run's files as its manifest lists them; an infeasible rerun without Pareto
    # writes neither: they go, the resumable points and the user's file stay
    from tests.ringpair.test_runs import INFEASIBLE

    study = tmp_path / "s.toml"
    study.write_text(INFEASIBLE)
    out = tmp_path / "opt"
    (out / "points").mkdir(parents=True)
    earlier = {
        "best_design.toml": "name = 'old'\n",
        "pareto_external_distance.csv": "epsilon,objective\n",
        "points/p.npz": "kept",
    }
    files = []
    for rel, text in earlier.items():
        (out / rel).write_text(text)
        digest = hashlib.sha256(text.encode()).hexdigest()
        files.append({"path": rel, "bytes": len(text), "sha256": digest})
    (out / "manifest.json").write_text(json.dumps({"files": files}))
    (out / "notes.txt").write_text("mine\n")
    time.sleep(0.01)  # the earlier files are older than this run
    result = run("optimize", str(study), "--no-pareto", "--out", str(out))
    assert result.exit_code == 0, result.output
    removed = _manifest(out)["run"]["removed_stale"]
    assert sorted(removed) == ["best_design.toml", "pareto_external_distance.csv"]
    assert (out / "points" / "p.npz").exists() and (out / "notes.txt").exists()
    assert (out / "summary.json").exists() and not (out / "best_design.toml").exists()
