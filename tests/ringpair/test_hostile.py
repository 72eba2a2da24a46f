"""Hostile-but-fair input through the command line (issue 17): odd output paths, requests
too big, absurd numbers, data a fit cannot explain. Each ends with exit 0 and honest
output, or exit 2 with one message naming the option, key or file, and nothing written."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import tomli_w

from design.atomic import _proof
from design.equilibrium import solve_design
from design.geometry import rest_position
from ringpair.tables import pose_rows


def files_under(folder):
    """Every path below ``folder``, relative to it, sorted."""
    return sorted(p.relative_to(folder) for p in folder.rglob("*"))


@pytest.fixture()
def places(tmp_path):
    """A file, a folder and the paths that misuse them."""
    (tmp_path / "afile").write_text("mine\n")
    (tmp_path / "adir").mkdir()
    return tmp_path


# --- 1. output paths, checked before any work ---------------------------------------

FILE_OUTPUTS = [  # a command writing one file: (arguments before the path, its option)
    (["simulate", "--theta1", "0", "--quiet"], "--out"),
    (["effects", "--theta1", "0"], "--out"),
    (["branch"], "--out"),
    (["show"], "--save"),
]
FOLDER_OUTPUTS = [
    (["workspace", "--step", "90"], "--out"),
    (["cad", "--no-render"], "--out"),
    (["synth", "--n", "6"], "--out"),
    (["optimize", "--no-pareto"], "--out"),
    (["study", "--samples", "2"], "--out"),
]


def _refused(result, option, path, words):
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert f"{option} {path}" in result.output
    for w in words:
        assert w in result.output


@pytest.mark.parametrize(("args", "option"), FILE_OUTPUTS, ids=[a[0] for a, _ in FILE_OUTPUTS])
def test_a_folder_where_a_file_is_wanted_is_refused(places, run, args, option):
    path = places / "adir"
    _refused(run(*args, option, str(path)), option, path, ["is a folder; expected a file"])
    assert list(path.iterdir()) == []


@pytest.mark.parametrize(("args", "option"), FOLDER_OUTPUTS, ids=[a[0] for a, _ in FOLDER_OUTPUTS])
def test_a_file_where_a_folder_is_wanted_is_refused(places, run, args, option):
    path = places / "afile"
    _refused(run(*args, option, str(path)), option, path, ["is a file; expected a folder"])
    assert (places / "afile").read_text() == "mine\n"


@pytest.mark.parametrize(
    ("args", "option"),
    FILE_OUTPUTS + FOLDER_OUTPUTS,
    ids=[a[0] for a, _ in FILE_OUTPUTS + FOLDER_OUTPUTS],
)
def test_a_path_under_a_file_is_refused(places, run, args, option):
    path = places / "afile" / "sub" / "x.out"
    _refused(run(*args, option, str(path)), option, path, ["afile is a file"])


def test_optional_outputs_are_checked_before_the_fit(places, run, tmp_path):
    data = tmp_path / "set"
    assert run("synth", "--n", "6", "--out", str(data)).exit_code == 0
    path = places / "adir"
    _refused(run("calibrate", str(data), "--json", str(path)), "--json", path, ["is a folder"])
    report = places / "afile"
    result = run("diagnose", str(data), "--report", str(report), "--folds", "2")
    _refused(result, "--report", report, ["is a file; expected a folder"])
    same = places / "new"
    result = run("diagnose", str(data), "--json", str(same), "--report", str(same))
    _refused(result, "--report", same, ["where --json writes"])
    assert [p for p in files_under(places) if p.parts[0] != "set"] == [
        p.relative_to(places) for p in (path, report)
    ]


def test_a_place_that_cannot_be_written_is_refused(places, run, monkeypatch):
    monkeypatch.setattr("ringpair.options.os.access", lambda *_: False)
    path = places / "adir" / "s.csv"
    result = run("simulate", "--theta1", "0", "--out", str(path))
    _refused(result, "--out", path, ["cannot write in", "permission denied"])


def test_nothing_is_computed_before_the_output_path_is_checked(places, run, monkeypatch):
    def solve(*_):
        raise AssertionError("solved before the output path was checked")

    monkeypatch.setattr("ringpair.commands.simulate.solve_design", solve)
    monkeypatch.setattr("ringpair.commands.workspace.sweep_workspace", solve)
    assert run("simulate", "--out", str(places / "adir")).exit_code == 2
    assert run("workspace", "--out", str(places / "afile")).exit_code == 2


def test_a_command_never_writes_over_its_input(tmp_path, run, demonstrator_doc):
    design = tmp_path / "mine.toml"
    design.write_text(tomli_w.dumps(demonstrator_doc))
    result = run("simulate", str(design), "--theta1", "0", "--out", str(design))
    _refused(result, "--out", design, ["is an input of this command"])
    assert "demonstrator" in design.read_text()


def test_the_default_message_blames_no_option(tmp_path, run, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "outputs" / "demonstrator").mkdir(parents=True)
    (tmp_path / "outputs" / "demonstrator" / "workspace").write_text("in the way\n")
    result = run("workspace", "--step", "90")
    assert result.exit_code == 2
    assert "the default output folder outputs/demonstrator/workspace (set with --out)" in (
        result.output
    )


@pytest.mark.parametrize(
    ("name", "folder"),
    [
        ("../../escape", "escape"),
        ("/tmp/absolute", "tmp_absolute"),
        ("a/b\\c", "a_b_c"),
        ("..", "unnamed"),
        ("[bold]x[/] ö", "bold_x_ö"),
    ],
)
def test_names_from_files_stay_inside_outputs(
    tmp_path, run, monkeypatch, demonstrator_doc, name, folder
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "work").mkdir()
    design = tmp_path / "named.toml"
    design.write_text(tomli_w.dumps({**demonstrator_doc, "name": name}))
    result = run("simulate", str(design), "--theta1", "0", "--quiet")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "outputs" / folder / "simulate.csv").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["named.toml", "outputs", "work"]


def killed_writer(target) -> None:
    """A process that dies (os._exit, no clean-up) while writing ``target`` atomically,
    leaving its temporary: what a killed run leaves."""
    code = (
        "import os, sys\n"
        "from design.atomic import atomic_path\n"
        "with atomic_path(sys.argv[1]) as tmp:\n"
        "    tmp.write_text('half')\n"
        "    os._exit(9)\n"
    )
    subprocess.run([sys.executable, "-c", code, str(target)], check=False)


def test_temporaries_of_a_killed_run_are_removed_and_a_live_ones_kept(tmp_path, run):
    out = tmp_path / "ws"
    (out / "points").mkdir(parents=True)
    for target in (out / "workspace.png", out / "points" / "p.npz"):
        killed_writer(target)
    dead = sorted(out.rglob("*.tmp"))
    assert len(dead) == 2
    stem = f".top.png.{os.getpid()}.abcd1234"  # a temporary of a writer still running
    live = out / f"{stem}.{_proof(stem)}.tmp"
    live.write_text("")
    assert run("workspace", "--step", "90", "--out", str(out)).exit_code == 0
    assert not any(p.exists() for p in dead)
    assert live.exists()
    killed_writer(tmp_path / "s.csv")
    killed_writer(tmp_path / "t.csv")
    single, other = sorted(tmp_path.glob(".[st].csv.*.tmp"))
    assert (
        run("simulate", "--theta1", "0", "--quiet", "--out", str(tmp_path / "s.csv")).exit_code == 0
    )
    assert not single.exists() and other.exists()  # only the temporaries of its own file


def test_files_that_only_look_like_temporaries_are_never_deleted(tmp_path, run):
    """A user's files named as ringpair's temporaries are (by name alone, with a dead
    process id, old and new patterns, three levels deep) survive the clean-up (issue 55)."""
    out = tmp_path / "ws"
    deep = out / "a" / "b"
    deep.mkdir(parents=True)
    planted = [
        out / ".workspace.png.999999999.abcd1234.tmp",
        out / ".summary.json.k2j3h4g5.tmp",
        out / f".top.png.999999999.abcd1234.{'0' * 16}.tmp",
        out / "a" / "tmpab12cd34.tmp",
        deep / ".x.csv.999999999.abcd1234.tmp",
    ]
    (out / "points").mkdir()
    planted.append(out / "points" / "tmpab12cd34.tmp")
    for p in planted:
        p.write_text("user data")
    assert run("workspace", "--step", "90", "--out", str(out)).exit_code == 0
    assert all(p.read_text() == "user data" for p in planted)


def test_show_save_replaces_a_file_only_with_force(tmp_path, run):
    path = tmp_path / "mine.toml"
    path.write_text("# edited by hand\n")
    refused = run("show", "--save", str(path))
    _refused(refused, "--save", path, ["exists; pass --force"])
    assert path.read_text() == "# edited by hand\n"
    assert run("show", "--save", str(path), "--force").exit_code == 0
    assert "demonstrator" in path.read_text()
    assert "--force" in run("show", "--help").output


def test_synth_keeps_measured_data_it_did_not_write(tmp_path, run):
    out = tmp_path / "bench"
    out.mkdir()
    (out / "measurements.csv").write_text("theta1_deg,theta2_deg,x_mm\n0,0,150\n")
    refused = run("synth", "--n", "6", "--out", str(out))
    assert refused.exit_code == 2 and "--force" in refused.output
    assert (out / "measurements.csv").read_text().startswith("theta1_deg")
    assert run("synth", "--n", "6", "--out", str(out), "--force").exit_code == 0
    assert run("synth", "--n", "6", "--out", str(out)).exit_code == 0  # its own: replaced


def test_help_states_the_overwrite_policy(run):
    for command in ("simulate", "workspace", "optimize", "cad", "calibrate", "diagnose"):
        text = " ".join(run(command, "--help").output.split())
        assert "replaced on a rerun" in text, command


# --- 2. sizes bounded up front -------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--theta1", "0:inf:1"], ["--theta1", "finite"]),
        (["--theta1", "0:360:1e-300"], ["--theta1", "values; at most 1000000"]),
        (["--theta1", "1e300"], ["--theta1", "within +-36000 deg"]),
        (
            ["--theta1", "0:360:0.001", "--theta2", "0:360:0.001"],
            ["129,600,720,001 configurations", "days", "--max-configs"],
        ),
        (
            ["--theta1", "0:360:0.05", "--theta2", "0:360:0.05"],
            ["51,854,401 configurations", "about 14 h", "--max-configs"],
        ),
        (
            ["--theta1", "0:10:1", "--theta2", "0:10:1", "--max-configs", "100"],
            ["121 configurations", "at most 100"],
        ),
    ],
)
def test_big_or_infinite_grids_are_refused_with_their_size(tmp_path, run, args, words):
    out = tmp_path / "s.csv"
    result = run("simulate", *args, "--out", str(out))
    assert result.exit_code == 2, result.output
    for w in words:
        assert w in result.output
    assert not out.exists()


def test_a_fine_workspace_and_a_long_effects_path_are_refused(run, tmp_path):
    result = run("workspace", "--step", "0.1", "--out", str(tmp_path / "w"))
    assert result.exit_code == 2 and "12,960,000 configurations" in result.output
    result = run("effects", "--theta1", "0:360:0.001", "--out", str(tmp_path / "e.csv"))
    assert result.exit_code == 2 and "x 7 models = 2,520,007 solves" in result.output
    assert list(tmp_path.iterdir()) == []


def test_simulate_in_chunks_equals_one_solve(tmp_path, run, read_csv, demonstrator):
    # More configurations than one chunk (4096): the CSV is written chunk by chunk.
    out = tmp_path / "s.csv"
    result = run(
        "simulate",
        "--theta1",
        "0:359:5.5",
        "--theta2",
        "0:359:5.5",
        "--effects",
        "none",
        "--no-multistable",
        "--out",
        str(out),
    )
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    t = np.deg2rad(np.arange(0, 359, 5.5))
    g1, g2 = (g.ravel() for g in np.meshgrid(t, t, indexing="ij"))
    eq = solve_design(demonstrator, g1, g2)
    assert len(rows) == len(g1) == 4356
    y = np.array([float(r["y_mm"] or "nan") for r in rows])
    np.testing.assert_allclose(y, eq.position[:, 1] * 1e3, rtol=1e-8)
    assert "(4296 rows not shown)" in result.output


# --- 3. absurd numbers, honest rows ----------------------------------------------------


@pytest.mark.parametrize(
    ("key", "value", "words"),
    [
        ("external_magnet.center_mm", [1e308, 0.0, 0.0], ["each >= -10000 and <= 10000"]),
        ("environment.gravity_m_s2", [0.0, 0.0, -1e308], ["each >= -100 and <= 100"]),
        ("tip.mass_g", 1e308, ["<= 1000"]),
        ("external_magnet.diameter_mm", 1e308, ["<= 10000"]),
    ],
)
def test_absurd_finite_numbers_name_the_key_and_its_range(
    tmp_path, run, demonstrator_doc, key, value, words
):
    section, leaf = key.rsplit(".", 1)
    doc = demonstrator_doc
    node = doc
    for part in section.split("."):
        node = node.setdefault(part, {})
    node[leaf] = value
    path = tmp_path / "bad.toml"
    path.write_text(tomli_w.dumps(doc))
    result = run("show", str(path))
    assert result.exit_code == 2 and key in result.output
    for w in words:
        assert w in result.output


def test_a_row_without_a_pose_never_claims_a_state(demonstrator):
    eq = solve_design(demonstrator, np.zeros(2), np.zeros(2))
    position = eq.position.copy()
    position[1] = np.nan  # converged, yet no pose
    broken = type(eq)(**{**eq.__dict__, "position": position})
    rows = pose_rows(broken, rest_position(demonstrator.robot.free_length))
    assert rows[0]["converged"] and rows[0]["stable"]
    assert not rows[1]["converged"] and not rows[1]["stable"]
    assert rows[1]["failure"] == "no finite pose"
    assert np.isnan([rows[1][k] for k in ("theta1_tip_deg", "tangent_x", "deflection_mm")]).all()


# --- 4. fits that cannot explain the data say so ---------------------------------------


@pytest.fixture()
def bench(tmp_path, run):
    """A small synthetic data set and its rows as CSV lines (header first)."""
    data = tmp_path / "bench"
    assert run("synth", "--n", "12", "--out", str(data)).exit_code == 0
    lines = (data / "measurements.csv").read_text().splitlines()
    return data, [ln for ln in lines if not ln.startswith("#")]


def _csv(tmp_path, name, lines):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def test_calibrate_on_one_row_names_the_file_and_the_parameters(tmp_path, run, bench):
    one = _csv(tmp_path, "one.csv", bench[1][:2])
    result = run("calibrate", str(one))
    assert result.exit_code == 2
    assert "one.csv: 3 measured number(s) in 1 row cannot determine 4 parameters" in (result.output)
    assert "bending_rigidity_scale" in result.output and "--free" not in result.output


def test_two_rows_say_which_parameters_they_cannot_separate(tmp_path, run, bench):
    two = _csv(tmp_path, "two.csv", bench[1][:3])
    result = run("calibrate", str(two), "--json", str(tmp_path / "c.json"))
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "the data cannot separate" in text and "external_center_x" in text
    assert json.loads((tmp_path / "c.json").read_text())["warnings"]


def _scaled(tmp_path, lines, factor):
    header = lines[0].split(",")
    columns = [header.index(c) for c in ("x_mm", "y_mm", "z_mm")]
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        for c in columns:
            cells[c] = f"{float(cells[c]) * factor:.9g}" if cells[c] else ""
        out.append(",".join(cells))
    return _csv(tmp_path, "scaled.csv", out)


def test_positions_in_the_wrong_unit_are_not_explained(tmp_path, run, bench):
    scaled = _scaled(tmp_path, bench[1], 1e4)
    result = run("calibrate", str(scaled), "--json", str(tmp_path / "c.json"))
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "the model does not explain" in text and "scaled.csv" in text
    assert "check the units" in text and "reaches 150.8 mm at most" in text
    assert "cannot separate" not in text  # data of another robot separate nothing
    assert len(json.loads((tmp_path / "c.json").read_text())["warnings"]) == 2


@pytest.mark.slow
def test_diagnose_does_not_call_wrong_units_explained(tmp_path, run, bench):
    scaled = _scaled(tmp_path, bench[1], 1e4)
    result = run("diagnose", str(scaled), "--json", str(tmp_path / "d.json"))
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "baseline explains the data" not in text
    assert "the model does not explain" in text and "check the units" in text
    assert sum(line.strip().startswith("│ baseline") for line in result.output.splitlines()) == 1
    assert json.loads((tmp_path / "d.json").read_text())["warnings"]


@pytest.mark.parametrize("rows", [1, 2])
def test_diagnose_on_few_rows_blames_the_data_not_folds(tmp_path, run, bench, rows):
    few = _csv(tmp_path, "few.csv", bench[1][: rows + 1])
    result = run("diagnose", str(few))
    assert result.exit_code == 2
    assert "few.csv" in result.output and "--folds" not in result.output
    typed = run("diagnose", str(few), "--folds", "3")
    assert typed.exit_code == 2 and "--folds 3" in typed.output


# --- 5. descending ranges ----------------------------------------------------------------


def test_the_readme_descending_path_runs(tmp_path, run, read_csv):
    out = tmp_path / "t.csv"
    result = run(
        "simulate",
        "--effects",
        "torsion",
        "--ordered",
        "--theta1",
        "60:-60:2",
        "--out",
        str(out),
        "--quiet",
    )
    assert result.exit_code == 0, result.output
    theta1 = [float(r["theta1_deg"]) for r in read_csv(out)]
    assert theta1 == list(range(60, -61, -2))
