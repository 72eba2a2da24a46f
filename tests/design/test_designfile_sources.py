"""The design file's [[field.sources]] (docs/formats.md): read, written back, and bad
input refused with one message naming the key or the map file's line."""

from __future__ import annotations

import numpy as np
import pytest

from design.designfile import DesignError, design_from_dict, dumps_design, loads_design
from design.fields.fieldmap import write_field_map


def with_sources(doc: dict, *sources: dict, external: bool = False) -> dict:
    doc = dict(doc)
    if not external:
        doc.pop("external_magnet")
    doc["field"] = {"sources": list(sources)}
    return doc


COIL = {"kind": "coil", "radius_mm": 100.0, "turns": 200, "current_a": 8.0,
        "center_mm": [150.0, 0.0, -50.0], "axis": [0.0, 0.0, 1.0]}  # fmt: skip
CUBOID = {"kind": "cuboid", "dimensions_mm": [20.0, 20.0, 10.0],
          "center_mm": [150.0, 0.0, -60.0], "magnetization": [0.0, 0.0, 1.0],
          "remanence_t": 1.3}  # fmt: skip


def test_sources_read_in_si_and_write_back(demonstrator_doc, tmp_path):
    uniform = {"kind": "uniform", "b_t": [3.0, 0.0, 0.0]}
    design = design_from_dict(with_sources(demonstrator_doc, uniform, COIL, CUBOID))
    assert design.external_magnet is None
    assert [s.kind for s in design.sources] == ["uniform", "coil", "cuboid"]
    assert design.sources[1].radius == pytest.approx(0.1)
    assert design.sources[2].center == pytest.approx((0.15, 0.0, -0.06))
    again = loads_design(dumps_design(design))
    assert again == design


def test_a_map_source_reads_its_grid_beside_the_design_file(demonstrator_doc, tmp_path):
    axes = tuple(np.linspace(-0.01, 0.01, 4) + c for c in (0.15, 0.0, 0.0))
    flux = np.zeros((4, 4, 4, 3))
    flux[..., 2] = 0.02
    write_field_map(tmp_path / "field.csv", axes, flux)
    path = tmp_path / "design.toml"
    doc = with_sources(demonstrator_doc, {"kind": "map", "file": "field.csv"})
    import tomli_w

    path.write_text(tomli_w.dumps(doc))
    from design.designfile import load_design

    design = load_design(path)
    assert design.sources[0].fieldmap.flux[0, 0, 0, 2] == 0.02
    text = (tmp_path / "field.csv").read_text().splitlines()
    (tmp_path / "field.csv").write_text("\n".join(text[:-1]))
    with pytest.raises(DesignError, match=r"field.sources\[1\].file: .*no row for the node"):
        load_design(path)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({**COIL, "radius_mm": 0.0}, r"field.sources\[1\].radius_mm must be a number > 0"),
        ({"kind": "uniform", "b_t": [float("nan"), 0, 0]}, r"field.sources\[1\].b_t must be"),
        ({**CUBOID, "center_mm": [150.0, 0.0, 0.0]},
         r"field.sources\[1\].center_mm places the cuboid magnet on the straight robot"),
        ({**COIL, "axis": [0.0, 0.0, 2.0]}, r"field.sources\[1\].axis must be a unit vector"),
        ({**COIL, "currnet_a": 1.0}, r"unknown key field.sources\[1\].currnet_a"),
        ({"kind": "dipole"}, r"field.sources\[1\].kind must be one of"),
        ({"kind": "coil", "radius_mm": 10.0}, r"missing key field.sources\[1\].turns"),
        ({"kind": "map"}, r"missing key field.sources\[1\].file"),
    ],
)  # fmt: skip
def test_bad_sources_are_refused_naming_the_key(demonstrator_doc, change, message):
    with pytest.raises(DesignError, match=message):
        design_from_dict(with_sources(demonstrator_doc, change))


def test_a_design_needs_a_field(demonstrator_doc):
    doc = dict(demonstrator_doc)
    doc.pop("external_magnet")
    with pytest.raises(DesignError, match=r"missing section \[external_magnet\]"):
        design_from_dict(doc)
