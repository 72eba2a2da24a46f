"""``ringpair simulate``: the CSV and table of tip poses."""

from __future__ import annotations

import numpy as np
import pytest

from design.equilibrium import solve_design
from design.model import DEFAULT_EFFECTS, RingPairModel


def test_simulate_writes_the_paper_sweep(tmp_path, demonstrator, run, read_csv):
    out = tmp_path / "sim.csv"
    result = run("simulate", "--theta1", "0:180:12", "--theta2", "0", "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    assert [float(r["theta1_deg"]) for r in rows] == list(range(0, 181, 12))  # 16 like the paper
    # The default model for design work (DEFAULT_EFFECTS), configuration by configuration.
    model = RingPairModel(DEFAULT_EFFECTS)
    eq = solve_design(demonstrator, np.deg2rad(np.arange(0, 181, 12)), 0.0, model)
    np.testing.assert_allclose([float(r["y_mm"]) for r in rows], eq.position[:, 1] * 1e3, rtol=1e-8)
    assert all(r["converged"] == "true" and r["stable"] == "true" for r in rows)
    assert "180.00" in result.output and "stable" in result.output


def test_simulate_takes_every_pair_of_two_lists(tmp_path, run, read_csv):
    out = tmp_path / "s.csv"
    assert (
        run(
            "simulate", "--theta1", "0,90", "--theta2", "0:20:10", "--out", str(out), "--quiet"
        ).exit_code
        == 0
    )
    rows = read_csv(out)
    assert [(float(r["theta1_deg"]), float(r["theta2_deg"])) for r in rows] == [
        (0, 0),
        (0, 10),
        (0, 20),
        (90, 0),
        (90, 10),
        (90, 20),
    ]


def test_simulate_with_effects_and_an_ordered_path(tmp_path, run, read_csv):
    out = tmp_path / "g.csv"
    result = run(
        "simulate",
        "--effects",
        "gravity,hysteresis",
        "--ordered",
        "--theta1",
        "0:60:30",
        "--out",
        str(out),
        "--quiet",
    )
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    assert [r["snapped"] for r in rows] == ["false"] * 3
    assert float(rows[1]["theta1_tip_deg"]) == pytest.approx(30.0)  # no play in the demonstrator


def test_simulate_writes_the_tip_stiffness_of_beam_theory_with_the_field_off(
    tmp_path, run, read_csv, demonstrator_doc
):
    """The stiffness columns [mN/mm]: with the external magnet's remanence 0 (no field)
    the baseline robot is a cantilever, whose
    lateral stiffness at the tip is 3 EI / L^3 (both lateral directions) and whose axis is
    rigid (left out of the largest)."""
    import tomli_w

    from design.designfile import load_design

    doc = demonstrator_doc
    doc["external_magnet"]["remanence_t"] = 0.0
    path = tmp_path / "off.toml"
    path.write_bytes(tomli_w.dumps(doc).encode())
    out = tmp_path / "far.csv"
    result = run(
        "simulate",
        str(path),
        "--effects",
        "none",
        "--theta1",
        "0,90",
        "--out",
        str(out),
        "--quiet",
    )
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    robot = load_design(path).robot
    ei = sum(
        t.youngs_modulus * np.pi * (t.outer_diameter**4 - t.inner_diameter**4) / 64
        for t in (robot.catheter, robot.wire)
    )
    expected = 3 * ei / robot.free_length**3  # N/m = mN/mm
    for r in rows:
        assert float(r["stiffness_min_mN_per_mm"]) == pytest.approx(expected, rel=1e-6)
        assert float(r["stiffness_max_mN_per_mm"]) == pytest.approx(expected, rel=1e-6)
