"""The parameter registry: one name per quantity, read from and written into a design."""

from __future__ import annotations

import numpy as np
import pytest
from setups import random_design

from design.registry import (
    NAMES,
    PARAMETERS,
    RENAMED,
    current,
    design_with,
    file_key,
    file_unit,
    parameter_vector,
)


@pytest.mark.parametrize("seed", range(8000, 8010))
def test_design_with_is_the_inverse_of_parameter_vector(seed):
    rng = np.random.default_rng(seed)
    design = random_design(rng)
    v = parameter_vector(design)
    held = [n for n in NAMES if PARAMETERS[n].field is not None]
    changed = {n: v[NAMES.index(n)] * rng.uniform(0.5, 1.5) + rng.uniform(-1, 1) for n in held}
    w = parameter_vector(design_with(design, changed))
    for n in held:
        assert w[NAMES.index(n)] == changed[n], f"seed {seed}: {n}"
    same = design_with(design, {n: v[NAMES.index(n)] for n in held})
    assert np.array_equal(parameter_vector(same), v), f"seed {seed}"


def test_model_factors_are_not_quantities_of_a_design():
    design = random_design(np.random.default_rng(1))
    with pytest.raises(KeyError, match="bending_rigidity_scale"):
        design_with(design, {"bending_rigidity_scale": 2.0})


def test_file_keys_follow_the_design_file_units():
    assert file_key("magnet_length") == "magnet_length_mm"
    assert file_key("catheter_youngs_modulus") == "catheter_youngs_modulus_mpa"
    assert file_key("magnet_remanence") == "magnet_remanence"
    assert file_unit("wire_friction_angle") == ("deg", np.pi / 180)
    assert file_unit("tip_mass") == ("g", 1e-3)


def test_every_old_name_maps_to_a_parameter_and_warns():
    for old, new in RENAMED.items():
        assert new in PARAMETERS
        with pytest.warns(FutureWarning, match=new):
            assert current(old) == new
        with pytest.warns(FutureWarning):
            assert current(old + "_mm") == new + "_mm"
    assert current("magnet_gap") == "magnet_gap"
