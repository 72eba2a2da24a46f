"""``ringpair show``: a design and its derived quantities."""

from __future__ import annotations

from pathlib import Path

import click
from rich.table import Table

from design.designfile import save_design
from design.magnets import cylinder_moment, ring_moment
from design.sections import bending_rigidity, tube_torsional_rigidity
from design.units import MM
from ringpair.options import DESIGN, FORCE, console, design_from, output_path, path_option


def _source_words(source) -> str:
    """One line of a field source's numbers, in file units."""
    from design.fields.sources import KINDS

    parts = []
    for q in KINDS[source.kind]:
        value = getattr(source, q.name)
        text = (
            "[" + ", ".join(f"{v / q.scale:g}" for v in value) + "]"
            if q.size == 3
            else f"{value / q.scale:g}"
        )
        parts.append(f"{q.key} {text}")
    if source.kind == "map":
        parts.append(f"file {source.file}")
    return f"{source.kind}: " + ", ".join(parts)


@click.command()
@DESIGN
@path_option(
    "--save",
    help="Also write the (validated) design to this TOML file, e.g. to start a new one. "
    "An existing file is replaced only with --force.",
)
@FORCE
def show(design: Path | None, save: Path | None, force: bool) -> None:
    """Validate DESIGN and print it with its derived quantities."""
    d = design_from(design)
    if save is not None:
        output_path(save, "--save", folder=False, replace=force, inputs=[design])
    t, r, e = d.tip, d.robot, d.external_magnet
    table = Table(title=f"design '{d.name}'", show_header=True)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    m_ring = ring_moment(
        t.magnet_outer_diameter, t.magnet_inner_diameter, t.magnet_length, t.magnet_remanence
    )
    rows = [
        ("free length", f"{r.free_length / MM:g} mm"),
        ("bending rigidity EI (catheter + wire)", f"{bending_rigidity(r):.4g} N m^2"),
        ("torsional rigidity GJ catheter", f"{tube_torsional_rigidity(r.catheter):.4g} N m^2"),
        ("torsional rigidity GJ wire", f"{tube_torsional_rigidity(r.wire):.4g} N m^2"),
        ("ring moment (each)", f"{m_ring:.4g} A m^2"),
        ("ring centre spacing", f"{t.spacing / MM:g} mm"),
    ]
    if e is not None:
        rows += [
            (
                "external magnet moment",
                f"{cylinder_moment(e.diameter, e.length, e.remanence):.4g} A m^2",
            ),
            ("external magnet centre", "[" + ", ".join(f"{c / MM:g}" for c in e.center) + "] mm"),
        ]
    rows += [(f"field source {i + 1}", _source_words(s)) for i, s in enumerate(d.sources)]
    for k, v in rows:
        table.add_row(k, v)
    console.print(table)
    if save is not None:
        save_design(d, save)
        console.print(f"wrote {save}")
