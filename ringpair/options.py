"""What the commands share: the consoles, the bad-input error, the arguments and options
that several commands take (each written once) and the loaders that turn them into a
design, a model, angles, a study or measured data.

Bad input raises :class:`UserError`: one message naming the option or file, exit code 2,
no traceback.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import click
import numpy as np
from rich.console import Console
from rich.markup import escape

from design.designfile import DesignError, default_design, load_design
from design.model import DEFAULT_EFFECTS, EFFECTS, RingPairModel, parse_effects
from design.records import Design
from ringpair.angles import parse_angles

if TYPE_CHECKING:
    from optimize.fitting.measurements import Measurements
    from optimize.sizing.studyfile import Study

# No emoji codes: rich would print an angle range like 0:abc:5 as '0🔤5'.
console = Console(emoji=False)
err_console = Console(stderr=True, emoji=False)

F = TypeVar("F", bound=Callable[..., Any])


def print_error(message: str) -> None:
    """``error: message`` on stderr, the message as written (no markup, not wrapped)."""
    err_console.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)


class UserError(click.ClickException):
    """Bad input: printed as one message, exit code 2."""

    exit_code = 2

    def show(self, file: object = None) -> None:
        print_error(self.message)


@contextmanager
def bad_input(*errors: type[Exception], prefix: str = "") -> Iterator[None]:
    """Turn ``errors`` raised in the block into a UserError with ``prefix`` + their message."""
    try:
        yield
    except errors as exc:
        raise UserError(f"{prefix}{exc}") from None


# Arguments and options taken by several commands.

DESIGN = click.argument("design", required=False, type=click.Path(path_type=Path))
"""DESIGN: a design file (TOML, spec/formats.md); absent, the paper's demonstrator."""

STUDY = click.argument(
    "study_path", metavar="[STUDY]", required=False, type=click.Path(path_type=Path)
)
"""STUDY: a study file (TOML); absent, the embedded demonstrator study."""

DATA = click.argument("data", type=click.Path(path_type=Path))
"""DATA: measured data, a data-set folder or a CSV (spec/formats.md)."""

CSV_DESIGN = click.option(
    "--design",
    "design_path",
    type=click.Path(path_type=Path),
    default=None,
    help="Design file for a CSV DATA (default: the demonstrator); a data-set folder has its own.",
)

SCHEDULER = click.option("--scheduler", default=None, help="Address of a running Dask scheduler.")

EFFECTS_HELP = (
    "Model effects on top of the paper's baseline: 'none', 'default' ("
    + ",".join(sorted(DEFAULT_EFFECTS))
    + "), 'all' or a comma list of "
    + ", ".join(EFFECTS)
    + " (see the README for what each adds and costs)."
)


def effects_option(default: str) -> Callable[[F], F]:
    """--effects, read by :func:`model_from`; ``default`` is 'none' or 'default'."""
    return click.option("--effects", default=default, show_default=True, help=EFFECTS_HELP)


def angle_option(name: str, default: str, help: str) -> Callable[[F], F]:
    """--theta1 or --theta2: degrees as typed, read by :func:`angles` or :func:`one_angle`."""
    return click.option(name, default=default, show_default=True, help=help)


def path_option(*names: str, help: str) -> Callable[[F], F]:
    """An option naming a file or folder (--out, --json, ...); None when not given."""
    return click.option(*names, type=click.Path(path_type=Path), default=None, help=help)


def default_out(*parts: str) -> Path:
    """Where a command writes when --out is not given: outputs/<parts>."""
    return Path("outputs", *parts)


# Loaders: option values to the objects the commands work on.


def design_from(path: Path | None) -> Design:
    """The design in ``path``, or the demonstrator when None."""
    if path is None:
        return default_design()
    with bad_input(DesignError):
        return load_design(path)


def model_from(effects: str) -> RingPairModel:
    """The model with the --effects named in ``effects``."""
    with bad_input(ValueError, prefix="--effects: "):
        return RingPairModel(parse_effects(effects))


def angles(text: str, option: str) -> np.ndarray:
    """The angles typed for ``option`` (a range, a list or one value). [deg]"""
    with bad_input(ValueError):
        return parse_angles(text, option)


def one_angle(text: str, option: str) -> float:
    """The single angle typed for ``option``. [deg]"""
    values = angles(text, option)
    if values.size != 1:
        raise UserError(f"{option} takes one angle here; got {values.size}")
    return float(values[0])


def study_from(path: Path | None) -> Study:
    """The study in ``path``, or the embedded demonstrator study when None."""
    from optimize.sizing.studyfile import StudyError, default_study, load_study

    with bad_input(StudyError, OSError, UnicodeDecodeError):
        return default_study() if path is None else load_study(path)


def measured_data(data: Path, design: Path | None) -> tuple[Design, Measurements]:
    """(design, measurements) from a data-set folder, or from a CSV with --design (default
    the demonstrator)."""
    from optimize.fitting.measurements import MeasurementError, load_dataset, load_measurements

    if data.is_dir() and design is not None:
        raise UserError(
            f"--design is for a CSV; {data} is a data-set folder with its own design.toml"
        )
    with bad_input(MeasurementError, DesignError):
        if data.is_dir():
            return load_dataset(data)
        return design_from(design), load_measurements(data)
