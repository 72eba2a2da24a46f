"""The ``ringpair`` group: its commands, their help, the console script."""

from __future__ import annotations

import subprocess
import sys

import click

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
    ctx = click.Context(cli)
    assert set(cli.list_commands(ctx)) == COMMANDS
    for name in COMMANDS:  # each loads, under its own name
        command = cli.get_command(ctx, name)
        assert command is not None and command.name == name, name
    assert cli.get_command(ctx, "simulat") is None


HEAVY = ("cadquery", "OCP", "pyvista", "vtk", "dask", "distributed", "scipy.stats", "cyipopt")
"""Libraries that take seconds to import and that steering and simulating never use."""


def test_simulating_and_steering_load_no_cad_optimisation_or_cluster_library(tmp_path):
    """``ringpair simulate`` and ``steer`` start in about two seconds: the CAD kernel
    (3 s to import), the renderer, the cluster and the statistics library load only in
    the commands that use them (measured: 5.1 s -> 2.3 s to import the command line)."""
    script = (
        "import sys\n"
        "from click.testing import CliRunner\n"
        "from ringpair.cli import cli\n"
        f"out = {str(tmp_path)!r}\n"
        "for args in (['simulate', '--theta1', '0', '--theta2', '180', '--out', out + '/sim'],\n"
        "             ['steer', '--to', '5,0', '--out', out + '/steer']):\n"
        "    result = CliRunner().invoke(cli, args, catch_exceptions=False)\n"
        "    assert result.exit_code == 0, result.output\n"
        f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip() == "", f"loaded: {proc.stdout.strip()}"


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
