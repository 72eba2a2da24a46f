"""Design files (docs/formats.md): the demonstrator, round trips, and one clear message per
kind of bad value."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import tomli_w
from bad_designs import BAD_VALUES, edited

from design.designfile import (
    DesignError,
    default_design,
    design_from_dict,
    dumps_design,
    load_design,
    loads_design,
    save_design,
)
from design.mounting import design_tip_geometry


def test_demonstrator_matches_the_paper_in_si(demonstrator):
    # Sayres & Pittiglio, Sec. III-A: PTFE 1.8/1.2 mm, NiTi 0.4 mm, N52 rings 4/2/0.5 mm,
    # N52 cylinder 76.2 x 38.1 mm whose face is 80 mm beyond the 150 mm robot's tip.
    d = demonstrator
    assert d.robot.free_length == pytest.approx(0.150)
    assert d.robot.catheter.outer_diameter == pytest.approx(1.8e-3)
    assert d.robot.catheter.inner_diameter == pytest.approx(1.2e-3)
    assert d.robot.wire.outer_diameter == pytest.approx(0.4e-3)
    assert d.tip.magnet_outer_diameter == pytest.approx(4e-3)
    assert d.tip.spacing == pytest.approx(0.5e-3)
    ext = d.external_magnet
    face = ext.center[0] - ext.length / 2
    assert face - d.robot.free_length == pytest.approx(0.080)
    assert ext.magnetization == (-1.0, 0.0, 0.0)
    assert d.robot.catheter.youngs_modulus == pytest.approx(766e6)


def test_save_and_load_round_trip(tmp_path, demonstrator):
    path = tmp_path / "d.toml"
    save_design(demonstrator, path)
    assert load_design(path) == demonstrator
    assert "outer_diameter_mm = 1.8\n" in path.read_text()


def test_optional_environment_gravity(demonstrator_doc):
    demonstrator_doc["environment"] = {"gravity_m_s2": [0.0, 0.0, -9.81]}
    d = design_from_dict(demonstrator_doc)
    assert d.environment.gravity == (0.0, 0.0, -9.81)
    assert "gravity_m_s2" in dumps_design(d)


@pytest.mark.parametrize(
    ("key", "value", "words"), BAD_VALUES, ids=[f"{k}={v!r}"[:60] for k, v, _ in BAD_VALUES]
)
def test_bad_value_is_named(demonstrator_doc, key, value, words):
    with pytest.raises(DesignError) as info:
        design_from_dict(edited(demonstrator_doc, key, value))
    message = str(info.value)
    for w in words:
        assert w in message, message
    assert "\n" not in message


def test_missing_section_is_named(demonstrator_doc):
    doc = copy.deepcopy(demonstrator_doc)
    del doc["robot"]["wire"]
    with pytest.raises(DesignError, match=r"missing section \[robot.wire\]"):
        design_from_dict(doc)


def test_not_toml_names_the_file(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("name = 'x'\n[robot\n")
    with pytest.raises(DesignError, match="broken.toml is not valid TOML"):
        load_design(path)


def test_missing_file_is_named(tmp_path):
    with pytest.raises(DesignError, match="does not exist"):
        load_design(tmp_path / "nope.toml")


def test_nearly_unit_magnetization_is_normalised(demonstrator_doc):
    doc = edited(demonstrator_doc, "external_magnet.magnetization", [-0.9999, 0.0, 0.0])
    d = loads_design(tomli_w.dumps(doc))
    assert d.external_magnet.magnetization == (-1.0, 0.0, 0.0)


@pytest.mark.parametrize(("bore_mm", "fits"), [(0.45, True), (0.449, False), (0.4, False)])
def test_ring_bore_must_clear_the_wire_by_the_running_clearance(demonstrator_doc, bore_mm, fits):
    # The demonstrator's wire is 0.4 mm; the bore needs design.admissible.WIRE_CLEARANCE more.
    doc = edited(demonstrator_doc, "tip.magnet_inner_diameter_mm", bore_mm)
    if fits:
        assert design_from_dict(doc).tip.magnet_inner_diameter == pytest.approx(0.45e-3)
        return
    with pytest.raises(DesignError, match=r"robot.wire.outer_diameter_mm \(0.4\) plus 0.05"):
        design_from_dict(doc)


@pytest.mark.parametrize("process", ["resin", "fdm"])
def test_free_length_must_leave_a_rod_under_the_printed_tip(demonstrator_doc, process):
    # The flexible rod ends where the catheter enters the proximal piece, the rigid offset
    # before the tracked point (design.mounting): a shorter free length has no rod at all.
    doc = edited(demonstrator_doc, "tip.mounting", {"process": process})
    offset_mm = design_tip_geometry(design_from_dict(doc)).rigid_offset * 1e3
    assert 1.0 < offset_mm < 150.0
    longer = design_from_dict(edited(doc, "robot.free_length_mm", offset_mm * 1.01))
    assert longer.robot.free_length == pytest.approx(offset_mm * 1.01e-3)
    for short in (offset_mm * 0.99, offset_mm):
        with pytest.raises(DesignError) as refused:
            design_from_dict(edited(doc, "robot.free_length_mm", short))
        message = str(refused.value)
        assert f"rigid offset ({offset_mm:.4g} mm" in message
        assert message.startswith("robot.free_length_mm") and f"got {short:g}" in message


def test_default_design_is_a_fresh_parse():
    assert default_design() == default_design()


def test_optional_friction_and_tip_mass_round_trip(tmp_path, demonstrator_doc):
    # Keys the project adds to the spec (optional, default 0): transmission play and tip mass.
    doc = edited(demonstrator_doc, "robot.wire.friction_angle_deg", 3.0)
    doc = edited(doc, "tip.mass_g", 0.25)
    d = design_from_dict(doc)
    assert d.robot.wire.friction_angle == pytest.approx(np.deg2rad(3.0))
    assert d.tip.mass == pytest.approx(0.25e-3)
    assert d.robot.catheter.friction_angle == 0.0
    save_design(d, tmp_path / "d.toml")
    assert load_design(tmp_path / "d.toml") == d
    with pytest.raises(DesignError, match="robot.wire.friction_angle_deg"):
        design_from_dict(edited(doc, "robot.wire.friction_angle_deg", -1.0))


def _with_mounting(doc: dict, **keys) -> dict:
    doc = copy.deepcopy(doc)
    doc["tip"]["mounting"] = keys
    return doc


def test_mounting_section_is_optional_and_defaults_to_resin(demonstrator):
    # Issue 16: the tip's mounting pieces default to resin, stops at 0 and 180 deg (the
    # paper's range), no pre-twist.
    m = demonstrator.tip.mounting
    assert (m.process, m.wall, m.fit_allowance, m.running_clearance) == (
        "resin",
        pytest.approx(0.5e-3),
        pytest.approx(0.05e-3),
        pytest.approx(0.1e-3),
    )
    assert m.stop_angle == pytest.approx(np.pi)
    assert m.pretwist == 0.0
    assert "mounting" not in dumps_design(demonstrator)


def test_mounting_process_sets_the_numbers_and_keys_override_them(tmp_path, demonstrator_doc):
    doc = _with_mounting(
        demonstrator_doc, process="fdm", wall_mm=1.2, stop_angle_deg=150.0, pretwist_deg=-20.0
    )
    m = design_from_dict(doc).tip.mounting
    assert m.process == "fdm"
    assert m.wall == pytest.approx(1.2e-3)  # given
    assert m.fit_allowance == pytest.approx(0.15e-3)  # fdm's
    assert m.density == pytest.approx(1240.0)
    assert m.stop_angle == pytest.approx(np.deg2rad(150.0))
    assert m.pretwist == pytest.approx(np.deg2rad(-20.0))
    d = design_from_dict(doc)
    save_design(d, tmp_path / "d.toml")
    assert load_design(tmp_path / "d.toml") == d


@pytest.mark.parametrize(
    ("keys", "words"),
    [
        ({"process": "sls"}, ["tip.mounting.process", "'resin', 'fdm'", "'sls'"]),
        ({"stop_angle_deg": 0.0}, ["tip.mounting.stop_angle_deg", "> 0", "<= 270"]),
        ({"stop_angle_deg": 300.0}, ["tip.mounting.stop_angle_deg", "<= 270"]),
        ({"pretwist_deg": "a lot"}, ["tip.mounting.pretwist_deg", "a number"]),
        ({"wall_mm": -0.1}, ["tip.mounting.wall_mm", "> 0"]),
        ({"stops_deg": 90.0}, ["unknown key tip.mounting.stops_deg"]),
    ],
)
def test_bad_mounting_keys_name_the_key(demonstrator_doc, keys, words):
    with pytest.raises(DesignError) as err:
        design_from_dict(_with_mounting(demonstrator_doc, **keys))
    for w in words:
        assert w in str(err.value)


def test_mounting_must_be_a_table(demonstrator_doc):
    doc = copy.deepcopy(demonstrator_doc)
    doc["tip"]["mounting"] = 3
    with pytest.raises(DesignError, match=r"\[tip.mounting\] must be a table"):
        design_from_dict(doc)


def test_locked_parallel_example_reads_its_stops_and_pretwist():
    # examples/locked_parallel.toml: the demonstrator locked parallel as in the paper.
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "locked_parallel.toml"
    m = load_design(path).tip.mounting
    assert (m.process, m.stop_angle, m.pretwist) == (
        "resin",
        pytest.approx(np.pi),
        pytest.approx(np.deg2rad(-40.0)),
    )


def test_every_example_design_file_reads():
    """Each file of examples/ is a valid design (the README's field examples among them)."""
    from pathlib import Path

    examples = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.toml"))
    assert len(examples) >= 5
    for path in examples:
        assert load_design(path).name == path.stem, path
