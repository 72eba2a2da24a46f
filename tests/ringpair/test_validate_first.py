"""Validate before work (issue 55): options, files and designs that would end late, hang
or raise end at once with one message naming the option, file or key, exit 2: a negative
or huge --seed, --effects '' (not silently the baseline), --samples beyond what a study
takes (with its size), a --scheduler nobody answers at (named, within seconds, nothing
written), input files that are FIFOs, devices or oversized, TOML nested too deeply, an
acquisition number beyond int64, a design with no stable state to map and a ring too
short for the CAD to draw."""

from __future__ import annotations

import os
import socket
import threading
import time

import pytest
import tomli_w
from bad_designs import edited
from studies import SMALL

PARETO = SMALL + '[[pareto]]\nagainst = "external_distance"\npoints = 3\n'


def one_message(result, *words):
    text = " ".join(result.output.split())
    assert result.exit_code == 2, result.output
    assert result.output.count("error:") + result.output.count("Error:") == 1, result.output
    assert "Traceback" not in result.output
    for w in words:
        assert w in text, (w, text)


@pytest.mark.parametrize(
    "args, words",
    [
        (("study", "--seed", "-1"), ["--seed", "-1"]),
        (("synth", "--seed", str(2**70)), ["--seed"]),
        (("diagnose", "x", "--seed", "-1"), ["--seed"]),
        (("simulate", "--effects", "", "--theta1", "0"), ["--effects", "no model effect"]),
        (("simulate", "--effects", ",,", "--theta1", "0"), ["--effects", "no model effect"]),
        (("study", "--samples", "100000000"), ["--samples", "100,000", "GB"]),
        (("study", "--samples", str(10**400)), ["--samples", "(401 characters)"]),
        (("study", "--samples", "1"), ["--samples", "between 2 and 100,000", "got 1"]),
        (
            ("steer", "--to", "1,1", "--to", "2,2", "--to", "1,2", "--max-targets", "2"),
            ["--to: 3 targets, about", "at most 2 unless --max-targets"],
        ),
        (("synth", "--set", "free_length=3"), ["--set free_length", "rigid offset", "got 3"]),
    ],
    ids=[
        "study seed -1",
        "synth seed 2^70",
        "diagnose seed -1",
        "effects ''",
        "effects ,,",
        "samples",
        "samples 10^400",
        "samples 1",
        "steer targets",
        "synth rod",
    ],
)
def test_bad_options_are_one_message(tmp_path, run, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    one_message(run(*args), *words)
    assert not (tmp_path / "outputs").exists()


def closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("command", ["optimize", "study"])
def test_a_scheduler_nobody_answers_at_is_named_before_any_work(tmp_path, run, command):
    (tmp_path / "s.toml").write_text(PARETO)
    out = tmp_path / "out"
    address = f"tcp://127.0.0.1:{closed_port()}"
    t0 = time.monotonic()
    result = run(command, str(tmp_path / "s.toml"), "--out", str(out), "--scheduler", address)
    assert time.monotonic() - t0 < 10
    one_message(result, "--scheduler", address, "no Dask scheduler answers")
    assert not out.exists()
    one_message(run(command, str(tmp_path / "s.toml"), "--scheduler", "http://x"), "--scheduler")


def test_a_fifo_input_is_refused_not_waited_on(tmp_path, run):
    fifo = tmp_path / "d.toml"
    os.mkfifo(fifo)
    done = []
    worker = threading.Thread(target=lambda: done.append(run("show", str(fifo))), daemon=True)
    worker.start()
    worker.join(timeout=30)
    assert done, "show hung on a FIFO"
    one_message(done[0], str(fifo), "not a regular file")


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_a_device_input_is_refused(run, device, tmp_path):
    one_message(run("show", device), device, "not a regular file")
    one_message(run("calibrate", device, "--json", str(tmp_path / "f.json")), "not a regular file")


def test_an_oversized_input_is_refused(tmp_path, run, monkeypatch):
    from design.designfile import inputs

    monkeypatch.setattr(inputs, "MAX_INPUT_BYTES", 1000)
    big = tmp_path / "d.toml"
    big.write_text("# " + "x" * 2000 + "\n")
    one_message(run("show", str(big)), "bytes, more than 1,000")


@pytest.mark.parametrize("kind", ["show", "optimize"])
def test_toml_nested_too_deeply_is_one_message(tmp_path, run, kind):
    path = tmp_path / "deep.toml"
    path.write_text("x = " + "[" * 100_000 + "]" * 100_000 + "\n")
    one_message(run(kind, str(path)), str(path), "nested too deeply")


def test_a_design_without_a_stable_state_has_no_workspace_and_says_so(
    tmp_path, run, demonstrator_doc
):
    # A rod a million times softer than rubber beside the magnet: every configuration's
    # load ramp folds and finds no stable state to fall into, so there is nothing to map
    # (this raised 'no configuration of the grid reached a stable equilibrium').
    doc = edited(demonstrator_doc, "robot.catheter.youngs_modulus_mpa", 1e-6)
    doc = edited(doc, "robot.wire.youngs_modulus_mpa", 1e-6)
    doc = edited(doc, "external_magnet.center_mm", [200.0, 0.0, 0.0])
    (tmp_path / "soft.toml").write_text(tomli_w.dumps(doc))
    out = tmp_path / "ws"
    result = run(
        "workspace", str(tmp_path / "soft.toml"), "--step=90", "--effects=none", "--out", str(out)
    )
    one_message(result, "no workspace to map", "none of the 16 configurations", "stable state")
    assert not out.exists()


def test_cad_refuses_a_ring_too_short_to_draw(tmp_path, run, demonstrator_doc):
    # 1e-300 mm passes the design file (> 0) but left the CAD's tessellation without faces
    doc = edited(demonstrator_doc, "tip.magnet_length_mm", 1e-300)
    (tmp_path / "thin.toml").write_text(tomli_w.dumps(doc))
    out = tmp_path / "cad"
    result = run("cad", str(tmp_path / "thin.toml"), "--no-render", "--out", str(out))
    one_message(result, "tip.magnet_length_mm", "chord tolerance", "got 1e-300 mm")
    assert not out.exists()


@pytest.mark.parametrize("number", [str(2**63), "12345678901234567890", "9" * 5000])
def test_an_acquisition_number_beyond_int64_is_one_message(tmp_path, run, number):
    # int64 holds the sequence column; a 20-digit number raised OverflowError
    data = tmp_path / "data.csv"
    data.write_text(
        f"theta1_deg,theta2_deg,x_mm,y_mm,z_mm,sequence\n0,0,150,1,1,0\n90,0,150,2,1,{number}\n"
    )
    result = run("calibrate", str(data), "--json", str(tmp_path / "fit.json"))
    one_message(result, str(data), "line 3", "column sequence", "non-negative integer")
    assert not (tmp_path / "fit.json").exists()


@pytest.mark.parametrize("command", ["optimize", "study"])
def test_a_study_too_big_to_solve_is_sized_before_any_work(tmp_path, run, command):
    # 1,001 solves (the optimum and 1,000 Pareto points) x 100 starts: hours of NLPs
    big = SMALL.replace("starts = 2", "starts = 100")
    (tmp_path / "s.toml").write_text(
        big + '[[pareto]]\nagainst = "external_distance"\npoints = 1000\n'
    )
    out = tmp_path / "out"
    result = run(command, str(tmp_path / "s.toml"), "--out", str(out))
    one_message(result, "100,100 NLP starts", "100 starts", "about 11 h", "at most 5,000")
    assert not out.exists()
