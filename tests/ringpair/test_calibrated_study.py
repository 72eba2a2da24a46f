"""``ringpair study --data``: the study designs with the robot as built (issue 16 item 5):
the diagnosed effects join the study's model and the calibrated properties of the tubes,
magnets and tip carry over to its start design, while the bench's own geometry does not."""

from __future__ import annotations

import pytest

from design.registry import index, parameter_vector
from optimize.sizing.nlp_designs import study_parameters
from optimize.sizing.studyfile import default_study
from ringpair.pipeline import CARRIED, calibrated_study


def test_calibrated_study_takes_the_diagnosed_model_and_carried_properties():
    study = default_study()
    before = parameter_vector(study.base)
    calibration = {
        "effects": ["gravity", "hysteresis", "torsion"],
        "estimate": {
            "bending_rigidity_scale": 0.8,
            "wire_torsion_scale": 3.0,
            "external_remanence": 1.2,
            "wire_friction_angle": 0.05,
            "external_center_y": 0.01,  # where the bench's magnet stood: not carried
        },
    }
    calibrated, taken = calibrated_study(study, calibration)
    assert calibrated.effects == study.effects | {"gravity", "torsion"}
    assert taken["left_out"] == ["hysteresis"]
    after = study_parameters(calibrated, calibrated.base)
    for name, value in calibration["estimate"].items():
        if name in CARRIED:
            assert after[index(name)] == pytest.approx(value), name
            assert taken["values"][name] == pytest.approx(value)
        else:
            assert after[index(name)] == before[index(name)], name
            assert name not in taken["values"]
    changed = {
        n for n in ("free_length", "magnet_outer_diameter") if after[index(n)] != before[index(n)]
    }
    assert not changed
    assert calibrated.base.external_magnet.remanence == pytest.approx(1.2)
    assert dict(calibrated.calibration) == {
        "bending_rigidity_scale": 0.8,
        "wire_torsion_scale": 3.0,
    }
