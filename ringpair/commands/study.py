"""``ringpair study``: the main job, from a study file to the report (see
:mod:`ringpair.pipeline`). While it runs, each stage is a live line on stderr (a terminal
only); when a stage ends, one line on stdout says how long it took; the run ends with the
result."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import click
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    Task,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)
from rich.text import Text

from design.designfile import read_regular
from design.designfile.keys import shown
from optimize.sizing.studyfile import Study
from ringpair.options import (
    ANNOUNCE,
    OVERWRITE_POLICY,
    ROW_BYTES,
    SCHEDULER,
    SOLVE_RATE,
    STUDY,
    UserError,
    bad_input,
    base_file,
    check_study_size,
    console,
    default_out,
    duration,
    err_console,
    output_path,
    path_option,
    print_error,
    scheduler_from,
    study_from,
    warn,
)
from ringpair.runs import RunFolder

FILES = ("report.html", "results.json", "manifest.json", "best_design.toml")
"""What ``study`` writes in its folder besides each stage's files."""
REPORT = "report: page, figures, PDF"
MAX_SAMPLES = 100_000
"""Most tolerance Monte Carlo samples a study takes (12 million configurations, about an
hour at SOLVE_RATE)."""


class _Stages:
    """The stages as the user sees them: a live line per running stage (spinner, bar,
    pieces done, elapsed time) on ``bar``, and when it ends one line with its duration."""

    def __init__(self, bar: Progress) -> None:
        self.bar = bar
        self.task: TaskID | None = None

    def start(self, what: str) -> None:
        self.task = self.bar.add_task(escape(what), total=None)

    def count(self, done: int, total: int) -> None:
        if self.task is not None:
            self.bar.update(self.task, completed=done, total=total)

    def end(self, what: str, seconds: float, reused: bool) -> None:
        if self.task is not None:
            self.bar.remove_task(self.task)
            self.task = None
        took = f"reused (it took {seconds:.1f} s)" if reused else f"{seconds:.1f} s"
        console.print(f"{what}: {took}", highlight=False, soft_wrap=True)


class _Count(MofNCompleteColumn):
    """'done/total' where a stage counts its work (Pareto points), nothing elsewhere."""

    def render(self, task: Task) -> Text:
        return super().render(task) if task.total is not None else Text("")


@contextmanager
def _stages() -> Iterator[_Stages]:
    """A :class:`_Stages` whose live lines show only where stderr is a terminal."""
    columns = (
        SpinnerColumn(),
        TextColumn("{task.description}"),
        BarColumn(),
        _Count(),
        TimeElapsedColumn(),
    )
    live = err_console.is_terminal
    with Progress(
        *columns,
        console=err_console,
        transient=True,
        disable=not live,
        redirect_stdout=live and console.is_terminal,
        redirect_stderr=False,
    ) as bar:
        yield _Stages(bar)


def _process(name: str) -> str:
    """``name`` if it is a print process CAD knows (cad.process.PROCESSES), else UserError."""
    from cad.process import PROCESSES

    if name not in PROCESSES:
        known = ", ".join(repr(p) for p in PROCESSES)
        raise UserError(f"--process must be one of {known}; got {name!r}")
    return name


@click.command()
@STUDY
@path_option("--out", help="Output directory. Default: outputs/<study name>. " + OVERWRITE_POLICY)
@path_option(
    "--data",
    help="Measured data set (folder with design.toml and measurements.csv, docs/formats.md) "
    "to diagnose.",
)
@click.option("--samples", default=200, show_default=True, help="Tolerance Monte Carlo samples.")
@click.option(
    "--seed",
    type=click.IntRange(0, 2**32 - 1),
    default=0,
    show_default=True,
    help="Seed of the Monte Carlo.",
)
@click.option(
    "--workers",
    type=click.IntRange(1, None),
    default=2,
    show_default=True,
    help="Local Dask workers.",
)
@SCHEDULER
@click.option(
    "--process",
    default="fdm",
    show_default=True,
    help="Print process of the actuator parts: 'fdm' or 'resin' (fit allowances, "
    "clearances, minimum wall, build volume, material). The two tip pieces are printed as "
    "the design says (tip.mounting.process, resin by default): they are the pieces the "
    "model carries.",
)
@click.option("--no-render", is_flag=True, help="Skip the part renders (faster).")
def study(
    study_path: Path | None,
    out: Path | None,
    data: Path | None,
    samples: int,
    seed: int,
    workers: int,
    scheduler: str | None,
    process: str,
    no_render: bool,
) -> None:
    """Run STUDY (default: the embedded demonstrator study) through every stage: starting
    workspace, optimisation, what each active limit costs (the NLP solved again with that
    limit moved 10 %), Pareto sweeps (Dask), forward re-simulation with the model for
    design work, tolerance Monte Carlo, model effects, CAD of the recommended design and
    (with --data) diagnosis.

    Writes report.html (self-contained; its first screen: the question, the recommended
    design and its gain, what limits it and the next decision), results.json,
    manifest.json, the hand-off (best_design.toml, a design file of the recommended design;
    pareto/pareto_<quantity>.csv; cad/parts.csv with the parts' STL and STEP files) and each
    stage's files. Finished
    stages are reused when rerun with the same inputs. File formats: docs/formats.md.

    Exit codes: 0 done; 2 bad input; 3 a stage failed (named, with what was written).
    """
    from ringpair.runs import FolderBusy, run_folder

    with bad_input(OSError, UnicodeDecodeError):
        text = read_regular(study_path) if study_path else ""
    s = study_from(study_path)
    process = _process(process)  # every option checked before the size is announced
    check_study_size(s, pareto=True)
    if data is not None and not (data / "measurements.csv").is_file():
        raise UserError(f"--data: {data} is not a data set (expected {data}/measurements.csv)")
    from ringpair.pipeline import TOLERANCE_LOOP

    if not 2 <= samples <= MAX_SAMPLES:
        size = ""  # no estimate for a count beyond any machine (a float cannot hold 10^400)
        if MAX_SAMPLES < samples < 10**15:
            size = (
                f"{samples:,} (each sample solves {TOLERANCE_LOOP} configurations: about "
                f"{duration(samples * TOLERANCE_LOOP / SOLVE_RATE)} and "
                f"{samples * TOLERANCE_LOOP * ROW_BYTES / 1e9:.3g} GB)"
            )
        raise UserError(
            f"--samples must be between 2 and {MAX_SAMPLES:,}; got {size or shown(samples)}"
        )
    if samples * TOLERANCE_LOOP / SOLVE_RATE > ANNOUNCE:
        err_console.print(
            f"--samples: {samples:,} samples x {TOLERANCE_LOOP} configurations, about "
            f"{duration(samples * TOLERANCE_LOOP / SOLVE_RATE)} in the tolerance stage"
        )
    if s.pareto:
        scheduler = scheduler_from(scheduler)
    out = output_path(
        out or default_out(s.name),
        "--out",
        folder=True,
        typed=out is not None,
        files=FILES,
        inputs=[study_path, base_file(s), data],
    )
    t0 = time.perf_counter()
    try:
        with run_folder(out, "study") as folder:
            _run(
                s,
                out,
                folder,
                study_path,
                text,
                data,
                workers,
                scheduler,
                samples,
                seed,
                process,
                no_render,
                t0,
            )
    except FolderBusy as exc:
        raise UserError(f"--out {out}: {exc}") from None


def _run(
    s: Study,
    out: Path,
    folder: RunFolder,
    study_path: Path | None,
    text: str,
    data: Path | None,
    workers: int,
    scheduler: str | None,
    samples: int,
    seed: int,
    process: str,
    no_render: bool,
    t0: float,
) -> None:
    """The study in its held folder ``folder`` (:func:`ringpair.runs.run_folder`)."""
    from ringpair.pipeline import StageError, headline, run_study, write_manifest
    from ringpair.report_html import write_report

    if folder.interrupted is not None:
        warn(
            f"the previous run into {out} was interrupted; its files are replaced, and "
            "those of its that this run does not write again are removed"
        )

    def about() -> dict[str, object]:
        return {
            "previous_run_interrupted": folder.interrupted is not None,
            "removed_stale": folder.removed,
        }

    try:
        with _stages() as stages:
            run = run_study(
                s,
                out,
                study_text=text or repr(s),
                data=data,
                workers=workers,
                scheduler=scheduler,
                samples=samples,
                seed=seed,
                cad_process=process,
                render=not no_render,
                watch=stages,
            )
            folder.remove_stale([n for n, r in run.reused.items() if r])
            stages.start(REPORT)
            t1 = time.perf_counter()
            written = write_report(run)
            stages.end(REPORT, time.perf_counter() - t1, False)
    except StageError as exc:
        print_error(str(exc))
        if exc.run is not None:
            folder.remove_stale([n for n, r in exc.run.reused.items() if r])
            manifest = write_manifest(
                exc.run, study_path, data, seed, failed=exc.stage, folder=about()
            )
            done = ", ".join(exc.run.seconds) or "none"
            err_console.print(
                f"stages finished before it: {done}; their files are listed in {manifest}"
            )
        sys.exit(3)
    manifest = write_manifest(run, study_path, data, seed, folder=about())
    pdf = [str(p) for p in written if p.suffix == ".pdf"] or [
        "no PDF (headless Chromium, Debian package 'chromium', is not installed)"
    ]
    console.print(f"wrote {written[-2]}, {written[-1]}, {manifest}, {pdf[0]}", soft_wrap=True)
    console.print("hand-off: " + ", ".join(map(str, run.handoff)), soft_wrap=True)
    console.print(f"done in {time.perf_counter() - t0:.1f} s")
    console.print(headline(run), highlight=False, soft_wrap=True)
