"""The ``ringpair`` command line: the group of commands (one module each in
:mod:`ringpair.commands`) and the console-script entry point.

Exit codes: 0 done; 2 bad input (one message naming the key or option, no traceback);
3 a stage or a printability check failed (``study``, ``cad``); 130 interrupted (Ctrl-C or
SIGTERM); 1 an unexpected failure.
"""

from __future__ import annotations

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
from ringpair.commands.branch import branch
from ringpair.commands.cad import cad
from ringpair.commands.calibrate import calibrate
from ringpair.commands.diagnose import diagnose
from ringpair.commands.effects import effects
from ringpair.commands.force import force
from ringpair.commands.optimize import optimize
from ringpair.commands.show import show
from ringpair.commands.simulate import simulate
from ringpair.commands.steer import steer_command
from ringpair.commands.study import study
from ringpair.commands.synth import synth
from ringpair.commands.workspace import workspace
from ringpair.options import UserError, err_console, warn


class _Commands(click.Group):
    """The group, with one last net for a file that cannot be read or written found only
    while a command runs (a full disk, a permission changed meanwhile): one message naming
    the file, exit 2. The commands check their output paths before any work."""

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


for _command in (
    branch,
    cad,
    calibrate,
    diagnose,
    effects,
    force,
    optimize,
    show,
    simulate,
    steer_command,
    study,
    synth,
    workspace,
):
    cli.add_command(_command)


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
