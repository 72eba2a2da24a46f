"""The ``ringpair`` command line: the group of commands (one module each in
:mod:`ringpair.commands`) and the console-script entry point.

Exit codes: 0 done; 2 bad input (one message naming the key or option, no traceback);
3 a stage or a printability check failed (``study``, ``cad``); 130 interrupted (Ctrl-C or
SIGTERM); 1 an unexpected failure.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys
import warnings
from pathlib import Path


def _interrupted_while_starting(signum: int, frame: object) -> None:
    """Ctrl-C or SIGTERM before :func:`main` runs (while the libraries load): nothing was
    written yet, so end at once, as :func:`main` would."""
    sys.stderr.write("interrupted\n")
    os._exit(130)


if __name__ == "__main__" or Path(sys.argv[0]).name == "ringpair":  # the command, not a test
    for _signal in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(_signal) is not signal.SIG_IGN:  # nohup, a shell's & keep theirs
            signal.signal(_signal, _interrupted_while_starting)

import click  # the imports below take seconds: after the early handler

from design.processes import Interrupted, raise_if_interrupted, raise_on_signals
from ringpair.options import UserError, err_console, warn

COMMANDS = {
    "branch": "branch",
    "cad": "cad",
    "calibrate": "calibrate",
    "diagnose": "diagnose",
    "effects": "effects",
    "force": "force",
    "optimize": "optimize",
    "show": "show",
    "simulate": "simulate",
    "steer": "steer_command",
    "study": "study",
    "synth": "synth",
    "workspace": "workspace",
}
"""Each command's name and its click command in :mod:`ringpair.commands` ``.<name>``,
imported when the command runs (or ``--help`` lists them): the optimisation, fitting, CAD
and plotting libraries take seconds to load, and ``ringpair simulate`` needs none of
them."""


class _Commands(click.Group):
    """The group, with one last net for a file that cannot be read or written found only
    while a command runs (a full disk, a permission changed meanwhile): one message naming
    the file, exit 2. The commands check their output paths before any work."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name not in COMMANDS:
            return None
        module = importlib.import_module(f"ringpair.commands.{cmd_name}")
        command: click.Command = getattr(module, COMMANDS[cmd_name])
        return command

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except BrokenPipeError:
            raise  # the reader went away (``| head``): click ends quietly
        except OSError as exc:
            where = f" {exc.filename}" if exc.filename else ""
            raise UserError(f"cannot use{where}: {exc.strerror or exc}") from None


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="ringpair")
def cli() -> None:
    """ringpair: design magnetic continuum robots steered by a rotational ring pair.

    Two diametrically magnetised rings at the tip, each turned by its own coaxial element
    (inner wire: distal ring, theta1; outer catheter: proximal ring, theta2), steer the tip
    in the fixed field of an external magnet. Every command takes a design file
    (docs/formats.md) and defaults to the paper's demonstrator. Angles are in degrees,
    lengths in millimetres; base frame: origin at the clamp, x along the straight robot.
    """


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
    """A warning for the user is one line on stderr, not a source location."""
    warn(str(message))


def main() -> None:
    """Console-script entry point. Ctrl-C and SIGTERM end the run with ``interrupted`` and
    exit 130 (files written so far are whole; workers die with this process), without the
    traceback of whatever was running (a Dask cluster shutting down says nothing)."""
    warnings.showwarning = _show_warning
    raise_on_signals()
    try:
        try:
            cli.main(standalone_mode=True)
        finally:
            raise_if_interrupted()  # a signal a library swallowed still ends the run so
    except (Interrupted, KeyboardInterrupt):
        _quiet()
        err_console.print("interrupted")
        sys.exit(130)


def _quiet() -> None:
    """Nothing more from the libraries while this process ends (Dask's clean-up logs
    closed connections and cancelled tasks)."""
    import logging

    for name in ("distributed", "tornado", "asyncio"):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)


if __name__ == "__main__":
    main()
