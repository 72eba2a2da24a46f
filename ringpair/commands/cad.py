"""``ringpair cad``: printable parts of a design, checked and rendered."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ringpair.options import (
    DESIGN,
    OVERWRITE_POLICY,
    bad_input,
    console,
    default_out,
    design_from,
    held_run,
    output_path,
    path_option,
    progress,
)


@click.command()
@DESIGN
@path_option(
    "--out",
    help="Directory for the STEP assembly, STL parts, 3MF plates, check tables and renders. "
    "Default: outputs/<design name>/cad. " + OVERWRITE_POLICY,
)
@click.option(
    "--process",
    type=click.Choice(["fdm", "resin"]),
    default="fdm",
    show_default=True,
    help="Printing process of the actuator's parts: sets fit allowances, clearances, minimum "
    "wall and build volume. The two tip pieces are printed as the design file's "
    "[tip.mounting] says (resin by default), the pieces the model carries.",
)
@click.option("--no-render", is_flag=True, help="Skip the pyvista renders (faster).")
def cad(design: Path | None, out: Path | None, process: str, no_render: bool) -> None:
    """Printable parts of DESIGN: the two mounting pieces with the helical tracking groove
    and the worm-gear actuator, in millimetres.

    Writes ringpair_robot.step (assembly with named parts), stl/<part>.stl, 3MF print
    plates, checks.csv (watertight, volume, minimum wall, build volume, interference, gear
    centre distance), parts.csv, cad_summary.json, renders/*.png and manifest.json (what
    this run wrote; an earlier run's files it did not write again, e.g. another process's
    plates, are removed). Exits 3 if a printability check fails.
    """
    d = design_from(design)
    typed = out is not None
    out = output_path(
        out or default_out(d.name, "cad"), "--out", folder=True, typed=typed, inputs=[design]
    )
    from cad import CadError, build_parts  # after the inputs are checked: CAD loads slowly

    with held_run(out, "cad"):
        with progress("building, exporting, checking and rendering parts"), bad_input(CadError):
            report = build_parts(d, out, process, render=not no_render)
        console.print(report.summary(), highlight=False)
        if not report.passed:
            sys.exit(3)
