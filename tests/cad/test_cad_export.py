"""Exported files read back: STEP names and unit, STL meshes, the 3MF plate, the tables."""

from __future__ import annotations

import csv
import re
import zipfile
from xml.etree import ElementTree

import cadquery as cq
import numpy as np
import pytest
import trimesh

from cad.build import TIP_PIECES, CadReport
from cad.checks import COLUMNS
from cad.process import FDM, PROCESSES, RESIN

NS = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}


def test_step_assembly_has_named_parts_in_millimetres(fdm_build: CadReport) -> None:
    path = fdm_build.out_dir / "ringpair_robot.step"
    text = path.read_text(encoding="utf-8", errors="replace")
    assert "SI_UNIT(.MILLI.,.METRE.)" in text
    assert not re.search(r"SI_UNIT\(\$,\.METRE\.\)", text)  # no plain metres anywhere
    back = cq.Assembly.importStep(str(path))
    names = {child.name for child in back.children}
    expected = {inst.name for inst in fdm_build.assembly.instances}
    assert names == expected
    # Each instance is its own product, named as it is (issue 52: the distal ring arrived
    # in FreeCAD as ring_magnet_proximal001, a copy of the first instance's product).
    products = re.findall(r"PRODUCT\('([^']*)'", text)
    assert sorted(products) == sorted([*expected, "ringpair_robot"])
    # Read-back geometry is in mm: the housing keeps its modelled size.
    housing = next(c for c in back.children if c.name == "housing")
    bb = housing.toCompound().BoundingBox()
    lay = fdm_build.assembly.actuator.layout
    assert bb.xlen == pytest.approx(lay.length, abs=1e-3)
    assert bb.ylen == pytest.approx(lay.width, abs=1e-3)


def test_stl_per_printed_part_is_watertight_with_the_cad_volume(fdm_build: CadReport) -> None:
    printed = [p for p in fdm_build.parts if p["printed"]]
    assert len(printed) == 12
    for part in printed:
        mesh = trimesh.load_mesh(fdm_build.out_dir / "stl" / f"{part['name']}.stl")
        assert mesh.is_watertight, part["name"]
        assert mesh.is_winding_consistent, part["name"]
        assert mesh.volume == pytest.approx(part["volume_mm3"], rel=0.01), part["name"]
        # Print frame: the part stands on the bed.
        assert mesh.bounds[0][2] == pytest.approx(0.0, abs=1e-6), part["name"]


def test_3mf_plate_holds_every_copy_on_the_bed(fdm_build: CadReport) -> None:
    # The actuator's plates are FDM; the tip pieces are printed as the design says (resin).
    plates = sorted(fdm_build.out_dir.glob("plate_*.3mf"))
    assert {p.name.split("_")[1] for p in plates} == {"fdm", "resin"}
    copies: dict[str, int] = {}
    for plate in plates:
        bed = np.array(PROCESSES[plate.name.split("_")[1]].build_volume_mm[:2])
        with zipfile.ZipFile(plate) as z:
            assert "[Content_Types].xml" in z.namelist()
            model = ElementTree.fromstring(z.read("3D/3dmodel.model"))
        assert model.get("unit") == "millimeter"
        objects = {}
        for obj in model.findall("m:resources/m:object", NS):
            verts = np.array(
                [
                    [float(v.get(k)) for k in "xyz"]
                    for v in obj.findall("m:mesh/m:vertices/m:vertex", NS)
                ]
            )
            objects[obj.get("id")] = (obj.get("name"), verts)
        for item in model.findall("m:build/m:item", NS):
            name, verts = objects[item.get("objectid")]
            t = np.array([float(x) for x in item.get("transform").split()]).reshape(4, 3)
            placed = verts @ t[:3] + t[3]
            assert np.all(placed[:, :2] >= 0) and np.all(placed[:, :2] <= bed), name
            assert placed[:, 2].min() == pytest.approx(0.0, abs=1e-3), name
            copies[name] = copies.get(name, 0) + 1
    expected = {p["name"]: p["quantity"] for p in fdm_build.parts if p["printed"]}
    assert copies == expected


def test_check_table_is_written_and_all_pass_for_the_demonstrator(fdm_build: CadReport) -> None:
    with open(fdm_build.out_dir / "checks.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0].keys()) == COLUMNS
    assert len(rows) == len(fdm_build.checks)
    kinds = {r["check"] for r in rows}
    assert {
        "watertight",
        "volume",
        "min_wall",
        "build_volume",
        "interference",
        "centre_distance",
        "tooth_count",
    } <= kinds
    failed = [r for r in rows if r["passed"] != "True"]
    assert failed == []
    # Every printed part is checked against its process's minimum wall: the actuator's
    # FDM, the tip pieces the design's (resin).
    walls = {r["item"]: r for r in rows if r["check"] == "min_wall"}
    assert len(walls) == 12
    for name, r in walls.items():
        process = RESIN if name in TIP_PIECES else FDM
        assert f"({process.name})" in r["limit"], name
        assert float(r["value"]) >= process.min_wall_mm, name


def test_outputs_are_complete_and_no_temporary_file_is_left(fdm_build: CadReport) -> None:
    out = fdm_build.out_dir
    for f in fdm_build.files:
        assert f.exists() and f.stat().st_size > 0, f
    leftovers = [p for p in out.rglob("*") if p.name.startswith(".") and p.suffix == ".tmp"]
    assert leftovers == []
    assert set(fdm_build.timings_s) == {"build", "export", "check", "render", "total"}
