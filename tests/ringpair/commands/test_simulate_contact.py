"""``ringpair simulate`` with ``[[environment.obstacles]]``: the contact columns, and bad
obstacle input (one message naming the key, exit 2, nothing written)."""

from __future__ import annotations

import numpy as np
import pytest
import tomli_w

from design.contact import solve_in_contact
from design.designfile import load_design
from design.model import DEFAULT_EFFECTS, RingPairModel
from design.obstacles import gaps, tip_body
from design.units import MM

WALL = {"kind": "plane", "point_mm": [150.0, 12.0, 0.0], "normal": [0.0, -1.0, 0.0]}


def _write(tmp_path, doc, obstacles):
    doc.setdefault("environment", {})["obstacles"] = obstacles
    path = tmp_path / "set-up.toml"
    path.write_bytes(tomli_w.dumps(doc).encode())
    return path


def test_simulate_presses_the_tip_on_a_wall(tmp_path, run, read_csv, demonstrator_doc):
    """A wall at y = 12 mm across the demonstrator's reach: the rows in contact have their
    contact point on the wall and the solver's contact force (the force the tip exerts,
    along the wall's inward normal +y); the others keep the tip's body clear of it."""
    path = _write(tmp_path, demonstrator_doc, [WALL])
    out = tmp_path / "wall.csv"
    result = run("simulate", str(path), "--theta1", "0:180:45", "--out", str(out), "--quiet")
    assert result.exit_code == 0, result.output
    rows = read_csv(out)
    design = load_design(path)
    model = RingPairModel(DEFAULT_EFFECTS)
    body = tip_body(design, printed=True)
    theta = np.deg2rad(np.arange(0, 181, 45.0))
    eq, contact = solve_in_contact(
        model, model.parameters(design), theta, 0.0, list(design.environment.obstacles), body
    )
    touching = [r["in_contact"] == "true" for r in rows]
    assert any(touching) and not all(touching)  # (the set-up presses some, not all)
    for k, r in enumerate(rows):
        force = [float(r[f"contact_force_{a}_mN"]) for a in "xyz"]
        np.testing.assert_allclose(force, contact.force[k] * 1e3, rtol=1e-8, atol=1e-12)
        if touching[k]:
            assert float(r["contact_y_mm"]) == pytest.approx(12.0, abs=1e-6)
            assert force[1] > 0 and abs(force[0]) + abs(force[2]) < 1e-12
        else:
            g = gaps(
                design.environment.obstacles[0], eq.position[k : k + 1], eq.tangent[k : k + 1], body
            )
            assert g[0][0] >= -1e-9 and force == [0.0, 0.0, 0.0]


@pytest.mark.parametrize(
    "obstacle, key",
    [
        ({**WALL, "normal": [0.0, 0.0, 0.0]}, "environment.obstacles[0].normal"),
        ({**WALL, "point_mm": [150.0, 1.0, 0.0]}, "environment.obstacles[0]: the straight"),
        (
            {"kind": "lumen", "point_mm": [0.0, 0.0, 0.0], "normal": [1.0, 0, 0], "radius_mm": 2.0},
            "environment.obstacles[0].radius_mm",
        ),
        ({"kind": "sphere", "point_mm": [150.0, 30.0, 0.0]}, "environment.obstacles[0].radius_mm"),
        ({**WALL, "kind": "cube"}, "environment.obstacles[0].kind"),
        ({**WALL, "friction": 0.2}, "environment.obstacles[0].friction"),
        ({**WALL, "radius_mm": 3.0}, "environment.obstacles[0].radius_mm does not apply"),
    ],
)
def test_bad_obstacles_are_one_message_naming_the_key(
    tmp_path, run, demonstrator_doc, obstacle, key
):
    path = _write(tmp_path, demonstrator_doc, [obstacle])
    out = tmp_path / "never.csv"
    result = run("simulate", str(path), "--theta1", "0", "--out", str(out), "--quiet")
    assert result.exit_code == 2, result.output
    assert key in result.output and "Traceback" not in result.output
    assert not out.exists()


def test_a_design_with_obstacles_round_trips(tmp_path, demonstrator_doc):
    from design.designfile import dumps_design, loads_design

    sphere = {"kind": "sphere", "point_mm": [160.0, 25.0, 0.0], "radius_mm": 5.0}
    design = load_design(_write(tmp_path, demonstrator_doc, [WALL, sphere]))
    assert loads_design(dumps_design(design)) == design
    assert design.environment.obstacles[1].radius == pytest.approx(5.0 * MM)
