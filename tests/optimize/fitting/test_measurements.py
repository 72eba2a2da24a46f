"""Measured-data CSV and data-set folders (docs/formats.md): every bad file ends in one
message naming the file, line and column, what was expected and what was found; good
files round-trip."""

from __future__ import annotations

import numpy as np
import pytest

from design.designfile import DesignError
from optimize.fitting.measurements import (
    MeasurementError,
    load_dataset,
    load_measurements,
    loads_measurements,
    make_measurements,
    save_dataset,
    save_measurements,
)

HEADER = "theta1_deg,theta2_deg,x_mm,y_mm,z_mm"
GOOD = f"""# bench run 3, top camera
{HEADER}
0,0,150.0,1.0,
12,0,149.5,5.0,
# a comment between rows
24,0,149.0,10.0,2.5
"""

# (name, file text, fragments the message must contain)
BAD_FILES = [
    ("empty", "", ["is empty", "header"]),
    ("only comments", "# nothing here\n#\n", ["is empty"]),
    ("header only", f"{HEADER}\n", ["no measurement rows"]),
    ("missing theta2", "theta1_deg,x_mm\n0,1\n", ["line 1", "missing required column", "theta2"]),
    ("no position column", "theta1_deg,theta2_deg,sigma_mm\n0,0,1\n", ["x_mm, y_mm, z_mm"]),
    ("unknown column", "theta1_deg,theta2_deg,x_mm,y_mn\n0,0,1,2\n", ["y_mn", "'y_mm'"]),
    ("unknown far column", "theta1_deg,theta2_deg,x_mm,colour\n0,0,1,2\n", ["'colour'"]),
    ("twice a column", "theta1_deg,theta2_deg,x_mm,x_mm\n0,0,1,2\n", ["'x_mm' appears twice"]),
    ("not a number", f"{HEADER}\n0,0,150,abc,1\n", ["line 2", "column y_mm", "'abc'"]),
    ("comma decimal", f"{HEADER}\n0,0,150,1;5,1\n", ["line 2", "column y_mm", "'1;5'"]),
    ("empty angle", f"{HEADER}\n0,0,150,1,1\n,0,150,1,1\n", ["line 3", "theta1_deg", "empty"]),
    ("no position", f"{HEADER}\n0,0,150,1,1\n12,0,,,\n", ["line 3", "no tip position", "sequence"]),
    ("no row seen", f"{HEADER},sequence\n0,0,,,,0\n12,0,,,,1\n", ["no row has a tip position"]),
    ("angle range", f"{HEADER}\n0,0,150,1,1\n0,1000,150,1,1\n", ["line 3", "theta2_deg", "1000"]),
    ("tip angle range", "theta1_deg,theta2_deg,x_mm,theta1_tip_deg\n0,0,1,-800\n", ["-800"]),
    ("nan", f"{HEADER}\n0,0,150,nan,1\n", ["line 2", "y_mm", "finite", "'nan'"]),
    ("inf", f"{HEADER}\n0,0,inf,1,1\n", ["line 2", "x_mm", "finite"]),
    ("negative sigma", f"{HEADER},sigma_mm\n0,0,150,1,1,-0.2\n", ["sigma_mm", "positive", "-0.2"]),
    ("zero sigma", f"{HEADER},sigma_mm\n0,0,150,1,1,0\n", ["sigma_mm", "positive"]),
    ("too few fields", f"{HEADER}\n0,0,150\n", ["line 2", "expected 5", "found 3"]),
    (
        "duplicate without sequence",
        f"{HEADER}\n0,0,150,1,1\n# c\n12,0,150,1,1\n0,0,150,2,1\n",
        ["duplicated row", "lines 2 and 5", "sequence"],
    ),
    (
        "duplicate with same sequence",
        f"{HEADER},sequence\n0,0,150,1,1,1\n0,0,150,2,1,1\n",
        ["duplicated row", "lines 2 and 3", "sequence 1"],
    ),
    (
        "repeated sequence number",
        f"{HEADER},sequence\n0,0,150,1,1,4\n12,0,150,2,1,4\n",
        ["repeated sequence number", "lines 2 and 3"],
    ),
    ("sequence not integer", f"{HEADER},sequence\n0,0,150,1,1,2.5\n", ["sequence", "'2.5'"]),
    ("sequence negative", f"{HEADER},sequence\n0,0,150,1,1,-1\n", ["non-negative", "-1"]),
    ("sequence empty", f"{HEADER},sequence\n0,0,150,1,1,\n", ["sequence", "empty cell"]),
]


@pytest.mark.parametrize(("name", "text", "fragments"), BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_csv_gives_one_clear_message(tmp_path, name, text, fragments):
    path = tmp_path / "data.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(MeasurementError) as info:
        load_measurements(path)
    message = str(info.value)
    assert str(path) in message
    for fragment in fragments:
        assert fragment in message, message
    assert "\n" not in message


def test_missing_file_and_folder_are_named(tmp_path):
    with pytest.raises(MeasurementError, match="does not exist"):
        load_measurements(tmp_path / "nope.csv")
    with pytest.raises(MeasurementError, match="is a folder"):
        load_measurements(tmp_path)
    with pytest.raises(MeasurementError, match="has no design.toml"):
        load_dataset(tmp_path)
    with pytest.raises(MeasurementError, match="does not exist"):
        load_dataset(tmp_path / "missing")


def test_not_utf8_is_named(tmp_path):
    path = tmp_path / "latin.csv"
    path.write_bytes(f"{HEADER}\n0,0,150,1,1 \xb5m\n".encode("latin-1"))
    with pytest.raises(MeasurementError, match="UTF-8"):
        load_measurements(path)


def test_good_file_in_si_with_partial_views_and_comments(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text(GOOD, encoding="utf-8")
    m = load_measurements(path)
    assert len(m) == 3
    np.testing.assert_allclose(m.command[:, 0], np.deg2rad([0, 12, 24]))
    np.testing.assert_allclose(m.position[0, :2], [0.150, 0.001])
    assert np.isnan(m.position[0, 2]) and np.isnan(m.position[1, 2])  # top view: no z
    assert m.position[2, 2] == pytest.approx(0.0025)
    assert m.sequence is None and np.isnan(m.sigma).all() and np.isnan(m.tip_angles).all()
    assert list(m.lines) == [3, 4, 6]  # physical lines, comments counted
    assert m.measured.sum() == 7


def test_round_trip_every_column(tmp_path):
    rng = np.random.default_rng(3)
    n = 7
    position = rng.normal(0, 0.02, (n, 3))
    position[::2, 2] = np.nan
    m = make_measurements(
        rng.uniform(-3, 3, (n, 2)),
        position,
        tip_angles=rng.uniform(-3, 3, (n, 2)),
        sequence=np.arange(n)[::-1],
        sigma=rng.uniform(1e-4, 1e-3, n),
    )
    path = tmp_path / "sub" / "m.csv"
    save_measurements(path, m, comment="made by a test\nsecond line")
    text = path.read_text()
    assert text.startswith("# made by a test\n# second line\ntheta1_deg,theta2_deg,x_mm")
    back = load_measurements(path)
    for name in ("command", "position", "tip_angles", "sigma"):
        np.testing.assert_allclose(getattr(back, name), getattr(m, name), rtol=1e-11, atol=1e-15)
    np.testing.assert_array_equal(back.sequence, m.sequence)
    assert list(back.order()) == list(range(n))[::-1]
    assert [p.name for p in path.parent.iterdir()] == ["m.csv"]  # no temporary left


def test_dataset_round_trip(tmp_path, demonstrator):
    m = make_measurements([[0.0, 0.0], [0.5, 0.0]], [[0.15, 0.001, np.nan], [0.149, 0.01, 0.0]])
    folder = save_dataset(tmp_path / "set", demonstrator, m)
    design, back = load_dataset(folder)
    assert design == demonstrator
    np.testing.assert_allclose(back.position, m.position, rtol=1e-11)
    assert sorted(p.name for p in folder.iterdir()) == ["design.toml", "measurements.csv"]


def test_dataset_with_bad_design_says_design(tmp_path, demonstrator):
    folder = save_dataset(
        tmp_path / "set", demonstrator, make_measurements([[0, 0]], [[0.15, 0, 0]])
    )
    (folder / "design.toml").write_text("name = 'x'\n")
    with pytest.raises(DesignError, match="design.toml"):
        load_dataset(folder)


def test_saving_data_the_reader_would_refuse_writes_nothing(tmp_path):
    m = make_measurements([[0.0, 0.0], [0.0, 0.0]], [[0.15, 0, 0], [0.15, 0, 0]])
    with pytest.raises(MeasurementError, match="duplicated row"):
        save_measurements(tmp_path / "m.csv", m)
    assert list(tmp_path.iterdir()) == []


def test_strings_parse_like_files():
    m = loads_measurements("theta1_deg, theta2_deg ,y_mm\n90,0,3\n", source="inline")
    assert m.command[0, 0] == pytest.approx(np.pi / 2) and np.isnan(m.position[0, 0])


@pytest.mark.parametrize(("name", "text", "fragments"), BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_csv_on_the_command_line_exits_2_and_writes_nothing(tmp_path, name, text, fragments):
    from click.testing import CliRunner

    from ringpair.cli import cli

    path = tmp_path / "data.csv"
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "fit.json"
    result = CliRunner().invoke(
        cli, ["calibrate", str(path), "--json", str(out)], catch_exceptions=False
    )
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in result.output, result.output
    assert not out.exists()


def test_cli_data_set_folder_problems_exit_2(tmp_path, demonstrator):
    from click.testing import CliRunner

    from ringpair.cli import cli

    def run(*args):
        return CliRunner().invoke(cli, ["calibrate", *args], catch_exceptions=False)

    assert "has no design.toml" in run(str(tmp_path)).output
    folder = save_dataset(
        tmp_path / "set", demonstrator, make_measurements([[0, 0]], [[0.15, 0, 0]])
    )
    result = run(str(folder), "--design", "x.toml")
    assert result.exit_code == 2 and "--design is for a CSV" in result.output
    result = run(str(folder), "--free", "bending_rigidity_scal")
    assert result.exit_code == 2 and "did you mean 'bending_rigidity_scale'" in result.output
    result = run(str(folder))  # one row, three coordinates: too few for four parameters
    assert result.exit_code == 2 and "cannot determine 4 parameters" in result.output
