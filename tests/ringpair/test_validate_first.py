"""Validate before work (issue 55): options and files that would end late, hang or raise
end at once with one message naming the option or file, exit 2: a negative or huge
--seed, --effects '' (not silently the baseline), --samples beyond what a study takes
(with its size), a --scheduler nobody answers at (named, within seconds, nothing
written), input files that are FIFOs, devices or oversized, and TOML nested too deeply."""

from __future__ import annotations

import os
import socket
import threading
import time

import pytest
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
    ],
    ids=[
        "study seed -1",
        "synth seed 2^70",
        "diagnose seed -1",
        "effects ''",
        "effects ,,",
        "samples",
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
