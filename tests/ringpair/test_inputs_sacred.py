"""Inputs are sacred (issue 55): every command refuses, before any work and with one
message (exit 2), an output that is one of its inputs or inside an input data set, and an
output that is a device, a FIFO or a socket; each input is byte for byte as it was."""

from __future__ import annotations

import os
import socket
import stat

import pytest
from studies import SMALL


@pytest.fixture()
def setup(tmp_path, run, demonstrator_doc):
    """A data set (``bench/``), design files and studies naming them."""
    import tomli_w

    assert run("synth", "--n", "8", "--out", str(tmp_path / "bench")).exit_code == 0
    (tmp_path / "d.toml").write_text(tomli_w.dumps(demonstrator_doc))
    (tmp_path / "s.toml").write_text('base_design = "d.toml"\n' + SMALL)
    # a study whose base design has the name of what optimize and study write
    (tmp_path / "best_design.toml").write_text(tomli_w.dumps(demonstrator_doc))
    (tmp_path / "s2.toml").write_text('base_design = "best_design.toml"\n' + SMALL)
    return tmp_path


def snapshot(folder):
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and "outputs" not in p.parts
    }


CASES = [
    ("calibrate bench --json bench/measurements.csv", "inside"),
    ("diagnose bench --json bench/measurements.csv", "inside"),
    ("diagnose bench --json bench/design.toml", "inside"),
    ("diagnose bench --report bench/report", "inside"),
    ("calibrate bench/measurements.csv --design d.toml --json d.toml", "input of this"),
    ("effects d.toml --theta1 0 --theta2 0 --out d.toml", "input of this"),
    ("branch d.toml --out d.toml", "input of this"),
    ("simulate d.toml --theta1 0 --out d.toml", "input of this"),
    ("show d.toml --save d.toml --force", "input of this"),
    ("study s.toml --data bench --out bench/run", "inside"),
    ("optimize s2.toml --out .", "input of this"),
    ("study s2.toml --out .", "input of this"),
]


@pytest.mark.parametrize("line, words", CASES, ids=[c[0] for c in CASES])
def test_an_output_onto_an_input_is_refused_and_the_input_kept(
    setup, run, line, words, monkeypatch
):
    monkeypatch.chdir(setup)
    before = snapshot(setup)
    result = run(*line.split())
    assert result.exit_code == 2, result.output
    assert words in " ".join(result.output.split()), result.output
    assert result.output.count("error:") == 1
    assert snapshot(setup) == before


@pytest.fixture()
def specials(tmp_path):
    """A FIFO, a socket and a link to a character device (the link, not /dev/null, would
    be replaced if the check failed)."""
    os.mkfifo(tmp_path / "fifo")
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(tmp_path / "sock"))
    (tmp_path / "null").symlink_to(os.devnull)
    yield tmp_path
    sock.close()


@pytest.mark.parametrize(
    "name, kind", [("fifo", "FIFO"), ("sock", "socket"), ("null", "character device")]
)
@pytest.mark.parametrize(
    "args",
    [
        ("simulate", "--theta1", "0", "--quiet", "--out"),
        ("effects", "--theta1", "0", "--theta2", "0", "--out"),
        ("branch", "--out"),
    ],
    ids=lambda a: a[0],
)
def test_a_device_fifo_or_socket_is_never_replaced(specials, run, name, kind, args):
    target = specials / name
    mode = os.stat(target).st_mode
    result = run(*args, str(target))
    assert result.exit_code == 2, result.output
    assert kind in result.output and "expected a regular file" in result.output
    assert os.stat(target).st_mode == mode and stat.S_IFMT(mode) != stat.S_IFREG
    assert sorted(p.name for p in specials.iterdir()) == ["fifo", "null", "sock"]


def test_a_device_inside_an_output_folder_is_refused(tmp_path, run):
    out = tmp_path / "ws"
    out.mkdir()
    os.mkfifo(out / "summary.json")
    result = run("workspace", "--step", "90", "--out", str(out))
    assert result.exit_code == 2 and "FIFO" in result.output, result.output
    assert stat.S_ISFIFO(os.stat(out / "summary.json").st_mode)
