"""Design files (spec/formats.md): the demonstrator, round trips, and one clear message per
kind of bad value."""

from __future__ import annotations

import copy
import math

import pytest
import tomli_w

from design.designfile import (
    DesignError,
    default_design,
    design_from_dict,
    dumps_design,
    load_design,
    loads_design,
    save_design,
)


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


def _set(doc: dict, path: str, value) -> dict:
    doc = copy.deepcopy(doc)
    *parents, last = path.split(".")
    node = doc
    for p in parents:
        node = node[p]
    if value is _DELETE:
        del node[last]
    else:
        node[last] = value
    return doc


_DELETE = object()

# (key path, bad value, words the message must contain)
BAD_VALUES = [
    ("tip.remanence_t", _DELETE, ["missing key tip.remanence_t"]),
    ("robot.catheter.outer_diamter_mm", 1.8, ["unknown key robot.catheter.outer_diamter_mm",
                                              "did you mean 'outer_diameter_mm'"]),
    ("tip.magnet_length_mm", "half a mm", ["tip.magnet_length_mm", "a number > 0", "half a mm"]),
    ("tip.magnet_length_mm", True, ["tip.magnet_length_mm", "True"]),
    ("robot.free_length_mm", math.nan, ["robot.free_length_mm", "nan"]),
    ("robot.free_length_mm", math.inf, ["robot.free_length_mm", "inf"]),
    ("robot.free_length_mm", -150.0, ["robot.free_length_mm", "> 0", "-150"]),
    ("robot.wire.outer_diameter_mm", 0.0, ["robot.wire.outer_diameter_mm", "> 0", "got 0"]),
    ("robot.catheter.inner_diameter_mm", 1.9, ["robot.catheter.inner_diameter_mm",
                                               "smaller than outer_diameter_mm (1.8)", "1.9"]),
    ("robot.wire.outer_diameter_mm", 1.3, ["robot.wire.outer_diameter_mm",
                                           "robot.catheter.inner_diameter_mm (1.2)", "1.3"]),
    ("tip.magnet_inner_diameter_mm", 0.3, ["tip.magnet_inner_diameter_mm",
                                           "robot.wire.outer_diameter_mm (0.4)", "0.3"]),
    ("tip.magnet_inner_diameter_mm", 4.5, ["tip.magnet_inner_diameter_mm",
                                           "smaller than magnet_outer_diameter_mm (4)", "4.5"]),
    ("external_magnet.magnetization", [0.0, 0.0, 0.0], ["external_magnet.magnetization",
                                                        "unit vector", "length 0"]),
    ("external_magnet.magnetization", [1.0, 1.0, 0.0], ["external_magnet.magnetization",
                                                        "unit vector", "1.41421"]),
    ("external_magnet.magnetization", [1.0, 0.0], ["external_magnet.magnetization",
                                                   "three finite numbers"]),
    ("external_magnet.center_mm", [150.0, 0.0, 0.0], ["external_magnet.center_mm",
                                                      "overlap", "straight robot"]),
    ("external_magnet.remanence_t", 2.1, ["external_magnet.remanence_t", "<= 1.6", "2.1"]),
    ("tip.remanence_t", -0.1, ["tip.remanence_t", ">= 0", "-0.1"]),
    ("external_magnet.shape", "sphere", ["external_magnet.shape", "'cylinder'", "sphere"]),
    ("robot.catheter.poisson_ratio", 0.7, ["robot.catheter.poisson_ratio", "<= 0.5"]),
    ("colour", "red", ["unknown key colour"]),
]


@pytest.mark.parametrize(("key", "value", "words"), BAD_VALUES,
                         ids=[f"{k}={v!r}"[:60] for k, v, _ in BAD_VALUES])
def test_bad_value_is_named(demonstrator_doc, key, value, words):
    with pytest.raises(DesignError) as info:
        design_from_dict(_set(demonstrator_doc, key, value))
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
    doc = _set(demonstrator_doc, "external_magnet.magnetization", [-0.9999, 0.0, 0.0])
    d = loads_design(tomli_w.dumps(doc))
    assert d.external_magnet.magnetization == (-1.0, 0.0, 0.0)


def test_default_design_is_a_fresh_parse():
    assert default_design() == default_design()
