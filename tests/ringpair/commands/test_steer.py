"""``ringpair steer``: targets in, every solution (or the closest point) out, as a CSV whose
angles, solved forward by ``simulate``'s solver, put the tip on the target."""

from __future__ import annotations

import numpy as np
import pytest
import tomli_w

from design.equilibrium import solve_design
from design.home import solve_home
from design.model import RingPairModel


def test_steer_writes_every_solution_and_they_land_on_the_target(
    tmp_path, demonstrator, run, read_csv
):
    out = tmp_path / "steer.csv"
    result = run("steer", "--effects", "none", "--to", "8,-3", "--to", "0,60", "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    first = [r for r in rows if r["target"] == "1"]
    assert len(first) >= 2 and all(r["reached"] == "true" for r in first)
    theta = np.deg2rad([[float(r["theta1_deg"]), float(r["theta2_deg"])] for r in first])
    eq = solve_design(demonstrator, theta[:, 0], theta[:, 1], RingPairModel(frozenset()))
    # The CSV keeps 9 significant digits of the angles: 1e-6 deg moves the tip < 1e-4 mm.
    np.testing.assert_allclose(eq.position[:, 1:] * 1e3, [[8.0, -3.0]] * len(first), atol=1e-4)
    (second,) = [r for r in rows if r["target"] == "2"]
    assert second["reached"] == "false" and float(second["error_mm"]) > 30
    assert "OUT OF REACH" in result.output


def test_steer_reads_targets_from_a_csv(tmp_path, run, read_csv):
    targets = tmp_path / "t.csv"
    targets.write_text("# two points\ny_mm,z_mm\n5,0\n0,-5\n")
    out = tmp_path / "s.csv"
    result = run(
        "steer", "--effects", "none", "--targets", str(targets), "--out", str(out), "--quiet"
    )
    assert result.exit_code == 0, result.output
    assert {r["target"] for r in read_csv(out)} == {"1", "2"}


@pytest.mark.parametrize(
    ("args", "content", "message"),
    [
        (["--to", "3"], None, "expected Y,Z in mm"),
        (["--to", "nan,2"], None, "two finite numbers"),
        (["--to", "400,0"], None, "farther from the robot's axis than its free length"),
        ([], None, "give a target"),
        (["--targets", "{t}"], "y_mm,q\n1,2\n", "missing z_mm"),
        (["--targets", "{t}"], "y_mm,z_mm\n1,2\n3,abc\n", "line 3"),
    ],
)
def test_steer_refuses_bad_targets_with_one_message(tmp_path, run, args, content, message):
    t = tmp_path / "t.csv"
    if content is not None:
        t.write_text(content)
    out = tmp_path / "s.csv"
    result = run("steer", *[a.format(t=t) for a in args], "--out", str(out))
    assert result.exit_code == 2, result.output
    assert message in result.output and "Traceback" not in result.output
    assert not out.exists()


def test_steer_path_writes_a_schedule_whose_angles_land_on_the_path(
    tmp_path, demonstrator, run, read_csv
):
    """A circle about the demonstrator's home (baseline model; the rings antiparallel, the
    default centre since issue 49): every step reached, its
    angles solved forward land on the point, knob turns are the actuator's 30 knob turns
    per ring turn (single-start worm, 30-tooth wheel) from step 1, and the plot is
    written."""
    out = tmp_path / "p.csv"
    result = run(
        "steer", "--effects", "none", "--path", "circle:10", "--points", "24", "--out", str(out)
    )
    assert result.exit_code == 0, result.output
    assert "FOLLOWED" in result.output
    rows = read_csv(out)
    assert len(rows) == 24 and all(r["reached"] == "true" for r in rows)
    theta = np.deg2rad([[float(r["theta1_deg"]), float(r["theta2_deg"])] for r in rows])
    eq = solve_design(demonstrator, theta[:, 0], theta[:, 1], RingPairModel(frozenset()))
    phi = 2 * np.pi * np.arange(24) / 24
    model = RingPairModel(frozenset())
    home = solve_home(model, model.parameters(demonstrator), demonstrator.robot.free_length)
    want = home.position[1:] * 1e3 + 10.0 * np.column_stack([np.cos(phi), np.sin(phi)])
    np.testing.assert_allclose(eq.position[:, 1:] * 1e3, want, atol=1e-4)
    knobs = np.array([[float(r["knob1_turns"]), float(r["knob2_turns"])] for r in rows])
    np.testing.assert_allclose(knobs, 30 * (theta - theta[0]) / (2 * np.pi), atol=1e-6)
    assert (tmp_path / "p.png").stat().st_size > 10_000


def test_steer_path_reads_a_csv_and_says_what_is_out_of_reach(tmp_path, run, read_csv):
    path = tmp_path / "path.csv"
    path.write_text("y_mm,z_mm\n5,0\n15,0\n60,0\n")
    out = tmp_path / "p.csv"
    result = run("steer", "--effects", "none", "--path", str(path), "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    assert [r["reached"] for r in rows] == ["true", "true", "false"]
    assert "OUT OF REACH: 1 point(s) (steps 3)" in " ".join(result.output.split())


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--path", "spiral:3"], "expected circle:R, ellipse:A,B"),
        (["--path", "circle:-2"], "radii must be positive"),
        (["--path", "ellipse:3"], "expected 2 number(s)"),
        (["--path", "line:1,2,x,4"], "expected 4 number(s)"),
        (["--path", "line:1,2,1,2"], "the two ends are the same point"),
        (["--path", "circle:400"], "farther from the robot's axis"),
        (["--path", "circle:5", "--to", "1,2"], "without --to or --targets"),
        (["--to", "1,2", "--points", "5"], "belong to --path"),
        (["--path", "circle:5", "--closed"], "--closed is for a CSV path"),
        (["--path", "{p}"], "at least two points"),
        (["--path", "circle:5", "--center", "1"], "expected Y,Z in mm"),
    ],
)
def test_steer_path_refuses_bad_paths_with_one_message(tmp_path, run, args, message):
    p = tmp_path / "one.csv"
    p.write_text("y_mm,z_mm\n1,2\n")
    out = tmp_path / "s.csv"
    result = run("steer", "--effects", "none", *[a.format(p=p) for a in args], "--out", str(out))
    assert result.exit_code == 2, result.output
    assert message in " ".join(result.output.split()) and "Traceback" not in result.output
    assert not out.exists()


def test_steer_largest_ellipse_reports_the_papers_numbers(tmp_path, run):
    out = tmp_path / "e.csv"
    result = run(
        "steer",
        "--effects",
        "none",
        "--path",
        "ellipse:largest",
        "--points",
        "24",
        "--out",
        str(out),
    )
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "FOLLOWED" in text and "mm on average; RMS distance to the ellipse fitted" in text


def test_steer_path_never_writes_its_plot_over_its_csv_or_an_input(tmp_path, run, demonstrator_doc):
    # --out p.png wrote the CSV to p.png and then the plot over it (issue 55)
    png = tmp_path / "p.png"
    result = run("steer", "--effects", "none", "--path", "circle:2", "--out", str(png))
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert "ending in .csv" in " ".join(result.output.split())
    assert not png.exists()
    # the plot beside s.csv is s.png: here the design file, which stays as it was
    design = tmp_path / "s.png"
    design.write_text(tomli_w.dumps(demonstrator_doc))
    before = design.read_text()
    out = tmp_path / "s.csv"
    result = run("steer", str(design), "--effects=none", "--path=circle:2", "--out", str(out))
    assert result.exit_code == 2 and "is an input of this command" in result.output
    assert design.read_text() == before and not out.exists()
