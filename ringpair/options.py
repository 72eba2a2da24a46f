"""What the commands share: the consoles, the bad-input error, the arguments and options
that several commands take (each written once), the loaders that turn them into a
design, a model, angles, a study or measured data, the checks of where a command writes
and of how big a request is, and the progress display.

Bad input raises :class:`UserError`: one message naming the option or file, exit code 2,
no traceback, nothing computed or written.

Overwrite policy (:data:`OVERWRITE_POLICY`, in the commands' help): results (CSV, JSON,
PNG, HTML, CAD files) are replaced on a rerun, each atomically; files that may be inputs
someone edited (a design file from ``show --save``, measured data in ``synth --out``)
are replaced only with ``--force``. No command writes over one of its inputs, inside an
input data set or onto a device, FIFO or socket. No command deletes a file it did not
write, except the temporaries an interrupted run of ringpair left behind, and only those
it proves are ringpair's (:mod:`design.atomic`).
"""

from __future__ import annotations

import json
import os
import re
import stat
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import click
import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.text import Text

from design.atomic import remove_stale_temporaries
from design.designfile import DesignError, default_design, load_design
from design.model import DEFAULT_EFFECTS, SWITCHES, RingPairModel, parse_effects
from design.records import Design
from design.strict_json import strict
from ringpair.angles import parse_angles, parse_lengths

if TYPE_CHECKING:
    from optimize.fitting.measurements import Measurements
    from optimize.sizing.studyfile import Study
    from ringpair.runs import RunFolder

# Text is printed as written: no emoji codes (rich would print an angle range like 0:abc:5
# as '0🔤5') and no markup (a design named 'a[/]b' or a path with brackets would break it
# or vanish); colour comes from styles (:func:`warn`, :func:`print_error`).
console = Console(emoji=False, markup=False)
err_console = Console(stderr=True, emoji=False, markup=False)

F = TypeVar("F", bound=Callable[..., Any])


def print_error(message: str) -> None:
    """``error: message`` on stderr, the message as written (not wrapped)."""
    err_console.print(
        Text.assemble(("error:", "bold red"), " ", message), highlight=False, soft_wrap=True
    )


def warn(message: str) -> None:
    """``warning: message`` on stderr, the message as written."""
    err_console.print(
        Text.assemble(("warning:", "yellow"), " ", message), highlight=False, soft_wrap=True
    )


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
"""DESIGN: a design file (TOML, docs/formats.md); absent, the paper's demonstrator."""

STUDY = click.argument(
    "study_path", metavar="[STUDY]", required=False, type=click.Path(path_type=Path)
)
"""STUDY: a study file (TOML); absent, the embedded demonstrator study."""

DATA = click.argument("data", type=click.Path(path_type=Path))
"""DATA: measured data, a data-set folder or a CSV (docs/formats.md)."""

CSV_DESIGN = click.option(
    "--design",
    "design_path",
    type=click.Path(path_type=Path),
    default=None,
    help="Design file for a CSV DATA (default: the demonstrator); a data-set folder has its own.",
)

PRIOR = click.option(
    "--prior",
    "prior_texts",
    multiple=True,
    metavar="KEY=SIGMA",
    help="One sigma of a free parameter's prior, overriding the default and the data "
    "folder's priors.toml: a length in mm with its suffix (external_center_mm=3 sets x, y "
    "and z; external_center_z_mm=1, free_length_mm=2), a log-fitted one as the sigma of "
    "ln(value/nominal) (bending_rigidity_scale=0.3); inf drops it. Repeatable.",
)
NO_PRIORS = click.option(
    "--no-priors",
    is_flag=True,
    help="Plain least squares: no priors (the parameters may go anywhere within their bounds).",
)


def priors_from(data: Path, texts: tuple[str, ...], off: bool) -> bool | dict[str, float]:
    """The priors of a fit of ``data``: False with --no-priors, else the defaults with a
    data-set folder's priors.toml and then ``texts`` (--prior) overriding them."""
    from optimize.fitting.calibrate import load_priors, parse_prior_options

    if off:
        if texts:
            raise UserError("--prior and --no-priors contradict each other")
        return False
    with bad_input(ValueError):
        widths = load_priors(data) if data.is_dir() else {}
        widths.update(parse_prior_options(texts))
    return widths or True


SCHEDULER = click.option("--scheduler", default=None, help="Address of a running Dask scheduler.")

EFFECTS_HELP = (
    "Model effects on top of the paper's baseline: 'none', 'default' ("
    + ",".join(sorted(DEFAULT_EFFECTS))
    + "), 'all' or a comma list of "
    + ", ".join(SWITCHES)
    + " (printed_tip: the printed mounting pieces' rigid segment, weight and, with torsion, "
    "stops; see the README for what each adds and costs)."
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


class FloatRange(click.FloatRange):
    """click's FloatRange without NaN, which it lets through (no comparison with NaN is
    true)."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        number = super().convert(value, param, ctx)
        if np.isnan(number):
            self.fail(f"{value!r} is not a number in {self._describe_range()}", param, ctx)
        return number


def grid_step_option(default: float) -> Callable[[F], F]:
    """--step: the grid step of both ring angles over a full turn [deg]."""
    return click.option(
        "--step",
        type=FloatRange(0.1, 90.0),
        default=default,
        show_default=True,
        help="Grid step of theta1 and theta2 over a full turn [deg].",
    )


FORCE = click.option(
    "--force", is_flag=True, help="Replace an existing file that may be someone's input."
)

OVERWRITE_POLICY = (
    "Results are replaced on a rerun (each file atomically); a file someone may have "
    "edited is replaced only with --force."
)

MAX_CONFIGURATIONS = 1_000_000
"""Configurations a command solves at most unless --max-configs says more: about a quarter
of an hour with the model for design work and 7 GB for a path (SOLVE_RATE, ROW_BYTES)."""
SOLVE_RATE = 1_000.0
"""Configurations solved per second by the model for design work with the search for other
stable states, as ``workspace`` does them (with its controllable workspace and plots): 1,070
to 2,230 measured on the development machine (2 cores) by benchmarks/estimates.py. [1/s]"""
ROW_BYTES = 7_000
"""Memory one configuration takes from its solve to its CSV row (measured). [bytes]"""
ANNOUNCE = 30.0
"""A run estimated longer than this is announced with its estimate. [s]"""

MAX_CONFIGS = click.option(
    "--max-configs",
    type=click.IntRange(1, None),
    default=MAX_CONFIGURATIONS,
    show_default=True,
    help="Refuse to solve more configurations than this, each model compared counting once "
    "(a guard against typing 0.001 for 1); raise it for a long run.",
)


def json_text(doc: object) -> str:
    """``doc`` as strict JSON text, indented, with a final newline; NaN and infinities,
    which JSON does not have, become null."""
    return json.dumps(strict(doc)[0], indent=2, allow_nan=False) + "\n"


def slug(name: str) -> str:
    """``name`` (free text from a design or study file) as one safe folder name: letters,
    digits, '_', '-' and inner dots; any other run of characters becomes '_', and leading
    or trailing dots and separators go, so it never climbs out of or above its folder
    (``../../x`` is ``x``, ``/etc`` is ``etc``); at most 100 bytes. 'unnamed' if nothing
    is left."""
    text = re.sub(r"[^\w.-]+", "_", name).strip("._-")
    while len(text.encode()) > 100:
        text = text[:-1]
    return text.rstrip("._-") or "unnamed"


def default_out(name: str, *parts: str) -> Path:
    """Where a command writes when --out is not given: outputs/<slug of name>/<parts>,
    ``name`` being a design's or a study's (never outside outputs/)."""
    return Path("outputs", slug(name), *parts)


NAME_BYTES = 200
"""Longest file or folder name an output may have (the file system allows 255 bytes, and
the temporary beside it adds a few dozen). [bytes]"""


def csv_with_picture(
    out: Path | None, default: Path, mode: str, picture: str, inputs: list
) -> tuple[Path, Path]:
    """The checked CSV path (``out`` or ``default``) and the picture written beside it
    (.png) for ``mode`` (the option that writes both, e.g. ``--path``); ``picture`` says
    what the picture is. A name not ending in .csv is refused: the picture's name would be
    the CSV's."""
    typed = out is not None
    out = out or default
    if out.suffix.lower() != ".csv":
        raise UserError(
            f"--out {out}: with {mode}, expected a CSV file name ending in .csv ({picture} "
            f"is written beside it as .png); got {out.suffix or 'no suffix'!r}"
        )
    csv_path, png = (
        output_path(p, "--out", folder=False, typed=typed, inputs=inputs)
        for p in (out, out.with_suffix(".png"))
    )
    return csv_path, png


def output_path(
    path: Path,
    option: str,
    *,
    folder: bool,
    typed: bool = True,
    replace: bool = True,
    files: Iterable[str] = (),
    inputs: Iterable[Path | None] = (),
) -> Path:
    """``path``, where a command will write, checked before any work; temporaries that an
    interrupted run left there are removed.

    folder : whether a folder is wanted (else a file).
    option : the option naming it, for the message; ``typed`` False when ``path`` is the
        command's default (the message then says so, rather than blame the option).
    replace : whether an existing file may be replaced (results); False asks for --force.
    files : the names the command writes inside the folder (each must not be a folder).
    inputs : files and folders (data sets) the command reads; it never writes over one of
        them nor anywhere inside an input folder.

    Raises UserError (exit 2) for a file where a folder is wanted or the reverse, a path
    under a file, a device, FIFO or socket where a file is wanted, a place the user cannot
    write, a file name too long, a file that must not be replaced, an input written over
    and a place inside an input data set.
    """
    kind = "folder" if folder else "file"
    who = f"{option} {path}" if typed else f"the default output {kind} {path} (set with {option})"

    def fail(problem: str) -> UserError:
        return UserError(f"{who}: {problem}")

    if "\x00" in str(path):
        raise fail("contains a NUL character")
    long = [p for p in path.parts if len(os.fsencode(p)) > NAME_BYTES]
    if long:
        raise fail(f"the name {long[0][:40]}... is longer than {NAME_BYTES} bytes")
    try:
        if path.is_symlink() and not path.exists():
            raise fail("is a symbolic link to nothing")
        if folder and path.exists() and not path.is_dir():
            raise fail("is a file; expected a folder")
        given = [Path(i) for i in inputs if i is not None]
        inside = next((i for i in given if i.is_dir() and _within(path, i)), None)
        if inside is not None:
            raise fail(f"is inside {inside}, a data set this command reads; write somewhere else")
        targets = [path / f for f in files] if folder else [path]
        for target in targets:
            where = "" if target == path else f"{target} "
            if target.is_dir():
                raise fail(f"{where}is a folder; expected a file name")
            special = _special(target)
            if special:
                raise fail(f"{where}is {special}; expected a regular file (or a new name)")
            if target.exists() and not replace:
                raise fail("exists; pass --force to replace it")
            if any(target.exists() and _same(target, i) for i in given):
                raise fail(f"{where}is an input of this command; writing there would destroy it")
        existing = path if folder else path.parent
        while not existing.exists() and existing != existing.parent:
            existing = existing.parent
        if not existing.is_dir():
            raise fail(f"{existing} is a file, so nothing can be created under it")
        if not os.access(existing, os.W_OK | os.X_OK):
            raise fail(f"cannot write in {existing} (permission denied)")
        if folder:
            remove_stale_temporaries(path)
        else:
            remove_stale_temporaries(path.parent, path.name)
    except OSError as exc:
        raise fail(exc.strerror or str(exc)) from None
    return path


def _within(path: Path, folder: Path) -> bool:
    """Whether ``path`` is ``folder`` or below it (links resolved; ``path`` may not exist)."""
    try:
        return path.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError):
        return False


def _special(path: Path) -> str:
    """What ``path`` is if it exists as neither a regular file nor a folder (a device, a
    FIFO, a socket; links followed), else ''."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return ""
    kinds = (
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "")


def _same(a: Path, b: Path) -> bool:
    try:
        return a.samefile(b)
    except OSError:
        return False


def check_configurations(
    n: int, limit: int, what: str, *, solves: int = 1, held: bool = True
) -> None:
    """Size a request up front (:func:`check_request`): ``n`` configurations, each solved
    ``solves`` times (models compared), at most ``limit`` solves, at SOLVE_RATE, with the
    memory when all are ``held`` at once. ``what`` names the options that asked for them."""
    total = n * solves
    check_request(
        total,
        limit,
        what,
        f"{n:,} configurations" + (f" x {solves} models = {total:,} solves" if solves > 1 else ""),
        total / SOLVE_RATE,
        "--max-configs",
        n * ROW_BYTES if held else None,
    )


def check_request(
    count: int,
    limit: int,
    what: str,
    size: str,
    seconds: float,
    raise_with: str | None,
    memory: float | None = None,
) -> None:
    """Size a request before any work: refuse (UserError) ``count`` pieces of work above
    ``limit``, saying its ``size`` (text), the time estimate ``seconds`` [s] and, if given,
    the ``memory`` [bytes]; below it, announce on stderr a run estimated above ANNOUNCE
    seconds. ``what`` names the options that asked for it, ``raise_with`` the option that
    lifts the limit (None: none does; the request must be made smaller)."""
    if count <= limit:
        if seconds > ANNOUNCE:
            err_console.print(f"{what}: {size}, about {duration(seconds)}")
        return
    held = f" and {memory / 1e9:.3g} GB of memory" if memory is not None else ""
    lift = f"unless {raise_with} says more" if raise_with else "(ask for fewer)"
    raise UserError(f"{what}: {size}, about {duration(seconds)}{held}; at most {limit:,} {lift}")


MAX_NLP_STARTS = 5_000
"""NLP starts a study may ask for (optimum and Pareto points): hours at
:data:`optimize.sizing.nlp_designs.START_SECONDS_PER_CONFIGURATION`."""


def check_study_size(study: Study, pareto: bool) -> None:
    """Size a study's NLPs before any work (:func:`check_request`): its starts for the
    optimum and (``pareto``) every Pareto point, each material pair; the estimate on one
    worker."""
    from optimize.sizing.nlp_designs import material_combinations, nlp_seconds, nlp_starts

    n = nlp_starts(study, pareto)
    points = sum(p.points for p in study.pareto) if pareto else 0
    check_request(
        n,
        MAX_NLP_STARTS,
        f"study '{study.name}' (solver.starts, pareto points, materials)",
        f"{n:,} NLP starts ({1 + points} solves x {study.starts} starts x "
        f"{len(material_combinations(study))} material pairs)",
        nlp_seconds(study, pareto),
        None,
    )


def duration(seconds: float) -> str:
    """``seconds`` for people: '40 s', '12 min', '3.5 h', '1,500 days'."""
    for unit, size in (("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= 2 * size:
            value = seconds / size
            return f"{value:,.0f} {unit}" if value >= 10 else f"{value:.1f} {unit}"
    return f"{seconds:.0f} s" if seconds >= 1 else "under a second"


@contextmanager
def progress(description: str, total: float | None = None) -> Iterator[Callable[..., None]]:
    """A progress display on stderr (bar, count, elapsed and remaining time) while the
    block runs, on a terminal (nothing in a pipe or a log); yields ``update(**fields)``,
    rich's task update: ``advance=n``, ``completed=, total=`` or ``description=``."""
    columns = (
        SpinnerColumn(),
        "[progress.description]{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    shown = err_console.is_terminal
    with Progress(*columns, console=err_console, transient=True, disable=not shown) as bar:
        task = bar.add_task(escape(description), total=total)

        def update(**fields: Any) -> None:
            if "description" in fields:
                fields["description"] = escape(str(fields["description"]))
            bar.update(task, **fields)

        yield update


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


def lengths(text: str, option: str) -> np.ndarray:
    """The lengths typed for ``option`` (a range, a list or one value). [mm]"""
    with bad_input(ValueError):
        return parse_lengths(text, option)


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
        study = default_study() if path is None else load_study(path)
    external_magnet_only(study.base, study.base_source)
    return study


def external_magnet_only(design: Design, source: object) -> None:
    """UserError (exit 2) where ``design`` (read from ``source``, for the message) has
    ``[[field.sources]]``: calibration, diagnosis, the study and the design NLP model the
    ``[external_magnet]`` alone (their parameter vectors are
    :data:`design.registry.NAMES`); simulate, workspace and steer take the sources."""
    if design.sources:
        kinds = ", ".join(s.kind for s in design.sources)
        raise UserError(
            f"{source}: [[field.sources]] ({kinds}): calibrate, diagnose, study and optimize "
            "model the [external_magnet] alone so far; remove the sources for them "
            "(simulate, workspace and steer take them)"
        )


SCHEDULER_TIMEOUT = 3.0
"""How long --scheduler's address is given to answer before any work. [s]"""


def scheduler_from(address: str | None) -> str | None:
    """--scheduler checked before any work: a ``tcp://host:port`` (or ``host:port``)
    address that accepts a connection within SCHEDULER_TIMEOUT; UserError otherwise."""
    if address is None:
        return None
    import socket
    from urllib.parse import urlsplit

    text = address.strip()
    url = urlsplit(text if "://" in text else f"tcp://{text}")
    try:
        host, port = url.hostname, url.port
    except ValueError:
        host, port = None, None
    if url.scheme not in ("tcp", "tls") or not host or port is None:
        raise UserError(
            f"--scheduler {address!r}: expected a Dask scheduler address tcp://host:port "
            "(e.g. tcp://127.0.0.1:8786)"
        )
    try:
        socket.create_connection((host, port), timeout=SCHEDULER_TIMEOUT).close()
    except OSError as exc:
        reason = "no answer" if isinstance(exc, TimeoutError) else exc.strerror or str(exc)
        raise UserError(
            f"--scheduler {address}: no Dask scheduler answers at {host}:{port} within "
            f"{SCHEDULER_TIMEOUT:g} s ({reason}); start one or leave --scheduler out for a "
            "local cluster"
        ) from None
    return text


def base_file(study: Study) -> Path | None:
    """The base design file a study names (None for the embedded design): an input."""
    return None if study.base_source == "embedded" else Path(study.base_source)


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
            found = load_dataset(data)
        else:
            found = design_from(design), load_measurements(data)
    external_magnet_only(found[0], data / "design.toml" if data.is_dir() else design)
    return found


@contextmanager
def held_run(out: Path, command: str, keep: Iterable[str] = ()) -> Iterator[RunFolder]:
    """A command's run writing the folder ``out`` as one run's
    (:func:`ringpair.runs.run_folder`), for commands that write a folder without a study's
    stages (``cad``, ``workspace``): another run in it is refused (UserError naming --out);
    an interrupted earlier run is warned about; when the run ends whole (normally or by its
    exit code, e.g. ``cad``'s 3 for a failed check), :func:`ringpair.runs.finish_run`
    removes the earlier run's outputs that this run did not write again (never under the
    folders ``keep``) and writes ``manifest.json`` of the files this run wrote. A run that
    fails in a folder it made, before writing anything, leaves no folder."""
    from ringpair.runs import LOCK, FolderBusy, finish_run, run_folder

    made = not out.exists()
    try:
        with run_folder(out, command) as folder:
            if folder.interrupted is not None:
                warn(
                    f"the previous run into {out} was interrupted; its files are replaced, "
                    "and those of its that this run does not write again are removed"
                )
            try:
                yield folder
            except SystemExit:
                finish_run(folder, keep)
                raise
            finish_run(folder, keep)
    except FolderBusy as exc:
        raise UserError(f"--out {out}: {exc}") from None
    except Exception:
        if made and {p.name for p in out.iterdir()} <= {LOCK}:
            (out / LOCK).unlink(missing_ok=True)
            out.rmdir()
        raise
