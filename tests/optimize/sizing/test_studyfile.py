"""Study files: the embedded default study, SI conversion, the materials table, and one
clear message (key, expectation, what was found) per kind of bad value."""

from __future__ import annotations

import math

import pytest

from design.designfile import default_design, save_design
from design.mounting import design_tip_geometry
from optimize.sizing.materials import MATERIALS, material
from optimize.sizing.studyfile import (
    Study,
    StudyError,
    default_study,
    load_study,
    loads_study,
)

MINIMAL = """
name = "s"
[free]
magnet_length_mm = [0.5, 2.0]
[materials]
catheter = ["ptfe"]
wire = ["niti"]
"""


def test_default_study_is_the_demonstrator_set_up():
    s = default_study()
    assert isinstance(s, Study)
    assert s.base == default_design()
    assert s.objective == (("disc_radius", 1.0),)
    bound = s.bound("external_distance")
    assert bound is not None and (bound.low, bound.high) == pytest.approx((0.060, 0.200))
    assert s.limits.twist_limit == pytest.approx(math.radians(15.0))
    assert s.limits.max_outer_diameter == pytest.approx(4e-3)
    assert [p.against for p in s.pareto] == [
        "catheter_outer_diameter",
        "external_distance",
        "magnet_volume",
    ]
    with pytest.raises(AttributeError):
        s.starts = 9  # type: ignore[misc]  # frozen


def test_minimal_study_defaults_in_si():
    s = loads_study(MINIMAL)
    assert s.free[0].name == "magnet_length"
    assert (s.free[0].low, s.free[0].high) == pytest.approx((0.5e-3, 2e-3))
    lim = s.limits
    # the demonstrator's printed tip (its rings are 4 mm across)
    assert lim.max_outer_diameter == pytest.approx(
        design_tip_geometry(default_design()).outer_diameter
    )
    assert lim.max_outer_diameter > 4e-3
    assert lim.wire_clearance == pytest.approx(0.05e-3)
    assert lim.neutral_tolerance == pytest.approx(1e-3)
    assert lim.stable
    assert s.effects == frozenset()
    assert s.starts == 4 and s.configurations == 24


def test_base_design_path_is_relative_to_the_study_file(tmp_path):
    save_design(default_design(), tmp_path / "base.toml")
    text = MINIMAL.replace('name = "s"', 'name = "s"\nbase_design = "base.toml"')
    (tmp_path / "study.toml").write_text(text)
    s = load_study(tmp_path / "study.toml")
    assert s.base.robot.free_length == pytest.approx(0.150)
    assert s.base_source.endswith("base.toml")


def test_weighted_objective_and_effects_list():
    text = MINIMAL.replace(
        'name = "s"',
        'name = "s"\nobjective = { disc_radius = 1.0, reach_ratio = 0.5 }\n'
        'effects = ["torsion", "gravity"]',
    )
    s = loads_study(text)
    assert s.objective == (("disc_radius", 1.0), ("reach_ratio", 0.5))
    assert s.effects == frozenset({"torsion", "gravity"})


def test_materials_table_has_sources_and_sane_values():
    for m in MATERIALS.values():
        assert m.source
        assert 1e8 < m.youngs_modulus < 3e11
        assert 0 < m.poisson_ratio < 0.5
        assert 0 < m.allowable_strain <= 0.08
    assert material("niti").allowable_strain == pytest.approx(0.06)  # superelastic, ~6 %
    with pytest.raises(KeyError, match="did you mean 'ptfe'"):
        material("ptef")


# (edit: old text -> new text, or an appended line; words the message must contain)
BAD = [
    ('name = "s"', 'name = ""', ["name must be a non-empty string"]),
    ('name = "s"', 'name = "s"\nobjektive = "area"', ["unknown key study.objektive", "objective"]),
    (
        "magnet_length_mm = [0.5, 2.0]",
        "magnet_lenght_mm = [0.5, 2.0]",
        ["unknown key free.magnet_lenght_mm", "did you mean 'magnet_length_mm'"],
    ),
    (
        "magnet_length_mm = [0.5, 2.0]",
        "magnet_length_mm = [2.0, 0.5]",
        ["free.magnet_length_mm", "low <= high", "[2.0, 0.5]"],
    ),
    (
        "magnet_length_mm = [0.5, 2.0]",
        "magnet_length_mm = [-1.0, 2.0]",
        ["free.magnet_length_mm", "physical range", "> 0", "[-1.0, 2.0]"],
    ),
    (
        "magnet_length_mm = [0.5, 2.0]",
        "magnet_length_mm = 1.0",
        ["free.magnet_length_mm must be [low, high]", "got 1.0"],
    ),
    ("[free]\nmagnet_length_mm = [0.5, 2.0]\n", "", ["missing section [free]"]),
    ('catheter = ["ptfe"]', 'catheter = ["tefon"]', ["materials.catheter", "got 'tefon'"]),
    ('catheter = ["ptfe"]', "", ["constraints.catheter_max_strain is required"]),
    ('name = "s"', 'name = "s"\nobjective = "volume"', ["objective must be one of", "'volume'"]),
    ('name = "s"', 'name = "s"\neffects = "torsoin"', ["effects", "'torsoin'", "torsion"]),
    (
        'name = "s"',
        'name = "s"\neffects = "hysteresis"',
        ["effects", "'hysteresis'", "not usable in a study"],
    ),
    (
        'name = "s"',
        'name = "s"\nobjective = { controllable_disc_radius = 1.0, area = 1.0 }',
        ["controllable_disc_radius stands alone"],
    ),
    (
        "[free]\n",
        "[free]\nstop_angle_deg = [10.0, 90.0]\n",
        ["free.stop_angle_deg", "torsion and printed_tip", "got effects none"],
    ),
    (
        'name = "s"',
        'name = "s"\nbase_design = "nowhere.toml"',
        ["base_design", "does not exist"],
    ),
    (None, "[constraints]\ntwist_limit_deg = -5.0", ["constraints.twist_limit_deg", "-5.0"]),
    (None, "[constraints]\nmax_strain = 0.1", ["unknown key constraints.max_strain"]),
    (
        None,
        "[constraints]\nwire_clearance_mm = 0.01",  # below design.geometry.WIRE_CLEARANCE
        ["constraints.wire_clearance_mm", "0.05", "0.01"],
    ),
    (None, "[solver]\nstarts = 0", ["solver.starts must be an integer between 1", "got 0"]),
    (None, "[solver]\nseed = 1.5", ["solver.seed must be an integer", "got 1.5"]),
    (
        None,
        '[[pareto]]\nagainst = "catheter_od"',
        ["pareto[0].against must be one of", "'catheter_od'"],
    ),
    (
        None,
        '[[pareto]]\nagainst = "magnet_volume"\nrange_mm = [1.0, 2.0]',
        ["pareto[0].range_mm does not fit", "range_mm3"],
    ),
    (
        "magnet_length_mm = [0.5, 2.0]",
        "catheter_youngs_modulus_mpa = [300.0, 900.0]",
        [],  # one catheter material: fine (checked below with two)
    ),
]


@pytest.mark.parametrize(("old", "new", "words"), BAD)
def test_bad_study_gives_one_clear_message(old, new, words):
    text = MINIMAL + "\n" + new if old is None else MINIMAL.replace(old, new)
    if not words:
        loads_study(text)
        return
    with pytest.raises(StudyError) as info:
        loads_study(text, source="study.toml")
    message = str(info.value)
    assert message.startswith("study.toml: ")
    for w in words:
        assert w in message, message


def test_free_modulus_with_several_materials_is_refused():
    text = MINIMAL.replace(
        "magnet_length_mm = [0.5, 2.0]", "catheter_youngs_modulus_mpa = [300.0, 900.0]"
    ).replace('catheter = ["ptfe"]', 'catheter = ["ptfe", "nylon_12"]')
    with pytest.raises(StudyError, match="at most one catheter material"):
        loads_study(text)


def test_missing_and_malformed_files(tmp_path):
    with pytest.raises(StudyError, match="does not exist"):
        load_study(tmp_path / "none.toml")
    (tmp_path / "bad.toml").write_text("name = [")
    with pytest.raises(StudyError, match="is not valid TOML"):
        load_study(tmp_path / "bad.toml")


def test_old_ring_keys_still_load_with_a_warning_that_names_the_new_key():
    old = MINIMAL.replace("magnet_length_mm", "ring_length_mm")
    with pytest.warns(FutureWarning, match="'ring_length_mm' is now called 'magnet_length_mm'"):
        study = loads_study(old)
    assert study == loads_study(MINIMAL)
