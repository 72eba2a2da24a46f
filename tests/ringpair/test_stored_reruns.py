"""What a rerun reads back cannot run code (issue 55): a payload planted in every file a
rerun of ``study`` reads (``OUT/.stages``) or a Pareto sweep resumes from
(``OUT/pareto/points``), and pickles under the old ``.pkl`` names, never run; each planted
file is refused with a warning and its work done again. A stage of a study whose base
design file was edited, with the study's text unchanged, is not reused."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest
from studies import SMALL

from optimize.sizing.nlp import pareto_values
from optimize.sizing.pareto import POINTS, _load, point_key
from optimize.sizing.studyfile import loads_study

pytestmark = pytest.mark.slow  # three short studies through the command line

INFEASIBLE = (
    SMALL.replace(
        "magnet_clearance_mm = 5.0", "magnet_clearance_mm = 5.0\nmin_disc_radius_mm = 500.0"
    )
    .replace("starts = 2", "starts = 1")
    .replace("configurations = 24", "configurations = 8")
)
"""A study that stops after its optimisation (exit 3: no design reaches a 500 mm disc),
so a rerun reads back its first two stages within seconds; its base design is a file."""


class Payload:
    """Unpickling it creates ``marker``: the proof that code from a file ran."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.makedirs, (str(self.marker),))


def ringpair(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "ringpair.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


def test_a_payload_planted_in_every_stage_file_never_runs(tmp_path, demonstrator_doc):
    import tomli_w

    (tmp_path / "base.toml").write_text(tomli_w.dumps(demonstrator_doc))
    (tmp_path / "s.toml").write_text('base_design = "base.toml"\n' + INFEASIBLE)
    args = ("study", "s.toml", "--out", "out", "--no-render")
    first = ringpair(*args, cwd=tmp_path)
    assert first.returncode == 3, first.stderr
    stages = sorted((tmp_path / "out" / ".stages").iterdir())
    assert {p.name.split("-")[0] for p in stages} == {"baseline", "optimise"}
    marker = tmp_path / "code-ran"
    bomb = pickle.dumps((Payload(marker), 1.0))
    for path in stages:
        path.write_bytes(bomb)
        path.with_suffix(".pkl").write_bytes(bomb)  # the names of earlier versions
    rerun = ringpair(*args, cwd=tmp_path)
    assert not marker.exists()
    assert rerun.returncode == 3, rerun.stderr
    for path in stages:
        assert f"{path.name}: not reused" in " ".join(rerun.stderr.split()), rerun.stderr
    assert "reused" not in rerun.stdout  # both stages computed again
    # the base design file edited, the study's text not: nothing is reused
    edited = dict(demonstrator_doc)
    edited["robot"] = dict(edited["robot"]) | {"free_length_mm": 140.0}
    (tmp_path / "base.toml").write_text(tomli_w.dumps(edited))
    changed = ringpair(*args, cwd=tmp_path)
    assert changed.returncode == 3, changed.stderr
    assert "reused" not in changed.stdout, changed.stdout


def test_a_payload_planted_where_a_pareto_point_is_resumed_never_runs(tmp_path):
    study = loads_study(SMALL + '[[pareto]]\nagainst = "external_distance"\npoints = 3\n')
    marker = tmp_path / "code-ran"
    store = tmp_path / POINTS
    store.mkdir()
    sweep = study.pareto[0]
    for e in pareto_values(study, sweep):
        key = point_key(study, sweep.against, e)
        path = store / f"{key[:24]}.npz"  # where run_sweeps resumes this point from
        path.write_bytes(pickle.dumps(Payload(marker)))
        with pytest.warns(UserWarning, match="not reused"):
            assert _load(path, key) is None
    assert not marker.exists()
