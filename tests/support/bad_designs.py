"""Bad design-file values and the words their error message must contain; shared by the
design-file tests and the command-line tests."""

from __future__ import annotations

import copy
import math


def edited(doc: dict, path: str, value) -> dict:
    doc = copy.deepcopy(doc)
    *parents, last = path.split(".")
    node = doc
    for p in parents:
        node = node[p]
    if value is DELETE:
        del node[last]
    else:
        node[last] = value
    return doc


class _Delete:
    """The key is removed (its repr names the test case the same in every process)."""

    def __repr__(self) -> str:
        return "<deleted>"


DELETE = _Delete()

# (key path, bad value, words the message must contain)
BAD_VALUES = [
    ("tip.remanence_t", DELETE, ["missing key tip.remanence_t"]),
    (
        "robot.catheter.outer_diamter_mm",
        1.8,
        ["unknown key robot.catheter.outer_diamter_mm", "did you mean 'outer_diameter_mm'"],
    ),
    ("tip.magnet_length_mm", "half a mm", ["tip.magnet_length_mm", "a number > 0", "half a mm"]),
    ("tip.magnet_length_mm", True, ["tip.magnet_length_mm", "True"]),
    ("robot.free_length_mm", math.nan, ["robot.free_length_mm", "nan"]),
    ("robot.free_length_mm", math.inf, ["robot.free_length_mm", "inf"]),
    ("robot.free_length_mm", -150.0, ["robot.free_length_mm", "> 0", "-150"]),
    # finite but absurd: no robot is 1e308 mm long or as stiff as 1e308 MPa
    ("robot.free_length_mm", 1e308, ["robot.free_length_mm", "<= 10000", "1e+308"]),
    # an integer no float holds (TOML's have any number of digits): OverflowError before
    ("robot.free_length_mm", 10**400, ["robot.free_length_mm", "<= 10000", "(401 characters)"]),
    # shorter than the printed tip's rigid offset: no flexible rod left under the rings
    ("robot.free_length_mm", 3.0, ["robot.free_length_mm", "rigid offset", "got 3"]),
    ("robot.wire.youngs_modulus_mpa", 1e308, ["robot.wire.youngs_modulus_mpa", "<= 1e+06"]),
    ("robot.wire.outer_diameter_mm", 0.0, ["robot.wire.outer_diameter_mm", "> 0", "got 0"]),
    (
        "robot.catheter.inner_diameter_mm",
        1.9,
        ["robot.catheter.inner_diameter_mm", "smaller than outer_diameter_mm (1.8)", "1.9"],
    ),
    (
        "robot.wire.outer_diameter_mm",
        1.3,
        ["robot.wire.outer_diameter_mm", "robot.catheter.inner_diameter_mm (1.2)", "1.3"],
    ),
    (
        "tip.magnet_inner_diameter_mm",
        0.3,
        ["tip.magnet_inner_diameter_mm", "robot.wire.outer_diameter_mm (0.4)", "0.3"],
    ),
    (
        "tip.magnet_inner_diameter_mm",
        4.5,
        ["tip.magnet_inner_diameter_mm", "smaller than magnet_outer_diameter_mm (4)", "4.5"],
    ),
    (
        "external_magnet.magnetization",
        [0.0, 0.0, 0.0],
        ["external_magnet.magnetization", "unit vector", "length 0"],
    ),
    (
        "external_magnet.magnetization",
        [1.0, 1.0, 0.0],
        ["external_magnet.magnetization", "unit vector", "1.41421"],
    ),
    (
        "external_magnet.magnetization",
        [1.0, 0.0],
        ["external_magnet.magnetization", "three finite numbers"],
    ),
    (
        "external_magnet.center_mm",
        [150.0, 0.0, 0.0],
        ["external_magnet.center_mm", "overlap", "straight robot"],
    ),
    ("external_magnet.remanence_t", 2.1, ["external_magnet.remanence_t", "<= 1.6", "2.1"]),
    ("tip.remanence_t", -0.1, ["tip.remanence_t", ">= 0", "-0.1"]),
    ("external_magnet.shape", "sphere", ["external_magnet.shape", "'cylinder'", "sphere"]),
    ("robot.catheter.poisson_ratio", 0.7, ["robot.catheter.poisson_ratio", "<= 0.5"]),
    ("colour", "red", ["unknown key colour"]),
]
