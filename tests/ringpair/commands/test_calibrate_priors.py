"""``ringpair calibrate`` with priors (issue 53): the pulls it prints and writes follow
their definition, (estimate - nominal) / prior sigma, with the prior the user gave
(``--prior`` over the data folder's ``priors.toml`` over the defaults); ``--paper`` fits
the paper's two-factor model (Authors, "Design of Magnetic Continuum Robots with Tunable
Force Response Using Rotational Ring Pairs": K_E on the bending rigidity, K_B on the
external dipole's moment and position) and judges it by the same priors; bad priors are
one message naming the key, exit 2, nothing written."""

from __future__ import annotations

import json
import math

from optimize.fitting.calibrate import FREE_PARAMETERS, PULL_LIMIT


def test_calibrate_prints_and_writes_pulls_against_the_priors_given(tmp_path, run):
    data = tmp_path / "set"
    args = ("--n", "12", "--seed", "5", "--noise-mm", "0.3", "--out", str(data))
    assert run("synth", "--set", "external_center_y=20", *args).exit_code == 0
    (data / "priors.toml").write_text("external_center_mm = 4\nbending_rigidity_scale = 0.2\n")
    out = tmp_path / "c.json"
    result = run(
        "calibrate", str(data), "--prior", "external_center_y_mm=2", "--paper", "--json", str(out)
    )
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    assert doc["priors"] is True
    given = {"external_center_x": 4, "external_center_y": 2, "external_center_z": 4}
    for name, pull in doc["pull"].items():
        spec = FREE_PARAMETERS[name]
        est, nom = doc["estimate"][name], doc["nominal"][name]
        if spec.kind == "log":
            assert name == "bending_rigidity_scale"
            assert math.isclose(pull, math.log(est / nom) / 0.2, rel_tol=1e-9)
        else:  # sigma in mm on the command line or in the file
            assert math.isclose(pull, (est - nom) * 1e3 / given[name], rel_tol=1e-9), name
    # the magnet 20 mm off along y: 10 sigmas of the 2 mm prior, said not physical
    assert set(doc["beyond_prior"]) == {"external_center_y"}
    assert doc["pull"]["external_center_y"] > PULL_LIMIT
    assert "not physical: external_center_y moved" in " ".join(result.output.split())
    paper = doc["paper"]
    assert math.isclose(
        paper["pull"]["bending_rigidity_scale"], math.log(paper["stiffness_scale"]) / 0.5
    )
    assert paper["physical"] is not bool(paper["beyond_prior"])
    assert "the paper's fit: K_E =" in result.output


def test_a_bad_prior_is_one_message_naming_the_key(tmp_path, run):
    data = tmp_path / "set"
    assert run("synth", "--n", "6", "--out", str(data)).exit_code == 0
    out = tmp_path / "c.json"
    for args, fragment in [
        (("--prior", "magnet_gap_mm=1"), "'magnet_gap_mm' is no parameter calibration can free"),
        (("--prior", "external_center_mm=-1"), "must be a positive one-sigma width"),
        (("--prior", "external_center_mm=1", "--no-priors"), "contradict"),
    ]:
        result = run("calibrate", str(data), *args, "--json", str(out))
        assert result.exit_code == 2 and fragment in " ".join(result.output.split()), args
        assert not out.exists()
    (data / "priors.toml").write_text("bending_rigidity_scale_mm = 1\n")
    result = run("diagnose", str(data), "--json", str(out))
    assert result.exit_code == 2 and "priors.toml" in result.output
    assert "ln(value / nominal)" in " ".join(result.output.split()) and not out.exists()
