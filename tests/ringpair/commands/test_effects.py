"""``ringpair effects``: the tip shift of each model effect against the baseline."""

from __future__ import annotations


def test_effects_table_compares_every_available_effect(tmp_path, run, read_csv):
    out = tmp_path / "effects.csv"
    result = run("effects", "--theta1", "0:24:12", "--out", str(out))
    assert result.exit_code == 0, result.output
    rows = {r["effect"]: r for r in read_csv(out)}
    assert set(rows) == {
        "near_field",
        "large_deflection",
        "torsion",
        "gravity",
        "hysteresis",
        "all",
    }
    assert float(rows["hysteresis"]["max_shift_mm"]) == 0.0  # the demonstrator has no play
    assert float(rows["gravity"]["max_shift_mm"]) > 5.0  # it droops by millimetres
    assert 0.5 < float(rows["near_field"]["max_shift_mm"]) < 5.0
