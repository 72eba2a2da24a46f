"""``ringpair synth``: writes a data set that loads back; bad input exits 2 with one
message, no traceback, nothing written."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from optimize.fitting.measurements import load_dataset
from ringpair.cli import cli


def run(*args: str):
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


def test_synth_writes_a_data_set(tmp_path, demonstrator):
    out = tmp_path / "set"
    result = run(
        "synth",
        "--effects",
        "hysteresis",
        "--noise-mm",
        "0.2",
        "--seed",
        "3",
        "--view",
        "top",
        "--n",
        "12",
        "--set",
        "wire_friction_angle=3",
        "--set",
        "external_center_x=250",
        "--out",
        str(out),
    )
    assert result.exit_code == 0, result.output
    design, m = load_dataset(out)
    assert design == demonstrator  # the nominal design, not the truth
    assert len(m) == 15 and np.isnan(m.position[:, 2]).all() and m.sequence is not None
    assert "configurations written" in result.output and "3 deg" in result.output
    text = (out / "measurements.csv").read_text()
    assert text.startswith("# ringpair synth") and "wire_friction_angle=3" in text


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--effects", "torsoin"], "unknown model effect 'torsoin'"),
        (["--set", "wire_torsion_scal=2"], "did you mean 'wire_torsion_scale'"),
        (["--set", "wire_torsion_scale"], "NAME=VALUE"),
        (["--set", "wire_torsion_scale=two"], "expects a number"),
        (["--noise-mm", "-1"], "--noise-mm"),
        (["--view", "side"], "--view"),
        (["--n", "2"], "--n"),
    ],
)
def test_synth_bad_input_exits_2_and_writes_nothing(tmp_path, args, fragment):
    out = tmp_path / "set"
    result = run("synth", *args, "--out", str(out))
    assert result.exit_code == 2
    assert fragment in result.output
    assert "Traceback" not in result.output
    assert not out.exists()


def test_synth_bad_design_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\n")
    result = run("synth", str(bad), "--out", str(tmp_path / "set"))
    assert result.exit_code == 2 and "missing section" in result.output
    assert not (tmp_path / "set").exists()


def test_calibrate_fits_a_synthetic_data_set(tmp_path):
    out = tmp_path / "set"
    truth = "bending_rigidity_scale=0.8"
    assert run("synth", "--n", "24", "--set", truth, "--out", str(out)).exit_code == 0
    result = run("calibrate", str(out), "--json", str(tmp_path / "fit.json"))
    assert result.exit_code == 0, result.output
    doc = json.loads((tmp_path / "fit.json").read_text())
    est, se = doc["estimate"], doc["standard_error"]
    assert abs(est["bending_rigidity_scale"] - 0.8) < 3 * se["bending_rigidity_scale"]
    assert doc["converged"] and "tip error: RMS" in result.output


def test_calibrate_profile_gives_intervals_around_the_estimates(tmp_path):
    out = tmp_path / "set"
    assert run("synth", "--n", "24", "--effects", "gravity", "--out", str(out)).exit_code == 0
    result = run(
        "calibrate",
        str(out),
        "--effects",
        "gravity",
        "--profile",
        "--json",
        str(tmp_path / "f.json"),
    )
    assert result.exit_code == 0, result.output
    assert "profile" in result.output  # the column (its header may wrap)
    doc = json.loads((tmp_path / "f.json").read_text())
    for name, (lower, upper) in doc["profile_interval"].items():
        assert lower <= doc["estimate"][name] <= upper, name
    assert set(doc["profile_interval"]) == set(doc["estimate"])
    both = run("calibrate", str(out), "--priors", "--no-priors")
    assert both.exit_code == 2 and "contradict" in both.output


def test_calibrate_fits_torsion_from_stiff_and_soft_transmissions_too(tmp_path):
    """A drawn set-up with the magnet on the robot's axis (optimize.fitting.planted, seed
    [99, 10]: a 97 mm rod, 18 rows, top view, 0.36 mm noise, transmissions as drawn):
    from the nominal design the torsion fit ends 7.4 mm RMS from the data, beyond a
    snap-through of the rings; the fit from stiff transmissions reaches the noise
    (reference: the noise's RMS distance, noise x sqrt(measured axes))."""
    from optimize.fitting.measurements import save_dataset
    from optimize.fitting.planted import draw_planted

    seed = [99, 10]
    case = draw_planted(
        np.random.default_rng(seed), frozenset({"torsion"}), points=(16, 30), on_axis=True
    )
    data = save_dataset(tmp_path / "set", case.design, case.measurements)
    # without priors: with them the fit from nominal no longer runs past the snap-through
    # (it ends at 0.60 mm, the stiff start's 0.47), and the starts are what is tested here
    args = ("--effects", "torsion", "--no-priors", "--json", str(tmp_path / "f.json"))
    result = run("calibrate", str(data), *args)
    assert result.exit_code == 0, result.output
    doc = json.loads((tmp_path / "f.json").read_text())
    starts = doc["starts_rmse_mm"]
    why = f"seed {seed}: {case.describe()}; {starts}"
    assert set(starts) == {"nominal", "stiff", "soft"}, why
    assert doc["rmse_mm"] == min(starts.values()), why
    axes = 3 if case.view == "3d" else 2
    assert doc["rmse_mm"] <= 1.3 * case.noise_mm * np.sqrt(axes), why
    assert starts["nominal"] > 3 * doc["rmse_mm"], why  # the set shows what the starts are for
    assert "best of 3 fits" in result.output


def _settable(key: str, value) -> str | None:
    """The ``--set`` item for a bad design-file value of one scalar quantity (file
    units), None where --set cannot say it (a vector, a deleted or non-numeric value)."""
    from design.registry import PARAMETERS

    for name, p in PARAMETERS.items():
        if p.field is not None and "[" not in p.field:
            unit_suffix = key.rsplit(".", 1)[-1].removeprefix(p.field.rsplit(".", 1)[-1])
            if key.startswith(p.field) and unit_suffix in ("", "_mm", "_mpa", "_deg", "_g", "_t"):
                if isinstance(value, float) and np.isfinite(value) and abs(value) < 1e300:
                    return f"{name}={value:g}"
    return None


def _bad_truths():
    from bad_designs import BAD_VALUES

    for key, value, words in BAD_VALUES:
        item = _settable(key, value)
        if item is not None:
            yield pytest.param(item, [w for w in words if w != key], id=item)


@pytest.mark.parametrize(("item", "words"), list(_bad_truths()))
def test_a_true_robot_a_design_file_refuses_is_refused_by_set(tmp_path, item, words):
    """Every bad scalar the design file refuses (tests/support/bad_designs.py), given as
    a true parameter, is one message saying why, exit 2, nothing written: the truth must
    be a robot too (the rod under the printed tip, the wire in the bores, the magnet clear
    of the robot), not only a number in range."""
    out = tmp_path / "set"
    result = run("synth", "--set", item, "--out", str(out))
    assert result.exit_code == 2, result.output
    assert all(w in result.output for w in words), (words, result.output)
    assert "Traceback" not in result.output and not out.exists()
