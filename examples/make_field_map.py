"""Write ``demonstrator_map.csv``, the field map of ``field_map.toml``: the demonstrator's
external magnet (an axially magnetised N52 cylinder, 76.2 x 38.1 mm, 249.05 mm ahead of
the robot's base) sampled on a 5 mm grid over the volume its tip's rings visit, in the
field-map format of docs/formats.md. It stands in for a map measured on the bench or
exported from COMSOL; a design with it steers as the demonstrator does (to about
0.001 mm, tests/design/model/test_field_map_example.py). Run from anywhere:

    python examples/make_field_map.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from design.cylinder_field import cylinder_field_function
from design.designfile import default_design
from design.fields.fieldmap import write_field_map
from design.units import MM

SPACING_MM = 5.0
GRID_MM = ((120.0, 165.0), (-35.0, 35.0), (-45.0, 25.0))
"""The grid's extent along x, y, z in the base frame [mm]: the rings' centres of every
state of the demonstrator (tip 146.8-150.0, -17.2-17.2, -28.1-4.8 mm with gravity) and
the load ramp to them, with a margin."""


OUT = Path(__file__).resolve().parent / "demonstrator_map.csv"


def main(out: Path = OUT) -> None:
    magnet = default_design().external_magnet
    axes = [np.arange(lo, hi + SPACING_MM / 2, SPACING_MM) * MM for lo, hi in GRID_MM]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    field = cylinder_field_function(gradient=False)
    flux = np.array(
        field(
            (points - np.array(magnet.center)).T,
            np.array(magnet.magnetization),
            magnet.diameter / 2,
            magnet.length,
            magnet.remanence,
        )
    ).T
    write_field_map(out, axes, flux.reshape(*(len(a) for a in axes), 3), digits=12)
    print(f"wrote {out} ({len(points)} nodes, {SPACING_MM:g} mm apart)")


if __name__ == "__main__":
    main()
