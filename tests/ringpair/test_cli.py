"""The ``ringpair`` group: its commands, their help, the console script."""

from __future__ import annotations

import subprocess
import sys

from ringpair.cli import cli

COMMANDS = {
    "branch",
    "cad",
    "calibrate",
    "diagnose",
    "effects",
    "force",
    "optimize",
    "show",
    "simulate",
    "steer",
    "study",
    "synth",
    "workspace",
}


def test_every_command_is_registered():
    assert set(cli.commands) == COMMANDS


def test_console_script_reports_missing_file_without_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "ringpair.cli", "simulate", str(tmp_path / "none.toml")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert "does not exist" in proc.stderr and "Traceback" not in proc.stderr


def test_help_documents_every_command(run):
    result = run("--help")
    for command in ("simulate", "workspace", "show"):
        assert command in result.output
        sub = run(command, "--help")
        assert sub.exit_code == 0 and "DESIGN" in sub.output
