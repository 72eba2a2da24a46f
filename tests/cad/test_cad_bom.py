"""The bill of materials (``cad/bom.csv``) and the plates' print set-ups, on the demonstrator.

Issue 52: what to buy was in no list (magnets, tube and wire with cut lengths, screws,
glue) and no part said how it goes on the bed. The cut lengths are checked against the
assembled solids, the grades against the design's remanence, the printed rows against the
parts table and the 3MF plates.
"""

from __future__ import annotations

import csv
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from cad.bom import BOM_COLUMNS, NDFEB_GRADES, bom_totals, field_rows, magnet_grade
from cad.build import CadReport
from cad.printing import PRINT_SETUP
from cad.stock import cuts
from design.designfile import load_design
from design.records import Design

NS = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}


@pytest.fixture(scope="module")
def bom(fdm_build: CadReport) -> dict[str, dict[str, str]]:
    with open(fdm_build.out_dir / "bom.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == BOM_COLUMNS
    return {r["item"]: r for r in rows}


def test_every_bought_item_is_listed_with_what_to_order(demonstrator: Design, bom) -> None:
    for item in ("ring_magnet", "external_magnet", "catheter", "wire", "lid_screw",
                 "set_screw", "adhesive"):  # fmt: skip
        assert bom[item]["kind"] == "bought", item
    ring = bom["ring_magnet"]
    assert ring["quantity"] == "2" and "diametrically" in ring["specification"]
    assert "N52" in ring["specification"]  # 1.45 T
    assert "OD 4, ID 2, length 0.5" in ring["size_mm"]
    assert "axially" in bom["external_magnet"]["specification"]
    assert "[-1, 0, 0]" in bom["external_magnet"]["note"]
    assert bom["lid_screw"]["quantity"] == "4" and "M3" in bom["lid_screw"]["specification"]


def test_cut_lengths_are_the_assembled_tubes(demonstrator: Design, fdm_build, bom) -> None:
    a = fdm_build.assembly
    tubes = cuts(demonstrator, a.actuator.layout, a.mounting.dims)
    for name, c in tubes.items():
        listed = float(bom[name]["cut_length_mm"])
        solid = a.parts[name].solid.BoundingBox().zlen
        assert listed == pytest.approx(c.length, abs=0.05) and solid == pytest.approx(
            c.length, abs=0.01
        )
        parts_row = next(p for p in fdm_build.parts if p["name"] == name)
        assert max(parts_row["size_mm"]) == pytest.approx(c.length, abs=0.01)


def test_every_printed_part_says_process_mass_orientation_and_supports(fdm_build, bom) -> None:
    printed = {p["name"]: p for p in fdm_build.parts if p["printed"]}
    assert {k for k, r in bom.items() if r["kind"] == "printed"} == set(printed)
    for name, p in printed.items():
        r = bom[name]
        assert r["process"] == p["process"] and float(r["mass_g"]) == p["mass_g"], name
        assert r["on_bed"] == PRINT_SETUP[name].on_bed and r["supports"], name
    assert bom["mounting_piece_proximal"]["process"] == "resin"  # the design's own
    assert bom["worm"]["process"] == "fdm" and "none" in bom["worm"]["supports"]
    totals = bom_totals(fdm_build.bom)
    assert totals["printed_pieces"] == sum(p["quantity"] for p in printed.values())
    assert set(totals["printed_mass_g"]) == {"fdm", "resin"}


def test_3mf_objects_carry_their_print_setup(fdm_build) -> None:
    for plate in fdm_build.out_dir.glob("plate_*.3mf"):
        with zipfile.ZipFile(plate) as z:
            model = ElementTree.fromstring(z.read("3D/3dmodel.model"))
        for obj in model.findall("m:resources/m:object", NS):
            meta = {m.get("name"): m.text for m in obj.findall("m:metadatagroup/m:metadata", NS)}
            setup = PRINT_SETUP[obj.get("name")]
            assert meta["ringpair:on_bed"] == setup.on_bed, plate.name
            assert meta["ringpair:supports"] == setup.supports
            assert meta["ringpair:process"] == plate.name.split("_")[1]


@pytest.mark.parametrize("grade", sorted(NDFEB_GRADES))
def test_grade_named_for_its_own_remanence(grade) -> None:
    assert f"NdFeB {grade} " in magnet_grade(NDFEB_GRADES[grade])
    assert "no NdFeB grade" in magnet_grade(0.9)


# Every field source is in the list: a design with no [external_magnet] (a field map, an
# MRI bore, coils, blocks) crashed the bill of materials before.
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_every_field_source_has_a_row_with_its_own_numbers() -> None:
    seen = set()
    for name in ("block_magnets", "helmholtz_pair", "mri_bore", "field_map"):
        design = load_design(EXAMPLES / f"{name}.toml")
        rows = {r["item"]: r for r in field_rows(design)}
        assert ("external_magnet" in rows) == (design.external_magnet is not None), name
        for n, s in enumerate(design.sources, start=1):
            r, seen = rows[f"source_{n}"], seen | {s.kind}
            centre = ", ".join(f"{c * 1e3:.3g}" for c in s.center)
            if s.kind == "cuboid":
                a, b, c = (x * 1e3 for x in s.dimensions)
                assert r["kind"] == "bought" and f"{a:g} x {b:g} x {c:g}" in r["size_mm"]
                # sintered NdFeB at 7.5 g/cm^3, the block's own volume in cm^3
                assert r["mass_g"] == pytest.approx(7.5 * a * b * c / 1e3, rel=1e-3)
                assert magnet_grade(s.remanence) in r["specification"]
            elif s.kind == "coil":
                assert r["kind"] == "bought" and f"{s.turns:g} turns" in r["specification"]
                assert f"{s.current:.3g} A" in r["specification"]
                assert f"{s.radius * 1e3:g}" in r["size_mm"]
            else:
                assert r["kind"] == "provided" and "nothing to buy" in r["note"], name
            assert s.kind == "uniform" or f"[{centre}]" in r["note"], (name, r["note"])
    assert seen == {"cuboid", "coil", "uniform", "map"}
