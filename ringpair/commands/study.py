"""``ringpair study``: the main job, from a study file to the report (see
:mod:`ringpair.pipeline`)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import click

from ringpair.options import (
    OVERWRITE_POLICY,
    SCHEDULER,
    STUDY,
    UserError,
    bad_input,
    console,
    default_out,
    err_console,
    output_path,
    path_option,
    print_error,
    progress,
    study_from,
)

FILES = ("report.html", "results.json", "manifest.json")
"""What ``study`` writes in its folder besides each stage's files."""


@click.command()
@STUDY
@path_option("--out", help="Output directory. Default: outputs/<study name>. " + OVERWRITE_POLICY)
@path_option(
    "--data",
    help="Measured data set (folder with design.toml and measurements.csv) to diagnose.",
)
@click.option("--samples", default=200, show_default=True, help="Tolerance Monte Carlo samples.")
@click.option("--seed", default=0, show_default=True, help="Seed of the Monte Carlo.")
@click.option(
    "--workers",
    type=click.IntRange(1, None),
    default=2,
    show_default=True,
    help="Local Dask workers.",
)
@SCHEDULER
@click.option("--no-render", is_flag=True, help="Skip the part renders (faster).")
def study(
    study_path: Path | None,
    out: Path | None,
    data: Path | None,
    samples: int,
    seed: int,
    workers: int,
    scheduler: str | None,
    no_render: bool,
) -> None:
    """Run STUDY (default: the embedded demonstrator study) through every stage: starting
    workspace, optimisation, Pareto sweeps (Dask), forward re-simulation with the model for
    design work, tolerance Monte Carlo, model effects, CAD and (with --data) diagnosis.
    Writes report.html (self-contained), results.json, manifest.json and each stage's
    files. Finished stages are reused when rerun with the same inputs.

    Exit codes: 0 done; 2 bad input; 3 a stage failed (named, with what was written).
    """
    from ringpair.pipeline import StageError, run_study, write_manifest
    from ringpair.report_html import write_report

    with bad_input(OSError, UnicodeDecodeError):
        text = study_path.read_text() if study_path else ""
    s = study_from(study_path)
    if data is not None and not (data / "measurements.csv").is_file():
        raise UserError(f"--data: {data} is not a data set (expected {data}/measurements.csv)")
    if samples < 2:
        raise UserError(f"--samples must be at least 2; got {samples}")
    out = output_path(
        out or default_out(s.name), "--out", folder=True, typed=out is not None, files=FILES
    )
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    try:
        with progress("starting") as update:

            def say(stage: str) -> None:
                update(description=stage)
                console.print(f"{time.perf_counter() - t0:6.1f} s {stage}")

            run = run_study(
                s,
                out,
                study_text=text or repr(s),
                data=data,
                workers=workers,
                scheduler=scheduler,
                samples=samples,
                seed=seed,
                render=not no_render,
                say=say,
            )
            say("report")
            written = write_report(run)
    except StageError as exc:
        print_error(str(exc))
        if exc.run is not None:
            manifest = write_manifest(exc.run, study_path, data, seed, failed=exc.stage)
            done = ", ".join(exc.run.seconds) or "none"
            err_console.print(
                f"stages finished before it: {done}; their files are listed in {manifest}"
            )
        sys.exit(3)
    manifest = write_manifest(run, study_path, data, seed)
    for name, sec in run.seconds.items():
        console.print(f"  {name:10s} {sec:7.1f} s" + ("  (reused)" if run.reused[name] else ""))
    pdf = [str(p) for p in written if p.suffix == ".pdf"] or [
        "no PDF (headless Chromium, Debian package 'chromium', is not installed)"
    ]
    console.print(f"wrote {written[-2]}, {written[-1]}, {manifest}, {pdf[0]}")
    console.print(f"done in {time.perf_counter() - t0:.1f} s")
